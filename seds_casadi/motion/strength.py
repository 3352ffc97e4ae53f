"""The strength factor v(x) > 0 of Eq. 12 (GMR of log speed on position).

It lives in :mod:`seds_casadi.core.strength` (the core's point-to-point models use it too); this
module keeps the hitting motion's import path.
"""

from ..core.strength import StrengthFactor, StrengthFactorLearner, saturate_sx, strength_sx

__all__ = ["StrengthFactor", "StrengthFactorLearner", "strength_sx", "saturate_sx"]
