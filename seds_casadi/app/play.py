"""``seds-casadi play``: the whole pipeline end to end (paper Fig. 5).

1. **Hitting motion**: SEDS + strength factor from the demonstrations (shipped putts by default).
2. **Teacher**: good shots on the field's ball model (:mod:`seds_casadi.minigolf.teacher`),
   over the situations the field declares (:mod:`seds_casadi.minigolf.situations`); first the
   robot is checked to reach the declared ball positions (:mod:`seds_casadi.game.reach`).
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
from threadpoolctl import threadpool_limits

from ..core._io import atomic_csv, atomic_text
from ..core.demo_files import load_demonstrations
from ..game.adapt import World, adapt, fastest_launch
from ..game.launch import calibrate_launch
from ..game.reach import check_launch_reach, check_reach, check_swing_accuracy, fastest_gain
from ..game.scene import Scene
from ..game.shot import Shot, play_round, play_shot
from ..minigolf._progress import progress_bar
from ..minigolf.fields import load_field
from ..minigolf.hitting_data import HittingDataset, paper_situations
from ..minigolf.parameters import make_model
from ..minigolf.strategies import StrategySet, explore
from ..minigolf.strategy_choice import StrategyChoice
from ..minigolf.stroke import Stroke
from ..minigolf.table1 import N_COMPONENTS, training_indices
from ..minigolf.teacher import Teacher, teacher_ranges
from ..motion.hitting import HittingMotion, HittingMotionLearner
from ..motion.putting_demos import load_hitting_demos
from ..robots.models import load_robot, robot_names
from ._config import names_tuple, whole_number, with_overrides
from .executors import InlineExecutor, open_executor
from .outdir import path_under
from .play_figures import adaptation_figure, play_figures, strategy_figure
from .replay import write_replay
from .shot_table import SHOT_COLUMNS, shot_row
from .teacher_cache import cached_dataset

__all__ = ["play", "PlayConfig", "LEARNERS"]

_LOG = logging.getLogger(__name__)

LEARNERS = ("gpr", "gmr")
_VALID_LEARNERS = ("gpr", "gmr", "sep_gmr")


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
    world : str or None
        Where the shots are really played (:class:`~seds_casadi.game.adapt.World`): a field
        name or ``.json`` file of the same course whose green differs, or ``"exudyn"`` (the
        field in exudyn's multibody model); the robot is taught on ``field`` only. None: the
        field itself.
    adapt : int
        Adaptation shots on the world before the round (:func:`~seds_casadi.game.adapt.adapt`):
        the round is played with the taught models and again with the corrected ones.
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
    world: str | None = None
    adapt: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "replay", whole_number("replay", self.replay, 0))
        object.__setattr__(self, "learners", names_tuple("learner", self.learners,
                                                         _VALID_LEARNERS))
        object.__setattr__(self, "shots", whole_number("shots", self.shots, 1))
        object.__setattr__(self, "validate_shots",
                           whole_number("validate_shots", self.validate_shots, 0))
        object.__setattr__(self, "workers", whole_number("workers", self.workers, 1))
        object.__setattr__(self, "seed", whole_number("seed", self.seed, 0))
        object.__setattr__(self, "adapt", whole_number("adapt", self.adapt, 0))
        if self.world is not None and not str(self.world).strip():
            raise ValueError("world must be a field name, a .json field file or 'exudyn'")
        if self.adapt and self.strategies is not None:
            raise ValueError("adapt corrects the model of the teacher's one strategy; leave out "
                             "strategies")
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


def _situations(field, n: int, rng):
    """Random situations (balls, holes) drawn from the field's declaration."""
    return field.situations.sample(n, rng)


def _reuse_models(models: str, fld, strategies=None):
    """Steps 1-2 from an earlier run's ``models/`` folder."""
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
    src = os.path.join(models, f"strategies_{fld.name}.npz")
    if not os.path.exists(src):
        raise ValueError(f"--models {models}: no strategies_{fld.name}.npz there; run play "
                         f"--strategies once without --models to explore them")
    ss = StrategySet.load(src)
    _LOG.info("reused %d strategies:\n%s", len(ss), ss.describe())
    return motion, data, ss


