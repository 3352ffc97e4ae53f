"""The LASA handwriting benchmark: fit every shape, reproduce, and score.

Protocols
---------
``all``: train on all 7 demonstrations, evaluate on the same 7.
``split``: train on demonstrations 1-4, evaluate on 5-7 (held out).

Per (shape, objective, protocol) it reports the velocity RMSE and the direction error e_dot of the
model at the evaluation demonstrations' points, the DTW distance (mean over evaluation
demonstrations) of reproductions integrated from each demonstration's start (RK4, with the
demonstrations' own time step, until ||x - x*|| < 1 mm or 20x the demonstration's length), the fit
time and IPOPT's iterations. Units are LASA's: mm and mm/s.
"""

from __future__ import annotations

import os
import time
import warnings
from concurrent.futures import Executor
from dataclasses import asdict, dataclass

import numpy as np

from ..core._io import atomic_csv, atomic_text
from ..core.datasets import LASA_SHAPES, load_lasa
from ..core.errors import ConvergenceWarning
from ..core.metrics import direction_error, dtw_distance, velocity_rmse
from ..core.parametrization import OBJECTIVES
from ..core.seds import SEDS

__all__ = ["LasaResult", "evaluate_shape", "run_lasa", "write_csv", "summary_table", "PROTOCOLS"]

PROTOCOLS = ("all", "split")
_CONVERGED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
CSV_COLUMNS = ("shape", "objective", "protocol", "rmse", "e_dot", "dtwd", "seconds", "iterations")


@dataclass
class LasaResult:
    """One row of the LASA benchmark (see module docstring for the definitions)."""

    shape: str
    objective: str
    protocol: str
    rmse: float
    e_dot: float
    dtwd: float
    seconds: float
    iterations: int
    status: str = ""


def _validate(shapes, objectives, protocols):
    for s in shapes:
        if s not in LASA_SHAPES:
            raise ValueError(f"unknown LASA shape {s!r}; valid: {', '.join(LASA_SHAPES)}")
    for o in objectives:
        if o not in OBJECTIVES:
            raise ValueError(f"unknown objective {o!r}; valid: {', '.join(OBJECTIVES)}")
    for p in protocols:
        if p not in PROTOCOLS:
            raise ValueError(f"unknown protocol {p!r}; valid: {', '.join(PROTOCOLS)}")


def evaluate_shape(shape: str, objective: str = "direction", protocol: str = "all",
                   n_components: int = 5, n_samples: int = 100, random_state: int = 0,
                   figure_path: str | None = None) -> LasaResult:
    """Fit one LASA shape with one objective under one protocol and score it.

    Parameters
    ----------
    shape : str
        A LASA shape name.
    objective : {"direction", "mse", "likelihood"}
    protocol : {"all", "split"}
    n_components : int
    n_samples : int
        Samples kept per demonstration (evenly spaced).
    random_state : int
    figure_path : str, optional
        Write a figure (demonstrations, reproductions, streamlines) there.
    """
    _validate([shape], [objective], [protocol])
    demos = load_lasa(shape, n_samples=n_samples)
    if protocol == "all":
        train, test = demos, demos
    else:
        train, test = demos.select([0, 1, 2, 3]), demos.select([4, 5, 6])
    t0 = time.perf_counter()
    with warnings.catch_warnings():  # the status is recorded and counted in the summary
        warnings.simplefilter("ignore", ConvergenceWarning)
        model = SEDS(n_components, objective=objective, random_state=random_state).fit(train).model_
    seconds = time.perf_counter() - t0
    X = np.concatenate(test.positions)
    V = np.concatenate(test.velocities)
    F = model.predict(X)
    raw_dt = test.estimated_dt()
    starts = np.stack([p[0] for p in test.positions])
    max_len = 20 * max(len(p) for p in test.positions)
    repro = model.rollout(starts, dt=raw_dt, max_steps=max_len, tol=1.0)
    dtw = [dtw_distance(r, p) for r, p in zip(repro, test.positions)]
    if figure_path:
        from .plotting import _plt, plot_streamlines, save_figure

        fig, ax = _plt().subplots(figsize=(5, 4.5))
        plot_streamlines(model, test, repro, ax=ax,
                         title=f"{shape} · {objective} · {protocol} · K={n_components}")
        save_figure(fig, figure_path)
    return LasaResult(shape, objective, protocol, velocity_rmse(F, V), direction_error(F, V),
                      float(np.mean(dtw)), seconds, int(model.fit_info["iterations"]),
                      str(model.fit_info["status"]))


