"""``seds-casadi validate``: shots chosen by the learned hitting-parameter model, executed on a
robot in Pinocchio and checked again in exudyn (:mod:`seds_casadi.sim`).

Settings are a :class:`ValidateConfig`; progress goes to the ``logging`` logger of this module
(the command line prints it).
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass, replace

import numpy as np
from threadpoolctl import threadpool_limits

from ..core._io import atomic_csv, atomic_text
from ..game.launch import calibrate_launch
from ..game.reach import check_reach, check_swing_accuracy
from ..game.scene import Scene, SceneSpec
from ..game.shot import Shot, play_shot
from ..minigolf._progress import progress_bar
from ..minigolf.fields import load_field
from ..minigolf.parameters import make_model
from ..minigolf.teacher import collect_dataset, teacher_ranges
from ..motion.hitting import HittingMotionLearner
from ..motion.putting_demos import load_hitting_demos
from ._config import whole_number, with_overrides
from .executors import open_executor
from .plotting import plot_field, pyplot, save_figure

__all__ = ["validate", "ValidateConfig", "VALIDATION_COLUMNS"]

_LOG = logging.getLogger(__name__)

#: columns of ``validation.csv``; a unit ends the name (deg, m), impact_speed_error is relative
#: to the fast model's launch speed
VALIDATION_COLUMNS = ("field", "robot", "shot", "sunk_fast", "sunk_exudyn",
                      "impact_direction_error_deg", "impact_speed_error", "final_distance_m")
_NOT_COMPARED = {"impact_direction_error_deg": np.nan, "impact_speed_error": np.nan,
                 "final_distance_m": np.nan}


@dataclass(frozen=True)
class ValidateConfig:
    """Settings of :func:`validate` (the options of ``seds-casadi validate``).

    Attributes
    ----------
    robot : str
        A robot name or a ``.urdf`` file.
    field : str
        A field name or a ``.json`` field file.
    shots : int
        Shots to play (at least 1).
    out : str
        Output folder.
    seed : int
    progress : bool
        Progress bars (on stderr, only on a terminal).
    quick : bool
        At most 3 shots and a coarser teacher: a check in well under a minute.
    workers : int
        Local worker processes for the shots (each plays its shots in Pinocchio and exudyn;
        the results do not depend on the number).
    """

    robot: str = "wam"
    field: str = "flat"
    shots: int = 10
    out: str = "validate_out"
    seed: int = 0
    progress: bool = True
    quick: bool = False
    workers: int = 1

    def __post_init__(self) -> None:
        object.__setattr__(self, "shots", whole_number("shots", self.shots, 1))
        object.__setattr__(self, "workers", whole_number("workers", self.workers, 1))
        object.__setattr__(self, "seed", whole_number("seed", self.seed, 0))


def _learn(fld, robot: str, progress: bool, quick: bool = False):
    """The scene (the hitting motion and the robot's measured launch), the teacher's data set
    for the field on that launch (checked against the robot's reach) and GPR fitted on it."""
    t0 = time.perf_counter()
    motion = HittingMotionLearner(n_components=3).fit(load_hitting_demos()).motion_
    scene = Scene(robot, fld, motion)
    _, krange = teacher_ranges(fld)
    check_swing_accuracy(scene, fld.teacher.get("kappa", max(1.0, krange[0])))
    scene = scene.with_launch(calibrate_launch(scene))
    data = collect_dataset(fld, scene.stroke, resolution=(81, 26) if quick else (121, 41),
                           progress=progress)
    check_reach(robot, fld, data.ball, data.alpha, motion.hitting_direction,
                "situations the teacher taught")
    with threadpool_limits(1):   # see play: BLAS threads slow small GPR fits down
        model = make_model("gpr").fit(data.situations, data.outputs)
    _LOG.info("hitting motion, the robot's launch, teacher (%d good shots) and GPR: %.1f s",
              len(data), time.perf_counter() - t0)
    return scene, data, model


def _play_shots(cfg: ValidateConfig, scene: Scene, model, data, rng):
    """Every shot (situations drawn in order, the model's prediction), played here or on
    ``cfg.workers`` processes (each loads the scene once); rows and figure data in the shots'
    order."""
    shots = []
    for i in range(cfg.shots):
        ball, hole = _situation(scene.field, rng)
        pred = model.predict((hole - ball)[None])[0]
        shots.append(Shot(ball, hole, float(np.deg2rad(pred[0])),
                          float(pred[1]) if len(pred) > 1 else float(data.kappa[0]), index=i))
    if cfg.workers > 1:   # processes load the motion from its folder
        folder = os.path.join(cfg.out, "models", "motion")
        scene.motion.save(folder)
        scene = Scene(scene.robot, scene.field, scene.motion, scene.launch_table, folder)
    where = scene.spec() if cfg.workers > 1 else scene
    with open_executor(cfg.workers) as ex:
        futures = [ex.submit(_shot, where, s, cfg.robot) for s in shots]
        done = [f.result() for f in progress_bar(
            futures, cfg.progress, desc=f"validate {cfg.robot} on {scene.field.name}",
            unit="shot")]
    return [r for r, _ in done], [s for _, s in done]


def _situation(fld, rng):
    """A random situation (ball, hole) drawn from the field's declaration."""
    balls, holes = fld.situations.sample(1, rng)
    return balls[0], holes[0]


def _shot(scene: Scene | SceneSpec, shot: Shot, robot: str):
    """One shot on both engines (a picklable task): its row of ``validation.csv``, and what
    the figure needs (the paths, the swing and the exudyn shot; None without a hit in
    exudyn)."""
    if isinstance(scene, SceneSpec):
        scene = scene.load()
    row = {"field": scene.field.name, "robot": robot, "shot": shot.index}
    # the robot stands at its default place beside each ball; the face as the robot holds it
    # and the arm's effective mass at the face launch the ball (game.shot.swing_launch)
    fast = play_shot(scene, shot, "ball", keep_swing=True)
    if not fast.hit:
        row.update(sunk_fast=False, sunk_exudyn=False, **_NOT_COMPARED)
        return row, None
    # the same swing in exudyn: the arm as a kinematic tree under the same controller, the
    # ball struck by the club face's contact triangles
    ex = play_shot(scene, shot, "exudyn")
    if not ex.hit:
        row.update(sunk_fast=fast.sunk, sunk_exudyn=False, **_NOT_COMPARED)
        return row, None
    a, b2 = ex.launch_velocity, fast.launch_velocity
    cosang = a @ b2 / max(np.linalg.norm(a) * np.linalg.norm(b2), 1e-12)
    row.update(sunk_fast=fast.sunk, sunk_exudyn=ex.sunk,
               impact_direction_error_deg=float(np.degrees(np.arccos(np.clip(cosang, -1, 1)))),
               impact_speed_error=float(abs(np.linalg.norm(a) / np.linalg.norm(b2) - 1)),
               final_distance_m=float(np.linalg.norm(ex.final_position - fast.final_position)))
    return row, (fast.path, ex.path, shot.hole, shot.ball, fast.swing, ex.exudyn)


def _report(cfg: ValidateConfig, fld, rows: list[dict], shots: list) -> str:
    """The text of ``report.txt``: agreement of the sinks, the impact and final positions."""
    hit = [r for r in rows if np.isfinite(r["impact_speed_error"])]
    agree = np.mean([r["sunk_fast"] == r["sunk_exudyn"] for r in rows])
    lines = [f"validation of {cfg.robot} on {fld.name}: {len(rows)} shots, {len(hit)} hit",
             f"sinks agree: {agree:.0%} (fast sank {sum(r['sunk_fast'] for r in rows)}, "
             f"exudyn sank {sum(r['sunk_exudyn'] for r in rows)})"]
    if hit:
        wall = sum(s[5].wall_time for s in shots if s is not None)
        simulated = sum(s[5].simulated_time for s in shots if s is not None)
        lines += [
            f"impact direction error: max {max(r['impact_direction_error_deg'] for r in hit):.2f}"
            f" deg (target 2)",
            f"impact speed error: max {max(r['impact_speed_error'] for r in hit):.1%} "
            f"(target 10 %)",
            f"final distance: median {np.median([r['final_distance_m'] for r in hit]):.3f} m, "
            f"max {max(r['final_distance_m'] for r in hit):.3f} m",
            f"exudyn speed: {simulated / max(wall, 1e-9):.2f} simulated s per wall s"]
    return "\n".join(lines) + "\n"


def validate(config: ValidateConfig | None = None, **overrides) -> list[dict]:
    """``seds-casadi validate``: shots chosen by the learned hitting-parameter model (GPR on the
    teacher's data set for the field), executed by the robot's 500 Hz controller on Pinocchio,
    then played on the fast ball model and in exudyn; writes ``validation.csv``,
    ``report.txt`` and ``validation.png`` into ``config.out``.

    Parameters
    ----------
    config : ValidateConfig, optional
        The settings (default: ``ValidateConfig()``).
    **overrides
        Settings replaced in ``config``, e.g. ``validate(robot="katana", shots=3)``.

    Returns
    -------
    list of dict
        The rows of ``validation.csv`` (:data:`VALIDATION_COLUMNS`).
    """
    cfg = with_overrides(ValidateConfig, config, overrides)
    if cfg.quick:
        cfg = replace(cfg, shots=min(cfg.shots, 3))
    fld = load_field(cfg.field)
    os.makedirs(cfg.out, exist_ok=True)
    rng = np.random.default_rng(cfg.seed)
    scene, data, model = _learn(fld, cfg.robot, cfg.progress, cfg.quick)
    rows, shots = _play_shots(cfg, scene, model, data, rng)
    atomic_csv(os.path.join(cfg.out, "validation.csv"), VALIDATION_COLUMNS,
               ([r[c] for c in VALIDATION_COLUMNS] for r in rows))
    text = _report(cfg, fld, rows, shots)
    atomic_text(os.path.join(cfg.out, "report.txt"), text)
    _report_figure(fld, shots, os.path.join(cfg.out, "validation.png"), cfg.robot)
    _LOG.info("%s", text.rstrip("\n"))
    return rows


def _report_figure(fld, paths, path, robot: str = ""):
    plt = pyplot()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(14, 3.8), gridspec_kw={"width_ratios": [2.2, 1]})
    plot_field(fld, ax=a1, legend=False)
    for k, p in enumerate(paths):
        if p is None:
            continue
        fast, ex, hole, ball, swing, shot = p
        c = plt.rcParams["axes.prop_cycle"].by_key()["color"][k % 10]
        a1.plot(fast[:, 0], fast[:, 1], "-", color=c, lw=1)
        a1.plot(ex[:, 0], ex[:, 1], "--", color=c, lw=1)
        a1.add_patch(plt.Circle(hole, fld.hole_radius, color=c, fill=False, lw=1))
        v = np.linalg.norm(np.gradient(swing.head, swing.t, axis=0), axis=1)
        a2.plot(swing.t - swing.hit_time, v, "-", color=c, lw=1)
        if len(shot.head_speed):
            a2.plot(shot.head_speed[:, 0] - shot.contact_time, shot.head_speed[:, 1], ":",
                    color=c, lw=1.2)
    a1.set_title(f"{fld.name}, the {robot}: ball paths, one colour per shot", fontsize=9)
    a1.legend(handles=[plt.Line2D([], [], color="k", lw=1, label="fast ball model"),
                       plt.Line2D([], [], color="k", ls="--", lw=1, label="exudyn"),
                       plt.Line2D([], [], color="k", marker="o", mfc="none", ms=8, ls="",
                                  label="hole")], fontsize=7, loc="upper left",
              framealpha=0.85)
    a2.legend(handles=[plt.Line2D([], [], color="k", lw=1, label="Pinocchio swing"),
                       plt.Line2D([], [], color="k", ls=":", lw=1.2, label="exudyn arm")],
              fontsize=7)
    a2.set_xlim(-0.3, 0.15)
    a2.set_xlabel("time from the hit [s]")
    a2.set_ylabel("club-head speed [m/s]")
    a2.set_title("club-head speed: Pinocchio swing (solid), exudyn arm (dotted)", fontsize=9)
    save_figure(fig, path)
