"""R_alpha, the turn of the hitting motion by the hitting angle alpha about +z (Eq. 14)."""

from __future__ import annotations

import casadi as ca
import numpy as np


def rotation_z(alpha: float) -> np.ndarray:
    """R_alpha: rotation by alpha [rad] about +z, array of shape (3, 3)."""
    c, s = np.cos(alpha), np.sin(alpha)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation_z_sx(alpha) -> ca.SX:
    """R_alpha of :func:`rotation_z` for a symbolic (or numeric) angle, a (3, 3) SX matrix."""
    c, s = ca.cos(alpha), ca.sin(alpha)
    return ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))
