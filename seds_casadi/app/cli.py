"""Command line: ``seds-casadi <command>`` (also ``python -m seds_casadi``).

Commands
--------
fit     fit a stable DS to demonstrations in a .npz/.csv file; write the model and a figure
lasa    run the LASA handwriting benchmark; write lasa.csv, summary.txt and figures
table1  the paper's Table 1 (GPR vs GMR for the hitting parameters); write table1.csv, figures
validate shots by a robot checked in exudyn against the fast ball model; validation.csv, report
play    the main job: learn, teach, play a round with the robot, check a few shots in exudyn
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import warnings

__all__ = ["main", "build_parser"]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``seds-casadi``."""
    from ..core.datasets import LASA_SHAPES
    from ..core.parametrization import OBJECTIVES
    from .lasa import PROTOCOLS

    p = argparse.ArgumentParser(
        prog="seds-casadi",
        description="Learn stable dynamical systems (SEDS in CasADi/IPOPT) and play minigolf.",
    )
    sub = p.add_subparsers(dest="command", metavar="COMMAND")

    f = sub.add_parser("fit", help="fit a stable DS to demonstrations from a .npz or .csv file",
                       description="Fit SEDS to demonstrations (formats: see "
                                   "seds_casadi.demonstrations) and write model.npz and "
                                   "streamlines.png to --out.")
    f.add_argument("demonstrations", help="path to a .npz or .csv demonstrations file")
    f.add_argument("--components", "-K", type=int, default=5, help="number of Gaussians [5]")
    f.add_argument("--objective", choices=OBJECTIVES, default="direction",
                   help="objective [direction]")
    f.add_argument("--dt", type=float, default=None,
                   help="time step [s] if the file has neither velocities nor time stamps")
    f.add_argument("--seed", type=int, default=0, help="random seed of the initialisation [0]")
    f.add_argument("--max-iter", type=int, default=1000, help="IPOPT iteration limit [1000]")
    f.add_argument("--out", default="seds_out", help="output folder [seds_out]")

    la = sub.add_parser("lasa", help="run the LASA handwriting benchmark",
                        description="Fit LASA shapes, score reproductions (RMSE, e_dot, DTW) "
                                    "and write lasa.csv, summary.txt and figures to --out.")
    la.add_argument("--shapes", nargs="+", default=None, metavar="SHAPE",
                    help=f"shapes to run [all 30]; valid: {', '.join(LASA_SHAPES)}")
    la.add_argument("--objectives", nargs="+", default=list(OBJECTIVES), choices=OBJECTIVES,
                    help="objectives to compare [all three]")
    la.add_argument("--protocols", nargs="+", default=list(PROTOCOLS), choices=PROTOCOLS,
                    help="all: train and test on 7 demos; split: train 1-4, test 5-7 [both]")
    la.add_argument("--components", "-K", type=int, default=5, help="number of Gaussians [5]")
    la.add_argument("--samples", type=int, default=100,
                    help="samples kept per demonstration [100]")
    la.add_argument("--seed", type=int, default=0, help="random seed [0]")
    la.add_argument("--workers", type=int, default=1, help="local worker processes [1]")
    la.add_argument("--no-figures", action="store_true", help="skip the per-shape figures")
    la.add_argument("--quick", action="store_true",
                    help="a fast check: Angle, CShape and GShape, direction objective, "
                         "protocol all")
    la.add_argument("--out", default="lasa_out", help="output folder [lasa_out]")
    la.add_argument("--dask", default=None, metavar="ADDRESS",
                    help="run on a Dask scheduler (tcp://host:8786) instead of local workers")

    from ..minigolf.table1 import TABLE1_FIELDS

    t = sub.add_parser("table1", help="reproduce the paper's Table 1 on the simulated fields",
                       description="Learn the hitting motion, let the teacher collect good "
                                   "shots on each field, and compare GPR and GMR for the "
                                   "hitting parameters as in the paper's Table 1.")
    t.add_argument("--field", nargs="+", default=list(TABLE1_FIELDS), metavar="FIELD",
                   help="field names or .json field files [rough_flat double_hill arctan]")
    t.add_argument("--repetitions", type=int, default=100, help="repetitions [100]")
    t.add_argument("--seed", type=int, default=0, help="random seed [0]")
    t.add_argument("--workers", type=int, default=1, help="local worker processes [1]")
    t.add_argument("--dask", default=None, metavar="ADDRESS",
                   help="run the repetitions on a Dask scheduler (tcp://host:8786)")
    t.add_argument("--demos", default=None,
                   help="demonstrations of the hitting motion (.npz/.csv) [shipped putts]")
    t.add_argument("--no-figures", action="store_true", help="skip Fig. 10 and 11")
    t.add_argument("--quick", action="store_true",
                   help="3 repetitions and a coarser teacher: a check in about a minute")
    t.add_argument("--out", default="table1_out", help="output folder [table1_out]")

    v = sub.add_parser("validate", help="check shots in an exudyn multibody model",
                       description="Shots chosen by the learned hitting-parameter model and "
                                   "executed by the robot's controller, played on the fast ball "
                                   "model and in exudyn (ball on the field mesh with contact).")
    v.add_argument("--robot", default="wam", help="robot name [wam]")
    v.add_argument("--field", default="flat", help="field name or .json file [flat]")
    v.add_argument("--shots", type=int, default=10, help="number of shots [10]")
    v.add_argument("--seed", type=int, default=0, help="random seed [0]")
    v.add_argument("--out", default="validate_out", help="output folder [validate_out]")

    pl = sub.add_parser("play", help="the main job: learn the motion and the hitting parameters, "
                                     "then play a round",
                        description="Learn the hitting motion (SEDS), let the teacher collect "
                                    "good shots, learn the hitting parameters (GPR and GMR) and "
                                    "play a round of shots with the robot on the field's ball "
                                    "model, a few checked in exudyn.")
    pl.add_argument("--robot", default="wam", help="robot name or .urdf [wam]")
    pl.add_argument("--field", default="arctan", help="field name or .json file [arctan]")
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
    pl.add_argument("--quick", action="store_true",
                    help="3 situations, a coarse teacher, 1 exudyn check: under a minute")
    pl.add_argument("--out", default="play_out", help="output folder [play_out]")
    return p


