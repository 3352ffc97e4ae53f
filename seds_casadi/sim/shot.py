"""The run loop of an exudyn shot: two integration phases and the stop criterion.

:func:`simulate_shot_exudyn` builds the scene (:func:`seds_casadi.sim.scene.build_scene`), then
integrates it with Dormand-Prince 5(4) and Lie-group rotations: the swing and the impact with
short steps (``impact_step``, ``impact_tolerance``), and, from :data:`ROLL_AFTER` after the
launch, the roll with longer ones (``step``, ``tolerance``) continuing from the same state. A
pre-step function (:class:`ShotMonitor`) runs the arm's controller, notices the club's contact
and the launch, records the path, and ends the shot when the ball drops, stops or leaves the
field, when the swing never reaches the ball, or when the computing-time budget is spent.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import exudyn as exu
import numpy as np

from ..core._signals import deferred_interrupts
from ..minigolf.ball import RESTITUTION, capture_speed
from ..minigolf.ball_physics import STOP_SPEED
from ..minigolf.fields import Field
from ..motion.golf import BALL_RADIUS
from .scene import HEAD_RADIUS, Scene, build_scene

__all__ = ["ExudynShot", "simulate_shot_exudyn", "ShotMonitor", "ROLL_AFTER"]

ROLL_AFTER = 0.02  # s after the launch: the rolling phase's longer steps begin
PATH_INTERVAL = 0.01  # s between the recorded points of the ball's path
STOP_DURATION = 0.05  # s below the stop speed that end a shot
RESTING_MODE = 0.5  # s after the contact during which the arm's controller still runs


@dataclass
class ExudynShot:
    """Result of one exudyn shot.

    Attributes
    ----------
    sunk, stopped : bool
    final_position : array (2,)
    launch_velocity : array (2,)
        Ball velocity (horizontal) just after the impact.
    path : array (k, 3)
        Ball centre every 10 ms: t, x, y.
    head_speed : array (k, 2)
        Club-head speed around the impact: t, |v|.
    simulated_time, wall_time : float
    hit : bool
        The club touched the ball (False: a miss, e.g. a swing too slow to arrive).
    head_velocity : array (3,)
        Club-head velocity at the first contact (NaN without one).
    contact_time : float
        When the club first touched the ball [s] (NaN without contact).
    """

    sunk: bool
    stopped: bool
    final_position: np.ndarray
    launch_velocity: np.ndarray
    path: np.ndarray
    head_speed: np.ndarray
    simulated_time: float
    wall_time: float
    hit: bool = False
    head_velocity: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    contact_time: float = np.nan

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        return self.simulated_time / max(self.wall_time, 1e-12)


class ShotMonitor:
    """The pre-step function of a shot (:meth:`pre_step`).

    Before the launch it runs the arm's controller, watches the club head for the contact
    (releasing the ball's holder at the first touch) and for the ball leaving the club; after
    it, it switches to the rolling phase once and then ends the shot when the ball drops into
    the hole (the fast model's capture speed), has been slower than the stop speed for
    :data:`STOP_DURATION`, or leaves the field. It ends the shot at once when an interrupt
    (Ctrl-C, SIGTERM) is pending in ``interrupt``: exudyn turns an exception raised in a user
    function into its own error, so the run holds the signals' exceptions and raises them after
    exudyn returns (:class:`~seds_casadi.core._signals.deferred_interrupts`).
    """

    def __init__(self, scene: Scene, max_wall_time: float) -> None:
        self.scene = scene
        self.state = scene.state
        self.max_wall_time = max_wall_time
        self.interrupt: deferred_interrupts | None = None
        self._t0 = time.perf_counter()
        self._next_record = 0.0

    def start(self) -> None:
        """Start the computing-time budget's clock."""
        self._t0 = time.perf_counter()

    @property
    def elapsed(self) -> float:
        """Computing time since :meth:`start` [s]."""
        return time.perf_counter() - self._t0

    def pre_step(self, mbs, t: float) -> bool:
        """exudyn pre-step user function: False ends the current phase."""
        if self.interrupt is not None and self.interrupt.pending:
            return False
        st, sc = self.state, self.scene
        dt_step, st.t_prev = t - st.t_prev, t
        if self.elapsed > self.max_wall_time:
            st.timed_out = True
            return False
        contact_time = np.inf if st.contact_time is None else st.contact_time
        if t < contact_time + RESTING_MODE:
            sc.club.control(mbs, t)  # the swing, then the resting mode
        p = mbs.GetNodeOutput(sc.ball_node, exu.OutputVariableType.Position)
        v = mbs.GetNodeOutput(sc.ball_node, exu.OutputVariableType.Velocity)
        if not st.launched:
            self._watch_club(mbs, t, p, v)  # the head is needed only until the ball leaves
        if t >= self._next_record - 1e-12:
            st.path.append((t, p[0], p[1]))
            self._next_record += PATH_INTERVAL
        if not st.launched:
            return not t > sc.club.give_up  # a swing that never reached the ball: a miss
        if st.rolling_from is None and t > st.launch_time + ROLL_AFTER:
            st.rolling_from = t
            return False  # continue with the rolling phase's settings
        return not self._finished(np.asarray(p), np.asarray(v), dt_step)

    def _watch_club(self, mbs, t: float, p, v) -> None:
        """Contact (the first releases the ball's holder) and launch (the contact ends)."""
        st = self.state
        ph, vh, nrm = self.scene.club.head(mbs)
        d = np.asarray(p) - ph
        touching = (d @ d < (BALL_RADIUS + HEAD_RADIUS) ** 2 if nrm is None
                    else float(d @ nrm) < BALL_RADIUS)
        if touching:
            if not st.contact:
                st.head_velocity = vh.copy()
                st.contact_time = t
                mbs.SetObjectParameter(self.scene.holder, "activeConnector", False)
            st.contact = True
        elif st.contact:
            st.launch = np.array(v[:2])
            st.launch_time = t
        st.heads.append((t, float(np.linalg.norm(vh))))

    def _finished(self, p: np.ndarray, v: np.ndarray, dt_step: float) -> bool:
        """Whether the rolling ball is done: sunk, stopped or off the field."""
        st, f = self.state, self.scene.field
        R, b = f.hole_radius, f.bounds
        off = float(np.linalg.norm(p[:2] - self.scene.hole))
        sp = float(np.linalg.norm(v))
        if off < R and sp < float(capture_speed(off, R)):
            st.sunk = True
            return True
        # (steps are adaptive: accumulate the time actually spent slow)
        st.slow = st.slow + dt_step if sp < STOP_SPEED else 0.0
        if st.slow > STOP_DURATION:
            st.stopped = True
            return True
        return not (b[0] - 0.05 <= p[0] <= b[1] + 0.05 and b[2] - 0.05 <= p[1] <= b[3] + 0.05)


def _settings(start: float, end: float, largest_step: float, tol: float):
    """exudyn's settings of one phase: adaptive steps up to ``largest_step``, no output."""
    so = exu.SimulationSettings()
    with warnings.catch_warnings():  # exudyn renamed some settings; old names still work
        warnings.simplefilter("ignore", DeprecationWarning)
        so.timeIntegration.startTime = start
        so.timeIntegration.endTime = end
        so.timeIntegration.numberOfSteps = max(1, int(np.ceil((end - start) / largest_step)))
        so.timeIntegration.automaticStepSize = True
        so.timeIntegration.absoluteTolerance = tol
        so.timeIntegration.relativeTolerance = tol
        so.timeIntegration.explicitIntegration.useLieGroupIntegration = True
        so.timeIntegration.verboseMode = 0
        so.solutionSettings.writeSolutionToFile = False
        so.displayComputationTime = False
    return so


def _run(scene: Scene, monitor: ShotMonitor, max_time: float, impact_phase: tuple[float, float],
         rolling_phase: tuple[float, float]) -> None:
    """The two phases, (largest step, tolerance) each; exudyn's failures become RuntimeError.
    Ctrl-C or SIGTERM ends the shot at the next step and raises the signal's exception here."""
    mbs, st = scene.mbs, scene.state
    monitor.start()
    exu.SetWriteToConsole(False)  # its note on per-step allocations by user functions
    try:
        with deferred_interrupts() as interrupt:
            monitor.interrupt = interrupt
            _solve(mbs, st, max_time, impact_phase, rolling_phase, interrupt)
    finally:
        monitor.interrupt = None
        exu.SetWriteToConsole(True)
    if st.timed_out:
        raise RuntimeError(
            f"exudyn took more than {monitor.max_wall_time:g} s of computing and reached only "
            f"t = {st.t_prev:.3f} s of the shot (its step control is taking tiny steps); "
            "loosen tolerance or raise max_wall_time")


def _solve(mbs, st, max_time: float, impact_phase: tuple[float, float],
           rolling_phase: tuple[float, float], interrupt: deferred_interrupts) -> None:
    try:
        # the swing and the impact with short steps; the roll, once the ball is clear of the
        # club, continues from the same state with longer ones
        exu.SolveDynamic(mbs, _settings(0.0, max_time, *impact_phase),
                         solverType=exu.DynamicSolverType.DOPRI5)
        if st.rolling_from is not None and not interrupt.pending:
            sd = mbs.systemData
            sd.SetSystemState(sd.GetSystemState(exu.ConfigurationType.Current),
                              exu.ConfigurationType.Initial)
            exu.SolveDynamic(mbs, _settings(st.rolling_from, max_time, *rolling_phase),
                             solverType=exu.DynamicSolverType.DOPRI5)
    except Exception as exc:  # noqa: BLE001 - exudyn raises its own error types
        t_fail = st.path[-1][0] if st.path else 0.0
        raise RuntimeError(f"exudyn failed near t = {t_fail:.3f} s of the shot: {exc}") from None


def _result(scene: Scene, wall_time: float) -> ExudynShot:
    st = scene.state
    p = np.asarray(scene.mbs.GetNodeOutput(scene.ball_node, exu.OutputVariableType.Position))
    t_end = st.path[-1][0] if st.path else 0.0
    launch = st.launch if st.launched else np.zeros(2)
    return ExudynShot(st.sunk, st.stopped, p[:2].copy(), launch, np.array(st.path),
                      np.array(st.heads), t_end, wall_time, hit=st.launched,
                      head_velocity=(np.full(3, np.nan) if st.head_velocity is None
                                     else st.head_velocity),
                      contact_time=np.nan if st.contact_time is None else st.contact_time)


def simulate_shot_exudyn(field: Field, ball_xy, club_velocity=None, hole=None,
                         max_time: float = 12.0, step: float = 1e-3, tolerance: float = 1e-6,
                         impact_step: float = 2e-4, impact_tolerance: float = 1e-7,
                         mesh_spacing: float | None = None, gap: float = 0.01,
                         restitution: float = RESTITUTION, arm: dict | None = None,
                         max_wall_time: float = 600.0) -> ExudynShot:
    """One shot in exudyn (the model: :mod:`seds_casadi.sim`); the ball rolls until it drops,
    stops or the time runs out.

    Without ``arm``: a free club head of the impact model's effective mass starts ``gap``
    behind the ball moving with ``club_velocity`` (3,). With ``arm`` (a dict with ``robot``,
    ``motion``, ``alpha``, ``kappa`` and optionally ``gains``): the robot is an exudyn
    kinematic tree converted from its Pinocchio model, driven by :class:`SwingController`'s
    torques every 2 ms from exudyn's joint state, and the ball is struck by a contact sphere at
    the club face on its last link: the impact then involves the whole arm, not a formula.

    ``impact_step`` and ``impact_tolerance`` are the largest integration step [s] and the step
    control's tolerance for the swing and the impact, ``step`` and ``tolerance`` for the roll
    that follows (from 20 ms after the ball leaves the club). Raises ``RuntimeError`` naming
    the time when exudyn's solver fails, or when the shot has taken more than ``max_wall_time``
    seconds of computing (the step control shrinking its steps without end; a run with
    tolerance 1e-7 through the whole roll once took 44 minutes for one shot); never a silently
    truncated result.
    """
    if not (max_wall_time > 0 and step > 0 and impact_step > 0 and tolerance > 0
            and impact_tolerance > 0):
        raise ValueError("max_wall_time, step, impact_step, tolerance and impact_tolerance "
                         "must be positive")
    scene = build_scene(field, ball_xy, club_velocity, hole, mesh_spacing, gap, restitution, arm)
    monitor = ShotMonitor(scene, max_wall_time)
    scene.mbs.SetPreStepUserFunction(monitor.pre_step)
    scene.mbs.Assemble()
    _run(scene, monitor, max_time, (impact_step, impact_tolerance), (step, tolerance))
    return _result(scene, monitor.elapsed)
