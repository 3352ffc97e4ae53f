"""Where a swing starts: the robot's base beside the ball, and a configuration with the club head
at a start point, its face towards the hit (damped least squares on the pose error)."""

from __future__ import annotations

import numpy as np

from ..codegen import FastEvaluator
from .models import Robot, load_robot
from .orientation import face_orientation, orientation_error_function


def _levenberg_marquardt(robot: Robot, q, err, W, iterations: int, tol: float,
                         angle_tol: float = 1e-4):
    """Damped least squares on the weighted pose error ``err(q)`` from ``q`` (within the
    joint limits), until the position error is below ``tol`` and the orientation error below
    ``angle_tol`` [rad] (or no step improves it): (q, error)."""
    q = np.clip(q.copy(), robot.lower, robot.upper)
    e = err(q)
    lam = 1e-2
    for _ in range(iterations):
        if (np.linalg.norm(e[:3]) < tol
                and np.linalg.norm(e[3:]) < angle_tol * max(float(np.min(W[3:])), 1e-12)):
            break
        J = W[:, None] * robot.head_jacobian(q)
        dq = np.linalg.solve(J.T @ J + lam * np.eye(robot.nv), J.T @ e)
        q_new = np.clip(q + dq, robot.lower, robot.upper)
        e_new = err(q_new)
        if e_new @ e_new < e @ e:
            q, e, lam = q_new, e_new, max(lam / 3, 1e-6)
        else:
            lam *= 5
            if lam > 1e6:
                break
    return q, e


def place_head(robot: Robot, position, direction, q0=None, iterations: int = 200,
               tol: float = 1e-3, orientation_weight: float = 0.3, restarts: int = 8,
               random_state: int = 0) -> np.ndarray:
    """A configuration with the club head at ``position`` (field frame) and its face towards
    ``direction``: Levenberg-Marquardt on the weighted pose error (position; the orientation
    error of :func:`~seds_casadi.robots.orientation.orientation_error_sx`), from ``q0``
    (default the home posture) and, if that fails, from seeded random configurations within the
    limits.

    Raises ``ValueError`` when the point cannot be reached within ``tol``.
    """
    target = np.asarray(position, float)
    Rd = face_orientation(direction).ravel(order="F")
    W = np.array([1, 1, 1] + [orientation_weight] * 3)
    rng = np.random.default_rng(random_state)
    orientation = FastEvaluator(orientation_error_function(robot.nv >= 6))

    def err(q):
        x, R = robot.head_pose(q)
        return W * np.concatenate([target - x, orientation(R.ravel(order="F"), Rd)])

    best_pos = np.inf
    seeds = [robot.q_home if q0 is None else np.asarray(q0, float)]
    seeds += [rng.uniform(robot.lower * 0.8, robot.upper * 0.8) for _ in range(restarts)]
    # the full orientation first; an arm that cannot hold it there (five joints) gets the
    # position with the orientation as close as its weight allows
    for q, w in [(s, orientation_weight) for s in seeds] + [(s, 0.03) for s in seeds]:
        W[3:] = w
        q, e = _levenberg_marquardt(robot, q, err, W, iterations, tol)
        pos = float(np.linalg.norm(e[:3]))
        best_pos = min(best_pos, pos)
        if pos < tol:
            return q
    raise ValueError(f"{robot.name}: cannot place the club head at {np.round(target, 3).tolist()}"
                     f" (closest {best_pos:.3f} m away): move the base or the start")


def place_robot(name: str, ball_xy, field=None, **kwargs) -> Robot:
    """The robot ``name`` standing at its :func:`default_base` beside the ball at ``ball_xy``
    (field frame), on the field's surface there when ``field`` is given; ``kwargs`` go to
    :func:`seds_casadi.robots.load_robot`."""
    base = np.asarray(default_base(name), float)
    base[:2] += np.asarray(ball_xy, float)[:2]
    if field is not None:
        base[2] += max(0.0, float(field.surface.height(base[None, :2])[0]))
    return load_robot(name, base=tuple(base), field=field, **kwargs)


def default_base(name: str) -> tuple:
    """A base placement beside a ball at the origin, the robot facing the field's -y side:
    (x, y, z, yaw) [m, rad].

    The Katana's (0.45 m to +y, 0.1 m up) lets its joints' velocity limits give at most
    0.87-0.89 m/s of club speed along a hit towards +x, a launch of at most 1.41 m/s
    (:func:`~seds_casadi.robots.speed_bound.hitting_speed_bound`); no base up to 0.1 m high
    gives more than 1.78 m/s, short of the 1.9-2.1 m/s the 3.3 m ``flat`` field needs
    (``benchmarks/eval_katana_speed_bound.py``): the base is kept, sized for the Katana's own
    green."""
    return {"wam": (0.0, 0.55, 0.0, -np.pi / 2), "katana": (0.0, 0.45, 0.1, -np.pi / 2)}.get(
        name, (0.0, 0.5, 0.0, -np.pi / 2))
