"""The hit: the learned motion's default hit (direction psi*, speed v*) turned by alpha and
scaled by kappa (Eq. 14 at the ball), and the ball's launch velocity it gives
(:func:`seds_casadi.minigolf.ball.impact`).

A :class:`Stroke` alone is an ideal club: the commanded velocity exactly, a square face and the
impact model's club mass. A stroke with a :class:`LaunchTable` is a particular arm's: the
launch that the arm's own swings produce (its effective mass at the face, its speed and face
errors at the hit), measured over an (alpha, kappa) grid by the game layer
(:func:`seds_casadi.game.launch.calibrate_launch`) and interpolated here, so the teacher and
the hitting-parameter learners are taught what the arm can do.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .ball import CLUB_MASS, RESTITUTION, impact

__all__ = ["Stroke", "LaunchTable"]


@dataclass(frozen=True)
class LaunchTable:
    """A robot's launch, measured: the ball's launch velocity relative to the ideal club's
    commanded velocity, over a grid of hitting angles and speed gains.

    The launch of a hit (alpha, kappa) is ``speed_factor * R(angle_offset) c``, with ``c`` the
    horizontal part of the commanded club velocity kappa v* R_alpha psi* (Eq. 14 at the ball)
    and R a rotation about the field's normal. ``speed_factor`` carries the impact
    ((1 + e) m_eff / (m_eff + m_b), m_eff the arm's effective mass at the face), the arm's
    speed error and the face's tilt; ``angle_offset`` the direction in which the face sends the
    ball. Both are interpolated bilinearly (clamped at the grid's edges). A grid point the arm
    could not swing to a hit has a speed factor of 0: the ball stays where it is.

    Attributes
    ----------
    alphas : array, shape (n_alpha,)
        Hitting angles [rad], increasing.
    kappas : array, shape (n_kappa,)
        Speed gains, increasing.
    speed_factor : array, shape (n_kappa, n_alpha)
        |launch| / |c|.
    angle_offset : array, shape (n_kappa, n_alpha)
        Angle from c to the launch [rad].
    robot : str
        Whose launch it is (for the record).
    """

    alphas: np.ndarray
    kappas: np.ndarray
    speed_factor: np.ndarray
    angle_offset: np.ndarray
    robot: str = ""

    def __post_init__(self) -> None:
        a = np.asarray(self.alphas, float).ravel()
        k = np.asarray(self.kappas, float).ravel()
        f = np.asarray(self.speed_factor, float)
        o = np.asarray(self.angle_offset, float)
        if len(a) < 2 or len(k) < 2 or np.any(np.diff(a) <= 0) or np.any(np.diff(k) <= 0):
            raise ValueError("a launch table needs at least 2 increasing alphas and kappas")
        if f.shape != (len(k), len(a)) or o.shape != f.shape:
            raise ValueError(f"speed_factor and angle_offset must have the shape (n_kappa, "
                             f"n_alpha) = {(len(k), len(a))}, got {f.shape} and {o.shape}")
        if not (np.all(np.isfinite(f)) and np.all(np.isfinite(o)) and np.all(f >= 0)):
            raise ValueError("speed factors must be finite and >= 0, angle offsets finite")
        for name, v in (("alphas", a), ("kappas", k), ("speed_factor", f),
                        ("angle_offset", o)):
            object.__setattr__(self, name, v)

    def at(self, alpha, kappa) -> tuple[np.ndarray, np.ndarray]:
        """(speed factor, angle offset) at each (alpha, kappa), shapes (n,)."""
        a, k = np.broadcast_arrays(np.asarray(alpha, float), np.asarray(kappa, float))
        a, k = a.ravel(), k.ravel()
        ia, wa = _cell(self.alphas, a)
        ik, wk = _cell(self.kappas, k)

        def interp(T):
            return ((1 - wk) * ((1 - wa) * T[ik, ia] + wa * T[ik, ia + 1])
                    + wk * ((1 - wa) * T[ik + 1, ia] + wa * T[ik + 1, ia + 1]))

        return interp(self.speed_factor), interp(self.angle_offset)

    def to_dict(self) -> dict:
        return {"alphas": self.alphas.tolist(), "kappas": self.kappas.tolist(),
                "speed_factor": self.speed_factor.tolist(),
                "angle_offset": self.angle_offset.tolist(), "robot": self.robot}

    @classmethod
    def from_dict(cls, d: dict) -> LaunchTable:
        return cls(np.array(d["alphas"], float), np.array(d["kappas"], float),
                   np.array(d["speed_factor"], float), np.array(d["angle_offset"], float),
                   str(d.get("robot", "")))


def _cell(grid: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index of the grid cell holding each x (clamped to the grid) and the weight of its
    upper end."""
    xc = np.clip(x, grid[0], grid[-1])
    i = np.clip(np.searchsorted(grid, xc, side="right") - 1, 0, len(grid) - 2)
    return i, (xc - grid[i]) / (grid[i + 1] - grid[i])


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
        Impact model of the ideal club (see :func:`seds_casadi.minigolf.ball.impact`).
    launch_table : LaunchTable or None
        A robot's measured launch; None: the ideal club.
    """

    direction: np.ndarray
    speed: float
    club_mass: float = CLUB_MASS
    restitution: float = RESTITUTION
    launch_table: LaunchTable | None = None

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
        """Ball velocity after the impact, shape (n, 2): the ideal club's
        (:func:`~seds_casadi.minigolf.ball.impact`), or the robot's measured launch with a
        :class:`LaunchTable`."""
        if self.launch_table is None:
            return impact(self.club_velocity(alpha, kappa), self.club_mass, self.restitution)
        c = self.club_velocity(alpha, kappa)[:, :2]
        f, off = self.launch_table.at(alpha, kappa)
        co, so = np.cos(off), np.sin(off)
        return f[:, None] * np.column_stack([co * c[:, 0] - so * c[:, 1],
                                             so * c[:, 0] + co * c[:, 1]])

    def with_launch(self, table: LaunchTable | None) -> Stroke:
        """The same stroke with a robot's measured launch (None: the ideal club)."""
        return Stroke(self.direction, self.speed, self.club_mass, self.restitution, table)

    def aim(self, s) -> np.ndarray:
        """The angle alpha (radians) that points the hit straight at the hole, s of shape (n, 2)."""
        s = np.atleast_2d(s)
        return np.arctan2(s[:, 1], s[:, 0]) - np.arctan2(self.direction[1], self.direction[0])

    def to_dict(self) -> dict:
        d = {"direction": self.direction.tolist(), "speed": self.speed,
             "club_mass": self.club_mass, "restitution": self.restitution}
        if self.launch_table is not None:
            d["launch_table"] = self.launch_table.to_dict()
        return d

    @classmethod
    def from_dict(cls, d: dict) -> Stroke:
        """The inverse of :meth:`to_dict` (ValueError, KeyError or TypeError on a bad dict)."""
        table = d.get("launch_table")
        stroke = cls(np.array(d["direction"], float), float(d["speed"]), float(d["club_mass"]),
                     float(d["restitution"]),
                     None if table is None else LaunchTable.from_dict(table))
        if not (stroke.club_mass > 0 and 0 <= stroke.restitution <= 1):
            raise ValueError("club_mass must be positive and restitution in [0, 1]")
        return stroke
