"""Command line: ``seds-casadi <command>`` (also ``python -m seds_casadi``).

Commands
--------
fit     fit a stable DS to demonstrations in a .npz/.csv file; write the model and a figure
lasa    run the LASA handwriting benchmark; write lasa.csv, summary.txt and figures
table1  the paper's Table 1 (GPR vs GMR for the hitting parameters); write table1.csv, figures
validate shots by a robot checked in exudyn against the fast ball model; validation.csv, report
play    the main job: learn, teach, play a round with the robot, check a few shots in exudyn

The commands' library code reports progress through ``logging`` (loggers under
``seds_casadi.app``); :func:`main` prints those messages plainly on stdout, as the commands
always printed them (``--quiet``: warnings and errors only).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import os
import sys
import warnings
from collections.abc import Iterator


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``seds-casadi``."""
    p = argparse.ArgumentParser(
        prog="seds-casadi",
        description="Learn stable dynamical systems (SEDS in CasADi/IPOPT) and play minigolf.",
    )
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    # options of the commands that report their progress through logging
    quiet = argparse.ArgumentParser(add_help=False)
    quiet.add_argument("--quiet", "-q", action="store_true",
                       help="print only warnings and errors: no progress messages or bars "
                            "(bars show only on a terminal anyway)")
    _add_fit(sub, quiet)
    _add_lasa(sub, quiet)
    _add_table1(sub, quiet)
    _add_validate(sub, quiet)
    _add_play(sub, quiet)
    return p


def _robot_help() -> str:
    try:
        from ..robots.models import robot_names
    except ImportError:  # a core-only install: no robots to list
        return "a robot name (install the [robots] extra) [wam]"
    return (f"a robot name: {', '.join(robot_names())} (the arms other than wam and katana "
            f"come from example-robot-data) [wam]")


def _field_help(default: str) -> str:
    from ..minigolf.fields import field_names

    return f"a field name ({', '.join(field_names())}) or a .json field file [{default}]"


def _at_least(low: int):
    """An argparse type: a whole number >= ``low`` (``--replay 0`` or ``--samples 0`` would be
    accepted and mean nothing, or "all", silently)."""
    def whole(text: str) -> int:
        try:
            n = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if n < low:
            raise argparse.ArgumentTypeError(f"must be at least {low}, got {n}")
        return n
    return whole


def _components(text: str) -> int | str | range:
    if text in ("bic", "auto"):
        return text
    lo, sep, hi = text.partition("-")
    try:
        return range(int(lo), int(hi) + 1) if sep and lo else int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, a range such as 4-8, 'auto' or "
                                         f"'bic', got {text!r}") from None