def _task(args) -> LasaResult:
    return evaluate_shape(**args)


def run_lasa(shapes=None, objectives=("direction",), protocols=PROTOCOLS, n_components: int = 5,
             n_samples: int = 100, random_state: int = 0, out_dir: str | None = None,
             figures: bool = True, workers: int = 1, executor: Executor | None = None,
             progress: bool = True, dask: str | None = None) -> list[LasaResult]:
    """Run the LASA benchmark over shapes x objectives x protocols.

    Parameters
    ----------
    shapes : list of str, optional
        Default: all 30 shapes.
    objectives, protocols : sequences of names
    n_components, n_samples, random_state : see :func:`evaluate_shape`
    out_dir : str, optional
        Folder for ``lasa.csv``, ``summary.txt`` and ``figures/`` (one figure per shape and
        objective, drawn for the ``all`` protocol, or ``split`` if that is the only one).
    workers : int
        Local processes when no ``executor`` is given (1: run in this process).
    executor : concurrent.futures.Executor, optional
        Any executor (e.g. a Dask ``distributed.Client().get_executor()``).
    progress : bool
        Show a progress bar.
    dask : str, optional
        Address of a Dask scheduler to run the fits on (see
        :func:`seds_casadi.app.executors.open_executor`).
        Show a progress bar.

    Returns
    -------
    list of LasaResult
    """
    shapes = list(LASA_SHAPES if shapes is None else shapes)
    objectives, protocols = list(objectives), list(protocols)
    _validate(shapes, objectives, protocols)
    if int(workers) < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    fig_dir = None
    if out_dir is not None:
        os.makedirs(out_dir, exist_ok=True)
        if figures:
            fig_dir = os.path.join(out_dir, "figures")
            os.makedirs(fig_dir, exist_ok=True)
    fig_protocol = "all" if "all" in protocols else protocols[0]
    tasks = []
    for s in shapes:
        for o in objectives:
            for p in protocols:
                fp = None
                if fig_dir and p == fig_protocol:
                    fp = os.path.join(fig_dir, f"{s}_{o}.png")
                tasks.append(dict(shape=s, objective=o, protocol=p, n_components=n_components,
                                  n_samples=n_samples, random_state=random_state,
                                  figure_path=fp))
    from tqdm.auto import tqdm

    bar = tqdm(total=len(tasks), desc="LASA fits", unit="fit", disable=not progress)
    results: list[LasaResult] = []
    from .executors import open_executor

    try:
        if executor is not None:
            for r in executor.map(_task, tasks):
                results.append(r)
                bar.update(1)
        else:
            with open_executor(workers, dask) as ex:
                for r in ex.map(_task, tasks):
                    results.append(r)
                    bar.update(1)
    finally:
        bar.close()
    if out_dir is not None:
        write_csv(results, os.path.join(out_dir, "lasa.csv"))
        atomic_text(os.path.join(out_dir, "summary.txt"), summary_table(results))
    return results


def write_csv(results: list[LasaResult], path: str) -> None:
    """Write results with the columns ``shape, objective, protocol, rmse, e_dot, dtwd, seconds,
    iterations`` (atomically: a partial file is never left under the final name)."""
    atomic_csv(path, CSV_COLUMNS, ([asdict(r)[c] for c in CSV_COLUMNS] for r in results))


def summary_table(results: list[LasaResult]) -> str:
    """Text table: per objective and protocol, mean/median of the metrics over shapes, and how
    many fits stopped without converging (IPOPT's iteration limit; still certified stable)."""
    lines = [f"{'objective':<11} {'protocol':<8} {'shapes':>6} {'rmse':>9} {'e_dot':>7} "
             f"{'dtwd':>10} {'median s':>9} {'mean iter':>9} {'unconverged':>11}"]
    keys = sorted({(r.objective, r.protocol) for r in results})
    for o, p in keys:
        rs = [r for r in results if r.objective == o and r.protocol == p]
        lines.append(
            f"{o:<11} {p:<8} {len(rs):>6} {np.mean([r.rmse for r in rs]):>9.3f} "
            f"{np.mean([r.e_dot for r in rs]):>7.4f} {np.mean([r.dtwd for r in rs]):>10.1f} "
            f"{np.median([r.seconds for r in rs]):>9.2f} "
            f"{np.mean([r.iterations for r in rs]):>9.1f} "
            f"{sum(r.status not in _CONVERGED for r in rs):>11d}")
    return "\n".join(lines) + "\n"
