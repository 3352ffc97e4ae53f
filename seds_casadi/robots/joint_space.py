"""Demonstrations in joint space: Cartesian club-head demonstrations mapped through the IK.

The paper notes that the SEDS formulation works in any state space, joint space included. This
module maps Cartesian putting demonstrations (club head relative to the ball, the default hit
along +x) to the configurations of a robot standing beside the ball, so that SEDS can learn the
swing as a 7-D motion of the WAM's joints with the hitting configuration as its attractor.

Each demonstration is mapped *backwards* from the hitting configuration q* (the IK at the ball,
club face along the hit): every sample's IK starts from the configuration of the sample after
it, so the joint trajectories are continuous, every one ends exactly at q*, and a redundant arm
does not jump between IK branches.
"""

from __future__ import annotations

import numpy as np

from ..core.demonstrations import Demonstrations
from .models import Robot
from .placement import place_head

__all__ = ["joint_space_demos"]


def joint_space_demos(robot: Robot, demos: Demonstrations, ball=(0.0, 0.0, 0.0),
                      direction=(1.0, 0.0, 0.0), tol: float = 1e-3) -> Demonstrations:
    """The configurations that put the club head on each demonstrated point.

    Parameters
    ----------
    robot : Robot
        A robot placed beside the ball (e.g. :func:`~seds_casadi.robots.place_robot`).
    demos : Demonstrations
        Club-head positions relative to the ball [m] (e.g.
        :func:`~seds_casadi.motion.load_hitting_demos`), with their time step.
    ball : array, shape (3,)
        The ball in the robot's field frame [m].
    direction : array, shape (3,)
        The hitting direction the club face is held towards.
    tol : float
        IK position tolerance [m].

    Returns
    -------
    Demonstrations
        Joint trajectories (rad), target q* (the IK at the demonstrations' target), same
        time step.

    Raises
    ------
    ValueError
        A demonstrated point the robot cannot reach (names the demonstration and sample).
    """
    ball = np.asarray(ball, dtype=float)
    dt = demos.estimated_dt()
    q_star = place_head(robot, ball + demos.target, direction, tol=tol)
    out = []
    for n, p in enumerate(demos.positions):
        qs = np.empty((len(p), robot.nv))
        q = q_star
        for i in range(len(p) - 1, -1, -1):
            try:
                q = place_head(robot, ball + p[i], direction, q0=q, tol=tol, restarts=2)
            except ValueError as exc:
                raise ValueError(f"demonstration {n}, sample {i}: {exc}") from None
            qs[i] = q
        out.append(qs)
    return Demonstrations(out, dt=dt, target=q_star)
