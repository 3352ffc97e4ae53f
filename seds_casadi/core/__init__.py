"""The SEDS core: demonstrations and their preprocessing, the parametrization of the constrained
problem, the per-sample objectives (Eq. 9 and the original SEDS objectives) with their exact
derivatives, the learner (CasADi + IPOPT), the certified model ``StableDS`` (Eq. 5, Eq. 10),
GMM/GMR, the metrics and the LASA data set. It needs only casadi, numpy, scipy, scikit-learn
(and the LASA data package); it may import :mod:`seds_casadi.codegen` and nothing else of the
package.
"""

from .datasets import LASA_SHAPES, LASA_SINGLE_SHAPES, load_lasa
from .demo_files import load_demonstrations, save_demonstrations
from .demonstrations import Demonstrations
from .errors import ConvergenceWarning, ModelFileError, SEDSError, SolverError, StabilityError
from .model_selection import bic_n_components
from .problem import SEDSProblem
from .search import DemoSearchCV
from .seds import SEDS
from .stable_ds import StableDS, certify
from .strength import StrengthFactor, StrengthFactorLearner

__all__ = [
    "Demonstrations", "load_demonstrations", "save_demonstrations", "SEDS", "SEDSProblem",
    "StableDS", "certify", "load_lasa", "LASA_SHAPES", "LASA_SINGLE_SHAPES", "SEDSError",
    "SolverError", "StabilityError", "ModelFileError", "ConvergenceWarning", "bic_n_components",
    "StrengthFactor", "StrengthFactorLearner", "DemoSearchCV",
]
