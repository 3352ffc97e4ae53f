"""A swing simulated on the robot's forward dynamics under the 500 Hz controller: tracking,
torque limits and the club-head velocity at impact are measured rather than assumed.

:func:`simulate_swing` integrates the robot's forward dynamics (ABA, classical Runge-Kutta with
sub-steps) under the torques of :class:`~seds_casadi.robots.controller.SwingController`, with
perturbations (the ball or the hole moved during the swing, the paper's Fig. 8) applied by the
motion's :class:`~seds_casadi.motion.rollout.Perturbations`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..motion.hitting import HittingMotion
from ..motion.rollout import Perturbations
from ..motion.rotation import rotation_z
from .controller import Gains, SwingController
from .dynamics import effective_mass
from .limits import limit_report
from .models import Robot
from .placement import place_head


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
        max |tau_i| / effort_i over the swing (tau_i - g_i(q) for arms whose efforts exclude
        gravity, the Katana).
    limits_ok : bool
        Joint positions stayed within their limits.
    peak_speed, peak_torque : array (nv,)
        Largest |qd_i| [rad/s] and |tau_i| [N m] (as counted against the efforts) over the
        simulated swing.
    speed_ratio, torque_ratio : array (nv,)
        The same against each joint's velocity limit and effort.
    limits_broken : list of str
        Every limit the simulated arm broke (speed, torque, position), by joint; empty for a
        swing within its limits (:attr:`within_limits`).
    tick_us : array (n,)
        Wall time of each control tick [us] (the controller only, not the simulation).
    face_normal : array (3,)
        The club face's normal at the hit (for :func:`seds_casadi.minigolf.ball.impact`).
    effective_mass : float
        The arm's mass as the ball feels it at the face along its normal at the hit
        (:func:`~seds_casadi.robots.dynamics.effective_mass`; the impact model's club mass for
        this robot).
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
    peak_speed: np.ndarray = field(default_factory=lambda: np.zeros(0))
    peak_torque: np.ndarray = field(default_factory=lambda: np.zeros(0))
    speed_ratio: np.ndarray = field(default_factory=lambda: np.zeros(0))
    torque_ratio: np.ndarray = field(default_factory=lambda: np.zeros(0))
    limits_broken: list = field(default_factory=list)

    @property
    def within_limits(self) -> bool:
        """No joint over its velocity, torque or position limit at any tick."""
        return not self.limits_broken

    @property
    def direction_error_deg(self) -> float:
        """Angle between the measured and the commanded hitting velocity [deg]."""
        a, b = self.hit_velocity, self.commanded
        c = a @ b / (np.linalg.norm(a) * np.linalg.norm(b))
        return float(np.degrees(np.arccos(np.clip(c, -1, 1))))

    @property
    def face_error_deg(self) -> float:
        """Horizontal angle between the club face's normal and the commanded direction at the
        hit [deg]: where a flat face sends the ball (:func:`seds_casadi.minigolf.ball.impact`)."""
        a, b = self.face_normal[:2], self.commanded[:2]
        c = a @ b / (np.linalg.norm(a) * np.linalg.norm(b))
        return float(np.degrees(np.arccos(np.clip(c, -1, 1))))

    @property
    def speed_error(self) -> float:
        """Relative error of the hitting speed (unsigned; :attr:`signed_speed_error`)."""
        return abs(self.signed_speed_error)

    @property
    def signed_speed_error(self) -> float:
        """|measured| / |commanded| - 1 at the hit: negative when the club is slower."""
        return float(np.linalg.norm(self.hit_velocity) / np.linalg.norm(self.commanded) - 1)


def _rk4_period(robot: Robot, q, qd, tau, period: float, substeps: int):
    """Classical RK4 on (q, qd) under the forward dynamics (ABA), the torque held over the
    period, in ``substeps`` steps."""
    import pinocchio as pin

    m, d = robot.model, robot.data
    h = period / int(substeps)
    for _ in range(int(substeps)):
        a1 = pin.aba(m, d, q, qd, tau)
        a2 = pin.aba(m, d, q + 0.5 * h * qd, qd + 0.5 * h * a1, tau)
        a3 = pin.aba(m, d, q + 0.5 * h * (qd + 0.5 * h * a1), qd + 0.5 * h * a2, tau)
        a4 = pin.aba(m, d, q + h * (qd + 0.5 * h * a2), qd + h * a3, tau)
        q = q + h * qd + h * h / 6 * (a1 + a2 + a3)
        qd = qd + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
    return q, qd


@dataclass
class _SwingLog:
    """The samples of a swing as it is simulated, and what was measured at the hit."""

    T: list = field(default_factory=list)
    Q: list = field(default_factory=list)
    QD: list = field(default_factory=list)
    TAU: list = field(default_factory=list)
    X: list = field(default_factory=list)
    TICK: list = field(default_factory=list)
    at_hit: dict | None = None

    def add(self, robot: Robot, t, q, qd, tau) -> None:
        self.T.append(t)
        self.Q.append(q.copy())
        self.QD.append(qd.copy())
        self.TAU.append(tau.copy())
        self.X.append(robot.head_pose(q)[0])

    def measure_hit(self, robot: Robot, q, v_prev, v_now, lam: float) -> None:
        """The velocity at the crossing of the contact plane, interpolated between this tick
        and the previous one (near the ball the direction turns quickly), the face's normal and
        the arm's effective mass there."""
        v = v_now if v_prev is None else v_prev + lam * (v_now - v_prev)
        normal = robot.head_pose(q)[1][:, 0]
        self.at_hit = {"velocity": v, "normal": normal,
                       "mass": effective_mass(robot, q, normal)}

    def result(self, robot: Robot, ctl: SwingController) -> SwingResult:
        tau, Q, QD = np.array(self.TAU), np.array(self.Q), np.array(self.QD)
        lim = limit_report(robot, Q, QD, tau)
        res = SwingResult(np.array(self.T), Q, QD, tau, np.array(self.X),
                          ctl.hit is not None,
                          peak_torque_ratio=float(np.max(lim["torque_ratio"])),
                          limits_ok=bool(np.all(Q >= robot.lower - 1e-6)
                                         and np.all(Q <= robot.upper + 1e-6)),
                          tick_us=np.array(self.TICK) / 1e3, peak_speed=lim["peak_speed"],
                          peak_torque=lim["peak_torque"], speed_ratio=lim["speed_ratio"],
                          torque_ratio=lim["torque_ratio"], limits_broken=lim["broken"])
        if ctl.hit is not None:
            res.hit_time = ctl.hit["t"]
            res.hit_velocity = self.at_hit["velocity"]
            res.face_normal = self.at_hit["normal"]
            res.effective_mass = self.at_hit["mass"]
            res.commanded = ctl.hit["commanded"]
        return res


