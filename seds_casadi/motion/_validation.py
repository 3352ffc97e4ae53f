"""Input checks shared by the hitting motion's modules (messages say what to pass instead)."""

from __future__ import annotations

import numpy as np


def check_alpha_kappa(alpha, kappa) -> tuple[float, float]:
    """The hitting angle alpha [rad] (finite) and speed gain kappa (> 0) as floats."""
    try:
        alpha, kappa = float(alpha), float(kappa)
    except (TypeError, ValueError):
        raise TypeError(f"alpha and kappa must be numbers, got {alpha!r}, {kappa!r}") from None
    if not np.isfinite(alpha):
        raise ValueError(f"the hitting angle alpha must be finite (radians), got {alpha}")
    if not (np.isfinite(kappa) and kappa > 0):
        raise ValueError(f"the speed gain kappa must be positive and finite, got {kappa}")
    return alpha, kappa
