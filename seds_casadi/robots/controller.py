"""The 500 Hz controller that executes the hitting motion on a robot: damped-least-squares IK
and inverse dynamics (paper Sections 6 and 7.1-7.2).

Every control period (2 ms by default) :class:`SwingController` reads the club-head pose and
the ball (from the simulation standing in for the sensors) and computes

1. the Cartesian velocity of Eq. 14 at the club head, xdot = kappa R_a v(R_a^T x) h(R_a^T x)
   (x relative to the ball; :func:`seds_casadi.motion.hitting_ds_sx`), or after the hit the
   resting mode that stops the club;
2. an orientation reference that keeps the club face perpendicular to the direction of approach
   (the face's normal along the commanded hitting direction R_a psi* projected on the field,
   the shaft vertical), tracked by an angular velocity proportional to the orientation error
   (:mod:`seds_casadi.robots.orientation`); arms with five joints (the Katana) track only the
   horizontal direction of the face's normal, where the ball goes (a turn about the vertical);
3. joint velocities by damped least squares, qdot = J_w^T (J_w J_w^T + lambda^2 I)^-1 w e,
   with task weights w (position before orientation) and, in the null space of the task, a
   pull towards the home posture and away from joint limits (the WAM's redundancy); over the
   first 80 ms of a swing they are blended in from rest (:func:`~seds_casadi.robots.limits.
   start_blend`: the arm starts at rest, the DS does not), then scaled down together to a
   margin inside the velocity limits (so that the tracking error keeps the simulated arm
   within them), and the integrated reference is kept inside the position limits;
4. torques by inverse dynamics (RNEA) on the reference acceleration with PD feedback on the
   joint errors: tau = RNEA(q, qd, qdd_ref + Kp (q_ref - q) + Kd (qd_ref - qd)); when a torque
   would exceed its limit, the acceleration part is scaled down (gravity is always
   compensated), so the limits hold unless gravity alone exceeds them (for arms whose
   efforts exclude gravity, the Katana, the limit is on tau - g(q)).

Steps 1-3 and the reference acceleration of step 4 are one CasADi Function compiled to C
(:func:`tick_function`); the hit is detected by the motion's
:func:`~seds_casadi.motion.rollout.plane_crossing`.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..codegen import FastEvaluator, compile_functions
from ..motion.golf import BALL_RADIUS
from ..motion.hitting import HittingMotion, hitting_ds_sx
from ..motion.resting import check_rest_mode, resting_system
from ..motion.rollout import plane_crossing
from .dynamics import gravity_ratio
from .ik import (
    CARTESIAN_SPEED_LIMIT,
    IK_METHODS,
    dls_velocities,
    limit_velocities,
    qp_solver,
    qp_terms,
    speed_points,
)
from .limits import START_BLEND, start_blend_scalar
from .models import Robot
from .orientation import face_orientation_sx, orientation_error_sx

__all__ = ["Gains", "SwingController", "tick_function", "qp_terms_function"]


@dataclass
class Gains:
    """Controller settings (defaults suit the WAM and the Katana at 500 Hz).

    Attributes
    ----------
    damping : float
        lambda of the damped least squares.
    orientation_gain : float
        Angular velocity per radian of orientation error [1/s].
    orientation_weight : float
        Weight of the orientation rows against the position rows.
    posture_gain : float
        Null-space pull towards the home posture [1/s].
    kp, kd : float
        Joint feedback as the natural frequency [rad/s] and damping ratio of the joint errors:
        the PD term is an acceleration that RNEA multiplies by the arm's inertia (computed
        torque), so one setting fits arms of any size.
    """

    damping: float = 0.01
    orientation_gain: float = 6.0
    orientation_weight: float = 0.3
    posture_gain: float = 1.0
    kp: float = 120.0
    kd: float = 1.0

    @classmethod
    def for_robot(cls, robot: Robot) -> Gains:
        """Defaults by arm: the same for all since five-joint arms (the Katana) hold only the
        horizontal direction of the face's normal (a turn about the vertical), which their
        joints can follow without pulling the club head off its path (face within 0.2 deg at
        the hit on 15 random swings; holding the whole normal had left it 3-15 deg off)."""
        return cls()


class SwingController:
    """The 500 Hz controller (module docstring).

    Parameters
    ----------
    robot : Robot
    motion : HittingMotion
    period : float
        Control period [s] (2 ms: 500 Hz).
    gains : Gains, optional
    rest_mode : {"flat", "arc"}
        Resting motion after the hit (``"arc"`` lifts the club, for fields it could touch).
    hit_radius : float
        The club hits the ball when it crosses the plane through the ball perpendicular to the
        commanded direction within this distance of the ball's centre [m].
    torque_limit : bool or None
        Scale the commanded joint acceleration down when a torque would exceed its effort
        limit (gravity and velocity terms are kept): the arm then lags its reference, which the
        closed-loop DS corrects. Without it, torques are whatever inverse dynamics asks for.
        None: on when the arm can hold its home posture against gravity within its effort
        limits, and on arms whose efforts exclude gravity (the Katana: see
        ``robots/README.md``).
    blend_time : float
        The commanded joint velocities are blended in from rest over this time [s]
        (:func:`~seds_casadi.robots.limits.start_blend`; 0: no blending, a velocity step).
    velocity_margin : float
        The reference joint velocities are kept within this share of the velocity limits.
    ik : {"dls", "qp"}
        Damped least squares (the paper's; compiled, the fastest) or the same problem as a QP
        with the velocity and position limits as constraints (:mod:`seds_casadi.robots.ik`),
        solved by ``qp_solver_name`` through CasADi's conic interface.
    cartesian_speed_limit : float or None
        Speed limit of the elbow and the wrist centre [m/s] (libbarrett's safety limit on the
        same points; 1.5 m/s as in its examples); None: none.
    """

    def __init__(self, robot: Robot, motion: HittingMotion, period: float = 0.002,
                 gains: Gains | None = None, rest_mode: str = "flat",
                 hit_radius: float = 0.02, torque_limit: bool | None = None,
                 blend_time: float = START_BLEND, velocity_margin: float = 0.95,
                 ik: str = "dls", qp_solver_name: str = "qrqp",
                 cartesian_speed_limit: float | None = CARTESIAN_SPEED_LIMIT) -> None:
        if not (np.isfinite(period) and period > 0):
            raise ValueError(f"the control period must be positive, got {period}")
        if not (np.isfinite(blend_time) and blend_time >= 0):
            raise ValueError(f"blend_time must be >= 0 s, got {blend_time}")
        if not (np.isfinite(velocity_margin) and 0 < velocity_margin <= 1):
            raise ValueError(f"velocity_margin must be in (0, 1], got {velocity_margin}")
        self.blend_time, self.velocity_margin = float(blend_time), float(velocity_margin)
        self.robot, self.motion, self.period = robot, motion, float(period)
        self.gains = gains or Gains.for_robot(robot)
        self.rest_mode = check_rest_mode(rest_mode)
        self.hit_radius = float(hit_radius)
        if torque_limit is None:
            torque_limit = (robot.effort_excludes_gravity
                            or gravity_ratio(robot, robot.q_home) < 1.0)
        self.torque_limit = bool(torque_limit)
        self._ds = motion.compiled()
        self._psi_cache = (np.nan, motion.commanded_direction(0.0))
        self._zero_rest = (np.zeros(9), np.zeros(3))
        Mb = robot.base_placement
        self._base = (Mb.rotation.copy(), Mb.translation.copy())
        self._base_flat = np.concatenate([Mb.rotation.ravel(order="F"), Mb.translation])
        self._margin = 0.05 * (robot.upper - robot.lower)
        self._effort = np.where(robot.effort > 0, robot.effort, np.inf)
        self._zeros = np.zeros(robot.nv)
        if ik not in IK_METHODS:
            raise ValueError(f"ik must be one of {', '.join(IK_METHODS)}, got {ik!r}")
        if cartesian_speed_limit is not None and not (np.isfinite(cartesian_speed_limit)
                                                      and cartesian_speed_limit > 0):
            raise ValueError("cartesian_speed_limit must be positive [m/s] or None, got "
                             f"{cartesian_speed_limit}")
        self.ik, self.cartesian_speed_limit = ik, cartesian_speed_limit
        self._points = speed_points(robot) if cartesian_speed_limit is not None else []
        if ik == "qp":
            terms_sx = qp_terms_function(self)
            tick, terms = compile_functions([tick_function(self), terms_sx])
            self._step = FastEvaluator(_qp_tick(self, tick, terms,
                                                qp_solver(robot.nv, qp_solver_name)))
        else:
            self._step = FastEvaluator(_compiled_tick(self))
        self.reset(robot.q_home)

    def reset(self, q: np.ndarray) -> None:
        """Start a swing from the measured configuration ``q``."""
        self.q_ref = np.asarray(q, float).copy()
        self.qd_ref = np.zeros(self.robot.nv)
        self.hit = None
        self._rest = None
        self._prev = None
        self._t0 = None

    def _psi(self, alpha: float) -> np.ndarray:
        """R_alpha psi* (cached for the last alpha: it rarely changes between ticks)."""
        if alpha != self._psi_cache[0]:
            self._psi_cache = (alpha, self.motion.commanded_direction(alpha))
        return self._psi_cache[1]

    def contact_point(self, ball, alpha: float) -> np.ndarray:
        """Where the club face meets the ball: the ball's centre minus one ball radius along
        the commanded direction (horizontal). The DS's target is this point: the club face
        (the ``club_head`` frame) passes through it with the commanded velocity."""
        psi = self._psi(alpha)
        h = np.hypot(psi[0], psi[1])
        return np.asarray(ball, float) - (BALL_RADIUS / h) * np.array([psi[0], psi[1], 0.0])

    def _detect_hit(self, x, target, alpha, kappa, t) -> None:
        """The club hits when it crosses the plane through the contact point perpendicular to
        the commanded direction, within ``hit_radius`` (:func:`plane_crossing`, the motion's
        hit reading); then the resting mode takes over."""
        psi = self._psi(alpha)
        if self.hit is None and self._prev is not None:
            p0 = self._prev
            hit, lam, p_hit = plane_crossing(p0, x, target, psi, self.hit_radius)
            if hit:
                lam = float(lam)
                self.hit = {"t": t - (1 - lam) * self.period, "lam": lam,
                            "position": p_hit, "psi": psi.copy(),
                            "commanded": kappa * self.motion.hitting_speed * psi}
                # the DS's velocity just before the contact point (past it, the attractor
                # points back): the resting mode continues it and slows down
                v = np.asarray(self._ds(p0 - target, alpha, kappa))
                self._rest = resting_system(p_hit, v, self.motion.rest_length, self.rest_mode)
        self._prev = x

    def tick(self, q, qd, ball, alpha: float = 0.0, kappa: float = 1.0,
             t: float = 0.0) -> np.ndarray:
        """Torques for one period from the measured state (q, qd) and the ball position."""
        import pinocchio as pin

        r = self.robot
        q = np.asarray(q, float)
        qd = np.asarray(qd, float)
        model, data = r.model, r.data
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        M = data.oMf[r.head_frame]
        Jl = pin.getFrameJacobian(model, data, r.head_frame, pin.LOCAL_WORLD_ALIGNED)
        Jp = (np.vstack([pin.getJointJacobian(model, data, j, pin.LOCAL_WORLD_ALIGNED)[:3]
                         for j in self._points]).ravel(order="F") if self._points else ())
        Rb, pb = self._base
        x = Rb @ M.translation + pb
        target = self.contact_point(ball, alpha)
        self._detect_hit(x, target, alpha, kappa, t)
        direction = self.hit["psi"] if self.hit is not None else self._psi(alpha)
        rest = ((self._rest[0].ravel(order="F"), self._rest[1]) if self._rest is not None
                else self._zero_rest)
        if self._t0 is None:
            self._t0 = t
        s = (t - self._t0) / self.blend_time if self.blend_time > 0 else 1.0
        blend = 1.0 if s >= 1.0 else start_blend_scalar(max(s, 0.0))
        out = self._step(np.concatenate([
            q, qd, self.q_ref, self.qd_ref, M.translation, M.rotation.ravel(order="F"),
            Jl.ravel(order="F"), Jp, target, (alpha, kappa, float(self._rest is not None),
                                              blend),
            rest[0], rest[1], direction, self._base_flat]))
        n = r.nv
        self.qd_ref, self.q_ref, a = out[:n], out[n:2 * n], out[2 * n:3 * n]
        tau = pin.rnea(r.model, r.data, q, qd, a).copy()
        if not self.torque_limit:
            return tau
        # the torque that counts against the limits: tau, or tau - g(q) (efforts without gravity)
        g = (pin.computeGeneralizedGravity(r.model, r.data, q) if r.effort_excludes_gravity
             else self._zeros)
        if np.any(np.abs(tau - g) > self._effort):
            tau = self._limit_torque(q, qd, tau, g)
        return tau

    def _limit_torque(self, q, qd, tau, g) -> np.ndarray:
        """Torque-limited computed torque: scale the commanded acceleration (not gravity and
        velocity terms) until every joint's |tau - g| is within its effort limit (g: gravity
        for arms whose efforts exclude it, else zero)."""
        import pinocchio as pin

        r, eff = self.robot, self._effort
        bias = pin.rnea(r.model, r.data, q, qd, self._zeros)
        d = tau - bias
        load = bias - g
        over = np.abs(load + d) > eff
        if not over.any():
            return tau
        # largest s in [0, 1] with |load + s d| <= eff on the joints that are over
        s = float(np.clip(np.min((np.sign(d[over]) * eff[over] - load[over]) / d[over]),
                          0.0, 1.0))
        return bias + s * d


#: compiled DLS ticks of this process, by what :func:`tick_function` reads (at most 16)
_TICKS: dict = {}


def _tick_key(ctl: SwingController) -> tuple:
    """Everything :func:`tick_function` reads with the DLS inverse kinematics: the motion (by
    identity: a value), the arm's limits and home posture, the speed points' count, the gains
    and the controller's numbers. The base placement is an input of the tick, not part of it."""
    r = ctl.robot
    return (id(ctl.motion), r.nv, r.lower.tobytes(), r.upper.tobytes(),
            r.velocity_limit.tobytes(), np.asarray(r.q_home, float).tobytes(),
            len(ctl._points), tuple(vars(ctl.gains).items()), ctl.period, ctl.velocity_margin,
            ctl.cartesian_speed_limit)


