"""The hit: the learned motion's default hit (direction psi*, speed v*) turned by alpha and
scaled by kappa (Eq. 14 at the ball), and the ball's launch velocity it gives
(:func:`seds_casadi.minigolf.ball.impact`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .ball import CLUB_MASS, RESTITUTION, impact

__all__ = ["Stroke"]


@dataclass(frozen=True)
class Stroke:
    """The learned motion's default hit: direction psi* and speed v* (Eq. 13).

    Attributes
    ----------
    direction : array, shape (3,)
        psi*, unit; the field's normal is +z.
    speed : float
        v* [m/s].
    club_mass, restitution : float
        Impact model (see :func:`seds_casadi.minigolf.ball.impact`).
    """

    direction: np.ndarray
    speed: float
    club_mass: float = CLUB_MASS
    restitution: float = RESTITUTION

    def __post_init__(self) -> None:
        d = np.asarray(self.direction, dtype=float).reshape(-1)
        if d.shape != (3,) or not np.all(np.isfinite(d)) or np.linalg.norm(d[:2]) < 1e-6:
            raise ValueError("direction must be a finite 3-vector with a horizontal part")
        if not (np.isfinite(self.speed) and self.speed > 0):
            raise ValueError(f"speed must be positive, got {self.speed}")
        object.__setattr__(self, "direction", d / np.linalg.norm(d))
        object.__setattr__(self, "speed", float(self.speed))

    @classmethod
    def from_motion(cls, motion) -> Stroke:
        """The stroke of a fitted :class:`~seds_casadi.motion.HittingMotion`."""
        return cls(np.asarray(motion.hitting_direction), float(motion.hitting_speed))

    def club_velocity(self, alpha, kappa) -> np.ndarray:
        """kappa v* R_alpha psi* (Eq. 14 at the ball), shape (n, 3); alpha in radians."""
        a, k = np.broadcast_arrays(np.asarray(alpha, dtype=float), np.asarray(kappa, dtype=float))
        a, k = a.ravel(), k.ravel()
        c, s = np.cos(a), np.sin(a)
        d = self.direction
        return (k * self.speed)[:, None] * np.column_stack(
            [c * d[0] - s * d[1], s * d[0] + c * d[1], np.full_like(a, d[2])])

    def launch_velocity(self, alpha, kappa) -> np.ndarray:
        """Ball velocity after the impact, shape (n, 2)."""
        return impact(self.club_velocity(alpha, kappa), self.club_mass, self.restitution)

    def aim(self, s) -> np.ndarray:
        """The angle alpha (radians) that points the hit straight at the hole, s of shape (n, 2)."""
        s = np.atleast_2d(s)
        return np.arctan2(s[:, 1], s[:, 0]) - np.arctan2(self.direction[1], self.direction[0])

    def to_dict(self) -> dict:
        return {"direction": self.direction.tolist(), "speed": self.speed,
                "club_mass": self.club_mass, "restitution": self.restitution}
