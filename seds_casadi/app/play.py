"""``seds-casadi play``: the whole pipeline end to end (paper Fig. 5).

1. **Hitting motion**: SEDS + strength factor from the demonstrations (shipped putts by default).
2. **Teacher**: good shots on the field's ball model (:mod:`seds_casadi.minigolf.teacher`),
   over the situations the field declares (:mod:`seds_casadi.minigolf.situations`); first the
   robot is checked to reach the declared ball positions (:mod:`seds_casadi.app.reach`).
3. **Hitting parameters**: each learner (GPR, GMR) fitted on the teacher's data set (all of it,
   or ``train_size`` equally spaced situations, as one of Table 1's training sets).
4. **A round**: random situations drawn from the field's declaration (the draw of Table 1's
   success column); for each shot and learner the
   predicted (alpha, kappa) is executed by the 500 Hz controller on the simulated robot
   (Pinocchio) and the ball, launched by the club face as the robot holds it, rolls on the
   field's ball model. Shots are independent tasks: local processes or a Dask cluster.
5. **Validation**: the first few shots again in exudyn (arm, club face, ball on the mesh).

With ``strategies`` (``--strategies auto|N``, the paper's Section 8 extension) step 2 explores
every successful way to play the teacher's situations, bank shots included, and clusters them
into strategies (:mod:`seds_casadi.minigolf.strategies`); step 3 fits one model per strategy
and learner and a model of each strategy's robustness; step 4 plays, at each situation, the
strategy most likely to succeed (:mod:`seds_casadi.minigolf.strategy_choice`). ``shots.csv``
then names the strategy of each shot and ``strategies.png`` shows the strategies on the
success map of the first situation (Fig. 4a, coloured).

Everything learned is saved in ``OUT/models`` (the motion as ``.npz`` files, the teacher's data
set); ``--models DIR`` reuses them and skips steps 1-2 (the learners of step 3 are refitted from
the saved data set: they take well under a second). Settings are a :class:`PlayConfig`;
progress goes to the ``logging`` logger of this module (the command line prints it).
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass, replace

import numpy as np

from ..core._io import atomic_csv, atomic_text
from ..minigolf._progress import progress_bar
from ._config import names_tuple, whole_number, with_overrides
from .reach import check_reach, fastest_gain

__all__ = ["play", "play_shot", "PlayConfig", "SHOT_COLUMNS", "LEARNERS"]

_LOG = logging.getLogger(__name__)

#: columns of ``shots.csv``; a unit ends the name (m, deg), dimensionless ones have none
#: (kappa, the gain; speed_error, relative to the commanded speed). direction_error_deg is the
#: club velocity's error at the hit, launch_direction_error_deg the club face's (the ball
#: leaves along the face's normal); within_limits: no joint over a speed, torque or position
#: limit during the swing
SHOT_COLUMNS = ("method", "shot", "ball_x_m", "ball_y_m", "hole_x_m", "hole_y_m", "alpha_deg",
                "kappa", "hit", "sunk", "direction_error_deg", "speed_error",
                "launch_direction_error_deg", "within_limits", "final_x_m", "final_y_m",
                "sunk_exudyn", "strategy")
LEARNERS = ("gpr", "gmr")
_VALID_LEARNERS = ("gpr", "gmr", "sep_gmr")

_MOTIONS: dict = {}


@dataclass(frozen=True)
class PlayConfig:
    """Settings of :func:`play` (the options of ``seds-casadi play``).

    Attributes
    ----------
    robot : str
        A robot name (:func:`~seds_casadi.robots.models.robot_names`) or a ``.urdf`` file.
    field : str
        A field name or a ``.json`` field file.
    demos : str or None
        Hitting demonstrations (``.npz``/``.csv``); None: the shipped putts.
    learners : tuple of {"gpr", "gmr", "sep_gmr"}
    shots : int
        Situations in the round (at least 1).
    seed : int
    out : str
        Output folder.
    models : str or None
        The ``models/`` folder of an earlier run to reuse (skips learning and teaching).
    quick : bool
        At most 3 situations, a coarse teacher and 1 exudyn check.
    train_size : int or None
        Train the learners on this many equally spaced situations of the teacher's data set
        (Table 1's ``"equally spaced"`` kind); None: all of them.
    strategies : "auto", int or None
        Several strategies (module docstring): ``"auto"`` keeps those found in at least half
        the situations, N the N most widespread; None: the teacher's one strategy.
    validate_shots : int
        Shots checked again in exudyn (0: none).
    workers : int
        Local worker processes for the round.
    dask : str or None
        Address of a Dask scheduler (overrides ``workers``).
    progress : bool
        Progress bars (on stderr, only on a terminal).
    cache : bool
        Take the teacher's data set from the cache when the same field, motion and teacher
        settings were taught before (:mod:`seds_casadi.app.teacher_cache`).
    replay : int
        Replay the first learner's first ``replay`` shots (:mod:`seds_casadi.app.replay`):
        ``replay.html`` and a GIF per shot in ``out`` (0: none).
    """

    robot: str = "wam"
    field: str = "arctan"
    demos: str | None = None
    learners: tuple[str, ...] = LEARNERS
    shots: int = 20
    seed: int = 0
    out: str = "play_out"
    models: str | None = None
    quick: bool = False
    validate_shots: int = 2
    workers: int = 1
    dask: str | None = None
    progress: bool = True
    train_size: int | None = None
    strategies: str | int | None = None
    replay: int = 0
    cache: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "replay", whole_number("replay", self.replay, 0))
        object.__setattr__(self, "learners", names_tuple("learner", self.learners,
                                                         _VALID_LEARNERS))
        object.__setattr__(self, "shots", whole_number("shots", self.shots, 1))
        object.__setattr__(self, "validate_shots",
                           whole_number("validate_shots", self.validate_shots, 0))
        object.__setattr__(self, "workers", whole_number("workers", self.workers, 1))
        object.__setattr__(self, "seed", whole_number("seed", self.seed, 0))
        if self.train_size is not None:
            object.__setattr__(self, "train_size", whole_number("train_size", self.train_size,
                                                                2))
        if self.strategies is not None:
            s = self.strategies
            if isinstance(s, str) and s != "auto":
                try:
                    s = int(s)
                except ValueError:
                    raise ValueError(f"strategies must be 'auto' or a whole number, got "
                                     f"{self.strategies!r}") from None
            if s != "auto":
                s = whole_number("strategies", s, 1)
            object.__setattr__(self, "strategies", s)
            if self.train_size is not None:
                raise ValueError("train_size picks equally spaced situations of one strategy's "
                                 "data set; leave it out with strategies")

    def effective(self) -> PlayConfig:
        """The settings actually played: ``quick`` caps the shots and the exudyn checks."""
        if not self.quick:
            return self
        return replace(self, shots=min(self.shots, 3), validate_shots=min(self.validate_shots, 1))


def _motion(folder):
    from ..motion.hitting import HittingMotion

    if isinstance(folder, HittingMotion):
        return folder
    if folder not in _MOTIONS:
        _MOTIONS[folder] = HittingMotion.load(folder)
    return _MOTIONS[folder]


def play_shot(task: dict) -> dict:
    """One shot: the robot's swing on Pinocchio, then the ball model (a picklable task).

    ``task`` has ``method, shot, ball (2,), hole (2,), alpha [rad], kappa, robot, field (name),
    field_spec (dict), motion`` (a :class:`~seds_casadi.motion.HittingMotion` or the folder it
    was saved in). Returns the shot's row of ``shots.csv`` (:data:`SHOT_COLUMNS`: the angle
    in degrees) plus the ball's ``path`` when the robot hit it, and ``error`` when the swing
    could not start."""
    from ..minigolf.ball import BALL_RADIUS, impact, simulate_shots
    from ..minigolf.fields import Field
    from ..robots.control import place_robot, simulate_swing

    field = Field.from_dict(task["field_spec"], source=task["field"])
    motion = _motion(task["motion"])
    ball, hole = np.asarray(task["ball"]), np.asarray(task["hole"])
    robot = place_robot(task["robot"], ball, field)
    z = float(field.surface.height(ball[None])[0]) + BALL_RADIUS
    row = {"method": task["method"], "shot": task["shot"], "strategy": task.get("strategy", ""),
           "ball_x_m": ball[0],
           "ball_y_m": ball[1], "hole_x_m": hole[0], "hole_y_m": hole[1],
           "alpha_deg": float(np.rad2deg(task["alpha"])), "kappa": task["kappa"], "hit": False,
           "sunk": False, "direction_error_deg": np.nan, "speed_error": np.nan,
           "launch_direction_error_deg": np.nan, "within_limits": "",
           "final_x_m": ball[0], "final_y_m": ball[1], "sunk_exudyn": ""}
    try:
        swing = simulate_swing(robot, motion, np.array([ball[0], ball[1], z]), task["alpha"],
                               task["kappa"])
    except ValueError as exc:  # out of reach, no start configuration: a miss, with the reason
        row["error"] = str(exc)
        return row
    row["within_limits"] = swing.within_limits
    if not swing.hit:
        if task.get("keep_swing"):
            row["swing"] = swing
        return row
    launch = impact(swing.hit_velocity[None], face_normal=swing.face_normal[None],
                    club_mass=swing.effective_mass)
    res = simulate_shots(field, ball[None], launch, hole=hole, engine="numpy", record_paths=True)
    row.update(hit=True, sunk=bool(res.sunk[0]),
               direction_error_deg=swing.direction_error_deg, speed_error=swing.speed_error,
               launch_direction_error_deg=swing.face_error_deg,
               final_x_m=float(res.final_position[0, 0]),
               final_y_m=float(res.final_position[0, 1]), path=res.paths[0])
    if task.get("keep_swing"):  # for a replay (seds_casadi.app.replay)
        row["swing"] = swing
    return row


def _situations(field, n: int, rng):
    """Random situations (balls, holes) drawn from the field's declaration."""
    return field.situations.sample(n, rng)