def _measure_launch(cfg: PlayConfig, scene: Scene, times: dict) -> Scene:
    """The robot's launch over the teacher's (alpha, kappa) ranges
    (:func:`~seds_casadi.game.launch.calibrate_launch`): the scene the teacher searches."""
    t = time.perf_counter()
    arange, krange = teacher_ranges(scene.field)
    # an arm too slow for the field is refused on the first grid, before its refinement
    table = calibrate_launch(scene, check=lambda t: Teacher(scene.field,
                                                             scene.stroke.with_launch(t)))
    times["the robot's launch"] = time.perf_counter() - t
    f = table.speed_factor[table.speed_factor > 0]
    _LOG.info("the %s's launch: %.2f-%.2f x the commanded club speed over alpha %g..%g deg, "
              "kappa %g..%g (%.1f s)", cfg.robot, f.min(), f.max(), *arange, *krange,
              times["the robot's launch"])
    return scene.with_launch(table)


def _learn_and_teach(cfg: PlayConfig, fld, times: dict):
    """Steps 1-2: the hitting motion from the demonstrations, the robot's launch, the
    teacher's good shots on that launch."""
    t0 = time.perf_counter()
    _LOG.info("learning the hitting motion (SEDS + GMR) ...")
    d = load_demonstrations(cfg.demos) if cfg.demos else load_hitting_demos()
    motion = HittingMotionLearner(n_components=3).fit(d).motion_
    times["hitting motion (SEDS + GMR)"] = time.perf_counter() - t0
    _LOG.info("hitting motion: v* = %.3f m/s (%.1f s)", motion.hitting_speed,
              times["hitting motion (SEDS + GMR)"])
    t1 = time.perf_counter()
    _check_declared_reach(cfg.robot, fld, motion)
    fastest = fastest_gain(cfg.robot, fld, motion)
    _LOG.info("the %s swings within 2 %% of the commanded speed up to kappa %.2f (%.2f m/s)",
              cfg.robot, fastest, fastest * motion.hitting_speed)
    scene = Scene(cfg.robot, fld, motion)
    check_launch_reach(scene, fastest)   # an arm too slow for the field: refused here
    _, krange = teacher_ranges(fld)
    check_swing_accuracy(scene, fld.teacher.get("kappa", min(max(1.0, krange[0]), fastest)))
    times["reach, speed and accuracy checks"] = time.perf_counter() - t1
    scene = _measure_launch(cfg, scene, times)
    stroke = scene.stroke
    t1 = time.perf_counter()
    if cfg.strategies is not None:
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
    if strategies is not None:
        return {m: StrategyChoice(m, n_components=N_COMPONENTS[2]).fit(strategies)
                for m in learners}

    S, Y = data.situations, data.outputs
    if train_size is not None and train_size < len(data):
        idx = training_indices(S, train_size, "spaced", np.random.default_rng(0))
        S, Y = S[idx], Y[idx]
    k = N_COMPONENTS[Y.shape[1]]
    return {m: make_model(m, **({} if m == "gpr" else {"n_components": k})).fit(S, Y)
            for m in learners}


def _round_shots(data, fitted: dict, balls, holes) -> list[Shot]:
    """Step 4's shots: each learner's (alpha, kappa) for each situation."""
    shots = []
    for m, model in fitted.items():
        if isinstance(model, StrategyChoice):
            pred, labels, _ = model.predict(holes - balls, return_choice=True)
        else:
            pred, labels = model.predict(holes - balls), [""] * len(balls)
        for i in range(len(balls)):
            kappa = float(pred[i, 1]) if pred.shape[1] > 1 else float(data.kappa[0])
            shots.append(Shot(balls[i], holes[i], float(np.deg2rad(pred[i, 0])), kappa,
                              method=m, index=i, strategy=str(labels[i])))
    return shots