def _add_fit(sub, quiet) -> None:
    from ..core.settings import OBJECTIVES, Formulation, GMMMode, Init, Lyapunov, SpeedCalibration

    f = sub.add_parser("fit", help="fit a stable DS to demonstrations from a .npz or .csv file",
                       parents=[quiet],
                       description="Fit SEDS to demonstrations (formats: see "
                                   "seds_casadi.core.demo_files) and write model.npz and "
                                   "streamlines.png to --out. Shows the solver's progress.")
    f.add_argument("demonstrations", help="path to a .npz or .csv demonstrations file")
    f.add_argument("--components", "-K", type=_components, default="auto",
                   help="number of Gaussians; 'auto': the K in 4-10 whose reproductions fit the "
                        "demonstrations best (with the automatic settings); 'bic' [auto]")
    f.add_argument("--objective", choices=OBJECTIVES + ("auto",), default="auto",
                   help="objective; 'auto': mse with the automatic settings (see SEDS) [auto]")
    f.add_argument("--dt", type=float, default=None,
                   help="time step [s] of the samples, needed only when the file has neither "
                        "velocities nor time stamps [from the file]")
    f.add_argument("--seed", type=int, default=0, help="random seed of the initialisation [0]")
    f.add_argument("--max-iter", type=int, default=1000, help="IPOPT iteration limit [1000]")
    f.add_argument("--lyapunov", choices=Lyapunov.values() + ("auto",), default="auto",
                   help="the certificate's V = (x - x*)^T P (x - x*): P = I (SEDS) or a "
                        "learned P [auto: learned]")
    f.add_argument("--formulation", choices=Formulation.values(), default="by-construction",
                   help="Eq. 10 by the parametrization or as NLP constraints [by-construction]")
    f.add_argument("--gain-limit", type=_gain_limit, default="auto",
                   help="bound the stiffness of the components (units of the data's rate; "
                        "10 suited the LASA shapes, but it can also hold a fit back: "
                        "compare with and without); 'none' for no limit [auto: 10]")
    f.add_argument("--init", choices=Init.values() + ("auto",), default="auto",
                   help="IPOPT's start: EM on [x; xdot] (SEDS), LPV-DS's (EM on x, "
                        "least-squares stable gains) or the same from a physically-consistent "
                        "clustering (PC-GMM's similarity) [auto: pc]")
    f.add_argument("--gmm", choices=GMMMode.values() + ("auto",), default="auto",
                   help="optimise the GMM with the dynamics (SEDS) or keep the start's GMM and "
                        "optimise the dynamics only (LPV-DS's split; with --init pc) "
                        "[auto: fixed]")
    f.add_argument("--speed", choices=SpeedCalibration.values(), default="strength",
                   help="how a direction-objective model gets the demonstrated speeds: a "
                        "strength factor v(x) by GMR along the certified streamlines (Eq. 12), "
                        "or one factor on every gain [strength]")
    f.add_argument("--choose", action="append", type=_choice, default=[], metavar="NAME=A,B",
                   help="choose this SEDS setting among the values by leave-one-demonstration-"
                        "out reproduction (DemoSearchCV), e.g. --choose objective=mse,direction "
                        "--choose lyapunov=identity,learned; repeat for a grid. The other "
                        "options are common to every candidate; the chosen one is refitted on "
                        "all demonstrations [no search]")
    f.add_argument("--out", default="seds_out", help="output folder [seds_out]")


def _gain_limit(text: str) -> float | str | None:
    """``--gain-limit``: a number, 'auto' or 'none'."""
    if text.strip().lower() in ("auto", "none"):
        return None if text.strip().lower() == "none" else "auto"
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, 'auto' or 'none', got {text!r}"
                                         ) from None


def _choice(text: str) -> tuple[str, list]:
    """``NAME=A,B,...`` of ``fit --choose``: a SEDS parameter and its candidate values."""
    name, sep, values = text.partition("=")
    name = name.strip().replace("-", "_")
    if not sep or not name or not values.strip():
        raise argparse.ArgumentTypeError(f"expected NAME=A,B (e.g. objective=mse,direction), got "
                                         f"{text!r}")

    def value(v: str):
        v = v.strip()
        if v.lower() == "none":
            return None
        for cast in (int, float):
            try:
                return cast(v)
            except ValueError:
                pass
        return v

    return name, [value(v) for v in values.split(",") if v.strip()]


