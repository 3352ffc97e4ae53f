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

:func:`simulate_swing` integrates the robot's forward dynamics (ABA, semi-implicit Euler with
sub-steps) under these torques, so tracking, torque limits and the club-head velocity at impact
are measured rather than assumed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .ball import BALL_RADIUS
from .motion import HittingMotion, rotation_z
from .robots import Robot

__all__ = ["SwingController", "SwingResult", "Gains", "simulate_swing", "place_head",
           "default_base", "gravity_ratio", "face_orientation"]


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
        n = robot.nv
        self._margin = 0.05 * (robot.upper - robot.lower)
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

    def contact_point(self, ball, alpha: float) -> np.ndarray:
        """Where the club face meets the ball: the ball's centre minus one ball radius along
        the commanded direction (horizontal). The DS's target is this point: the club face
        (the ``club_head`` frame) passes through it with the commanded velocity."""
        d = rotation_z(alpha) @ self.motion.hitting_direction
        d[2] = 0.0
        return np.asarray(ball, float) - BALL_RADIUS * d / np.linalg.norm(d)

    def cartesian_command(self, x: np.ndarray, ball: np.ndarray, alpha: float,
                          kappa: float, t: float) -> np.ndarray:
        """Eq. 14 before the hit, the resting mode after; detects the hit."""
        psi = rotation_z(alpha) @ self.motion.hitting_direction
        if self.hit is None and self._prev is not None:
            p0 = self._prev
            s0, s1 = float(psi @ (p0 - ball)), float(psi @ (x - ball))
            if s0 < 0 <= s1:
                lam = -s0 / (s1 - s0)
                p_hit = p0 + lam * (x - p0)
                if np.linalg.norm(p_hit - ball) <= self.hit_radius:
                    self.hit = {"t": t, "position": p_hit, "psi": psi,
                                "commanded": kappa * self.motion.hitting_speed * psi}
                    v = np.asarray(self._ds(x - ball, alpha, kappa))
                    self._rest = self.motion._rest_system(p_hit, v, self.rest_mode)
        self._prev = x.copy()
        if self._rest is not None:
            A, rest = self._rest
            return (x - rest) @ A.T
        return np.asarray(self._ds(x - ball, alpha, kappa))

    def tick(self, q, qd, ball, alpha: float = 0.0, kappa: float = 1.0,
             t: float = 0.0) -> np.ndarray:
        """Torques for one period from the measured state (q, qd) and the ball position."""
        import pinocchio as pin

        r, g = self.robot, self.gains
        q = np.asarray(q, float)
        qd = np.asarray(qd, float)
        x, R = r.head_pose(q)
        v = self.cartesian_command(x, self.contact_point(ball, alpha), alpha, kappa, t)
        direction = self.hit["psi"] if self.hit is not None else \
            rotation_z(alpha) @ self.motion.hitting_direction
        w = g.orientation_gain * orientation_error(R, face_orientation(direction), r.nv >= 6)
        J = r.head_jacobian(q)
        W = np.array([1, 1, 1] + [g.orientation_weight] * 3, float)
        Jw = W[:, None] * J
        e = W * np.concatenate([v, w])
        JJt = Jw @ Jw.T + g.damping**2 * np.eye(6)
        qd_task = Jw.T @ np.linalg.solve(JJt, e)
        # null space: home posture, and a push away from the limits within the margin
        pull = g.posture_gain * (r.q_home - q)
        lo, hi = r.lower + self._margin, r.upper - self._margin
        pull += 5.0 * (np.maximum(lo - q, 0) - np.maximum(q - hi, 0))
        N = np.eye(r.nv) - Jw.T @ np.linalg.solve(JJt, Jw)
        qd_new = qd_task + N @ pull
        lim = r.velocity_limit
        scale = np.max(np.abs(qd_new) / np.where(lim > 0, lim, np.inf))
        if scale > 1:
            qd_new = qd_new / scale
        qdd_ref = (qd_new - self.qd_ref) / self.period
        self.qd_ref = qd_new
        self.q_ref = np.clip(self.q_ref + self.period * qd_new, r.lower, r.upper)
        # the reference follows the arm: it never runs away from the measured state
        self.q_ref = q + np.clip(self.q_ref - q, -0.05, 0.05)
        wn = g.kp
        a = qdd_ref + wn * wn * (self.q_ref - q) + 2 * g.kd * wn * (self.qd_ref - qd)
        tau = pin.rnea(r.model, r.data, q, qd, a).copy()
        if self.torque_limit:
            # torque-limited computed torque: scale the commanded acceleration (not gravity
            # and velocity terms) until every joint is within its effort limit
            eff = np.where(r.effort > 0, r.effort, np.inf)
            if np.any(np.abs(tau) > eff):
                bias = pin.rnea(r.model, r.data, q, qd, np.zeros(r.nv))
                d = tau - bias
                with np.errstate(divide="ignore", invalid="ignore"):
                    room = np.where(d > 0, (eff - bias) / d, np.where(d < 0, (-eff - bias) / d,
                                                                      np.inf))
                s = float(np.clip(np.min(room), 0.0, 1.0))
                tau = bias + s * d
        return tau


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

    @property
    def direction_error_deg(self) -> float:
        """Angle between the measured and the commanded hitting velocity [deg]."""
        a, b = self.hit_velocity, self.commanded
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


