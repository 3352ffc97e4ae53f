"""seds_casadi: learning to play minigolf with stable dynamical systems (SEDS in CasADi/IPOPT).

Reference implementation of Khansari-Zadeh, Kronander and Billard, "Learning to Play Minigolf:
A Dynamical System-based Approach" (Advanced Robotics, 2012), and of SEDS in Python.
"""

# first: in the console script, Ctrl-C or SIGTERM while the rest is imported exits 130 at once
from ._startup import STARTUP_HANDLERS  # noqa: F401
from .core.demo_files import load_demonstrations, save_demonstrations
from .core.demonstrations import Demonstrations
from .core.errors import ConvergenceWarning, ModelFileError, SEDSError, SolverError, StabilityError
from .core.problem import SEDSProblem
from .core.search import DemoSearchCV
from .core.seds import SEDS
from .core.stable_ds import StableDS, certify

__version__ = "0.1.0"

__all__ = [
    "Demonstrations",
    "load_demonstrations",
    "save_demonstrations",
    "SEDS",
    "SEDSProblem",
    "DemoSearchCV",
    "StableDS",
    "certify",
    "SEDSError",
    "SolverError",
    "StabilityError",
    "ModelFileError",
    "ConvergenceWarning",
    "__version__",
]
