"""The hitting motion: the target field h(x) = f(x) / |f(x)| of a certified SEDS model (Eq. 8),
the strength factor v(x) learned by GMR (Eq. 12), and the steerable hitting DS
xdot = kappa R_alpha v(R_alpha^T x) h(R_alpha^T x) (Eq. 13-14) with its rollouts; plus the
synthetic putting demonstrations shipped with the package. It imports :mod:`seds_casadi.core`
and :mod:`seds_casadi.codegen` only.
"""

from .golf import BALL_MASS, BALL_RADIUS, G
from .hitting import (
    HittingMotion,
    RolloutResult,
    StrengthFactor,
    TargetField,
    approach_paths,
    rotation_z,
)
from .putting_demos import HITTING_DEMOS_FILE, generate_putting_demos, load_hitting_demos

__all__ = ["HittingMotion", "TargetField", "StrengthFactor", "RolloutResult", "rotation_z",
           "approach_paths", "generate_putting_demos", "load_hitting_demos",
           "HITTING_DEMOS_FILE", "BALL_MASS", "BALL_RADIUS", "G"]