def _add_lasa(sub, quiet) -> None:
    from ..core.datasets import LASA_SHAPES
    from ..core.settings import OBJECTIVES
    from .lasa import DEFAULT_PROTOCOLS, PROTOCOLS

    def components(text: str) -> int | str:
        if text in ("bic", "published"):
            return text
        try:
            k = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected a positive integer, 'bic' or 'published', got {text!r}") from None
        if k < 1:
            raise argparse.ArgumentTypeError(f"K must be at least 1, got {k}")
        return k

    la = sub.add_parser("lasa", help="run the LASA handwriting benchmark", parents=[quiet],
                        description="Fit LASA shapes, score reproductions (RMSE, e_dot, DTW) "
                                    "and write lasa.csv (lasa_dsopt.csv for --protocol ds-opt), "
                                    "summary.txt and figures to --out.")
    la.add_argument("--shapes", nargs="+", default=None, metavar="SHAPE",
                    help=f"shapes to run [all 30; ds-opt: the 26 single-pattern ones]; valid: "
                         f"{', '.join(LASA_SHAPES)}")
    la.add_argument("--objectives", nargs="+", default=None, choices=OBJECTIVES,
                    help="objectives to compare [all three; ds-opt: mse]")
    la.add_argument("--protocols", "--protocol", nargs="+", default=list(DEFAULT_PROTOCOLS),
                    choices=PROTOCOLS, metavar="PROTOCOL",
                    help="all: train and test on 7 demos; split: train 1-4, test 5-7; ds-opt: "
                         "the published protocol of the LPV-DS authors (26 shapes, train 1-4, "
                         "test 5-7, every 2nd sample, their RMSE/e_dot/DTWD, printed beside the "
                         "published SEDS and LPV-DS figures) [all split]")
    la.add_argument("--components", "-K", type=components, default=None, metavar="K",
                    help="number of Gaussians; for ds-opt also 'bic' (ds-opt's choice by BIC on "
                         "[x; xdot], up to --k-max) or 'published' (the K of the published run "
                         "per shape) [5; ds-opt: bic]")
    la.add_argument("--k-max", type=_at_least(1), default=15, help="largest K of -K bic [15]")
    la.add_argument("--samples", type=_at_least(2), default=100,
                    help="samples kept per demonstration, at least 2 (1000 or more: all of "
                         "LASA's 1000) [100; ds-opt: every 2nd of 1000]")
    la.add_argument("--seed", type=int, default=0, help="random seed [0]")
    la.add_argument("--workers", type=int, default=1, help="local worker processes [1]")
    la.add_argument("--no-figures", action="store_true", help="skip the per-shape figures")
    la.add_argument("--quick", action="store_true",
                    help="a fast check: Angle, CShape and GShape, direction objective, "
                         "protocol all")
    la.add_argument("--out", default="lasa_out", help="output folder [lasa_out]")
    la.add_argument("--dask", default=None, metavar="ADDRESS",
                    help="run on a Dask scheduler (tcp://host:8786) instead of local workers")


def _add_table1(sub, quiet) -> None:
    from ..minigolf.table1 import PROTOCOLS, TABLE1_FIELDS

    t = sub.add_parser("table1", help="reproduce the paper's Table 1 on the simulated fields",
                       parents=[quiet],
                       description="Learn the hitting motion, let the teacher collect good "
                                   "shots on each field, and compare GPR and GMR for the "
                                   "hitting parameters as in the paper's Table 1.")
    t.add_argument("--field", nargs="+", default=list(TABLE1_FIELDS), metavar="FIELD",
                   help=_field_help("rough_flat double_hill arctan").replace(
                       "a field name", "field names").replace("a .json field file",
                                                              ".json field files"))
    t.add_argument("--repetitions", type=int, default=100, help="repetitions [100]")
    t.add_argument("--seed", type=int, default=0, help="random seed [0]")
    t.add_argument("--workers", type=int, default=1, help="local worker processes [1]")
    t.add_argument("--dask", default=None, metavar="ADDRESS",
                   help="run the repetitions on a Dask scheduler (tcp://host:8786)")
    t.add_argument("--demos", default=None,
                   help="demonstrations of the hitting motion (.npz/.csv) [shipped putts]")
    t.add_argument("--no-figures", action="store_true", help="skip Fig. 10 and 11")
    t.add_argument("--protocol", choices=PROTOCOLS, default="paper",
                   help="paper: Section 7.2.1 (noisy examples from the sinking set, random "
                        "points from the centred range); grid: the teacher's shots as they "
                        "are, random points over the whole range [paper]")
    t.add_argument("--quick", action="store_true",
                   help="3 repetitions and a coarser teacher: a check in about a minute")
    t.add_argument("--out", default="table1_out", help="output folder [table1_out]")