def _reuse_models(models: str, fld, strategies=None):
    """Steps 1-2 from an earlier run's ``models/`` folder."""
    from ..minigolf.teacher import HittingDataset
    from ..motion.hitting import HittingMotion

    src_motion = os.path.join(models, "motion")
    src_data = os.path.join(models, f"dataset_{fld.name}.npz")
    for p in (os.path.join(src_motion, "stable_ds.npz"), src_data):
        if not os.path.exists(p):
            raise ValueError(f"--models {models}: no {os.path.relpath(p, models)} there; "
                             f"give the folder a previous 'play --out' wrote as its models/ "
                             f"(for the field {fld.name!r})")
    motion = HittingMotion.load(src_motion)
    data = HittingDataset.load(src_data)
    _LOG.info("reused the hitting motion and %d good shots from %s", len(data), models)
    if not strategies:
        return motion, data, None
    from ..minigolf.strategies import StrategySet

    src = os.path.join(models, f"strategies_{fld.name}.npz")
    if not os.path.exists(src):
        raise ValueError(f"--models {models}: no strategies_{fld.name}.npz there; run play "
                         f"--strategies once without --models to explore them")
    ss = StrategySet.load(src)
    _LOG.info("reused %d strategies:\n%s", len(ss), ss.describe())
    return motion, data, ss


