"""Approach paths: short virtual paths into the ball added to the SEDS data of a hitting motion
so that swings line up with psi* before they reach the ball (an extension of the paper, on by
default in :class:`~seds_casadi.motion.hitting.HittingMotionLearner`).

Why: plain SEDS fixes the limit direction psi* but not how fast swings line up with it. With the
slowest and next eigenvalues of J = df/dx at the ball close (ratio ~1.6 on the shipped
demonstrations), the misalignment decays only as r^0.6 and a swing from the side still arrives
degrees off (4 of 50 random starts more than 1 deg off at the hit, all 50 commanded more than
1 deg off somewhere in the last centimetre; ``benchmarks/eval_hitting_accuracy.py
--no-approach-paths``).

What: paths over the last ``length`` (10 cm in the learner) before the ball, b = c a^``order``
(a: distance behind the ball along the demonstrations' arrival direction u, b: sideways offset,
8 sides, two initial slopes), all tangent to u at the ball. They teach the direction objective
(Eq. 9) to bring sideways motion in faster than the approach (order 3: the misalignment decays as
r^2 in the ideal case).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..core.demonstrations import Demonstrations

__all__ = ["approach_paths", "arrival_direction", "arrival_speed"]


def approach_paths(direction, speed: float, length: float = 0.05, order: float = 3.0,
                   n_sides: int = 8, slopes: Sequence[float] = (0.3, 0.8), n_samples: int = 12
                   ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Virtual paths into the ball along ``direction`` (see the module docstring).

    Each path is b = c a^order for a from ``length`` down to ``length / 30`` and then the ball,
    a the distance behind the ball along u = ``direction``, b the offset towards one of
    ``n_sides`` sides perpendicular to u, c set by the path's initial slope db/da (``slopes``).
    Velocities have magnitude ``speed`` and the path's tangent direction, u - order (b/a) w.

    Returns
    -------
    positions, velocities : lists of arrays, shape (n_samples + 1, 3), relative to the ball.
    """
    u = np.asarray(direction, dtype=float).ravel()
    if u.shape != (3,) or not np.all(np.isfinite(u)) or np.linalg.norm(u) == 0:
        raise ValueError(f"direction must be a finite non-zero 3-vector, got {direction!r}")
    u = u / np.linalg.norm(u)
    if not (length > 0 and order > 1 and speed > 0):
        raise ValueError(f"approach paths need length > 0, order > 1 and speed > 0, got "
                         f"{length}, {order}, {speed}")
    Q = np.linalg.svd(np.eye(3) - np.outer(u, u))[0][:, :2]
    a = np.geomspace(length, length / 30.0, int(n_samples))
    P, V = [], []
    for j in range(int(n_sides)):
        phi = 2.0 * np.pi * j / n_sides
        w = Q @ np.array([np.cos(phi), np.sin(phi)])
        for slope in slopes:
            b = slope * length / order * (a / length) ** order  # db/da = slope at a = length
            d = u[None, :] - (order * b / a)[:, None] * w[None, :]
            d /= np.linalg.norm(d, axis=1)[:, None]
            P.append(np.vstack([-a[:, None] * u + b[:, None] * w, np.zeros(3)]))
            V.append(speed * np.vstack([d, u]))
    return P, V


def arrival_direction(demos: Demonstrations) -> np.ndarray:
    """The demonstrations' mean direction of arrival at the ball (unit mean of the unit last
    velocities), shape (d,)."""
    u = np.mean([v[-1] / np.linalg.norm(v[-1]) for v in demos.velocities], axis=0)
    return u / np.linalg.norm(u)


def arrival_speed(demos: Demonstrations) -> float:
    """The demonstrations' mean speed at the ball."""
    return float(np.mean([np.linalg.norm(v[-1]) for v in demos.velocities]))