def _add_validate(sub, quiet) -> None:
    v = sub.add_parser("validate", help="check shots in an exudyn multibody model",
                       parents=[quiet],
                       description="Shots chosen by the learned hitting-parameter model and "
                                   "executed by the robot's controller, played on the fast ball "
                                   "model and in exudyn (ball on the field mesh with contact).")
    v.add_argument("--robot", default="wam", help=_robot_help())
    v.add_argument("--field", default="flat", help=_field_help("flat"))
    v.add_argument("--shots", type=int, default=10, help="number of shots [10]")
    v.add_argument("--seed", type=int, default=0, help="random seed [0]")
    v.add_argument("--workers", type=int, default=1,
                   help="local worker processes for the shots [1]")
    v.add_argument("--quick", action="store_true",
                   help="at most 3 shots and a coarser teacher: a check in about half a minute")
    v.add_argument("--out", default="validate_out", help="output folder [validate_out]")


def _add_play(sub, quiet) -> None:
    pl = sub.add_parser("play", help="the main job: learn the motion and the hitting parameters, "
                                     "then play a round", parents=[quiet],
                        description="Learn the hitting motion (SEDS), let the teacher collect "
                                    "good shots, learn the hitting parameters (GPR and GMR) and "
                                    "play a round of shots with the robot on the field's ball "
                                    "model, a few checked in exudyn.")
    pl.add_argument("--robot", default="wam", help=_robot_help())
    pl.add_argument("--field", default=None, help=_field_help("arctan"))
    pl.add_argument("--demos", default=None, help="hitting demonstrations (.npz/.csv) [shipped]")
    pl.add_argument("--learner", nargs="+", default=["gpr", "gmr"],
                    choices=["gpr", "gmr", "sep_gmr"], help="hitting-parameter learners [gpr gmr]")
    pl.add_argument("--shots", type=int, default=20, help="situations in the round [20]")
    pl.add_argument("--validate", type=int, default=2,
                    help="shots checked again in exudyn [2]")
    pl.add_argument("--seed", type=int, default=0, help="random seed [0]")
    pl.add_argument("--models", default=None,
                    help="reuse the models/ folder of an earlier run (skips learning)")
    pl.add_argument("--workers", type=int, default=1, help="local worker processes [1]")
    pl.add_argument("--dask", default=None, metavar="ADDRESS",
                    help="play the shots on a Dask scheduler (tcp://host:8786)")
    pl.add_argument("--strategies", default=None, metavar="auto|N",
                    help="several strategies (the paper's Section 8): explore every way to "
                         "sink the ball, keep those in half the situations (auto) or the N "
                         "most widespread, and play the one most likely to succeed [one "
                         "strategy, the teacher's]")
    pl.add_argument("--train-size", type=int, default=None, metavar="N",
                    help="train the learners on N equally spaced situations of the teacher's "
                         "data set (as Table 1's equally spaced rows) [all]")
    pl.add_argument("--replay", type=_at_least(1), nargs="?", const=1, default=0, metavar="N",
                    help="replay the first learner's first N shots (N >= 1; 1 when left out): "
                         "OUT/replay.html (a 3-D page that works offline) and a GIF per shot "
                         "[no replay]")
    pl.add_argument("--no-cache", action="store_true",
                    help="teach again even when the teacher's data set for this field and "
                         "motion is in the cache (~/.cache/seds_casadi/teacher)")
    pl.add_argument("--quick", action="store_true",
                    help="3 situations, a coarse teacher, 1 exudyn check (about 15 s after "
                         "the first run's compilation)")
    pl.add_argument("--world", default=None, metavar="WORLD",
                    help="play the shots on a world whose green differs from --field's (a "
                         "field name or .json file of the same course, or 'exudyn': the "
                         "multibody model); the robot is taught on --field only [the field]")
    pl.add_argument("--adapt", type=int, default=0, metavar="N",
                    help="adaptation shots on the world before the round: the robot estimates "
                         "the green from them and corrects its hitting parameters; the round "
                         "is played before and after the correction [0]")
    pl.add_argument("--out", default="play_out", help="output folder [play_out]")