def _learn_and_teach(cfg: PlayConfig, fld, times: dict):
    """Steps 1-2: the hitting motion from the demonstrations, the teacher's good shots."""
    from ..core.demonstrations import load_demonstrations
    from ..minigolf.teacher import Stroke, paper_situations
    from ..motion.hitting import HittingMotion
    from ..motion.putting_demos import load_hitting_demos
    from .teacher_cache import cached_dataset

    t0 = time.perf_counter()
    _LOG.info("learning the hitting motion (SEDS + GMR) ...")
    d = load_demonstrations(cfg.demos) if cfg.demos else load_hitting_demos()
    motion = HittingMotion.fit(d, n_components=3)
    times["hitting motion (SEDS + GMR)"] = time.perf_counter() - t0
    _LOG.info("hitting motion: v* = %.3f m/s (%.1f s)", motion.hitting_speed,
              times["hitting motion (SEDS + GMR)"])
    t1 = time.perf_counter()
    _check_declared_reach(cfg.robot, fld, motion)
    stroke = Stroke.from_motion(motion)
    fastest = fastest_gain(cfg.robot, fld, motion)
    _LOG.info("the %s swings within 2 %% of the commanded speed up to kappa %.2f (%.2f m/s)",
              cfg.robot, fastest, fastest * motion.hitting_speed)
    if cfg.strategies is not None:
        from ..minigolf.strategies import explore

        # a strategy the robot cannot swing fast enough for is none of its strategies
        lo, hi = fld.teacher.get("kappa_range", (0.6, 2.4))
        ss = explore(fld, stroke, *paper_situations(fld), n_strategies=cfg.strategies,
                     kappa_range=(lo, max(lo + 0.05, min(hi, fastest))),
                     progress=cfg.progress,
                     **({"resolution": (151, 37)} if cfg.quick else {}))
        times["exploring strategies"] = time.perf_counter() - t1
        _LOG.info("%d strategies on %s (of %d found; %.1f s):\n%s", len(ss), fld.name,
                  ss.settings["found"], times["exploring strategies"], ss.describe())
        return motion, ss.dataset(), ss
    _LOG.info("teacher: looking for good shots on %s ...", fld.name)
    data, cached = cached_dataset(fld, stroke, cfg.cache, progress=cfg.progress,
                                  **({"resolution": (81, 26)} if cfg.quick else {}))
    times["teacher" + (" (cached)" if cached else "")] = dt = time.perf_counter() - t1
    _LOG.info("teacher: %d good shots on %s (%.1f s%s)", len(data), fld.name, dt,
              ", from the cache: --no-cache computes them again" if cached else "")
    fast = int(np.sum(data.kappa > fastest))
    if fast:
        _LOG.warning("%d of the teacher's %d shots on %s need kappa above %.2f, faster than the "
                     "%s swings accurately (up to %.2f): they will be played too slowly; give "
                     "the field's teacher a lower kappa_range or another robot", fast,
                     len(data), fld.name, fastest, cfg.robot, data.kappa.max())
    return motion, data, None