def _cmd_fit(a) -> int:
    from ..core.demonstrations import load_demonstrations
    from ..core.seds import SEDS
    from .plotting import _plt, plot_streamlines, save_figure

    kw = {"dt": a.dt} if a.dt is not None else {}
    demos = load_demonstrations(a.demonstrations, **kw)
    print(f"loaded {demos}")
    model = SEDS(a.components, objective=a.objective, random_state=a.seed,
                 max_iter=a.max_iter).fit(demos).model_
    os.makedirs(a.out, exist_ok=True)
    path = os.path.join(a.out, "model.npz")
    model.save(path)
    starts = [p[0] for p in demos.positions]
    span = max(float(max(abs(p - demos.target).max() for p in demos.positions)), 1e-9)
    repro = model.rollout(starts, dt=demos.estimated_dt(), tol=1e-3 * span, max_steps=20000)
    fig, ax = _plt().subplots(figsize=(5.5, 5))
    plot_streamlines(model, demos, repro, ax=ax,
                     title=f"SEDS ({a.objective}, K={a.components})")
    save_figure(fig, os.path.join(a.out, "streamlines.png"))
    info = {k: model.fit_info[k] for k in ("status", "iterations", "objective", "seconds")}
    print(json.dumps(info, indent=1))
    print(f"wrote {path} and {os.path.join(a.out, 'streamlines.png')}")
    return 0


def _cmd_lasa(a) -> int:
    from .lasa import run_lasa, summary_table

    shapes, objectives, protocols = a.shapes, a.objectives, a.protocols
    if a.quick:
        shapes = shapes or ["Angle", "CShape", "GShape"]
        objectives, protocols = ["direction"], ["all"]
    results = run_lasa(shapes=shapes, objectives=objectives, protocols=protocols,
                       n_components=a.components, n_samples=a.samples, random_state=a.seed,
                       out_dir=a.out, figures=not a.no_figures, workers=a.workers,
                       dask=a.dask)
    print(summary_table(results))
    print(f"wrote {os.path.join(a.out, 'lasa.csv')} and {os.path.join(a.out, 'summary.txt')}")
    return 0


def _cmd_table1(a) -> int:
    from .table1 import table1_command

    table1_command(a.field, a.repetitions, a.seed, a.out, a.workers, a.dask, a.quick, a.demos,
                   not a.no_figures, progress=sys.stderr.isatty())
    return 0


def _cmd_validate(a) -> int:
    from .validate import validate

    validate(a.robot, a.field, a.shots, a.out, a.seed, progress=sys.stderr.isatty())
    return 0


def _cmd_play(a) -> int:
    from .play import play

    play(a.robot, a.field, a.demos, a.learner, a.shots, a.seed, a.out, a.models, a.quick,
         a.validate, a.workers, a.dask, progress=sys.stderr.isatty())
    return 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``seds-casadi``; returns the exit code."""
    parser = build_parser()
    a = parser.parse_args(argv)
    if a.command is None:
        parser.print_help()
        return 2
    from ..core.errors import ConvergenceWarning, SEDSError

    warnings.simplefilter("always", ConvergenceWarning)
    try:
        if a.command == "fit":
            return _cmd_fit(a)
        if a.command == "lasa":
            return _cmd_lasa(a)
        if a.command == "table1":
            return _cmd_table1(a)
        if a.command == "validate":
            return _cmd_validate(a)
        if a.command == "play":
            return _cmd_play(a)
    except (ValueError, TypeError, FileNotFoundError, SEDSError) as exc:
        print(f"seds-casadi {a.command}: error: {exc}", file=sys.stderr)
        return 2
    parser.error(f"unknown command {a.command}")
    return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
