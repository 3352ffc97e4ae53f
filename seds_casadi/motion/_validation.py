"""Input checks shared by the hitting motion's modules (messages say what to pass instead)."""

from __future__ import annotations

import numpy as np

__all__ = ["as_points", "check_alpha_kappa"]


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


def as_points(X, d: int, name: str = "X") -> tuple[np.ndarray, bool]:
    """``X`` as finite rows of shape (n, d), and whether it was one point of shape (d,)."""
    X = np.asarray(X, dtype=float)
    single = X.ndim == 1
    X2 = np.atleast_2d(X)
    if X2.ndim != 2 or X2.shape[1] != d:
        raise ValueError(f"{name} must have shape (n, {d}) or ({d},), got {X.shape}")
    if not np.all(np.isfinite(X2)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return X2, single