def _check_declared_reach(robot: str, fld, motion) -> None:
    """Before teaching: the robot reaches the declared ball positions (a 3 x 3 spread over a
    region, the ends and middle of a slider), hitting straight at the declared holes."""
    from ..minigolf.stroke import Stroke

    balls = fld.situations.ball.design(9)
    holes = fld.situations.hole.design(3)
    B = np.repeat(balls, len(holes), axis=0)
    H = np.tile(holes, (len(balls), 1))
    check_reach(robot, fld, B, Stroke.from_motion(motion).aim(H - B), motion.hitting_direction,
                "declared ball positions")


def _fit_learners(data, learners, train_size=None, strategies=None) -> dict:
    """Step 3: each hitting-parameter learner on the teacher's data set (or ``train_size``
    equally spaced situations of it); with ``strategies``, a
    :class:`~seds_casadi.minigolf.strategy_choice.StrategyChoice` per learner."""
    from ..minigolf.parameters import make_model
    from ..minigolf.table1 import N_COMPONENTS, training_indices

    if strategies is not None:
        from ..minigolf.strategy_choice import StrategyChoice

        return {m: StrategyChoice(m, n_components=N_COMPONENTS[2]).fit(strategies)
                for m in learners}

    S, Y = data.situations, data.outputs
    if train_size is not None and train_size < len(data):
        idx = training_indices(S, train_size, "spaced", np.random.default_rng(0))
        S, Y = S[idx], Y[idx]
    k = N_COMPONENTS[Y.shape[1]]
    return {m: make_model(m, **({} if m == "gpr" else {"n_components": k})).fit(S, Y)
            for m in learners}


def _round_tasks(cfg: PlayConfig, fld, data, fitted: dict, balls, holes,
                 motion_dir: str) -> list[dict]:
    """Step 4's tasks: each learner's (alpha, kappa) for each situation (:func:`play_shot`)."""
    from ..minigolf.strategy_choice import StrategyChoice

    tasks = []
    for m, model in fitted.items():
        if isinstance(model, StrategyChoice):
            pred, labels, _ = model.predict(holes - balls, return_choice=True)
        else:
            pred, labels = model.predict(holes - balls), [""] * len(balls)
        for i in range(len(balls)):
            kappa = float(pred[i, 1]) if pred.shape[1] > 1 else float(data.kappa[0])
            tasks.append({"method": m, "shot": i, "strategy": labels[i],
                          "ball": balls[i].tolist(),
                          "hole": holes[i].tolist(), "alpha": float(np.deg2rad(pred[i, 0])),
                          "kappa": kappa, "robot": cfg.robot, "field": fld.name,
                          "field_spec": fld.spec, "motion": os.path.abspath(motion_dir)})
    return tasks


