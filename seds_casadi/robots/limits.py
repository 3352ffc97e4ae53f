"""The arm's limits on a swing: the start from rest, and how close the simulated motion came to
each joint's velocity and torque limit.

* :func:`start_blend`: the factor by which the controller scales the commanded joint velocities
  over the first tens of milliseconds, so that a swing starting at rest does not ask for a
  velocity step (the hitting DS commands about 0.3 m/s at the start point).
* :func:`limit_report`: peak joint speed and torque against each limit over a simulated swing,
  and which limits were broken (what :class:`~seds_casadi.robots.swing.SwingResult` reports).
"""

from __future__ import annotations

import numpy as np

from .models import Robot

__all__ = ["START_BLEND", "start_blend", "start_blend_scalar", "limit_report", "torque_load"]

#: duration of the start-from-rest blending [s]
START_BLEND = 0.08


def start_blend(t, duration: float = START_BLEND):
    """Smooth ramp from 0 to 1 over ``duration``: s^3 (10 - 15 s + 6 s^2), s = t / duration
    (zero velocity, acceleration and jerk of the ramp at both ends). 1 for ``duration`` <= 0."""
    if duration <= 0:
        return np.ones_like(np.asarray(t, float))
    s = np.clip(np.asarray(t, float) / duration, 0.0, 1.0)
    return s**3 * (10 - 15 * s + 6 * s * s)


def start_blend_scalar(s: float) -> float:
    """:func:`start_blend` at the fraction s in [0, 1] of the blending (a float, for the tick)."""
    return s * s * s * (10.0 - 15.0 * s + 6.0 * s * s)


def torque_load(robot: Robot, q: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """The torques that count against the effort limits, (n, nv): tau itself, or tau minus
    gravity g(q) for arms whose published efforts exclude gravity (``robot.effort_excludes_
    gravity``: the Katana's were measured in Gazebo with gravity off)."""
    tau = np.atleast_2d(np.asarray(tau, float))
    if not getattr(robot, "effort_excludes_gravity", False):
        return tau
    import pinocchio as pin

    Q = np.atleast_2d(np.asarray(q, float))
    g = np.array([pin.computeGeneralizedGravity(robot.model, robot.data, qi) for qi in Q])
    return tau - g


def limit_report(robot: Robot, q: np.ndarray, qd: np.ndarray, tau: np.ndarray,
                 tol: float = 1e-6) -> dict:
    """Peak joint speed and torque of a swing against each joint's limit.

    Parameters
    ----------
    robot : Robot
    q, qd, tau : arrays, shape (n, nv)
        The simulated motion and the applied torques, per control tick.
    tol : float
        Relative tolerance before a limit counts as broken.

    Returns
    -------
    dict with ``peak_speed`` and ``peak_torque`` (nv,) (absolute maxima; torque as counted by
    :func:`torque_load`), ``speed_ratio`` and ``torque_ratio`` (nv,) (peak / limit; 0 where no
    limit is given), and ``broken``, a list of messages naming each broken limit.
    """
    vlim = np.where(robot.velocity_limit > 0, robot.velocity_limit, np.inf)
    eff = np.where(robot.effort > 0, robot.effort, np.inf)
    peak_speed = np.max(np.abs(qd), axis=0)
    peak_torque = np.max(np.abs(torque_load(robot, q, tau)), axis=0)
    speed_ratio, torque_ratio = peak_speed / vlim, peak_torque / eff
    broken = []
    for i in range(robot.nv):
        if speed_ratio[i] > 1 + tol:
            broken.append(f"joint {i + 1} speed {peak_speed[i]:.2f} rad/s > limit {vlim[i]:g}")
        if torque_ratio[i] > 1 + tol:
            broken.append(f"joint {i + 1} torque {peak_torque[i]:.3g} N m > effort {eff[i]:g}")
    lo, hi = np.min(q, axis=0), np.max(q, axis=0)
    for i in range(robot.nv):
        if lo[i] < robot.lower[i] - tol or hi[i] > robot.upper[i] + tol:
            broken.append(f"joint {i + 1} position outside [{robot.lower[i]:.3f}, "
                          f"{robot.upper[i]:.3f}]")
    return dict(peak_speed=peak_speed, peak_torque=peak_torque, speed_ratio=speed_ratio,
                torque_ratio=torque_ratio, broken=broken)
