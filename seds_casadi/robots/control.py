"""Executing the hitting motion on a robot: damped-least-squares IK and inverse dynamics at
500 Hz, simulated with Pinocchio's forward dynamics (paper Sections 6 and 7.1-7.2).

Every control period (2 ms by default) :class:`SwingController` reads the club-head pose and
the ball (from the simulation standing in for the sensors) and computes

1. the Cartesian velocity of Eq. 14 at the club head, xdot = kappa R_a v(R_a^T x) h(R_a^T x)
   (x relative to the ball), or after the hit the resting mode that stops the club;
2. an orientation reference that keeps the club face perpendicular to the direction of approach
   (the face's normal along the commanded hitting direction R_a psi* projected on the field,
   the shaft vertical), tracked by an angular velocity proportional to the orientation error;
   arms with five joints (the Katana) track the face's normal only;
3. joint velocities by damped least squares, qdot = J_w^T (J_w J_w^T + lambda^2 I)^-1 w e,
   with task weights w (position before orientation) and, in the null space of the task, a
   pull towards the home posture and away from joint limits (the WAM's redundancy); joint
   velocities are scaled down together to respect the velocity limits, and the integrated
   reference is kept inside the position limits;
4. torques by inverse dynamics (RNEA) on the reference acceleration with PD feedback on the
   joint errors: tau = RNEA(q, qd, qdd_ref + Kp (q_ref - q) + Kd (qd_ref - qd)); when a torque
   would exceed its limit, the acceleration part is scaled down (gravity is always
   compensated), so the limits hold unless gravity alone exceeds them.

:func:`simulate_swing` integrates the robot's forward dynamics (ABA, classical Runge-Kutta with
sub-steps) under these torques, so tracking, torque limits and the club-head velocity at impact
are measured rather than assumed.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..motion.golf import BALL_RADIUS
from ..motion.hitting import HittingMotion, rotation_z
from .models import Robot

__all__ = ["SwingController", "SwingResult", "Gains", "simulate_swing", "place_head",
           "default_base", "place_robot", "gravity_ratio", "face_orientation",
           "effective_mass"]


def _log3(R: np.ndarray) -> np.ndarray:
    """Rotation vector of R (so(3) log)."""
    c = np.clip((np.trace(R) - 1) / 2, -1.0, 1.0)
    th = np.arccos(c)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if th < 1e-6:
        return 0.5 * w
    if th > np.pi - 1e-4:
        # near pi: axis from the diagonal
        axis = np.sqrt(np.maximum((np.diag(R) + 1) / 2, 0))
        k = int(np.argmax(axis))
        axis[np.arange(3) != k] = R[k, np.arange(3) != k] / (2 * axis[k])
        return th * axis / np.linalg.norm(axis)
    return th / (2 * np.sin(th)) * w


def orientation_error(R: np.ndarray, Rd: np.ndarray, full: bool) -> np.ndarray:
    """Rotation vector from R towards Rd: all three axes (``full``), or only the face's normal
    (x axis) for arms with fewer than six joints, which cannot also hold the shaft."""
    if full:
        return _log3(Rd @ R.T)
    return np.cross(R[:, 0], Rd[:, 0])


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


def face_orientation(direction) -> np.ndarray:
    """Desired club-head rotation: x (face normal) along the horizontal part of ``direction``,
    z (shaft, towards the flange) up."""
    d = np.asarray(direction, float).copy()
    d[2] = 0.0
    n = np.linalg.norm(d)
    x = d / n if n > 1e-9 else np.array([1.0, 0, 0])
    z = np.array([0.0, 0.0, 1.0])
    return np.column_stack([x, np.cross(z, x), z])


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
        """Defaults by arm: five-joint arms (the Katana) hold the face's normal only, gently,
        so that it does not pull the club head off its path (measured on the Fig. 7 cases:
        direction errors up to 7 deg with the six-joint settings, 0.5 deg with these)."""
        if robot.nv < 6:
            return cls(orientation_gain=1.0, orientation_weight=0.1)
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
        limits (the Katana's published efforts cannot: see ``robots/README.md``).
    """

    def __init__(self, robot: Robot, motion: HittingMotion, period: float = 0.002,
                 gains: Gains | None = None, rest_mode: str = "flat",
                 hit_radius: float = 0.02, torque_limit: bool | None = None) -> None:
        if not (np.isfinite(period) and period > 0):
            raise ValueError(f"the control period must be positive, got {period}")
        if rest_mode not in ("flat", "arc"):
            raise ValueError(f"unknown resting mode {rest_mode!r}; valid: flat, arc")
        self.robot, self.motion, self.period = robot, motion, float(period)
        self.gains = gains or Gains.for_robot(robot)
        self.rest_mode = rest_mode
        self.hit_radius = float(hit_radius)
        if torque_limit is None:
            torque_limit = gravity_ratio(robot, robot.q_home) < 1.0
        self.torque_limit = bool(torque_limit)
        self._ds = motion.compiled()
        self._hd = np.asarray(motion.hitting_direction, float).copy()
        self._psi_cache = (np.nan, self._hd)
        self._zero_rest = (np.zeros(9), np.zeros(3))
        Mb = robot.base_placement
        self._base = (Mb.rotation.copy(), Mb.translation.copy())
        self._base_flat = np.concatenate([Mb.rotation.ravel(order="F"), Mb.translation])
        n = robot.nv
        self._margin = 0.05 * (robot.upper - robot.lower)
        self._effort = np.where(robot.effort > 0, robot.effort, np.inf)
        self._zeros = np.zeros(robot.nv)
        from ..codegen import FastEvaluator, compile_functions

        self._step = FastEvaluator(compile_functions([_tick_function(self)])[0])
        self.q_ref = robot.q_home.copy()
        self.qd_ref = np.zeros(n)
        self.hit = None
        self._rest = None
        self._prev = None

    def reset(self, q: np.ndarray) -> None:
        """Start a swing from the measured configuration ``q``."""
        self.q_ref = np.asarray(q, float).copy()
        self.qd_ref = np.zeros(self.robot.nv)
        self.hit = None
        self._rest = None
        self._prev = None

    def _psi(self, alpha: float) -> np.ndarray:
        """R_alpha psi* (cached for the last alpha: it rarely changes between ticks)."""
        if alpha != self._psi_cache[0]:
            c, s = np.cos(alpha), np.sin(alpha)
            d = self._hd
            self._psi_cache = (alpha, np.array([c * d[0] - s * d[1], s * d[0] + c * d[1], d[2]]))
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
        the commanded direction, within ``hit_radius``; then the resting mode takes over."""
        psi = self._psi(alpha)
        if self.hit is None and self._prev is not None:
            p0 = self._prev
            s0, s1 = float(psi @ (p0 - target)), float(psi @ (x - target))
            if s0 < 0 <= s1:
                lam = -s0 / (s1 - s0)
                p_hit = p0 + lam * (x - p0)
                if np.linalg.norm(p_hit - target) <= self.hit_radius:
                    self.hit = {"t": t - (1 - lam) * self.period, "lam": lam,
                                "position": p_hit, "psi": psi.copy(),
                                "commanded": kappa * self.motion.hitting_speed * psi}
                    # the DS's velocity just before the contact point (past it, the attractor
                    # points back): the resting mode continues it and slows down
                    v = np.asarray(self._ds(p0 - target, alpha, kappa))
                    self._rest = self.motion._rest_system(p_hit, v, self.rest_mode)
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
        Rb, pb = self._base
        x = Rb @ M.translation + pb
        target = self.contact_point(ball, alpha)
        self._detect_hit(x, target, alpha, kappa, t)
        direction = self.hit["psi"] if self.hit is not None else self._psi(alpha)
        rest = ((self._rest[0].ravel(order="F"), self._rest[1]) if self._rest is not None
                else self._zero_rest)
        out = self._step(np.concatenate([
            q, qd, self.q_ref, self.qd_ref, M.translation, M.rotation.ravel(order="F"),
            Jl.ravel(order="F"), target, (alpha, kappa, float(self._rest is not None)),
            rest[0], rest[1], direction, self._base_flat]))
        n = r.nv
        self.qd_ref, self.q_ref, a = out[:n], out[n:2 * n], out[2 * n:3 * n]
        tau = pin.rnea(r.model, r.data, q, qd, a).copy()
        if self.torque_limit and np.any(np.abs(tau) > self._effort):
            # torque-limited computed torque: scale the commanded acceleration (not gravity
            # and velocity terms) until every joint is within its effort limit
            eff = self._effort
            bias = pin.rnea(r.model, r.data, q, qd, self._zeros)
            d = tau - bias
            over = np.abs(tau) > eff
            # largest s in [0, 1] with |bias + s d| <= eff on the joints that are over
            s = float(np.clip(np.min((np.sign(d[over]) * eff[over] - bias[over]) / d[over]),
                              0.0, 1.0))
            tau = bias + s * d
        return tau


def _tick_function(ctl: SwingController):
    """One control tick after the kinematics (steps 1-4 of the module docstring, up to the
    acceleration handed to RNEA) as one CasADi Function, compiled to C: about 10x faster
    than the same numpy code, which a 500 Hz loop in Python needs."""
    import casadi as ca

    r, g, n = ctl.robot, ctl.gains, ctl.robot.nv
    q, qd, q_ref, qd_ref = (ca.SX.sym(s, n) for s in ("q", "qd", "q_ref", "qd_ref"))
    p_loc, R_loc = ca.SX.sym("p", 3), ca.SX.sym("R", 3, 3)
    J_loc = ca.SX.sym("J", 6, n)
    target, alpha, kappa, resting = (ca.SX.sym("target", 3), ca.SX.sym("alpha"),
                                     ca.SX.sym("kappa"), ca.SX.sym("resting"))
    A, rest, direction = ca.SX.sym("A", 3, 3), ca.SX.sym("rest", 3), ca.SX.sym("dir", 3)
    # the base placement is an input, so that one compiled tick serves any placement
    Rb, pb = ca.SX.sym("Rb", 3, 3), ca.SX.sym("pb", 3)
    x = Rb @ p_loc + pb
    R = Rb @ R_loc
    J = ca.vertcat(Rb @ J_loc[:3, :], Rb @ J_loc[3:, :])
    v_ds = ctl.motion.to_casadi()(x - target, alpha, kappa)
    v = ca.if_else(resting > 0.5, A @ (x - rest), v_ds)
    dh = ca.vertcat(direction[0], direction[1], 0)
    xd = dh / ca.fmax(ca.norm_2(dh), 1e-12)
    zd = ca.DM([0, 0, 1.0])
    Rd = ca.horzcat(xd, ca.cross(zd, xd), zd)
    if n >= 6:
        E = Rd @ R.T - R @ Rd.T  # 2 sin(theta) [axis]x: the rotation towards Rd
        w = 0.5 * ca.vertcat(E[2, 1], E[0, 2], E[1, 0])
    else:
        w = ca.cross(R[:, 0], xd)
    W = ca.DM([1, 1, 1] + [g.orientation_weight] * 3)
    Jw = ca.diag(W) @ J
    e = W * ca.vertcat(v, g.orientation_gain * w)
    JJt = Jw @ Jw.T + g.damping**2 * ca.DM.eye(6)
    lower, upper = ca.DM(r.lower), ca.DM(r.upper)
    lo, hi = lower + ca.DM(ctl._margin), upper - ca.DM(ctl._margin)
    pull = g.posture_gain * (ca.DM(r.q_home) - q) + 5.0 * (ca.fmax(lo - q, 0) - ca.fmax(q - hi, 0))
    # qd = Jw^T (JJt)^-1 e + (I - Jw^T (JJt)^-1 Jw) pull = pull + Jw^T (JJt)^-1 (e - Jw pull)
    qd_new = pull + Jw.T @ ca.solve(JJt, e - Jw @ pull)
    vlim = ca.DM(np.where(r.velocity_limit > 0, r.velocity_limit, 1e9))
    scale = ca.mmax(ca.fabs(qd_new) / vlim)
    qd_new = qd_new / ca.fmax(scale, 1.0)
    qdd_ref = (qd_new - qd_ref) / ctl.period
    q_next = ca.fmin(ca.fmax(q_ref + ctl.period * qd_new, lower), upper)
    # the reference follows the arm: it never runs away from the measured state
    q_next = q + ca.fmin(ca.fmax(q_next - q, -0.05), 0.05)
    wn = g.kp
    acc = qdd_ref + wn * wn * (q_next - q) + 2 * g.kd * wn * (qd_new - qd)
    parts = [q, qd, q_ref, qd_ref, p_loc, R_loc, J_loc, target, alpha, kappa, resting, A, rest,
             direction, Rb, pb]
    flat = ca.vertcat(*[ca.vec(s) for s in parts])
    # one packed input: a Python call then copies one array, not fourteen
    z = ca.SX.sym("z", flat.numel())
    out = ca.vertcat(qd_new, q_next, acc, v)
    return ca.Function("control_tick", [z], [ca.substitute(out, flat, z)])


@dataclass
class SwingResult:
    """A simulated swing.

    Attributes
    ----------
    t : array (n,)
    q, qd, tau : arrays (n, nv)
    head : array (n, 3)
        Club-head positions in the field frame.
    hit : bool
    hit_time : float
    hit_velocity : array (3,)
        Measured club-head velocity at the hit.
    commanded : array (3,)
        kappa v* R_alpha psi*.
    peak_torque_ratio : float
        max |tau_i| / effort_i over the swing.
    limits_ok : bool
        Joint positions stayed within their limits.
    tick_us : array (n,)
        Wall time of each control tick [us] (the controller only, not the simulation).
    face_normal : array (3,)
        The club face's normal at the hit (for :func:`seds_casadi.ball.impact`).
    effective_mass : float
        The arm's mass as the ball feels it at the face along its normal at the hit
        (:func:`effective_mass`; the impact model's club mass for this robot).
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    tau: np.ndarray
    head: np.ndarray
    hit: bool
    hit_time: float = np.nan
    hit_velocity: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    commanded: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    peak_torque_ratio: float = np.nan
    limits_ok: bool = True
    tick_us: np.ndarray = field(default_factory=lambda: np.zeros(0))
    face_normal: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    effective_mass: float = np.nan

    @property
    def direction_error_deg(self) -> float:
        """Angle between the measured and the commanded hitting velocity [deg]."""
        a, b = self.hit_velocity, self.commanded
        c = a @ b / (np.linalg.norm(a) * np.linalg.norm(b))
        return float(np.degrees(np.arccos(np.clip(c, -1, 1))))

    @property
    def face_error_deg(self) -> float:
        """Horizontal angle between the club face's normal and the commanded direction at the
        hit [deg]: where a flat face sends the ball (:func:`seds_casadi.ball.impact`)."""
        a, b = self.face_normal[:2], self.commanded[:2]
        c = a @ b / (np.linalg.norm(a) * np.linalg.norm(b))
        return float(np.degrees(np.arccos(np.clip(c, -1, 1))))

    @property
    def speed_error(self) -> float:
        """Relative error of the hitting speed."""
        return float(abs(np.linalg.norm(self.hit_velocity) / np.linalg.norm(self.commanded)
                         - 1))


def place_head(robot: Robot, position, direction, q0=None, iterations: int = 200,
               tol: float = 1e-3, orientation_weight: float = 0.3, restarts: int = 8,
               random_state: int = 0) -> np.ndarray:
    """A configuration with the club head at ``position`` (field frame) and its face towards
    ``direction``: Levenberg-Marquardt on the weighted pose error, from ``q0`` (default the
    home posture) and, if that fails, from seeded random configurations within the limits.

    Raises ``ValueError`` when the point cannot be reached within ``tol``.
    """
    target = np.asarray(position, float)
    Rd = face_orientation(direction)
    W = np.array([1, 1, 1] + [orientation_weight] * 3)
    rng = np.random.default_rng(random_state)

    def err(q):
        x, R = robot.head_pose(q)
        return W * np.concatenate([target - x, orientation_error(R, Rd, robot.nv >= 6)])

    best_pos = np.inf
    seeds = [robot.q_home if q0 is None else np.asarray(q0, float)]
    seeds += [rng.uniform(robot.lower * 0.8, robot.upper * 0.8) for _ in range(restarts)]
    # the full orientation first; an arm that cannot hold it there (five joints) gets the
    # position with the orientation as close as its weight allows
    for q, w in [(s, orientation_weight) for s in seeds] + [(s, 0.03) for s in seeds]:
        W[3:] = w
        q = np.clip(q.copy(), robot.lower, robot.upper)
        e = err(q)
        lam = 1e-2
        for _ in range(iterations):
            if np.linalg.norm(e[:3]) < tol:
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
    from .models import load_robot

    base = np.asarray(default_base(name), float)
    base[:2] += np.asarray(ball_xy, float)[:2]
    if field is not None:
        base[2] += max(0.0, float(field.surface.height(base[None, :2])[0]))
    return load_robot(name, base=tuple(base), field=field, **kwargs)


def default_base(name: str) -> tuple:
    """A base placement beside a ball at the origin, the robot facing the field's -y side."""
    return {"wam": (0.0, 0.55, 0.0, -np.pi / 2), "katana": (0.0, 0.45, 0.1, -np.pi / 2)}.get(
        name, (0.0, 0.5, 0.0, -np.pi / 2))


def simulate_swing(robot: Robot, motion: HittingMotion, ball, alpha: float = 0.0,
                   kappa: float = 1.0, start=None, period: float = 0.002, substeps: int = 4,
                   max_time: float = 3.0, rest_time: float = 0.4, gains: Gains | None = None,
                   perturb=None, rest_mode: str = "flat", hole=None,
                   params=None) -> SwingResult:
    """Swing at the ball with the 500 Hz controller on the robot's forward dynamics.

    Parameters
    ----------
    robot : Robot
    motion : HittingMotion
    ball : array, shape (3,)
        Ball centre in the field frame.
    alpha, kappa : float
    start : array, shape (3,), optional
        Club-face start relative to the contact point (default: 0.3 m behind it, 5 cm up,
        turned by alpha).
    period : float
        Control period [s].
    substeps : int
        Integration steps of the dynamics per control period.
    max_time, rest_time : float
        Give up without a hit after ``max_time``; simulate ``rest_time`` after the hit.
    perturb : list of dict, optional
        ``{"t": time, "ball": new position}`` and/or ``"hole"`` applied during the swing (no
        re-planning), as in the paper's Fig. 8.
    hole : array, shape (2,) or (3,), optional
        The hole, read by ``params`` every tick.
    params : callable, optional
        ``params(ball, hole) -> (alpha, kappa)``, evaluated every tick from the current ball
        and hole (e.g. a hitting-parameter model on the situation hole - ball); overrides
        ``alpha`` and ``kappa``.
    """
    import pinocchio as pin

    ball = np.asarray(ball, float).copy()
    hole = None if hole is None else np.asarray(hole, float).copy()
    robot.check_reach(ball)
    if params is not None:
        alpha, kappa = (float(v) for v in params(ball, hole))
    if start is None:
        start = rotation_z(alpha) @ np.array([-0.3, 0.0, 0.05])
    psi = rotation_z(alpha) @ motion.hitting_direction
    ctl = SwingController(robot, motion, period, gains, rest_mode)
    q = place_head(robot, ctl.contact_point(ball, alpha) + np.asarray(start, float), psi)
    qd = np.zeros(robot.nv)
    ctl.reset(q)
    h = period / int(substeps)
    events = sorted(perturb or [], key=lambda e: e["t"])
    T, Q, QD, TAU, X, TICK = [], [], [], [], [], []
    t, t_end = 0.0, max_time
    hit_v = v_prev = hit_n = hit_m = None
    ei = 0
    while t < t_end - 1e-12:
        while ei < len(events) and events[ei]["t"] <= t + 1e-12:
            if "ball" in events[ei]:
                ball = np.asarray(events[ei]["ball"], float).copy()
            if "hole" in events[ei]:
                hole = np.asarray(events[ei]["hole"], float).copy()
            ei += 1
        if params is not None and ctl.hit is None:
            alpha, kappa = (float(v) for v in params(ball, hole))
        had_hit = ctl.hit is not None
        t0 = time.perf_counter_ns()
        tau = ctl.tick(q, qd, ball, alpha, kappa, t)
        TICK.append(time.perf_counter_ns() - t0)
        v_now = robot.head_jacobian(q)[:3] @ qd
        if not had_hit and ctl.hit is not None:
            # the velocity at the crossing of the contact plane, interpolated between this
            # tick and the previous one (near the ball the direction turns quickly)
            lam = float(ctl.hit["lam"])
            hit_v = v_now if v_prev is None else v_prev + lam * (v_now - v_prev)
            hit_n = robot.head_pose(q)[1][:, 0]
            hit_m = effective_mass(robot, q, hit_n)
            t_end = t + rest_time
        v_prev = v_now
        x, _ = robot.head_pose(q)
        T.append(t)
        Q.append(q.copy())
        QD.append(qd.copy())
        TAU.append(tau.copy())
        X.append(x)
        for _ in range(int(substeps)):
            # classical RK4 on (q, qd) with the torque held over the period
            m, d = robot.model, robot.data
            a1 = pin.aba(m, d, q, qd, tau)
            a2 = pin.aba(m, d, q + 0.5 * h * qd, qd + 0.5 * h * a1, tau)
            a3 = pin.aba(m, d, q + 0.5 * h * (qd + 0.5 * h * a1), qd + 0.5 * h * a2, tau)
            a4 = pin.aba(m, d, q + h * (qd + 0.5 * h * a2), qd + h * a3, tau)
            q = q + h * qd + h * h / 6 * (a1 + a2 + a3)
            qd = qd + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
        t += period
    tau_arr = np.array(TAU)
    Q = np.array(Q)
    eff = np.where(robot.effort > 0, robot.effort, np.inf)
    res = SwingResult(np.array(T), Q, np.array(QD), tau_arr, np.array(X), ctl.hit is not None,
                      peak_torque_ratio=float(np.max(np.abs(tau_arr) / eff)),
                      limits_ok=bool(np.all(Q >= robot.lower - 1e-6)
                                     and np.all(Q <= robot.upper + 1e-6)),
                      tick_us=np.array(TICK) / 1e3)
    if ctl.hit is not None:
        res.hit_time = ctl.hit["t"]
        res.hit_velocity = hit_v
        res.face_normal = hit_n
        res.effective_mass = hit_m
        res.commanded = ctl.hit["commanded"]
    return res