def _cmd_fit(a) -> int:
    from ..core.demo_files import load_demonstrations
    from ..core.seds import SEDS
    from .plotting import plot_1d_reproductions, pyplot, save_figure

    kw = {"dt": a.dt} if a.dt is not None else {}
    demos = load_demonstrations(a.demonstrations, **kw)
    print(f"loaded {demos}")
    learner = SEDS(a.components, objective=a.objective, random_state=a.seed,
                   max_iter=a.max_iter, lyapunov=a.lyapunov, formulation=a.formulation,
                   gain_limit=a.gain_limit, init=a.init, gmm=a.gmm,
                   speed_calibration=a.speed)
    if a.choose:
        from ..core.search import DemoSearchCV

        grid = dict(a.choose)
        if len(grid) < len(a.choose):
            raise ValueError("--choose names a setting twice; give all its values in one: "
                             "--choose objective=mse,direction")
        search = DemoSearchCV(learner, grid, verbose=1).fit(demos)
        print(search.table())
        print(f"chosen: {search.best_params_}")
        model = search.model_
    else:
        model = learner.fit(demos).model_
    os.makedirs(a.out, exist_ok=True)
    path = os.path.join(a.out, "model.npz")
    model.save(path)
    starts = [p[0] for p in demos.positions]
    span = max(float(max(abs(p - demos.target).max() for p in demos.positions)), 1e-9)
    # the demonstrations' sampling step, or a smaller one the model's stiffest component allows
    # (rk4 is stable below about 2.8 / rate): the figure shows the model, not the integrator
    dt = demos.estimated_dt()
    rate = model.stiffness()
    if rate > 0:
        dt = min(dt, 1.0 / rate)
    repro = model.rollout(starts, dt=dt, tol=1e-3 * span, max_steps=200000)
    if demos.n_dims >= 2:
        from .plot_ds import plot_fit_views

        fig = plot_fit_views(model, demos, repro, title=f"{os.path.basename(a.demonstrations)}: "
                             f"SEDS ({model.fit_info['objective_name']}, "
                             f"K={model.n_components})")
    else:
        fig, ax = pyplot().subplots(figsize=(5.5, 5))
        plot_1d_reproductions(model, demos, repro, ax=ax,
                              title=f"SEDS ({model.fit_info['objective_name']}, "
                                    f"K={model.n_components})")
    save_figure(fig, os.path.join(a.out, "streamlines.png"))
    info = {k: model.fit_info[k] for k in ("status", "iterations", "objective", "seconds")}
    if "search" in model.fit_info:
        info["chosen"] = model.fit_info["search"]["best_params"]
    print(json.dumps(info, indent=1))
    from ..core.report import fit_report
    from .fit_report import plot_fit_report

    report = fit_report(model, demos)
    print(f"fit report (SEDS, {model.fit_info['objective_name']}, K={model.n_components}):")
    print(report)
    report.save(os.path.join(a.out, "report.json"))
    with open(os.path.join(a.out, "report.txt"), "w", encoding="utf-8") as fh:
        fh.write(str(report) + "\n")
    save_figure(plot_fit_report(report, demos, title=f"{os.path.basename(a.demonstrations)}: "
                                f"reproductions from each start, K={model.n_components}"),
                os.path.join(a.out, "report.png"))
    print(f"wrote {path}, {os.path.join(a.out, 'streamlines.png')}, report.txt, report.json "
          "and report.png")
    return 0


