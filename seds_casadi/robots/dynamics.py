"""What the arm's dynamics say about a swing: the share of its effort limits that holding a
posture takes, and the mass the ball feels at the club face."""

from __future__ import annotations

import numpy as np

from .models import Robot


def effective_mass(robot: Robot, q, direction) -> float:
    """The arm's effective mass at the club face along ``direction`` (field frame):
    1 / (n^T J M(q)^-1 J^T n), J the face point's linear Jacobian, M the joint-space inertia
    (club included). A short impact sees this mass (the torques change little in 1 ms)."""
    import pinocchio as pin

    q = np.asarray(q, float)
    M = pin.crba(robot.model, robot.data, q)
    M = np.triu(M) + np.triu(M, 1).T
    J = robot.head_jacobian(q)[:3]
    n = np.asarray(direction, float) / np.linalg.norm(direction)
    Jn = n @ J
    return float(1.0 / (Jn @ np.linalg.solve(M, Jn)))


def gravity_ratio(robot: Robot, q) -> float:
    """max_i |g_i(q)| / effort_i: the share of the effort limits that holding ``q`` takes."""
    import pinocchio as pin

    g = pin.computeGeneralizedGravity(robot.model, robot.data, np.asarray(q, float))
    eff = np.where(robot.effort > 0, robot.effort, np.inf)
    return float(np.max(np.abs(g) / eff))