def default_base(name: str) -> tuple:
    """A base placement beside a ball at the origin, the robot facing the field's -y side."""
    return {"wam": (0.0, 0.55, 0.0, -np.pi / 2), "katana": (0.0, 0.45, 0.1, -np.pi / 2)}.get(
        name, (0.0, 0.5, 0.0, -np.pi / 2))


def simulate_swing(robot: Robot, motion: HittingMotion, ball, alpha: float = 0.0,
                   kappa: float = 1.0, start=None, period: float = 0.002, substeps: int = 4,
                   max_time: float = 3.0, rest_time: float = 0.4, gains: Gains | None = None,
                   perturb=None, rest_mode: str = "flat") -> SwingResult:
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
        ``{"t": time, "ball": new position}`` applied during the swing (no re-planning).
    """
    import pinocchio as pin

    ball = np.asarray(ball, float).copy()
    robot.check_reach(ball)
    if start is None:
        start = rotation_z(alpha) @ np.array([-0.3, 0.0, 0.05])
    psi = rotation_z(alpha) @ motion.hitting_direction
    ctl = SwingController(robot, motion, period, gains, rest_mode)
    q = place_head(robot, ctl.contact_point(ball, alpha) + np.asarray(start, float), psi)
    qd = np.zeros(robot.nv)
    ctl.reset(q)
    h = period / int(substeps)
    events = sorted(perturb or [], key=lambda e: e["t"])
    T, Q, QD, TAU, X = [], [], [], [], []
    t, t_end = 0.0, max_time
    hit_v = None
    ei = 0
    while t < t_end - 1e-12:
        while ei < len(events) and events[ei]["t"] <= t + 1e-12:
            ball = np.asarray(events[ei]["ball"], float).copy()
            ei += 1
        had_hit = ctl.hit is not None
        tau = ctl.tick(q, qd, ball, alpha, kappa, t)
        if not had_hit and ctl.hit is not None:
            J = robot.head_jacobian(q)
            hit_v = J[:3] @ qd
            t_end = t + rest_time
        x, _ = robot.head_pose(q)
        T.append(t)
        Q.append(q.copy())
        QD.append(qd.copy())
        TAU.append(tau.copy())
        X.append(x)
        for _ in range(int(substeps)):
            qdd = pin.aba(robot.model, robot.data, q, qd, tau)
            qd = qd + h * qdd
            q = q + h * qd
        t += period
    tau_arr = np.array(TAU)
    Q = np.array(Q)
    eff = np.where(robot.effort > 0, robot.effort, np.inf)
    res = SwingResult(np.array(T), Q, np.array(QD), tau_arr, np.array(X), ctl.hit is not None,
                      peak_torque_ratio=float(np.max(np.abs(tau_arr) / eff)),
                      limits_ok=bool(np.all(Q >= robot.lower - 1e-6)
                                     and np.all(Q <= robot.upper + 1e-6)))
    if ctl.hit is not None:
        res.hit_time = ctl.hit["t"]
        res.hit_velocity = hit_v
        res.commanded = ctl.hit["commanded"]
    return res