def _play_round(cfg: PlayConfig, tasks: list[dict], ex) -> list[dict]:
    """Step 4: the tasks on this process, local workers or Dask; rows in the tasks' order."""
    _LOG.info("playing %d shots ...", len(tasks))
    futures = [ex.submit(play_shot, t) for t in tasks]
    it = progress_bar(futures, cfg.progress, desc=f"playing {len(tasks)} shots", unit="shot")
    return [f.result() for f in it]


def _check_in_exudyn(cfg: PlayConfig, fld, motion, tasks: list[dict], rows: list[dict]) -> None:
    """Step 5: the first learner's first hits again in exudyn (``sunk_exudyn`` of their rows)."""
    from ..robots.control import place_robot
    from ..sim.shot import simulate_shot_exudyn

    checked = [(t, r) for t, r in zip(tasks, rows) if r["method"] == cfg.learners[0] and r["hit"]]
    for i, (task, row) in enumerate(checked[:cfg.validate_shots]):
        _LOG.info("  exudyn %d/%d: %s shot %d", i + 1, min(len(checked), cfg.validate_shots),
                  task["method"], task["shot"])
        ball = np.asarray(task["ball"])
        ex_shot = simulate_shot_exudyn(fld, ball, hole=task["hole"], arm={
            "robot": place_robot(cfg.robot, ball, fld), "motion": motion,
            "alpha": task["alpha"], "kappa": task["kappa"]})
        row["sunk_exudyn"] = bool(ex_shot.sunk)


def _summary(cfg: PlayConfig, fld, rows: list[dict], n_situations: int, times: dict,
             started: float | None = None):
    """Success per learner, agreement with exudyn and the time per stage, as text."""
    rates = {m: float(np.mean([r["sunk"] for r in rows if r["method"] == m]))
             for m in cfg.learners}
    checked = [r for r in rows if r["sunk_exudyn"] != ""]
    lines = [f"played {n_situations} situations on {fld.name} with the {cfg.robot}"]
    for m in cfg.learners:
        lines.append(f"  {m}: {rates[m]:.0%} sunk")
        mine = [r for r in rows if r["method"] == m and r["strategy"] != ""]
        for k in sorted({r["strategy"] for r in mine}):
            rk = [r for r in mine if r["strategy"] == k]
            lines.append(f"    strategy {k}: played {len(rk)} times, "
                         f"{np.mean([r['sunk'] for r in rk]):.0%} sunk")
    hit = [r for r in rows if r["hit"]]
    if hit:
        lines.append("  at the hit: club direction error max "
                     f"{max(r['direction_error_deg'] for r in hit):.2f} deg, launch direction "
                     f"(face) error max {max(r['launch_direction_error_deg'] for r in hit):.2f}"
                     f" deg; {sum(r['within_limits'] is True for r in rows)} of {len(rows)} "
                     "swings within the arm's limits")
    if checked:
        agree = np.mean([r["sunk"] == r["sunk_exudyn"] for r in checked])
        lines.append(f"  exudyn agreed with the ball model on {agree:.0%} of "
                     f"{len(checked)} checked shots")
    lines.append("time per stage:")
    lines += [f"  {k}: {v:.1f} s" for k, v in times.items()]
    if started is not None:
        lines.append(f"  total (from the start of play): {time.perf_counter() - started:.1f} s")
    return rates, "\n".join(lines) + "\n"


def play(config: PlayConfig | None = None, **overrides) -> dict:
    """Run the main job (module docstring) and write its outputs into ``config.out``.

    Parameters
    ----------
    config : PlayConfig, optional
        The settings (default: ``PlayConfig()``).
    **overrides
        Settings replaced in ``config``, e.g. ``play(robot="katana", quick=True)``.

    Returns
    -------
    dict
        ``success`` (fraction sunk per learner), ``times`` (seconds per stage) and ``rows``
        (the rows of ``shots.csv``, with the ball paths).
    """
    from ..minigolf.fields import load_field
    from ..robots.models import load_robot, robot_names

    started = time.perf_counter()
    cfg = with_overrides(PlayConfig, config, overrides).effective()
    if cfg.robot not in robot_names() and ".urdf" not in str(cfg.robot):
        raise ValueError(f"unknown robot {cfg.robot!r}; known: {', '.join(robot_names())}")
    fld = load_field(cfg.field)
    load_robot(cfg.robot)  # a robot that does not load fails before any work
    from .executors import open_executor

    # the executor (a Dask scheduler too) is opened and checked before the long work starts
    with open_executor(cfg.workers, cfg.dask) as ex:
        return _play(cfg, fld, ex, started)