def _play_round(cfg: PlayConfig, scene: Scene, shots: list[Shot], ex,
                engine: str = "ball") -> list[dict]:
    """Step 4: the shots on this process, local workers or Dask (each worker loads the scene
    once); rows in the shots' order."""
    _LOG.info("playing %d shots%s ...", len(shots), "" if engine == "ball" else f" ({engine})")
    # in this process the scene in memory plays them; workers load it from its spec
    here = isinstance(ex, InlineExecutor)
    results = play_round(scene, shots, engine=engine, executor=None if here else ex,
                         progress=lambda it: progress_bar(
                             it, cfg.progress, desc=f"playing {len(shots)} shots",
                             unit="batch of 4"))
    return [shot_row(r) for r in results]


def _check_in_exudyn(cfg: PlayConfig, scene: Scene, shots: list[Shot],
                     rows: list[dict]) -> None:
    """Step 5: the first learner's first hits again in exudyn (``sunk_exudyn`` of their rows)."""
    checked = [(s, r) for s, r in zip(shots, rows) if r["method"] == cfg.learners[0] and r["hit"]]
    for i, (shot, row) in enumerate(checked[:cfg.validate_shots]):
        _LOG.info("  exudyn %d/%d: %s shot %d", i + 1, min(len(checked), cfg.validate_shots),
                  shot.method, shot.index)
        row["sunk_exudyn"] = play_shot(scene, shot, engine="exudyn").sunk


def _rates(rows: list[dict], learners) -> dict:
    return {m: float(np.mean([r["sunk"] for r in rows if r["method"] == m])) for m in learners}


