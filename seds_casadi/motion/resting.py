"""The resting mode that stops the club after the hit (paper Section 6: "the motion dynamics are
switched to a resting mode that smoothly stops the robot").

After the hit, xdot = A_r (x - x_r) with A_r = -g I + w (z psi^T - psi z^T) (symmetric part
-g I: stable), g = ||v_hit|| / rest_length, and the rest point x_r chosen so that the velocity is
continuous at the hit. w = 0 slows down along the hitting direction (``"flat"``, flat fields);
w = g curves the club upwards (``"arc"``, fields where it could touch the ground).
"""

from __future__ import annotations

import numpy as np

__all__ = ["REST_MODES", "check_rest_mode", "resting_system"]

#: the resting modes by name
REST_MODES = ("flat", "arc")


def check_rest_mode(mode: str) -> str:
    """``mode`` if it is one of :data:`REST_MODES`, else ValueError listing them."""
    if mode not in REST_MODES:
        raise ValueError(f"unknown resting mode {mode!r}; valid: {', '.join(REST_MODES)}")
    return mode


def resting_system(hit_position, hit_velocity, rest_length: float, mode: str = "flat"
                   ) -> tuple[np.ndarray, np.ndarray]:
    """A_r and x_r of the resting mode (module docstring), continuous with ``hit_velocity``.

    Parameters
    ----------
    hit_position, hit_velocity : array, shape (3,)
    rest_length : float
        Distance [m] over which the club stops.
    mode : {"flat", "arc"}

    Returns
    -------
    A : array, shape (3, 3)
    rest : array, shape (3,)
        A (hit_position - rest) = hit_velocity.
    """
    check_rest_mode(mode)
    p_hit = np.asarray(hit_position, float)
    v_hit = np.asarray(hit_velocity, float)
    speed = float(np.linalg.norm(v_hit))
    if speed <= 0:
        return -np.eye(3), p_hit.copy()
    psi = v_hit / speed
    g = speed / rest_length
    z = np.array([0.0, 0.0, 1.0])
    w = g if mode == "arc" else 0.0
    A = -g * np.eye(3) + w * (np.outer(z, psi) - np.outer(psi, z))
    rest = p_hit + np.linalg.solve(A, -v_hit)  # A (p_hit - rest) = v_hit
    return A, rest
