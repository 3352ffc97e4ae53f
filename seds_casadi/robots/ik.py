"""Inverse kinematics of the 500 Hz controller: joint velocities for the club head's task
(paper Section 7.1), by damped least squares (the paper's) or by a quadratic program with the
joint limits as constraints, and the limits both keep.

Both solve the same damped least-squares problem around the null-space posture pull p,

    min_qd  |W (J qd - e)|^2 + lambda^2 |S^-1 (qd - p)|^2,

with the joint velocities measured against their limits (S = diag(v_lim) / min v_lim; weighted
least norm: on the WAM the fast wrist and elbow joints then take what the slow base joint
cannot, and the swing keeps its speed within the limits), in closed form
(:func:`dls_velocities`) or as a QP (:func:`qp_terms`, solved through CasADi's ``conic``
interface: its own active-set qrqp by default, qpOASES, OSQP, ... by name) with box
constraints from the velocity limits (a margin inside them) and the position limits (the next
reference stays inside them). Where no constraint is active the two agree.

:func:`limit_velocities` then blends the velocities in from rest (the swing's start), scales
them down together to the velocity limits (DLS) and to a Cartesian speed limit of the elbow and
the wrist centre (libbarrett's safety module faults above a set speed of these points; its
examples use 1.5 m/s).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

__all__ = ["IK_METHODS", "dls_velocities", "qp_terms", "limit_velocities", "qp_solver",
           "speed_points", "CARTESIAN_SPEED_LIMIT"]

#: the inverse kinematics a controller can use
IK_METHODS = ("dls", "qp")
#: libbarrett's examples' limit on the elbow and wrist-centre speed [m/s]
CARTESIAN_SPEED_LIMIT = 1.5


def _weighted_task(ctl, q, J, v, w):
    """W J S, W e, the posture pull p / S (towards home, away from the position limits) and the
    joint scaling S: the problem is solved for y = qd / S, S_i = v_lim,i / min v_lim (weighted
    least norm: each joint's velocity measured against its own limit, so that the fast joints
    take the motion the slow ones cannot)."""
    r, g = ctl.robot, ctl.gains
    W = ca.DM([1, 1, 1] + [g.orientation_weight] * 3)
    vl = np.where(r.velocity_limit > 0, r.velocity_limit, np.nan)
    scale = np.nan_to_num(vl / np.nanmin(vl), nan=1.0) if np.any(vl > 0) else np.ones(r.nv)
    S = ca.DM(scale)
    Jw = ca.diag(W) @ J @ ca.diag(S)
    e = W * ca.vertcat(v, g.orientation_gain * w)
    lo, hi = ca.DM(r.lower) + ca.DM(ctl._margin), ca.DM(r.upper) - ca.DM(ctl._margin)
    pull = (g.posture_gain * (ca.DM(r.q_home) - q)
            + 5.0 * (ca.fmax(lo - q, 0) - ca.fmax(q - hi, 0)))
    return Jw, e, pull / S, S


def dls_velocities(ctl, q, J, v, w):
    """Damped least squares (module docstring), SX: the joint velocities (n,)."""
    Jw, e, pull, S = _weighted_task(ctl, q, J, v, w)
    JJt = Jw @ Jw.T + ctl.gains.damping**2 * ca.DM.eye(6)
    # y = Jw^T (JJt)^-1 e + (I - Jw^T (JJt)^-1 Jw) pull = pull + Jw^T (JJt)^-1 (e - Jw pull)
    return S * (pull + Jw.T @ ca.solve(JJt, e - Jw @ pull))


def qp_terms(ctl, q, q_ref, J, v, w):
    """The QP in y = qd / S: Hessian H (n, n), gradient g (n,) and bounds (lbx, ubx), SX: the
    same objective as :func:`dls_velocities`, the velocity limits (times the controller's
    margin) and the position limits over one period as bounds. qd = S y."""
    r = ctl.robot
    Jw, e, pull, S = _weighted_task(ctl, q, J, v, w)
    lam2 = ctl.gains.damping**2
    H = Jw.T @ Jw + lam2 * ca.DM.eye(r.nv)
    g = -(Jw.T @ e + lam2 * pull)
    vlim = ca.DM(np.where(r.velocity_limit > 0, ctl.velocity_margin * r.velocity_limit, 1e9))
    lower, upper = ca.DM(r.lower), ca.DM(r.upper)
    lbx = ca.fmin(ca.fmax(-vlim, (lower - q_ref) / ctl.period), 0) / S
    ubx = ca.fmax(ca.fmin(vlim, (upper - q_ref) / ctl.period), 0) / S
    return H, g, lbx, ubx, S


def limit_velocities(ctl, qd, J_points, blend):
    """Blend ``qd`` in from rest (factor ``blend``) and scale it down together so that every
    joint stays within the velocity limits and the elbow and wrist centre (``J_points``: their
    stacked 3 x n Jacobians) within the Cartesian speed limit (both times the margin), SX."""
    r = ctl.robot
    qd = blend * qd
    vlim = ca.DM(np.where(r.velocity_limit > 0, ctl.velocity_margin * r.velocity_limit, 1e9))
    scale = ca.mmax(ca.fabs(qd) / vlim)
    if ctl.cartesian_speed_limit is not None:
        for k in range(J_points.shape[0] // 3):
            speed = ca.norm_2(J_points[3 * k:3 * k + 3, :] @ qd)
            scale = ca.fmax(scale, speed / (ctl.velocity_margin * ctl.cartesian_speed_limit))
    return qd / ca.fmax(scale, 1.0)


def speed_points(robot) -> list[int]:
    """Joints whose origins are the elbow and the wrist centre (pinocchio joint ids): the
    WAM's joints 4 and 6 (libbarrett's elbow and wrist centre), otherwise the middle joint and
    the last but one."""
    n = robot.model.njoints - 1
    if robot.name == "wam":
        return [4, 6]
    return sorted({max(1, (n + 1) // 2), max(1, n - 1)})


def qp_solver(n: int, solver: str = "qrqp") -> ca.Function:
    """CasADi's ``conic`` for the box-constrained QP of :func:`qp_terms` over n variables."""
    opts = {"error_on_fail": False}
    if solver == "qpoases":
        opts.update(printLevel="none", sparse=False)
    elif solver == "osqp":
        opts["osqp"] = {"verbose": False, "eps_abs": 1e-8, "eps_rel": 1e-8}
    elif solver == "qrqp":
        opts.update(print_iter=False, print_header=False)
    if not ca.has_conic(solver):
        raise ValueError(f"CasADi has no QP solver {solver!r} here; try 'qpoases', 'osqp', "
                         f"'qrqp' or 'daqp'")
    return ca.conic("swing_ik", solver, {"h": ca.Sparsity.dense(n, n), "a": ca.Sparsity(0, n)},
                    opts)
