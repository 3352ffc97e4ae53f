"""The hitting motion: the target field h(x) = f(x) / |f(x)| of a certified SEDS model (Eq. 8,
:mod:`.target_field`), with the strength factor v(x) learned by GMR (Eq. 12,
:mod:`seds_casadi.core.strength`), the steerable hitting DS
xdot = kappa R_alpha v(R_alpha^T x) h(R_alpha^T x) (Eq. 13-14, :mod:`.hitting`), each equation
written once in CasADi; its learner (in :mod:`.hitting`, with the approach paths of
:mod:`.approach`), rollouts with hit detection and perturbations (:mod:`.rollout`) and the
resting mode after the hit (:mod:`.resting`); plus the synthetic putting demonstrations shipped
with the package. It imports :mod:`seds_casadi.core` and :mod:`seds_casadi.codegen` only.
"""

from .approach import approach_paths
from .golf import BALL_MASS, BALL_RADIUS, G
from .hitting import HittingMotion, HittingMotionLearner, hitting_ds_sx
from .putting_demos import HITTING_DEMOS_FILE, generate_putting_demos, load_hitting_demos
from .resting import resting_system
from .rollout import Perturbations, RolloutResult, period_mean_velocity, plane_crossing
from .rotation import rotation_z, rotation_z_sx
from .target_field import TargetField, target_field_sx

__all__ = ["HittingMotion", "HittingMotionLearner", "TargetField", "RolloutResult",
           "Perturbations", "rotation_z", "rotation_z_sx", "approach_paths", "plane_crossing",
           "period_mean_velocity", "resting_system", "hitting_ds_sx", "target_field_sx",
           "generate_putting_demos", "load_hitting_demos", "HITTING_DEMOS_FILE", "BALL_MASS",
           "BALL_RADIUS", "G"]