def _play(cfg: PlayConfig, fld, ex, started: float) -> dict:
    """The steps of :func:`play` with an open executor ``ex`` (``started``: the run's start,
    for the total time in summary.txt)."""
    os.makedirs(os.path.join(cfg.out, "models"), exist_ok=True)
    times: dict[str, float] = {}
    rng = np.random.default_rng(cfg.seed)
    motion_dir = os.path.join(cfg.out, "models", "motion")
    motion, data, strategies = (_reuse_models(cfg.models, fld, cfg.strategies) if cfg.models
                                else _learn_and_teach(cfg, fld, times))
    check_reach(cfg.robot, fld, data.ball, data.alpha, motion.hitting_direction,
                "situations the teacher taught")
    motion.save(motion_dir)
    data.save(os.path.join(cfg.out, "models", f"dataset_{fld.name}.npz"))
    if strategies is not None:
        strategies.save(os.path.join(cfg.out, "models", f"strategies_{fld.name}.npz"))
    t2 = time.perf_counter()
    _LOG.info("fitting the hitting-parameter models (%s) ...", ", ".join(cfg.learners))
    from threadpoolctl import threadpool_limits

    # one BLAS thread: on busy cores OpenBLAS's threads on these small matrices made GPR's
    # fit 20x slower (7.5 s against 0.36 s for arctan's 56 shots on 2 loaded cores)
    with threadpool_limits(1):
        fitted = _fit_learners(data, cfg.learners, cfg.train_size, strategies)
    times["hitting-parameter models"] = time.perf_counter() - t2
    t3 = time.perf_counter()
    balls, holes = _situations(fld, cfg.shots, rng)
    tasks = _round_tasks(cfg, fld, data, fitted, balls, holes, motion_dir)
    rows = _play_round(cfg, tasks, ex)
    times["round (robot + ball model)"] = time.perf_counter() - t3
    if cfg.validate_shots > 0:
        t4 = time.perf_counter()
        _LOG.info("checking %d shots again in exudyn ...", cfg.validate_shots)
        _check_in_exudyn(cfg, fld, motion, tasks, rows)
        times["exudyn validation"] = time.perf_counter() - t4
    rates = _write_outputs(cfg, fld, (motion, data, fitted, strategies), tasks, rows,
                           len(balls), times, started)
    return {"success": rates, "times": times, "rows": rows}


def _write_outputs(cfg: PlayConfig, fld, learned: tuple, tasks: list[dict], rows: list[dict],
                   n_situations: int, times: dict, started: float | None = None) -> dict:
    """``shots.csv``, the figures, the replay and ``summary.txt`` (with every stage's time)."""
    from .play_figures import play_figures, strategy_figure

    motion, data, fitted, strategies = learned
    atomic_csv(os.path.join(cfg.out, "shots.csv"), SHOT_COLUMNS,
               ([r[c] for c in SHOT_COLUMNS] for r in rows))
    t = time.perf_counter()
    _LOG.info("drawing the figures ...")
    play_figures(fld, motion, data, fitted, rows, cfg.learners, cfg.out, cfg.robot)
    if strategies is not None:
        strategy_figure(fld, strategies, rows, cfg.learners[0], cfg.out)
    times["figures"] = time.perf_counter() - t
    if cfg.replay:
        from .replay import write_replay

        t = time.perf_counter()
        mine = [t for t in tasks if t["method"] == cfg.learners[0]][:cfg.replay]
        write_replay(mine, cfg.out, progress=_LOG.info)
        times["replay"] = time.perf_counter() - t
        _LOG.info("wrote the replay of %d shots: %s and GIFs (%.1f s)", len(mine),
                  os.path.join(cfg.out, "replay.html"), times["replay"])
    rates, text = _summary(cfg, fld, rows, n_situations, times, started)
    atomic_text(os.path.join(cfg.out, "summary.txt"), text)
    _LOG.info("%s", text.rstrip("\n"))
    _LOG.info("wrote %s, summary.txt, figures and models/ in %s",
              os.path.join(cfg.out, "shots.csv"), cfg.out)
    return rates