def _compiled_tick(ctl: SwingController) -> ca.Function:
    """The compiled DLS tick of ``ctl``: built and compiled once per process for the same
    motion, arm and settings (about 18 ms each time before: every swing built its own)."""
    key = _tick_key(ctl)
    hit = _TICKS.get(key)
    if hit is not None and hit[0] is ctl.motion:
        return hit[1]
    f = compile_functions([tick_function(ctl)])[0]
    if len(_TICKS) >= 16:
        _TICKS.pop(next(iter(_TICKS)))
    _TICKS[key] = (ctl.motion, f)   # the motion is kept alive: its id stays its own
    return f


def _tick_symbols(ctl: SwingController) -> dict:
    """The symbols of the tick's packed input, in packing order (see :meth:`SwingController.tick`)."""
    n, k = ctl.robot.nv, 3 * len(ctl._points)
    S = {name: ca.SX.sym(name, n) for name in ("q", "qd", "q_ref", "qd_ref")}
    S.update(p=ca.SX.sym("p", 3), R=ca.SX.sym("R", 3, 3), J=ca.SX.sym("J", 6, n),
             J_points=ca.SX.sym("J_points", k, n), target=ca.SX.sym("target", 3),
             alpha=ca.SX.sym("alpha"), kappa=ca.SX.sym("kappa"), resting=ca.SX.sym("resting"),
             blend=ca.SX.sym("blend"), A=ca.SX.sym("A", 3, 3), rest=ca.SX.sym("rest", 3),
             direction=ca.SX.sym("dir", 3), Rb=ca.SX.sym("Rb", 3, 3), pb=ca.SX.sym("pb", 3))
    return S