def _cmd_lasa(a) -> int:
    from ..core.settings import OBJECTIVES
    from .lasa import run_lasa, summary_table

    shapes, objectives, protocols = a.shapes, a.objectives, a.protocols
    dsopt_objectives = objectives
    if a.quick:
        shapes = shapes or ["Angle", "CShape", "GShape"]
        objectives, protocols = ["direction"], ["all"]
    elif objectives is None:  # the defaults: all three for all/split, mse for ds-opt
        objectives, dsopt_objectives = list(OBJECTIVES), ["mse"]
    results = run_lasa(shapes=shapes, objectives=objectives, protocols=protocols,
                       n_components=a.components, n_samples=a.samples, random_state=a.seed,
                       out_dir=a.out, figures=not a.no_figures, workers=a.workers,
                       dask=a.dask, dsopt_objectives=dsopt_objectives, k_max=a.k_max,
                       progress=not a.quiet)
    print(summary_table(results))
    names = (["lasa.csv"] if set(protocols) - {"ds-opt"} else []) + \
        (["lasa_dsopt.csv"] if "ds-opt" in protocols else []) + ["summary.txt"]
    print("wrote " + ", ".join(os.path.join(a.out, n) for n in names))
    return 0


def _cmd_table1(a) -> int:
    from .table1 import Table1Config, table1_command

    table1_command(Table1Config(fields=tuple(a.field), repetitions=a.repetitions, seed=a.seed,
                                out=a.out, workers=a.workers, dask=a.dask, quick=a.quick,
                                demos=a.demos, figures=not a.no_figures,
                                progress=not a.quiet, protocol=a.protocol))
    return 0


def _cmd_validate(a) -> int:
    from .validate import ValidateConfig, validate

    validate(ValidateConfig(robot=a.robot, field=a.field, shots=a.shots, out=a.out, seed=a.seed,
                            quick=a.quick, workers=a.workers, progress=not a.quiet))
    return 0


def _cmd_play(a) -> int:
    from .play import PlayConfig, play

    if a.world is not None and a.field is None:
        raise ValueError("--world needs --field: the field the robot is taught on (the world "
                         "is where its shots are played)")
    if a.adapt < 0:
        raise ValueError(f"--adapt must be a number of shots >= 0, got {a.adapt}")
    play(PlayConfig(robot=a.robot, field=a.field or "arctan", demos=a.demos,
                    learners=tuple(a.learner), world=a.world, adapt=a.adapt,
                    shots=a.shots, seed=a.seed, out=a.out, models=a.models, quick=a.quick,
                    validate_shots=a.validate, workers=a.workers, dask=a.dask,
                    train_size=a.train_size, strategies=a.strategies, replay=a.replay,
                    cache=not a.no_cache,
                    progress=not a.quiet))
    return 0