def _check_swing_inputs(ball, alpha, kappa, period, substeps, max_time, rest_time, hole):
    """ValueError naming a bad input of :func:`simulate_swing`; the ball and hole as arrays."""
    b = np.asarray(ball, float).copy()
    if b.shape != (3,) or not np.all(np.isfinite(b)):
        raise ValueError(f"ball must be a finite 3-vector (x, y, z) in the field frame, got "
                         f"{np.asarray(ball).tolist()}")
    if not np.isfinite(alpha):
        raise ValueError(f"alpha must be a finite angle in radians, got {alpha}")
    if not (np.isfinite(kappa) and kappa > 0):
        raise ValueError(f"kappa (the speed gain) must be positive and finite, got {kappa}; "
                         "it scales the hitting speed, so 0 or less would not swing forwards")
    for name, v in (("period", period), ("max_time", max_time)):
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be positive [s], got {v}")
    if not (np.isfinite(rest_time) and rest_time >= 0):
        raise ValueError(f"rest_time must be >= 0 s, got {rest_time}")
    if int(substeps) != substeps or substeps < 1:
        raise ValueError(f"substeps must be a positive integer, got {substeps}")
    h = None if hole is None else np.asarray(hole, float).copy()
    if h is not None and (h.shape not in ((2,), (3,)) or not np.all(np.isfinite(h))):
        raise ValueError(f"hole must be a finite (x, y) or (x, y, z), got {np.asarray(hole)}")
    return b, h


def simulate_swing(robot: Robot, motion: HittingMotion, ball, alpha: float = 0.0,
                   kappa: float = 1.0, start=None, period: float = 0.002, substeps: int = 4,
                   max_time: float = 3.0, rest_time: float = 0.4, gains: Gains | None = None,
                   perturb=None, rest_mode: str = "flat", hole=None,
                   params=None, controller: dict | None = None) -> SwingResult:
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
        ``params(t, ball, hole) -> (alpha [rad], kappa)``, the same signature as
        :meth:`HittingMotion.rollout`'s, evaluated every tick from the current time, ball and
        hole (e.g. a hitting-parameter model on the situation hole - ball); overrides
        ``alpha`` and ``kappa``.
    controller : dict, optional
        Further options of :class:`~seds_casadi.robots.controller.SwingController`, e.g.
        ``{"ik": "qp"}`` (limits as QP constraints), ``{"cartesian_speed_limit": None}`` or
        ``{"blend_time": 0.0}`` (no start from rest: the velocity step of before).
    """
    ball, hole = _check_swing_inputs(ball, alpha, kappa, period, substeps, max_time,
                                     rest_time, hole)
    robot.check_reach(ball)
    events = Perturbations(perturb, ("ball", "hole"))
    if params is not None:
        alpha, kappa = (float(v) for v in params(0.0, ball.copy(), hole))
    if start is None:
        start = rotation_z(alpha) @ np.array([-0.3, 0.0, 0.05])
    ctl = SwingController(robot, motion, period, gains, rest_mode, **(controller or {}))
    q = place_head(robot, ctl.contact_point(ball, alpha) + np.asarray(start, float),
                   motion.commanded_direction(alpha))
    qd = np.zeros(robot.nv)
    ctl.reset(q)
    log = _SwingLog()
    t, t_end, v_prev = 0.0, max_time, None
    while t < t_end - 1e-12:
        for e in events.due(t):
            if "ball" in e:
                ball = np.asarray(e["ball"], float).copy()
            if "hole" in e:
                hole = np.asarray(e["hole"], float).copy()
        if params is not None and ctl.hit is None:
            alpha, kappa = (float(v) for v in params(t, ball.copy(), hole))
            if not (np.isfinite(alpha) and np.isfinite(kappa) and kappa > 0):
                raise ValueError(f"params returned alpha {alpha}, kappa {kappa} at t = {t:.3f}"
                                 " s: a finite alpha and a positive kappa are needed")
        had_hit = ctl.hit is not None
        t0 = time.perf_counter_ns()
        tau = ctl.tick(q, qd, ball, alpha, kappa, t)
        log.TICK.append(time.perf_counter_ns() - t0)
        v_now = robot.head_jacobian(q)[:3] @ qd
        if not had_hit and ctl.hit is not None:
            log.measure_hit(robot, q, v_prev, v_now, float(ctl.hit["lam"]))
            t_end = t + rest_time
        v_prev = v_now
        log.add(robot, t, q, qd, tau)
        q, qd = _rk4_period(robot, q, qd, tau, period, substeps)
        t += period
    return log.result(robot, ctl)
