"""``seds-casadi table1``: a protocol of :mod:`seds_casadi.minigolf.table1` (the paper's by
default) run end to end, with Fig. 10 and 11.

Settings are a :class:`Table1Config`; progress and the table go to the ``logging`` logger of
this module (the command line prints them).
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass, replace

import numpy as np

from ..core._io import atomic_text
from ..minigolf.hitting_data import HittingDataset
from ..minigolf.parameters import make_model
from ..minigolf.sinking import SinkingSet
from ..minigolf.table1 import (
    CENTRE_FRACTION,
    GPR_PRIOR_MEAN,
    PROTOCOLS,
    TABLE1_FIELDS,
    Table1Row,
    format_table1,
    run_table1,
    simulated_field,
    training_indices,
    write_table1_csv,
)
from ._config import names_tuple, whole_number, with_overrides
from .outdir import path_under

__all__ = ["table1_command", "Table1Config", "fig10", "fig11"]

_LOG = logging.getLogger(__name__)


@dataclass(frozen=True)
class Table1Config:
    """Settings of :func:`table1_command` (the options of ``seds-casadi table1``).

    Attributes
    ----------
    fields : tuple of str
        Field names or ``.json`` field files.
    repetitions : int
        Repetitions of the protocol (at least 1).
    seed : int
    out : str
        Output folder.
    workers : int
        Local worker processes for the repetitions.
    dask : str or None
        Address of a Dask scheduler (overrides ``workers``).
    quick : bool
        At most 3 repetitions and a coarser teacher search: a check in about a minute, not the
        paper's numbers.
    demos : str or None
        Hitting demonstrations (``.npz``/``.csv``); None: the shipped putts.
    figures : bool
        Write Fig. 10 and 11.
    progress : bool
        Progress bars (on stderr, only on a terminal).
    protocol : {"paper", "grid"}
        The protocol of :func:`~seds_casadi.minigolf.table1.run_table1`: the paper's (noisy
        examples from the sinking set, random points from the centred range) or the grid
        protocol this package ran before.
    simulated_fields : bool
        ``"paper"``: teach and play each field as the paper's simulator modelled it
        (:func:`~seds_casadi.minigolf.table1.simulated_field`: a rough surface without the
        grass's structure, Section 7.2.2); False: the field files as they are. ``"grid"``
        always uses the files as they are.
    """

    fields: tuple[str, ...] = TABLE1_FIELDS
    repetitions: int = 100
    seed: int = 0
    out: str = "table1_out"
    workers: int = 1
    dask: str | None = None
    quick: bool = False
    demos: str | None = None
    figures: bool = True
    progress: bool = True
    protocol: str = "paper"
    simulated_fields: bool = True

    def __post_init__(self) -> None:
        if self.protocol not in PROTOCOLS:
            raise ValueError(f"unknown protocol {self.protocol!r}; valid: "
                             f"{', '.join(PROTOCOLS)}")
        object.__setattr__(self, "fields", names_tuple("field", self.fields))
        object.__setattr__(self, "repetitions",
                           whole_number("repetitions", self.repetitions, 1))
        object.__setattr__(self, "workers", whole_number("workers", self.workers, 1))
        object.__setattr__(self, "seed", whole_number("seed", self.seed, 0))
        if not isinstance(self.simulated_fields, bool):
            raise TypeError(f"simulated_fields must be True or False, got "
                            f"{self.simulated_fields!r}")

    def effective(self) -> Table1Config:
        """The settings actually run: ``quick`` caps the repetitions at 3."""
        return replace(self, repetitions=min(self.repetitions, 3)) if self.quick else self


def fig10(field_name: str, ds: HittingDataset, n_train: int = 10, ax_row=None,
          sinking: SinkingSet | None = None, seed: int = 0,
          centre_fraction: float = CENTRE_FRACTION, prior_mean: str | None = None):
    """Fig. 10: GPR and GMR (K = 2) with their two-standard-deviation bands, fitted on
    ``n_train`` points drawn at random from the centred range of a data set along one input
    dimension (the hole along a slider; black crosses), the rest in red, over the input that
    varies.

    With ``sinking`` the examples are one draw from the sinking set (Eq. 15, the ``"paper"``
    protocol of :mod:`seds_casadi.minigolf.table1`), else the teacher's shots as they are.
    GPR's prior mean (``prior_mean``) defaults to the protocol's
    (:data:`~seds_casadi.minigolf.table1.GPR_PRIOR_MEAN`: zero with ``sinking``, Eq. 17a).
    """
    S, Y = ds.situations, ds.outputs
    rng = np.random.default_rng(seed)
    if sinking is not None:
        Y = sinking.draw(rng)[:, :Y.shape[1]]
    column = int(np.argmax(np.ptp(S, axis=0)))
    train = training_indices(S, n_train, "centred", rng, centre_fraction)
    if prior_mean is None:
        prior_mean = GPR_PRIOR_MEAN["paper" if sinking is not None else "grid"]
    models = {f"GPR ({field_name})": make_model("gpr", prior_mean=prior_mean).fit(S[train],
                                                                                  Y[train]),
              f"GMR, K=2 ({field_name})": make_model("gmr", n_components=2).fit(S[train],
                                                                                Y[train])}
    from .plotting import plot_regression_1d

    name = "sideways" if column == 1 else "ahead"
    lo, hi = float(S[:, column].min()), float(S[:, column].max())
    # the input range (where the test situations lie) and a tenth beyond it on each side
    query = np.linspace(lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo), 300)
    return plot_regression_1d(S, Y[:, 0], train, models, ax_row=ax_row, column=column,
                              xlabel=f"hole {name} of the ball, s_{'xy'[column]} [m]",
                              x_query=query)


def fig11(ds: HittingDataset, n_components: int = 3, ax_row=None,
          sinking: SinkingSet | None = None, seed: int = 0):
    """Fig. 11: the joint GMM (K=3) of an arctan data set, outputs and correlations (with
    ``sinking``: fitted on one draw of the noisy examples, Eq. 15)."""
    from .plotting import plot_joint_gmm

    Y = ds.outputs if sinking is None else sinking.draw(np.random.default_rng(seed))
    m = make_model("gmr", n_components=n_components).fit(ds.situations, Y)
    label = "teacher's shots" if sinking is None else "examples (Eq. 15)"
    return plot_joint_gmm(m, Y, ax_row=ax_row, label=label)


def _stroke(cfg: Table1Config):
    """The hitting motion's default hit, learned from the demonstrations."""
    from ..core.demo_files import load_demonstrations
    from ..minigolf.stroke import Stroke
    from ..motion.hitting import HittingMotionLearner
    from ..motion.putting_demos import load_hitting_demos

    t0 = time.perf_counter()
    d = load_demonstrations(cfg.demos) if cfg.demos else load_hitting_demos()
    motion = HittingMotionLearner(n_components=3).fit(d).motion_
    stroke = Stroke.from_motion(motion)
    _LOG.info("hitting motion: v* = %.3f m/s, psi* = %s (%.1f s)", stroke.speed,
              np.array2string(stroke.direction, precision=3), time.perf_counter() - t0)
    return stroke


def _teach(cfg: Table1Config, fields: list, stroke) -> dict:
    """The teacher's data set for each field, saved in ``out/datasets``."""
    from ..minigolf.teacher import collect_dataset

    teacher_kw = {"resolution": (81, 26)} if cfg.quick else {}
    datasets = {}
    for f in fields:
        t1 = time.perf_counter()
        _LOG.info("situations on %s: %s", f.name, f.situations.describe())
        ds = collect_dataset(f, stroke, progress=cfg.progress, **teacher_kw)
        ds.save(path_under(cfg.out, "datasets", f"{f.name}.npz"))
        fixed = f", kappa {ds.kappa[0]:.3f}" if ds.strategy == "fixed_speed" else ""
        _LOG.info("teacher on %s: %d good shots (%s%s; %d situations without one; %.1f s)",
                  f.name, len(ds), ds.strategy, fixed, ds.dropped, time.perf_counter() - t1)
        datasets[f.name] = (f, ds)
    return datasets


def _sinking_sets(datasets: dict, quick: bool = False) -> dict:
    """The sinking set of each field's data set (the ``"paper"`` protocol's noise; ``quick``:
    3 gains and a 0.05 deg scan instead of 5 and 0.02 deg)."""
    from ..minigolf.sinking import sinking_set
    from ..minigolf.teacher import Teacher

    scan = {"n_gains": 3, "step_deg": 0.05} if quick else {}
    out = {}
    for name, (f, ds) in datasets.items():
        t0 = time.perf_counter()
        out[name] = sinking_set(Teacher(f, ds.stroke, ds.strategy), ds, **scan)
        w = out[name].widths
        _LOG.info("sinking set on %s: angle intervals %.2f deg wide (median; %.2f-%.2f; "
                  "%.1f s)", name, float(np.nanmedian(w)), float(np.nanmin(w)),
                  float(np.nanmax(w)), time.perf_counter() - t0)
    return out


def _figures(datasets: dict, out: str, sinking: dict | None = None, seed: int = 0) -> None:
    """Fig. 10 on a one-output data set along a slider (the double hill's if there), Fig. 11
    on a two-output one; with ``sinking`` (field name -> sinking set) on noisy examples."""
    from .plotting import pyplot, save_figure

    plt = pyplot()
    one = [(n, ds) for n, (f, ds) in datasets.items()
           if ds.outputs.shape[1] == 1 and f.situations.dim == 1]
    two = [(n, ds) for n, (_, ds) in datasets.items() if ds.outputs.shape[1] == 2]
    sinking = sinking or {}
    if one:
        name, ds = next(((n, d) for n, d in one if n == "double_hill"), one[0])
        fig, axs = plt.subplots(1, 2, figsize=(10, 3.8), sharey=True)
        fig10(name, ds, ax_row=axs, sinking=sinking.get(name), seed=seed)
        what = ("noisy examples from the sinking set" if name in sinking
                else "the teacher's shots")
        fig.suptitle(f"Fig. 10: {name}, the hitting angle by GPR and GMR from 10 random "
                     f"training points of the centred range ({what})", fontsize=10)
        fig.tight_layout()
        save_figure(fig, os.path.join(out, "fig10_gpr_gmr.png"))
    if two:
        fig = plt.figure(figsize=(13, 4.0))
        grid = fig.add_gridspec(1, 4, width_ratios=[1.4, 1, 1, 1], wspace=0.35)
        axs = [fig.add_subplot(grid[0, i]) for i in range(4)]
        name, ds = two[0]
        fig11(ds, ax_row=axs, sinking=sinking.get(name), seed=seed)
        fig.suptitle(f"Fig. 11: {ds.field}, the joint GMM (K = 3) of the situation s and "
                     f"the hitting parameters (alpha [deg], kappa)", fontsize=10)
        save_figure(fig, os.path.join(out, "fig11_joint_gmm.png"))


def _played(cfg: Table1Config, fields: list) -> list:
    """The fields the protocol teaches and plays on: under ``"paper"`` (with
    ``simulated_fields``) as the paper's simulator modelled them, else as loaded."""
    if cfg.protocol != "paper" or not cfg.simulated_fields:
        return list(fields)
    out = []
    for f in fields:
        g = simulated_field(f)
        if g is not f:
            _LOG.info("%s as the paper's simulator modelled it: its %s surface's bumps and "
                      "friction variation left out (Section 7.2.2), a plane", f.name,
                      f.spec["surface"]["shape"])
        out.append(g)
    return out


def table1_command(config: Table1Config | None = None, **overrides) -> list[Table1Row]:
    """``seds-casadi table1``: learn the hitting motion, collect the teacher's data sets, run
    the protocol, log the table beside the paper's and write ``table1.csv``,
    ``table1_repetitions.csv``, ``table1.txt``, the data sets and Fig. 10 and 11 into
    ``config.out``.

    Parameters
    ----------
    config : Table1Config, optional
        The settings (default: ``Table1Config()``).
    **overrides
        Settings replaced in ``config``, e.g. ``table1_command(fields=["arctan"], quick=True)``.

    Returns
    -------
    list of Table1Row
        The means over the repetitions.
    """
    from ..minigolf.fields import load_field
    from .executors import open_executor

    cfg = with_overrides(Table1Config, config, overrides).effective()
    loaded = [load_field(f) for f in cfg.fields]  # bad names fail before any work
    os.makedirs(os.path.join(cfg.out, "datasets"), exist_ok=True)
    datasets = _teach(cfg, _played(cfg, loaded), _stroke(cfg))
    sinking = _sinking_sets(datasets, cfg.quick) if cfg.protocol == "paper" else None
    t2 = time.perf_counter()
    with open_executor(cfg.workers, cfg.dask) as ex:
        means, runs = run_table1(datasets, cfg.repetitions, cfg.seed, ex, cfg.progress,
                                 protocol=cfg.protocol, sinking=sinking)
    text = format_table1(means)
    _LOG.info("%s", text)
    _LOG.info("protocol %s, %d repetitions in %.1f s", cfg.protocol, cfg.repetitions,
              time.perf_counter() - t2)
    write_table1_csv(means, os.path.join(cfg.out, "table1.csv"))
    write_table1_csv(runs, os.path.join(cfg.out, "table1_repetitions.csv"))
    atomic_text(os.path.join(cfg.out, "table1.txt"), text)
    if cfg.figures:
        _figures(datasets, cfg.out, sinking, cfg.seed)
    _LOG.info("wrote table1.csv, table1_repetitions.csv, table1.txt, datasets/%s in %s",
              " and Fig. 10 and 11" if cfg.figures else "", cfg.out)
    return means
