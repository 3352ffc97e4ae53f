"""One shot: a situation and its hitting parameters, played in a scene on an engine.

:func:`play_shot` is the one place where the robot's swing, the impact and the ball meet:

* ``engine="ball"``: the swing on the robot's forward dynamics under the 500 Hz controller
  (:func:`~seds_casadi.robots.swing.simulate_swing`), the launch from the club face as the arm
  holds it with the arm's effective mass at the face (:func:`swing_launch`), then the field's
  fast ball model (:func:`~seds_casadi.minigolf.ball.simulate_shots`);
* ``engine="exudyn"``: the same controller driving the arm as an exudyn kinematic tree, the
  club face striking the ball on the field's triangle mesh
  (:func:`~seds_casadi.sim.shot.simulate_shot_exudyn`).

The result says what happened and, for a miss, why (:attr:`ShotResult.reason`).
:func:`play_round` plays many shots of one scene in this process or on an executor whose
workers load the scene once each.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..minigolf.ball import impact, simulate_shots, substeps
from ..robots.swing import SwingResult, simulate_swing
from .scene import Scene, SceneSpec

#: the engines :func:`play_shot` plays on
ENGINES = ("ball", "exudyn")
#: the ball model's step [s] (:func:`~seds_casadi.minigolf.ball.simulate_shots`' default)
BALL_STEP = 0.01
#: kinds of miss (:attr:`ShotResult.miss`): the swing could not start (out of reach), the club
#: never met the ball, the ball left the field, it crossed the hole too fast to drop, it
#: stopped beside the line from the ball to the hole more than short of or beyond the hole
#: ("wide"), or short of it or beyond it
MISSES = ("no swing", "no contact", "out", "too fast", "wide", "short", "long")


@dataclass(frozen=True)
class Shot:
    """A situation and the hitting parameters to play it with.

    Attributes
    ----------
    ball, hole : array, shape (2,)
        Positions on the field [m].
    alpha : float
        Hitting angle [rad] (Eq. 14).
    kappa : float
        Speed gain (Eq. 14), positive.
    method, index, strategy : str, int, str
        Who chose the parameters (a learner's name), the shot's number in its round and the
        strategy it plays ("" for one strategy): labels carried into the result.
    """

    ball: np.ndarray
    hole: np.ndarray
    alpha: float
    kappa: float
    method: str = ""
    index: int = 0
    strategy: str = ""

    def __post_init__(self) -> None:
        for name in ("ball", "hole"):
            v = np.asarray(getattr(self, name), float).ravel()
            if v.shape != (2,) or not np.all(np.isfinite(v)):
                raise ValueError(f"{name} must be a finite (x, y) position [m], got "
                                 f"{np.asarray(getattr(self, name)).tolist()}")
            object.__setattr__(self, name, v)
        if not np.isfinite(self.alpha):
            raise ValueError(f"alpha must be a finite angle [rad], got {self.alpha}")
        if not (np.isfinite(self.kappa) and self.kappa > 0):
            raise ValueError(f"kappa (the speed gain) must be positive, got {self.kappa}")
        object.__setattr__(self, "alpha", float(self.alpha))
        object.__setattr__(self, "kappa", float(self.kappa))
        object.__setattr__(self, "index", int(self.index))


@dataclass
class ShotResult:
    """What happened to a :class:`Shot`.

    Attributes
    ----------
    shot : Shot
    engine : str
        ``"ball"`` or ``"exudyn"``.
    hit, sunk : bool
    final_position : array, shape (2,)
        Where the ball ended (in the hole when sunk; the start without a hit).
    reason : str
        Why it missed, in words ("" when sunk).
    miss : str
        The kind of miss: one of :data:`MISSES` ("" when sunk).
    direction_error_deg, speed_error : float
        The club velocity's angle [deg] and relative speed error, signed (|v| / |commanded| - 1:
        negative when the club is slower), against the commanded kappa v* R_alpha psi* at the
        hit (NaN without a hit).
    launch_direction_error_deg : float
        The club face's horizontal angle from the commanded direction at the hit [deg]: where
        the face sends the ball (NaN without a hit or on exudyn).
    within_limits : bool or None
        No joint over a speed, torque or position limit during the swing (None: no swing).
    launch_velocity : array, shape (2,)
        The ball's velocity after the impact (NaN without a hit).
    effective_mass : float
        The arm's mass at the face along its normal at the hit [kg] (NaN on exudyn).
    path : array, shape (k, 2) or None
        The ball's path (every 10 ms) after a hit.
    path_time : array, shape (k,) or None
        The times of the path's points [s] (from the launch on engine ``"ball"``, from the
        start of the swing on ``"exudyn"``): what a camera's time stamps give.
    swing : SwingResult or None
        The simulated swing, with ``keep_swing`` (engine ``"ball"``).
    exudyn : ExudynShot or None
        exudyn's result (engine ``"exudyn"``).
    """

    shot: Shot
    engine: str
    hit: bool
    sunk: bool
    final_position: np.ndarray
    reason: str = ""
    miss: str = ""
    direction_error_deg: float = np.nan
    speed_error: float = np.nan
    launch_direction_error_deg: float = np.nan
    within_limits: bool | None = None
    launch_velocity: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))
    effective_mass: float = np.nan
    path: np.ndarray | None = None
    path_time: np.ndarray | None = None
    swing: SwingResult | None = None
    exudyn: object | None = None


def swing_launch(scene: Scene, ball_xy, alpha: float, kappa: float,
                 swing_options: dict | None = None) -> tuple[SwingResult, np.ndarray | None]:
    """The robot's swing at the ball and the ball's launch velocity it gives.

    The launch is the impact model (:func:`~seds_casadi.minigolf.ball.impact`) with the club
    face as the arm holds it at the hit (a flat face: only the velocity along its normal is
    passed on, and the ball leaves along the normal) and the arm's effective mass at the face
    as the club mass: the one definition of a robot's launch, used by the round's shots and
    measured for the teacher (:func:`~seds_casadi.game.launch.calibrate_launch`).

    Returns
    -------
    (SwingResult, array (2,) or None)
        The swing and the launch velocity (None when the club did not reach the ball).
    Raises ``ValueError`` when the swing cannot start (the ball out of reach, no start
    configuration).
    """
    swing = simulate_swing(scene.robot_at(ball_xy), scene.motion, scene.ball_position(ball_xy),
                           alpha, kappa, **(swing_options or {}))
    if not swing.hit:
        return swing, None
    launch = impact(swing.hit_velocity[None], face_normal=swing.face_normal[None],
                    club_mass=swing.effective_mass)
    return swing, launch[0]


def miss_reason(scene: Scene, shot: Shot, final, out: bool, path=None) -> tuple[str, str]:
    """Why a ball that was hit did not drop, as (kind of :data:`MISSES`, words): out of the
    field, over the hole too fast, or where it stopped relative to the hole (short or long
    along the line from the ball to the hole, and to which side)."""
    if out:
        return "out", "left the field"
    hole, r = shot.hole, scene.field.hole_radius
    if path is not None and len(path) and np.min(np.linalg.norm(path - hole, axis=1)) < r:
        return "too fast", "crossed the hole too fast to drop"
    u = hole - shot.ball
    dist = float(np.linalg.norm(u))
    u = u / max(dist, 1e-12)
    d = np.asarray(final, float) - shot.ball
    along = float(d @ u) - dist
    side = float(u[0] * d[1] - u[1] * d[0])
    kind = ("wide" if abs(side) > max(abs(along), r) else "long" if along > 0 else "short")
    return kind, (f"stopped {np.linalg.norm(np.asarray(final) - hole):.2f} m from the hole: "
                  f"{kind} by {abs(along):.2f} m, "
                  f"{abs(side):.2f} m {'left' if side > 0 else 'right'} of the line to it")


def play_shot(scene: Scene | SceneSpec, shot: Shot, engine: str = "ball",
              keep_swing: bool = False) -> ShotResult:
    """Play one shot in a scene.

    Parameters
    ----------
    scene : Scene or SceneSpec
        A spec is loaded once per process (:meth:`SceneSpec.load`).
    shot : Shot
    engine : {"ball", "exudyn"}
        The fast ball model after the simulated swing, or exudyn's multibody model of arm,
        club and ball (module docstring).
    keep_swing : bool
        Keep the simulated swing in the result (engine ``"ball"``; for replays and figures).

    Returns
    -------
    ShotResult
        A swing that cannot start (out of reach) is a miss with that reason, not an error.
    """
    return play_shots(scene, [shot], engine, keep_swing)[0]


def play_shots(scene: Scene | SceneSpec, shots: list[Shot], engine: str = "ball",
               keep_swing: bool = False) -> list[ShotResult]:
    """Play several shots of one scene: :func:`play_shot` for each, the same results, with
    the ball model run once for all the balls the swings launched (its vectorised engine
    costs about what one ball costs; balls are grouped by their integration sub-steps, so
    that each is integrated exactly as alone)."""
    if engine not in ENGINES:
        raise ValueError(f"unknown engine {engine!r}; choose one of {', '.join(ENGINES)}")
    if isinstance(scene, SceneSpec):
        scene = scene.load()
    if engine == "exudyn":
        return [_play_on_exudyn(scene, shot) for shot in shots]
    results: list[ShotResult | None] = [None] * len(shots)
    launched = []   # (index, swing, launch)
    for i, shot in enumerate(shots):
        start = shot.ball.copy()
        try:
            swing, launch = swing_launch(scene, shot.ball, shot.alpha, shot.kappa)
        except ValueError as exc:   # out of reach, no start configuration: a miss, with why
            results[i] = ShotResult(shot, engine, False, False, start,
                                    reason=f"the swing could not start: {exc}", miss="no swing")
            continue
        if launch is None:
            results[i] = ShotResult(shot, engine, False, False, start,
                                    within_limits=swing.within_limits,
                                    reason="the club did not reach the ball", miss="no contact",
                                    swing=swing if keep_swing else None)
            continue
        launched.append((i, swing, launch))
    groups: dict[int, list] = {}
    for item in launched:
        groups.setdefault(substeps(scene.field, item[2][None], BALL_STEP), []).append(item)
    for n_sub, group in groups.items():
        idx = [i for i, _, _ in group]
        res = simulate_shots(scene.field, np.array([shots[i].ball for i in idx]),
                             np.array([launch for _, _, launch in group]),
                             dt=BALL_STEP, hole=np.array([shots[i].hole for i in idx]),
                             engine="numpy", record_paths=True)
        for k, (i, swing, launch) in enumerate(group):
            shot = shots[i]
            final, sunk, path = res.final_position[k].copy(), bool(res.sunk[k]), res.paths[k]
            miss, reason = (("", "") if sunk
                            else miss_reason(scene, shot, final, bool(res.out[k]), path))
            results[i] = ShotResult(
                shot, engine, True, sunk, final, reason=reason, miss=miss,
                direction_error_deg=swing.direction_error_deg,
                speed_error=swing.signed_speed_error,
                launch_direction_error_deg=swing.face_error_deg,
                within_limits=swing.within_limits, launch_velocity=launch,
                effective_mass=swing.effective_mass, path=path,
                path_time=np.arange(len(path)) * (BALL_STEP / n_sub),
                swing=swing if keep_swing else None)
    return results


def _play_on_exudyn(scene: Scene, shot: Shot) -> ShotResult:
    from ..sim.shot import simulate_shot_exudyn

    ex = simulate_shot_exudyn(scene.field, shot.ball, hole=shot.hole, arm={
        "robot": scene.robot_at(shot.ball), "motion": scene.motion, "alpha": shot.alpha,
        "kappa": shot.kappa})
    final = np.asarray(ex.final_position, float).copy()
    if not ex.hit:
        return ShotResult(shot, "exudyn", False, False, final,
                          reason="the club did not reach the ball", miss="no contact",
                          exudyn=ex)
    commanded = shot.kappa * scene.motion.hitting_speed * scene.motion.commanded_direction(
        shot.alpha)
    v = np.asarray(ex.head_velocity, float)
    c = v @ commanded / max(np.linalg.norm(v) * np.linalg.norm(commanded), 1e-12)
    path = ex.path[:, 1:] if len(ex.path) else None
    path_time = ex.path[:, 0] if len(ex.path) else None
    b = scene.field.bounds
    out = not (b[0] <= final[0] <= b[1] and b[2] <= final[1] <= b[3])
    miss, reason = ("", "") if ex.sunk else miss_reason(scene, shot, final, out, path)
    return ShotResult(
        shot, "exudyn", True, bool(ex.sunk), final, reason=reason, miss=miss,
        direction_error_deg=float(np.degrees(np.arccos(np.clip(c, -1, 1)))),
        speed_error=float(np.linalg.norm(v) / np.linalg.norm(commanded) - 1),
        launch_velocity=np.asarray(ex.launch_velocity, float), path=path,
        path_time=path_time, exudyn=ex)


def _play_task(spec: SceneSpec, shots: list[Shot], engine: str,
               keep_swing: bool) -> list[ShotResult]:
    """A picklable task for a worker process: the scene is loaded once per process."""
    return play_shots(spec, shots, engine, keep_swing)


def play_round(scene: Scene, shots: list[Shot], engine: str = "ball", executor=None,
               keep_swing: bool = False, progress=None, chunk: int = 4) -> list[ShotResult]:
    """Play shots of one scene, in this process or on ``executor`` (anything with
    ``submit(fn, *args)`` returning futures: a process pool or a Dask client; its workers load
    the scene once each from :meth:`Scene.spec` and play ``chunk`` shots per task).

    ``progress``: optional callable wrapping an iterable (a progress bar) of the tasks.
    Results are in the shots' order and do not depend on the executor or the chunks.
    """
    wrap = progress or (lambda it: it)
    if int(chunk) < 1:
        raise ValueError(f"chunk must be a positive number of shots, got {chunk}")
    parts = [shots[i:i + int(chunk)] for i in range(0, len(shots), int(chunk))]
    if executor is None:
        return [r for part in wrap(parts) for r in play_shots(scene, part, engine, keep_swing)]
    spec = scene.spec()
    futures = [executor.submit(_play_task, spec, part, engine, keep_swing) for part in parts]
    return [r for f in wrap(futures) for r in f.result()]