def _summary(cfg: PlayConfig, fld, rows: list[dict], n_situations: int, times: dict,
             started: float | None = None, world: World | None = None,
             adaptations: dict | None = None, before: list[dict] | None = None):
    """Success per learner, agreement with exudyn and the time per stage, as text."""
    rates = _rates(rows, cfg.learners)
    checked = [r for r in rows if r["sunk_exudyn"] != ""]
    where = fld.name if world is None or world.field is fld and world.engine == "ball" else (
        f"the world {world.label} (taught on {fld.name})")
    lines = [f"played {n_situations} situations on {where} with the {cfg.robot}"]
    if adaptations:
        b = _rates(before, cfg.learners)
        lines.append("  test success before the correction (--adapt 0): "
                     + ", ".join(f"{m} {b[m]:.0%}" for m in cfg.learners))
        lines.append(f"  test success after {cfg.adapt} adaptation shots: "
                     + ", ".join(f"{m} {rates[m]:.0%}" for m in cfg.learners))
        for m, a in adaptations.items():
            lines.append(f"  {m}: {int(a.sunk.sum())} of {len(a.steps)} adaptation shots sunk; "
                         f"the green estimated: "
                         f"{a.green.describe() if a.green else 'as the field'}")
            n_lim, n_all, n_short = a.model.limited_
            if n_lim and a.green is not None:
                lines.append(
                    f"    {n_lim} of the {n_all} taught situations the correction was learned "
                    f"at need a faster launch than the {cfg.robot}'s "
                    f"({fastest_launch(a.green):.2f} m/s at its fastest, its swing saturating "
                    f"at its joints' speed limits) on the estimated green: at its fastest their "
                    f"balls reach the hole slower than taught, {n_short} of them stop short "
                    f"of its edge (a stronger arm, a faster green or nearer holes would serve them)")
    for m in cfg.learners:
        lines.append(f"  {m}: {rates[m]:.0%} sunk")
        mine = [r for r in rows if r["method"] == m and r["strategy"] != ""]
        for k in sorted({r["strategy"] for r in mine}):
            rk = [r for r in mine if r["strategy"] == k]
            lines.append(f"    strategy {k}: played {len(rk)} times, "
                         f"{np.mean([r['sunk'] for r in rk]):.0%} sunk")
    for m in cfg.learners:
        missed = [r["miss"] for r in rows if r["method"] == m and not r["sunk"]]
        if missed:
            kinds = ", ".join(f"{k} {missed.count(k)}" for k in sorted(set(missed)))
            lines.append(f"  {m} missed {len(missed)}: {kinds} (shots.csv, miss_reason)")
    hit = [r for r in rows if r["hit"]]
    if hit:
        se = [r["speed_error"] for r in hit]
        lines.append("  at the hit: club direction error max "
                     f"{max(r['direction_error_deg'] for r in hit):.2f} deg, speed error "
                     f"{min(se):+.1%} to {max(se):+.1%}, launch direction "
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
    started = time.perf_counter()
    cfg = with_overrides(PlayConfig, config, overrides).effective()
    if cfg.robot not in robot_names() and ".urdf" not in str(cfg.robot):
        raise ValueError(f"unknown robot {cfg.robot!r}; known: {', '.join(robot_names())}")
    fld = load_field(cfg.field)
    world = World.load(cfg.world, fld)   # another course than the field: refused here
    load_robot(cfg.robot)  # a robot that does not load fails before any work
    # the executor (a Dask scheduler too) is opened and checked before the long work starts
    with open_executor(cfg.workers, cfg.dask) as ex:
        return _play(cfg, fld, ex, started, world)


def _play(cfg: PlayConfig, fld, ex, started: float, world: World | None = None) -> dict:
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
    # the scene every shot is played in (workers load it once each from the saved motion)
    scene = Scene(cfg.robot, fld, motion, data.stroke.launch_table, motion_dir)
    data.save(path_under(cfg.out, "models", f"dataset_{fld.name}.npz"))
    if strategies is not None:
        strategies.save(path_under(cfg.out, "models", f"strategies_{fld.name}.npz"))
    t2 = time.perf_counter()
    _LOG.info("fitting the hitting-parameter models (%s) ...", ", ".join(cfg.learners))
    # one BLAS thread: on busy cores OpenBLAS's threads on these small matrices made GPR's
    # fit 20x slower (7.5 s against 0.36 s for arctan's 56 shots on 2 loaded cores)
    with threadpool_limits(1):
        fitted = _fit_learners(data, cfg.learners, cfg.train_size, strategies)
    times["hitting-parameter models"] = time.perf_counter() - t2
    t3 = time.perf_counter()
    balls, holes = _situations(fld, cfg.shots, rng)
    shots = _round_shots(data, fitted, balls, holes)
    world = world or World(fld)
    # the world the shots are really played on (the field itself unless --world)
    played = Scene(cfg.robot, world.field, motion, data.stroke.launch_table, motion_dir)
    rows = _play_round(cfg, played, shots, ex, world.engine)
    times["round (robot + ball model)" if world.engine == "ball"
          else "round (robot in exudyn)"] = time.perf_counter() - t3
    adaptations, before, curve = None, None, []
    if cfg.adapt:
        before = rows
        t = time.perf_counter()
        marks = _checkpoints(cfg.adapt) if world.engine == "ball" else [cfg.adapt]
        adaptations, adapt_rows = _adapt(cfg, scene, world, fitted, data, marks)
        times["adaptation"] = time.perf_counter() - t
        t = time.perf_counter()
        for k in marks:   # the round with the models corrected after k shots
            shots = _round_shots(data, {m: a.snapshots[k] for m, a in adaptations.items()},
                                 balls, holes)
            rows = _play_round(cfg, played, shots, ex, world.engine)
            for r in rows:
                r["adapt_shots"] = k
            curve += rows
        times["rounds after the correction"] = time.perf_counter() - t
    if cfg.validate_shots > 0 and world.engine == "ball":
        t4 = time.perf_counter()
        _LOG.info("checking %d shots again in exudyn ...", cfg.validate_shots)
        _check_in_exudyn(cfg, played, shots, rows)
        times["exudyn validation"] = time.perf_counter() - t4
    all_rows = rows if before is None else adapt_rows + before + curve
    rates = _write_outputs(cfg, scene, (data, fitted, strategies), shots, rows,
                           len(balls), times, started, all_rows=all_rows,
                           adaptation=(world, adaptations, before))
    return {"success": rates, "times": times, "rows": rows, "all_rows": all_rows,
            "adaptations": adaptations}


def _checkpoints(n: int) -> list[int]:
    """The numbers of adaptation shots after which the round is played (for the learning
    curve of ``adaptation.png``): 1, 2, 5, 10, 20, 30, 50, 100, ... below ``n``, and ``n``."""
    marks = [k for k in (1, 2, 5, 10, 20, 30, 50) if k < n]
    marks += [k for k in range(100, n, 100)]
    return marks + [n]


def _adapt(cfg: PlayConfig, scene: Scene, world: World, fitted: dict, data,
           marks: list[int]):
    """Each learner's model corrected from ``cfg.adapt`` shots on the world
    (:func:`~seds_casadi.game.adapt.adapt`, the models after ``marks`` shots kept); the
    adaptation shots as rows (phase "adapt")."""
    adaptations, rows = {}, []
    for m, model in fitted.items():
        _LOG.info("%s: %d adaptation shots on %s ...", m, cfg.adapt, world.label)
        a = adapt(scene, world, model, data, cfg.adapt, rng=np.random.default_rng(cfg.seed + 1),
                  method=m, progress=_LOG.info if cfg.progress else None, snapshots=marks)
        adaptations[m] = a
        _LOG.info("%s: %d of %d adaptation shots sunk; the green estimated: %s", m,
                  int(a.sunk.sum()), cfg.adapt, a.green.describe() if a.green else "nominal")
        for k, step in enumerate(a.steps):
            row = shot_row(step.result)
            row.update(phase="adapt", adapt_shots=k)
            rows.append(row)
    return adaptations, rows


def _write_outputs(cfg: PlayConfig, scene: Scene, learned: tuple, shots: list[Shot],
                   rows: list[dict], n_situations: int, times: dict,
                   started: float | None = None, all_rows: list[dict] | None = None,
                   adaptation: tuple | None = None) -> dict:
    """``shots.csv``, the figures, the replay and ``summary.txt`` (with every stage's time).
    ``rows``: the final round's; ``all_rows``: every shot played (with adaptation: the
    adaptation shots, the round before and after the correction)."""
    fld, motion = scene.field, scene.motion
    data, fitted, strategies = learned
    atomic_csv(os.path.join(cfg.out, "shots.csv"), SHOT_COLUMNS,
               ([r.get(c, "") for c in SHOT_COLUMNS] for r in (all_rows or rows)))
    t = time.perf_counter()
    _LOG.info("drawing the figures ...")
    play_figures(fld, motion, data, fitted, rows, cfg.learners, cfg.out, cfg.robot)
    if strategies is not None:
        strategy_figure(fld, strategies, rows, cfg.learners[0], cfg.out)
    world, adaptations, before = adaptation or (None, None, None)
    if adaptations:
        adaptation_figure(fld, adaptations, [r for r in all_rows if r["phase"] == "test"],
                          cfg.out)
    times["figures"] = time.perf_counter() - t
    if cfg.replay:
        t = time.perf_counter()
        mine = [s for s in shots if s.method == cfg.learners[0]][:cfg.replay]
        write_replay(scene, mine, cfg.out, progress=_LOG.info)
        times["replay"] = time.perf_counter() - t
        _LOG.info("wrote the replay of %d shots: %s and GIFs (%.1f s)", len(mine),
                  os.path.join(cfg.out, "replay.html"), times["replay"])
    rates, text = _summary(cfg, fld, rows, n_situations, times, started, world, adaptations,
                           before)
    atomic_text(os.path.join(cfg.out, "summary.txt"), text)
    _LOG.info("%s", text.rstrip("\n"))
    _LOG.info("wrote %s, summary.txt, figures and models/ in %s",
              os.path.join(cfg.out, "shots.csv"), cfg.out)
    return rates