class _PlainHandler(logging.Handler):
    """Writes each record's message as ``print`` would: INFO and below to the current
    ``sys.stdout``, warnings and errors to ``sys.stderr``."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            stream = sys.stderr if record.levelno >= logging.WARNING else sys.stdout
            stream.write(self.format(record) + "\n")
            stream.flush()
        except Exception:  # noqa: BLE001 - logging's own convention
            self.handleError(record)


@contextlib.contextmanager
def command_logging(quiet: bool = False,
                    names: tuple[str, ...] = ("seds_casadi.app", "seds_casadi.progress")
                    ) -> Iterator[None]:
    """For the duration of a command: the named loggers (default the commands' own,
    ``seds_casadi.app.*``) print their messages plainly, progress (INFO) on stdout, or with
    ``quiet`` only warnings and errors (on stderr). Other loggers are left as they are (their
    warnings reach stderr through Python's default handler)."""
    handler = _PlainHandler()
    logs = [logging.getLogger(n) for n in names]
    saved = [(log.level, log.propagate) for log in logs]
    for log in logs:
        log.addHandler(handler)
        log.setLevel(logging.WARNING if quiet else logging.INFO)
        log.propagate = False
    try:
        yield
    finally:
        for log, (level, propagate) in zip(logs, saved):
            log.removeHandler(handler)
            log.setLevel(level)
            log.propagate = propagate


#: loggers whose progress a command shows: ``fit`` also shows the solver's progress lines and
#: the compiler's ("compiling ..."), which a first fit in a new dimension can take a while on
_COMMAND_LOGGERS = {"fit": ("seds_casadi.app", "seds_casadi.core", "seds_casadi.codegen")}
_DEFAULT_LOGGERS = ("seds_casadi.app", "seds_casadi.progress")


_COMMANDS = {"fit": _cmd_fit, "lasa": _cmd_lasa, "table1": _cmd_table1,
             "validate": _cmd_validate, "play": _cmd_play}


#: errors a user's input or environment can cause: an ``error:`` line and exit code 2
_USER_ERRORS: tuple[type[BaseException], ...] = (ValueError, TypeError, OSError, MemoryError,
                                                 RecursionError)


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``seds-casadi``; returns the exit code.

    A user's mistake (bad input, options, files, an unusable ``--out``) prints one line
    ``seds-casadi COMMAND: error: ...`` on stderr and returns 2; an interruption (Ctrl-C,
    SIGTERM) stops the workers, removes temporary files and returns 130; ``--debug`` (anywhere
    on the line) shows the traceback instead.
    """
    program = argv is None  # the process's own command line: it ends when main returns
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv
    argv = [x for x in argv if x != "--debug"]
    from ..codegen.functions import interrupt_within
    from ..core._signals import ignore_until_exit, interrupt_on_termination, restore_handlers
    from ..core.errors import ConvergenceWarning, SEDSError
    from .outdir import output_folder

    # first: building the parser imports the robots' layer (a second on one core), and an
    # interrupt there ends the command like one later
    previous = interrupt_on_termination()  # SIGTERM, SIGHUP: as Ctrl-C; the first one counts
    command = next((x for x in argv if x in _COMMANDS), "")
    try:
        parser = build_parser()
        parser.add_argument("--debug", action="store_true",
                            help="show the full traceback of an error instead of one line")
        a = parser.parse_args(argv)
        if a.command is None:
            parser.print_help()
            return 2
        if a.command not in _COMMANDS:
            parser.error(f"unknown command {a.command}")
        command = a.command
        warnings.simplefilter("always", ConvergenceWarning)
        with output_folder(a.out), command_logging(
                quiet=getattr(a, "quiet", False),
                names=_COMMAND_LOGGERS.get(a.command, _DEFAULT_LOGGERS)):
            return _COMMANDS[a.command](a)
    except (KeyboardInterrupt, SystemError) as exc:
        # a SystemError from CasADi's C code (SWIG) that an interrupt raised inside it caused
        if not isinstance(exc, KeyboardInterrupt) and interrupt_within(exc) is None:
            raise
        if debug:
            raise
        print(f"seds-casadi{' ' + command if command else ''}: interrupted; the files written "
              "so far are complete, the rest was not written", file=sys.stderr)
        return 130
    except RuntimeError as exc:  # CasADi's errors (a setting it refused, a failed call)
        if debug or not ("casadi" in str(exc).lower() or "ipopt" in str(exc).lower()):
            raise
        lines = [ln for ln in str(exc).splitlines() if ln.strip()]
        print(f"seds-casadi {command}: error: CasADi/IPOPT failed: "
              f"{lines[-1].split(': ', 1)[-1].strip() if lines else type(exc).__name__} "
              "(--debug shows the traceback)", file=sys.stderr)
        return 2
    except (*_USER_ERRORS, SEDSError) as exc:
        if debug:
            raise
        text = str(exc) or type(exc).__name__
        if isinstance(exc, OSError) and exc.filename and str(exc.filename) not in text:
            text = f"{exc.filename}: {text}"
        print(f"seds-casadi {command}: error: {text}", file=sys.stderr)
        return 2
    finally:
        if program:  # the process ends: a signal now (a SIGTERM after Ctrl-C, a Ctrl-C just
            # as the results were written) would kill it while the interpreter shuts down
            # (default handlers) or be dropped by a finaliser; its exit code says what it did
            ignore_until_exit()
        else:
            restore_handlers(previous)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