def _task(ctl: SwingController, S: dict):
    """Steps 1-2: the field-frame Jacobian (angular rows reduced for five-joint arms), the
    Cartesian velocity v (Eq. 14, or the resting mode) and the orientation error w."""
    n = ctl.robot.nv
    Rb = S["Rb"]
    # the base placement is an input, so that one compiled tick serves any placement
    x = Rb @ S["p"] + S["pb"]
    R = Rb @ S["R"]
    J = ca.vertcat(Rb @ S["J"][:3, :], Rb @ S["J"][3:, :])
    v_ds = hitting_ds_sx(x - S["target"], S["alpha"], S["kappa"], ctl.motion.target_field,
                         ctl.motion.strength)
    v = ca.if_else(S["resting"] > 0.5, S["A"] @ (x - S["rest"]), v_ds)
    w = orientation_error_sx(R, face_orientation_sx(S["direction"]), n >= 6)
    if n < 6:
        # arms with five joints hold the horizontal direction of the face's normal only (a
        # turn about the vertical): the other two angular rows are left free
        J = ca.vertcat(J[:3, :], ca.DM.zeros(2, n), J[5, :])
    return J, v, w


def _flat(S: dict):
    parts = ca.vertcat(*[ca.vec(v) for v in S.values()])
    return parts, ca.SX.sym("z", parts.numel())


