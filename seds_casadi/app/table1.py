"""``seds-casadi table1``: the protocol of :mod:`seds_casadi.minigolf.table1` run end to end,
with Fig. 10 and 11."""

from __future__ import annotations

import os

import numpy as np

from ..core._io import atomic_text
from ..minigolf.parameters import make_model
from ..minigolf.table1 import (
    TABLE1_FIELDS,
    Table1Row,
    format_table1,
    run_table1,
    write_table1_csv,
)
from ..minigolf.teacher import HittingDataset

__all__ = ["table1_command", "fig10", "fig11"]


def fig10(field_name: str, ds: HittingDataset, n_train: int = 8, ax_row=None):
    """Fig. 10: GPR and GMR fitted on the points around the centre of a 1-D data set."""
    n = len(ds)
    lo = max(0, (n - n_train) // 2)
    train = np.arange(lo, min(n, lo + n_train))
    S, Y = ds.situations, ds.outputs
    models = {f"GPR ({field_name})": make_model("gpr").fit(S[train], Y[train]),
              f"GMR, K=2 ({field_name})": make_model("gmr", n_components=2).fit(S[train],
                                                                                Y[train])}
    from .plotting import plot_regression_1d

    return plot_regression_1d(S, Y[:, 0], train, models, ax_row=ax_row,
                              xlabel="hole sideways from the ball, s_y [m]")


def fig11(ds: HittingDataset, n_components: int = 3, ax_row=None):
    """Fig. 11: the joint GMM (K=3) of an arctan data set, outputs and correlations."""
    from .plotting import plot_joint_gmm

    m = make_model("gmr", n_components=n_components).fit(ds.situations, ds.outputs)
    return plot_joint_gmm(m, ds.outputs, ax_row=ax_row)


def table1_command(fields=TABLE1_FIELDS, repetitions: int = 100, seed: int = 0,
                   out: str = "table1_out", workers: int = 1, dask: str | None = None,
                   quick: bool = False, demos: str | None = None, figures: bool = True,
                   progress: bool = True) -> list[Table1Row]:
    """``seds-casadi table1``: learn the hitting motion, collect the teacher's data sets, run
    the protocol, print the table beside the paper's and write ``table1.csv``, the data sets,
    and Fig. 10 and 11 into ``out``.

    ``quick``: 3 repetitions and a coarser teacher search (a check that runs in about a
    minute, not the paper's numbers).
    """
    import time

    from ..core.demonstrations import load_demonstrations
    from ..minigolf.fields import load_field
    from ..minigolf.teacher import Stroke, collect_dataset
    from ..motion.hitting import HittingMotion
    from ..motion.putting_demos import load_hitting_demos
    from .executors import open_executor
    from .plotting import _plt, save_figure

    if quick:
        repetitions = min(int(repetitions), 3)
    fields = list(fields)
    loaded = [load_field(f) for f in fields]  # bad names fail before any work
    os.makedirs(os.path.join(out, "datasets"), exist_ok=True)
    t0 = time.perf_counter()
    d = load_demonstrations(demos) if demos else load_hitting_demos()
    motion = HittingMotion.fit(d, n_components=3)
    stroke = Stroke.from_motion(motion)
    print(f"hitting motion: v* = {stroke.speed:.3f} m/s, psi* = "
          f"{np.array2string(stroke.direction, precision=3)} "
          f"({time.perf_counter() - t0:.1f} s)", flush=True)
    teacher_kw = {"resolution": (81, 26)} if quick else {}
    datasets = {}
    for f in loaded:
        t1 = time.perf_counter()
        ds = collect_dataset(f, stroke, progress=progress, **teacher_kw)
        ds.save(os.path.join(out, "datasets", f"{f.name}.npz"))
        fixed = f", kappa {ds.kappa[0]:.3f}" if ds.strategy == "fixed_speed" else ""
        print(f"teacher on {f.name}: {len(ds)} good shots ({ds.strategy}{fixed}; "
              f"{ds.dropped} situations without one; {time.perf_counter() - t1:.1f} s)",
              flush=True)
        datasets[f.name] = (f, ds)
    t2 = time.perf_counter()
    with open_executor(workers, dask) as ex:
        means, runs = run_table1(datasets, repetitions, seed, ex, progress)
    text = format_table1(means)
    print(text)
    print(f"{repetitions} repetitions in {time.perf_counter() - t2:.1f} s")
    write_table1_csv(means, os.path.join(out, "table1.csv"))
    write_table1_csv(runs, os.path.join(out, "table1_repetitions.csv"))
    atomic_text(os.path.join(out, "table1.txt"), text)
    if figures:
        plt = _plt()
        one = [(n, ds) for n, (_, ds) in datasets.items() if ds.strategy == "fixed_speed"]
        two = [ds for _, ds in datasets.values() if ds.strategy == "minimal_speed"]
        if one:
            name, ds = next(((n, d) for n, d in one if n == "double_hill"), one[0])
            fig, axs = plt.subplots(1, 2, figsize=(10, 3.6), sharey=True)
            fig10(name, ds, ax_row=axs)
            save_figure(fig, os.path.join(out, "fig10_gpr_gmr.png"))
        if two:
            fig = plt.figure(figsize=(10.6, 3.8))
            axs = [fig.add_subplot(1, 4, i + 1) for i in range(4)]
            fig11(two[0], ax_row=axs)
            save_figure(fig, os.path.join(out, "fig11_joint_gmm.png"))
    print(f"wrote {os.path.join(out, 'table1.csv')} and figures in {out}")
    return means
