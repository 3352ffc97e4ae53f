"""How fast the club head can move along a hitting direction at a configuration, given only the
joints' velocity limits: a linear program, the physical bound no controller can beat.

At the hit the controller asks the club head for a velocity along the hitting direction d and
for the face to keep its orientation (:mod:`seds_casadi.robots.controller`, step 3: all three
angular rows for arms with six or more joints; the turn about the vertical only, the angular
velocity's z row, for five-joint arms such as the Katana). The fastest such motion within the
joints' velocity limits is the linear program

    max_{qd, s}  s   subject to   J_p(q) qd = s d,   J_w(q) qd = 0,   |qd_i| <= v_lim,i,

with J_p the club head's linear Jacobian and J_w the angular rows the controller holds (both in
the field frame). Its optimum saturates at least nv - rank(constraints) joints (a vertex of the
box); :func:`hitting_speed_bound` solves it with HiGHS (``scipy.optimize.linprog``). Any swing
of the 500 Hz controller through ``q`` along ``d`` is at most this fast there; the damped least
squares that scales all joints down together is slower still.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .models import Robot

__all__ = ["SpeedBound", "hitting_speed_bound", "held_rows"]


@dataclass(frozen=True)
class SpeedBound:
    """The solution of the linear program (module docstring).

    Attributes
    ----------
    speed : float
        The largest club-head speed along the direction [m/s] (inf when a joint without a
        velocity limit could make it unbounded; 0 when the configuration cannot move along the
        direction while holding the face).
    joint_velocities : array, shape (nv,)
        Joint velocities that reach it [rad/s] (NaN when unbounded).
    saturated : tuple of int
        The joints (0-based) at their velocity limit there: the joints that bound the speed.
    """

    speed: float
    joint_velocities: np.ndarray
    saturated: tuple[int, ...]


def held_rows(robot: Robot, J: np.ndarray) -> np.ndarray:
    """The angular rows of the field-frame Jacobian ``J`` (6, nv) that the controller holds at
    zero for the face: all three for arms with six or more joints, the z row (the turn about
    the vertical) for five-joint arms
    (:func:`~seds_casadi.robots.orientation.orientation_error_sx`)."""
    return J[3:] if robot.nv >= 6 else J[5:6]


def hitting_speed_bound(robot: Robot, q, direction) -> SpeedBound:
    """The largest club-head speed along ``direction`` at the configuration ``q`` that the
    joints' velocity limits allow, the face's orientation held as the controller holds it (the
    linear program of the module docstring).

    Parameters
    ----------
    robot : Robot
    q : array, shape (nv,)
        A configuration (within the joint limits).
    direction : array, shape (3,)
        The hitting direction in the field frame (any length > 0).

    Returns
    -------
    SpeedBound

    Raises
    ------
    ValueError
        For a configuration of the wrong size, outside the joint limits, or a direction that is
        not a finite non-zero 3-vector.
    """
    from scipy.optimize import linprog

    q = np.asarray(q, float).ravel()
    d = np.asarray(direction, float).ravel()
    if q.shape != (robot.nv,) or not np.all(np.isfinite(q)):
        raise ValueError(f"q must be {robot.nv} finite joint angles of the {robot.name}, got "
                         f"shape {np.shape(q)}")
    if np.any(q < robot.lower - 1e-9) or np.any(q > robot.upper + 1e-9):
        raise ValueError(f"q {np.round(q, 3).tolist()} is outside the {robot.name}'s joint "
                         f"limits")
    if d.shape != (3,) or not np.all(np.isfinite(d)) or np.linalg.norm(d) < 1e-12:
        raise ValueError(f"direction must be a finite non-zero 3-vector, got "
                         f"{np.asarray(direction).tolist()}")
    d = d / np.linalg.norm(d)
    n = robot.nv
    J = robot.head_jacobian(q)
    W = held_rows(robot, J)
    A = np.zeros((3 + len(W), n + 1))
    A[:3, :n], A[:3, n] = J[:3], -d
    A[3:, :n] = W
    vl = robot.velocity_limit
    bounds = [(-v, v) if v > 0 else (None, None) for v in vl] + [(0, None)]
    c = np.zeros(n + 1)
    c[n] = -1.0
    res = linprog(c, A_eq=A, b_eq=np.zeros(len(A)), bounds=bounds, method="highs")
    if res.status == 3:     # unbounded: a joint without a limit
        return SpeedBound(np.inf, np.full(n, np.nan), ())
    if res.status != 0:     # assert: s = 0, qd = 0 is always feasible
        raise RuntimeError(f"the speed bound's linear program failed: {res.message}")
    qd = np.asarray(res.x[:n], float)
    sat = tuple(int(i) for i in np.flatnonzero((vl > 0) & (np.abs(qd) >= vl * (1 - 1e-7))))
    return SpeedBound(float(res.x[n]), qd, sat)