def tick_function(ctl: SwingController) -> ca.Function:
    """One control tick after the kinematics (steps 1-4 of the module docstring, up to the
    acceleration handed to RNEA) as one CasADi Function of one packed input, to be compiled to
    C: about 10x faster than the same numpy code, which a 500 Hz loop in Python needs. With the
    QP inverse kinematics, the QP's solution is a second input (:func:`qp_terms_function`)."""
    r, g = ctl.robot, ctl.gains
    S = _tick_symbols(ctl)
    J, v, w = _task(ctl, S)
    if ctl.ik == "qp":
        qd_task = ca.SX.sym("qd_task", r.nv)
    else:
        qd_task = dls_velocities(ctl, S["q"], J, v, w)
    qd_new = limit_velocities(ctl, qd_task, S["J_points"], S["blend"])
    q, qd, q_ref, qd_ref = S["q"], S["qd"], S["q_ref"], S["qd_ref"]
    lower, upper = ca.DM(r.lower), ca.DM(r.upper)
    qdd_ref = (qd_new - qd_ref) / ctl.period
    q_next = ca.fmin(ca.fmax(q_ref + ctl.period * qd_new, lower), upper)
    # the reference follows the arm: it never runs away from the measured state
    q_next = q + ca.fmin(ca.fmax(q_next - q, -0.05), 0.05)
    wn = g.kp
    acc = qdd_ref + wn * wn * (q_next - q) + 2 * g.kd * wn * (qd_new - qd)
    flat, z = _flat(S)
    # one packed input: a Python call then copies one array, not fourteen
    out = ca.substitute(ca.vertcat(qd_new, q_next, acc, v), flat, z)
    inputs = [z, qd_task] if ctl.ik == "qp" else [z]
    return ca.Function("control_tick", inputs, [out])


def qp_terms_function(ctl: SwingController) -> ca.Function:
    """The QP of the tick (:func:`~seds_casadi.robots.ik.qp_terms`) from the packed input:
    (H, g, lbx, ubx)."""
    S = _tick_symbols(ctl)
    J, v, w = _task(ctl, S)
    H, g, lbx, ubx, scale = qp_terms(ctl, S["q"], S["q_ref"], J, v, w)
    ctl._qp_scale = np.array(scale).ravel()
    flat, z = _flat(S)
    return ca.Function("control_qp", [z], [ca.substitute(e, flat, z) for e in (H, g, lbx, ubx)])


def _qp_tick(ctl: SwingController, compiled_tick, compiled_terms, solver) -> ca.Function:
    """The whole QP tick as one Function of the packed input: the QP's terms, its solution
    (CasADi's conic interface), then the compiled tick on that solution."""
    z = ca.MX.sym("z", compiled_terms.nnz_in(0))
    H, g, lbx, ubx = compiled_terms(z)
    sol = ca.DM(ctl._qp_scale) * solver(h=H, g=g, lbx=lbx, ubx=ubx)["x"]
    return ca.Function("control_tick_qp", [z], [compiled_tick(z, sol)])
