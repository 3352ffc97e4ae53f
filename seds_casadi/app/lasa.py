"""The LASA handwriting benchmark: fit every shape, reproduce, and score.

Protocols
---------
``all``: train on all 7 demonstrations, evaluate on the same 7.
``split``: train on demonstrations 1-4, evaluate on 5-7 (held out).
``ds-opt``: the published protocol of the LPV-DS authors' evaluation of SEDS, so that our SEDS can
be set beside their numbers (see :func:`evaluate_shape_dsopt`; its own CSV and summary).

Per (shape, objective, protocol) of ``all`` and ``split`` it reports the velocity RMSE and the
direction error e_dot of the model at the evaluation demonstrations' points, the DTW distance
(mean over evaluation demonstrations) of reproductions integrated from each demonstration's start
(RK4, with the demonstrations' own time step, until ||x - x*|| < 1 mm or 20x the demonstration's
length), the fit time and IPOPT's iterations. Units are LASA's: mm and mm/s.

The ds-opt protocol
-------------------
As nbfigueroa/ds-opt ``evaluation-scripts/evaluate_SEDS.m`` (commit 01072b6, June 2018; its
results are ``results/seds_stats_all.mat``, dated 14 June 2018, and ``results/stats_all_test.fig``):

- the 26 single-pattern shapes (:data:`~seds_casadi.core.datasets.LASA_SINGLE_SHAPES`); the
  files are the same as ds-opt's ``datasets/lasaDataset_seds/Dataset`` (checked: identical
  positions, velocities and dt);
- demonstrations 1-4 train, 5-7 test; every 2nd sample (``1:2:end``: 500 per demonstration,
  2,000 training points) with the file's velocities, no trimming, target at the origin (where
  every LASA demonstration ends);
- SEDS's ``mse`` objective by default; K given, or chosen by BIC on [x; xdot] for K = 1..15
  (:func:`~seds_casadi.core.model_selection.choose_k_by_bic`);
- RMSE = mean over points of sqrt(mean over dims (f(x) - xdot)^2) [mm/s]
  (:func:`~seds_casadi.core.metrics.velocity_rmse`); e_dot = mean |1 - cos| with undefined
  directions counting 0 (:func:`~seds_casadi.core.metrics.pointwise_direction_error` with
  ``min_norm_product=0``); DTWD [mm]: forward Euler with dt = 0.01 s from the 20th subsampled
  point of each demonstration, the starts of a set integrated together until every velocity
  component is below 0.1 mm/s for 4 steps or 3,000 steps, the last point dropped
  (:func:`~seds_casadi.core.metrics.simulate_until_slow`), full DTW against the whole
  500-point demonstration, mean over the set's demonstrations
  (:func:`~seds_casadi.core.metrics.reproduction_dtw`).

Differences from the published run, kept on purpose: one fit per shape (a fixed seed) instead of
10 repetitions; our SEDS's own IPOPT settings (``max_iter`` 1000, its tolerances) instead of
SEDS's ``max_iter`` 500 and ``tol_stopping`` 1e-9; and scikit-learn's EM in the BIC search
instead of MATLAB's ``fitgmdist`` (see
:func:`~seds_casadi.core.model_selection.choose_k_by_bic`).
"""

from __future__ import annotations

import os
import time
import warnings
from concurrent.futures import Executor
from dataclasses import asdict, dataclass

import numpy as np

from ..core._io import atomic_csv, atomic_text
from ..core.datasets import LASA_SHAPES, LASA_SINGLE_SHAPES, load_lasa, load_lasa_raw
from ..core.demonstrations import Demonstrations
from ..core.errors import ConvergenceWarning
from ..core.metrics import (
    direction_error,
    dtw_distance,
    velocity_rmse,
)
from ..core.model_selection import BIC_RULES, choose_k_by_bic
from ..core.search import DemoSearchCV, held_out_scores
from ..core.seds import SEDS
from ..core.settings import OBJECTIVES

__all__ = ["LasaResult", "evaluate_shape", "run_lasa", "write_csv", "summary_table", "PROTOCOLS",
           "DEFAULT_PROTOCOLS", "DsOptResult", "DsOptSet", "dsopt_sets", "dsopt_scores",
           "evaluate_shape_dsopt", "write_dsopt_csv", "dsopt_table", "PUBLISHED_MEANS",
           "PUBLISHED_SEDS", "DSOPT_COLUMNS"]

PROTOCOLS = ("all", "split", "ds-opt")
#: what :func:`run_lasa` and ``seds-casadi lasa`` run unless told otherwise
DEFAULT_PROTOCOLS = ("all", "split")
_CONVERGED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
#: columns of ``lasa.csv``; a unit ends the name (the LASA data are in mm): the velocity RMSE
#: [mm/s], the DTW distance [mm], the fit's time [s]; e_dot (in [0, 2]) and iterations have none
CSV_COLUMNS = ("shape", "objective", "protocol", "rmse_mmps", "e_dot", "dtwd_mm", "seconds",
               "iterations")
_CSV_FIELDS = {"rmse_mmps": "rmse", "dtwd_mm": "dtwd"}   # column -> LasaResult's attribute
DSOPT_COLUMNS = ("shape", "objective", "set", "rmse_mmps", "e_dot", "dtwd_mm", "seconds",
                 "iterations", "n_components", "certified", "status", "k_choice", "seconds_k",
                 "repro_points", "max_end_distance_mm", "max_rate_per_s",
                 "published_rmse_mmps", "published_e_dot", "published_dtwd_mm", "published_k")

#: ds-opt's data selection: demonstrations (1-based, as in the script), sample step, and the
#: index (0-based) of the reproductions' start in each subsampled demonstration (MATLAB's 20)
DSOPT_TRAIN_DEMOS = (1, 2, 3, 4)
DSOPT_TEST_DEMOS = (5, 6, 7)
DSOPT_SAMPLE_STEP = 2
DSOPT_START_INDEX = 19
#: the protocol's reproductions (``Simulation.m`` as ``evaluate_SEDS.m`` calls it): Euler at
#: 0.01 s from the 20th point until every component is below 0.1 mm/s for 4 steps, 3,000 steps;
#: literally, so no Euler sub-steps even for a stiff model
DSOPT_REPRODUCTION = {"dt": 0.01, "speed_tol": 0.1, "max_steps": 3000,
                      "start_index": DSOPT_START_INDEX, "substeps": 1}

#: Published means over the 26 shapes, (method, set) -> (RMSE [mm/s], e_dot, DTWD [mm]).
#: SEDS: ``results/seds_stats_all.mat`` of nbfigueroa/ds-opt (means over shapes of the means over
#: 10 repetitions; recomputed from the file: 6.344 / 0.0992 / 3954 test, 3.580 / 0.0664 / 2782
#: train); LPV-DS: the heights of the test-set bars in ``results/stats_all_test.fig`` (a MATLAB
#: figure, readable as a MAT-file; its SEDS bars equal the means of the .mat above). O1/O2/O3 are
#: the three LPV-DS optimisation variants of Figueroa and Billard (CoRL 2018).
PUBLISHED_MEANS: dict[tuple[str, str], tuple[float, float, float]] = {
    ("SEDS", "test"): (6.34, 0.099, 3954.0),
    ("SEDS", "train"): (3.58, 0.066, 2782.0),
    ("LPV-DS EM-GMM O1", "test"): (6.64, 0.106, 2974.0),
    ("LPV-DS EM-GMM O2", "test"): (6.52, 0.079, 1990.0),
    ("LPV-DS EM-GMM O3", "test"): (6.58, 0.081, 2180.0),
    ("LPV-DS PC-GMM O1", "test"): (5.79, 0.097, 2941.0),
    ("LPV-DS PC-GMM O2", "test"): (5.19, 0.062, 1749.0),
    ("LPV-DS PC-GMM O3", "test"): (5.28, 0.063, 1751.0),
}

#: Published SEDS per shape, from ``results/seds_stats_all.mat`` (nbfigueroa/ds-opt): the K used
#: most often in the 10 repetitions (the smaller on a tie), then the means over the repetitions of
#: RMSE [mm/s], e_dot, DTWD [mm] on the training demos, then the same on the test demos.
PUBLISHED_SEDS: dict[str, tuple[int, float, float, float, float, float, float]] = {
    "Angle": (5, 4.693, 0.0212, 2147, 9.239, 0.0275, 1171),
    "BendedLine": (10, 4.128, 0.3042, 7272, 8.248, 0.2757, 10279),
    "CShape": (6, 4.037, 0.0625, 2574, 7.514, 0.1039, 19540),
    "DoubleBendedLine": (5, 3.023, 0.1806, 6528, 2.964, 0.1491, 7120),
    "GShape": (6, 2.876, 0.0203, 2578, 4.325, 0.0550, 3364),
    "heee": (5, 4.340, 0.0498, 4537, 6.012, 0.0713, 5972),
    "JShape": (5, 2.783, 0.0240, 833, 5.059, 0.1110, 819),
    "JShape_2": (13, 3.433, 0.0480, 4309, 13.941, 0.1038, 4854),
    "Khamesh": (5, 2.593, 0.0326, 565, 5.336, 0.0799, 595),
    "Leaf_1": (5, 4.859, 0.2414, 8011, 5.810, 0.2155, 7768),
    "Leaf_2": (6, 3.030, 0.0694, 6065, 3.354, 0.0983, 6025),
    "Line": (3, 3.535, 0.0391, 129, 14.410, 0.0783, 244),
    "LShape": (4, 3.290, 0.0355, 394, 7.073, 0.0600, 624),
    "NShape": (6, 5.783, 0.0950, 6912, 9.595, 0.1166, 4621),
    "PShape": (5, 2.746, 0.0289, 2152, 3.621, 0.0393, 1900),
    "RShape": (5, 2.767, 0.0356, 418, 4.842, 0.1005, 935),
    "Saeghe": (5, 3.332, 0.0591, 1025, 5.389, 0.1922, 1705),
    "Sharpc": (4, 4.442, 0.0348, 2678, 7.289, 0.0690, 2359),
    "Sine": (5, 1.785, 0.0160, 519, 2.616, 0.0306, 508),
    "Snake": (4, 3.715, 0.1174, 4468, 5.020, 0.1436, 4505),
    "Spoon": (5, 1.668, 0.0133, 621, 2.519, 0.0254, 486),
    "Sshape": (4, 6.348, 0.0632, 3542, 7.815, 0.1022, 5392),
    "Trapezoid": (5, 2.506, 0.0153, 539, 4.430, 0.0425, 864),
    "Worm": (5, 1.699, 0.0176, 472, 2.185, 0.0346, 396),
    "WShape": (6, 4.963, 0.0753, 1393, 5.647, 0.1115, 1716),
    "Zshape": (6, 4.698, 0.0272, 1652, 10.695, 0.1415, 9044),
}


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


@dataclass
class DsOptResult:
    """One row of the ds-opt protocol: one shape, objective and set ("train" or "test").

    ``seconds`` and ``iterations`` are those of the one SEDS fit (the same in both rows of a
    shape); ``seconds_k`` the time of the BIC search (0 when K is given); ``k_choice`` says how
    K was chosen ("given", "bic:ds-opt", "bic:min" or "published"); ``published_*`` are the
    published SEDS figures for the shape and set (:data:`PUBLISHED_SEDS`).
    """

    shape: str
    objective: str
    set: str
    rmse_mmps: float
    e_dot: float
    dtwd_mm: float
    seconds: float
    iterations: int
    n_components: int
    certified: bool
    status: str
    k_choice: str
    seconds_k: float
    repro_points: int
    max_end_distance_mm: float
    max_rate_per_s: float
    published_rmse_mmps: float
    published_e_dot: float
    published_dtwd_mm: float
    published_k: int
    #: the SEDS objective reached on the training set (``fit_info["objective"]``)
    objective_value: float = float("nan")
    #: with ``param_grid``: the settings :class:`~seds_casadi.core.search.DemoSearchCV` chose
    chosen: str = ""


@dataclass(frozen=True)
class DsOptSet:
    """The demonstrations of one set of the ds-opt protocol, subsampled.

    Attributes
    ----------
    demos : tuple of int
        The demonstrations' numbers in the file (1-based, as in ds-opt's script).
    positions, velocities : list of array, shape (500, 2)
        Every 2nd sample of each demonstration [mm, mm/s], the file's velocities.
    starts : array, shape (n_demos, 2)
        The reproductions' starts: the 20th subsampled point of each demonstration.
    """

    demos: tuple[int, ...]
    positions: list
    velocities: list
    starts: np.ndarray

    def demonstrations(self) -> Demonstrations:
        """The set as :class:`Demonstrations`, untrimmed, with the target at the origin."""
        d = Demonstrations(self.positions, velocities=self.velocities,
                           target=np.zeros(self.positions[0].shape[1]), trim_speed=0.0)
        assert d.n_samples == sum(len(p) for p in self.positions), "no sample may be trimmed"
        return d


def dsopt_sets(shape: str) -> dict[str, DsOptSet]:
    """The training and test sets of one LASA shape as ds-opt's ``evaluate_SEDS.m`` builds them.

    Demonstrations 1-4 train and 5-7 test; ``pos(:, 1:2:end)`` and ``vel(:, 1:2:end)`` of each
    (the file's velocities, 500 samples each); reproductions start at ``data_(1:2, 20)``.

    Parameters
    ----------
    shape : str
        One of the 26 single-pattern shapes.

    Returns
    -------
    dict
        ``{"train": DsOptSet, "test": DsOptSet}``.
    """
    _check_dsopt_shapes([shape])
    pos, vel, _ = load_lasa_raw(shape)
    out = {}
    for name, numbers in (("train", DSOPT_TRAIN_DEMOS), ("test", DSOPT_TEST_DEMOS)):
        P = [pos[n - 1][::DSOPT_SAMPLE_STEP].copy() for n in numbers]
        V = [vel[n - 1][::DSOPT_SAMPLE_STEP].copy() for n in numbers]
        out[name] = DsOptSet(tuple(numbers), P, V, np.stack([p[DSOPT_START_INDEX] for p in P]))
    return out


def _check_dsopt_shapes(shapes) -> None:
    for s in shapes:
        if s not in LASA_SINGLE_SHAPES:
            extra = (" (the ds-opt protocol covers the 26 single-pattern shapes; the Multi_Models "
                     "are not among them)" if s in LASA_SHAPES else "")
            raise ValueError(f"unknown shape {s!r} for the ds-opt protocol{extra}; valid: "
                             f"{', '.join(LASA_SINGLE_SHAPES)}")


def _resolve_k(shape: str, n_components, train: DsOptSet, k_max: int, random_state,
               bic_rule: str) -> tuple[int, str, float]:
    """(K, how it was chosen, seconds spent choosing)."""
    if isinstance(n_components, str):
        if n_components == "bic":
            t0 = time.perf_counter()
            k = choose_k_by_bic(np.concatenate(train.positions), np.concatenate(train.velocities),
                                k_max=k_max, random_state=random_state, rule=bic_rule)
            return k, f"bic:{bic_rule}", time.perf_counter() - t0
        if n_components == "published":
            return int(PUBLISHED_SEDS[shape][0]), "published", 0.0
        raise ValueError(f"n_components must be a positive integer, 'bic' or 'published'; got "
                         f"{n_components!r}")
    if isinstance(n_components, bool) or not isinstance(n_components, (int, np.integer)) \
            or n_components < 1:
        raise ValueError(f"n_components must be a positive integer, 'bic' or 'published'; got "
                         f"{n_components!r}")
    return int(n_components), "given", 0.0


def dsopt_scores(predict, data: DsOptSet) -> tuple[float, float, float, np.ndarray]:
    """ds-opt's scores of a model on one set: RMSE [mm/s], e_dot and DTWD [mm] (forward Euler
    at dt = 0.01 from the set's starts until every |xdot| component is below 0.1 for 4 steps or
    3,000 steps), and the reproductions (steps, demos, d).

    :func:`~seds_casadi.core.search.held_out_scores` with :data:`DSOPT_REPRODUCTION`.

    Parameters
    ----------
    predict : callable
        Velocity field, (n, d) positions -> (n, d) velocities (any model, e.g. a peer's).
    data : DsOptSet
    """
    s = held_out_scores(predict, data.demonstrations(), return_paths=True, **DSOPT_REPRODUCTION)
    return s["rmse"], s["e_dot"], s["dtw"], s["paths"]


def evaluate_shape_dsopt(shape: str, objective: str = "mse", n_components: int | str = "bic",
                         k_max: int = 15, random_state: int = 0, bic_rule: str = "ds-opt",
                         max_iter: int = 1000, figure_path: str | None = None,
                         seds_options: dict | None = None,
                         param_grid: dict | list | None = None) -> list[DsOptResult]:
    """Fit one shape under the ds-opt protocol and score it on the training and test sets.

    Parameters
    ----------
    shape : str
        One of the 26 single-pattern shapes.
    objective : {"mse", "direction", "likelihood"}, default "mse"
        ds-opt runs SEDS with ``mse``.
    n_components : int, "bic" or "published", default "bic"
        K; ``"bic"``: :func:`~seds_casadi.core.model_selection.choose_k_by_bic` on the
        training set (up to ``k_max``);
        ``"published"``: the K the published runs used most for this shape.
    k_max : int, default 15
    random_state : int
        Seed of the BIC search and of SEDS's initialisation.
    bic_rule : {"ds-opt", "min"}, default "ds-opt"
    max_iter : int, default 1000
        IPOPT's iteration limit.
    figure_path : str, optional
        Write a figure (test demonstrations, their reproductions, streamlines) there.
    seds_options : dict, optional
        More options of :class:`~seds_casadi.SEDS` (e.g. ``{"lyapunov": "learned"}``).
    param_grid : dict or list of dict, optional
        Choose among these settings by :class:`~seds_casadi.core.search.DemoSearchCV` on the
        training demonstrations alone (leave one out, each reproduced by the protocol's rule
        from its 20th point), then refit the chosen one on all four; ``seconds`` is then the
        whole search. The test demonstrations play no part in the choice.

    Returns
    -------
    list of DsOptResult
        Two rows: ``set="train"`` and ``set="test"``.
    """
    _validate([shape], [objective], ["ds-opt"])
    sets = dsopt_sets(shape)
    K, how, k_seconds = _resolve_k(shape, n_components, sets["train"], k_max, random_state,
                                   bic_rule)
    t0 = time.perf_counter()
    with warnings.catch_warnings():  # the status is recorded and counted in the summary
        warnings.simplefilter("ignore", ConvergenceWarning)
        learner = SEDS(K, objective=objective, random_state=random_state, max_iter=max_iter,
                       **(seds_options or {}))
        chosen = ""
        if param_grid:
            search = DemoSearchCV(learner, param_grid, **DSOPT_REPRODUCTION)
            model = search.fit(sets["train"].demonstrations()).model_
            chosen = ", ".join(f"{k}={v}" for k, v in search.best_params_.items())
        else:
            model = learner.fit(sets["train"].demonstrations()).model_
    seconds = time.perf_counter() - t0
    cert = model.certificate
    certified = bool(cert["max_eig_lyapunov"] < 0 and cert["min_eig_cov"] > 0)
    rate = model.stiffness()
    pub = PUBLISHED_SEDS[shape]
    rows, paths = [], {}
    for name, data in sets.items():
        rmse, e_dot, dtwd, paths[name] = dsopt_scores(model.predict, data)
        end = float(np.linalg.norm(paths[name][-1] - model.target, axis=1).max())
        off = 1 if name == "train" else 4
        rows.append(DsOptResult(
            shape, objective, name, rmse, e_dot, dtwd, seconds,
            int(model.fit_info["iterations"]), K, certified,
            str(model.fit_info["status"]), how, k_seconds, len(paths[name]), end, rate,
            float(pub[off]), float(pub[off + 1]), float(pub[off + 2]), int(pub[0]),
            float(model.fit_info["objective"]), chosen))
    if figure_path:
        from .plot_ds import plot_streamlines
        from .plotting import pyplot, save_figure

        test = sets["test"]
        fig, ax = pyplot().subplots(figsize=(5, 4.5))
        plot_streamlines(model, test.demonstrations(),
                         [paths["test"][:, n] for n in range(len(test.demos))], ax=ax,
                         title=f"{shape} · {objective} · ds-opt test · K={K}", unit="mm")
        save_figure(fig, figure_path)
    return rows


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
    if protocol == "ds-opt":
        raise ValueError("the ds-opt protocol scores a train and a test set: use "
                         "evaluate_shape_dsopt (or run_lasa(protocols=['ds-opt']))")
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
        from .plot_ds import plot_streamlines
        from .plotting import pyplot, save_figure

        fig, ax = pyplot().subplots(figsize=(5, 4.5))
        plot_streamlines(model, test, repro, ax=ax, unit="mm",
                         title=f"{shape} · {objective} · {protocol} · K={n_components}")
        save_figure(fig, figure_path)
    return LasaResult(shape, objective, protocol, velocity_rmse(F, V), direction_error(F, V),
                      float(np.mean(dtw)), seconds, int(model.fit_info["iterations"]),
                      str(model.fit_info["status"]))


def _task(args) -> LasaResult | list[DsOptResult]:
    args = dict(args)
    if args["protocol"] == "ds-opt":
        args.pop("protocol")
        return evaluate_shape_dsopt(**args)
    return evaluate_shape(**args)  # "all" or "split": evaluate_shape takes the protocol


def run_lasa(shapes=None, objectives=None, protocols=DEFAULT_PROTOCOLS,
             n_components: int | str | None = None, n_samples: int = 100, random_state: int = 0,
             out_dir: str | None = None, figures: bool = True, workers: int = 1,
             executor: Executor | None = None, progress: bool = True, dask: str | None = None,
             dsopt_objectives=None, k_max: int = 15,
             bic_rule: str = "ds-opt") -> list[LasaResult | DsOptResult]:
    """Run the LASA benchmark over shapes x objectives x protocols.

    Parameters
    ----------
    shapes : list of str, optional
        Default: all 30 shapes (the 26 single-pattern ones for ``ds-opt``, which accepts no
        other).
    objectives : sequence of names, optional
        Default: ``direction`` for ``all``/``split``; for ``ds-opt`` see ``dsopt_objectives``.
    protocols : sequence of names, default ("all", "split")
        Any of :data:`PROTOCOLS`.
    n_components : int, "bic" or "published", optional
        Default: 5 for ``all``/``split`` (which take an integer only), ``"bic"`` for ``ds-opt``
        (see :func:`evaluate_shape_dsopt`).
    n_samples : int
        Samples per demonstration for ``all``/``split`` (``ds-opt`` takes every 2nd sample).
    random_state : int
    out_dir : str, optional
        Folder for ``lasa.csv`` (``all``/``split``), ``lasa_dsopt.csv`` (``ds-opt``),
        ``summary.txt`` and ``figures/`` (one figure per shape and objective, drawn for the
        ``all`` protocol, or ``split`` if that is the only one; ``{shape}_{objective}_ds-opt.png``
        for ``ds-opt``).
    workers : int
        Local processes when no ``executor`` is given (1: run in this process).
    executor : concurrent.futures.Executor, optional
        Any executor (e.g. a Dask ``distributed.Client().get_executor()``).
    progress : bool
        Show a progress bar.
    dask : str, optional
        Address of a Dask scheduler to run the fits on (see
        :func:`seds_casadi.app.executors.open_executor`).
    dsopt_objectives : sequence of names, optional
        Objectives of the ``ds-opt`` runs. Default: ``objectives`` if given, else ``mse``.
    k_max, bic_rule : see :func:`~seds_casadi.core.model_selection.choose_k_by_bic`
        (``ds-opt`` with ``n_components="bic"``)

    Returns
    -------
    list of LasaResult and DsOptResult
        One :class:`LasaResult` per (shape, objective, protocol) of ``all``/``split``, then two
        :class:`DsOptResult` (train, test) per (shape, objective) of ``ds-opt``.
    """
    protocols = list(protocols)
    _validate([], [], protocols)
    classic = [p for p in protocols if p != "ds-opt"]
    dsopt = "ds-opt" in protocols
    c_objectives = list(("direction",) if objectives is None else objectives)
    d_objectives = list(dsopt_objectives if dsopt_objectives is not None
                        else ("mse",) if objectives is None else objectives)
    c_shapes = list(LASA_SHAPES if shapes is None else shapes)
    d_shapes = list(LASA_SINGLE_SHAPES if shapes is None else shapes)
    _validate(c_shapes, c_objectives, classic)
    if dsopt:
        _validate([], d_objectives, [])
        _check_dsopt_shapes(d_shapes)
        if bic_rule not in BIC_RULES:
            raise ValueError(f"unknown BIC rule {bic_rule!r}; valid: {', '.join(BIC_RULES)}")
        if int(k_max) < 1:
            raise ValueError(f"k_max must be at least 1, got {k_max}")
    c_k = 5 if n_components is None else n_components
    if classic and (isinstance(c_k, (str, bool)) or not isinstance(c_k, (int, np.integer))
                    or c_k < 1):
        raise ValueError(f"the {'/'.join(classic)} protocol(s) need a positive integer "
                         f"n_components, got {c_k!r} ('bic' and 'published' are for ds-opt)")
    d_k = "bic" if n_components is None else n_components
    if dsopt:
        if isinstance(d_k, str) and d_k not in ("bic", "published"):
            raise ValueError(f"n_components must be a positive integer, 'bic' or 'published'; "
                             f"got {d_k!r}")
        if not isinstance(d_k, str) and (isinstance(d_k, bool) or int(d_k) < 1):
            raise ValueError(f"n_components must be a positive integer, got {d_k!r}")
    if int(workers) < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    fig_dir = None
    if out_dir is not None:
        os.makedirs(out_dir, exist_ok=True)
        if figures:
            fig_dir = os.path.join(out_dir, "figures")
            os.makedirs(fig_dir, exist_ok=True)
    fig_protocol = "all" if "all" in classic else (classic[0] if classic else None)
    tasks = []
    for s in c_shapes if classic else []:
        for o in c_objectives:
            for p in classic:
                fp = None
                if fig_dir and p == fig_protocol:
                    fp = os.path.join(fig_dir, f"{s}_{o}.png")
                tasks.append(dict(shape=s, objective=o, protocol=p, n_components=c_k,
                                  n_samples=n_samples, random_state=random_state,
                                  figure_path=fp))
    for s in d_shapes if dsopt else []:
        for o in d_objectives:
            fp = os.path.join(fig_dir, f"{s}_{o}_ds-opt.png") if fig_dir else None
            tasks.append(dict(shape=s, objective=o, protocol="ds-opt", n_components=d_k,
                              k_max=int(k_max), random_state=random_state, bic_rule=bic_rule,
                              figure_path=fp))
    from ..minigolf._progress import progress_bar

    bar = progress_bar(None, progress, total=len(tasks), desc="LASA fits", unit="fit")
    results: list[LasaResult | DsOptResult] = []
    from .executors import open_executor

    def collect(r) -> None:
        results.extend(r if isinstance(r, list) else [r])
        bar.update(1)

    try:
        if executor is not None:
            for r in executor.map(_task, tasks):
                collect(r)
        else:
            with open_executor(workers, dask) as ex:
                for r in ex.map(_task, tasks):
                    collect(r)
    finally:
        bar.close()
    if out_dir is not None:
        if classic:
            write_csv([r for r in results if isinstance(r, LasaResult)],
                      os.path.join(out_dir, "lasa.csv"))
        if dsopt:
            write_dsopt_csv([r for r in results if isinstance(r, DsOptResult)],
                            os.path.join(out_dir, "lasa_dsopt.csv"))
        atomic_text(os.path.join(out_dir, "summary.txt"), summary_table(results))
    return results


def write_csv(results: list[LasaResult], path: str) -> None:
    """Write results with the columns :data:`CSV_COLUMNS` (``shape, objective, protocol,
    rmse_mmps, e_dot, dtwd_mm, seconds, iterations``; atomically: a partial file is never left
    under the final name)."""
    atomic_csv(path, CSV_COLUMNS, ([asdict(r)[_CSV_FIELDS.get(c, c)] for c in CSV_COLUMNS]
                                   for r in results))


def summary_table(results: list[LasaResult | DsOptResult]) -> str:
    """Text table: per objective and protocol, mean/median of the metrics over shapes, and how
    many fits stopped without converging (IPOPT's iteration limit; still certified stable).
    Rows of the ds-opt protocol are summarised by :func:`dsopt_table`, after the others."""
    dsopt = [r for r in results if isinstance(r, DsOptResult)]
    results = [r for r in results if not isinstance(r, DsOptResult)]
    if not results:
        return dsopt_table(dsopt)
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
    text = "\n".join(lines) + "\n"
    return text + ("\n" + dsopt_table(dsopt) if dsopt else "")


def write_dsopt_csv(results: list[DsOptResult], path: str) -> None:
    """Write ds-opt rows with the columns :data:`DSOPT_COLUMNS` (atomically). Units are in the
    names: ``rmse_mmps`` [mm/s], ``dtwd_mm`` [mm], ``seconds`` [s]; ``e_dot`` is in [0, 2]."""
    atomic_csv(path, DSOPT_COLUMNS, ([asdict(r)[c] for c in DSOPT_COLUMNS] for r in results))


def _fmt_row(label: str, n: int | str, rmse: float, e_dot: float, dtwd: float,
             extra: str = "") -> str:
    return f"{label:<34} {n!s:>6} {rmse:>11.2f} {e_dot:>7.3f} {dtwd:>10.0f}  {extra}".rstrip()


def dsopt_table(results: list[DsOptResult], per_shape: bool = True, worst: int = 3) -> str:
    """The ds-opt results beside the published means, per set, and per shape.

    For each objective and set: the means over the shapes run of RMSE [mm/s], e_dot and DTWD
    [mm], the median fit time, the median K, how many models are certified and how many fits
    stopped without converging; then published SEDS over the same shapes (:data:`PUBLISHED_SEDS`)
    and the published means over all 26 (:data:`PUBLISHED_MEANS`, LPV-DS for the test set only).
    With ``per_shape``: each shape's test figures against published SEDS (with the diagnostics
    of :class:`DsOptResult`: reproduction points, largest end distance, largest rate), and the
    ``worst`` shapes by the ratio ours / published for each metric.
    """
    if not results:
        return ""
    head = f"{'ds-opt protocol':<34} {'shapes':>6} {'RMSE mm/s':>11} {'e_dot':>7} {'DTWD mm':>10}"
    lines = ["ds-opt protocol (nbfigueroa/ds-opt evaluate_SEDS.m): demos 1-4 train, 5-7 test, "
             "every 2nd sample; means over shapes", head]
    for o in sorted({r.objective for r in results}):
        for st in ("test", "train"):
            rs = [r for r in results if r.objective == o and r.set == st]
            if not rs:
                continue
            shapes = [r.shape for r in rs]
            extra = (f"median fit {np.median([r.seconds for r in rs]):.1f} s, median K "
                     f"{np.median([r.n_components for r in rs]):g} ({rs[0].k_choice}), "
                     f"certified {sum(r.certified for r in rs)}/{len(rs)}, unconverged "
                     f"{sum(r.status not in _CONVERGED for r in rs)}")
            lines.append(_fmt_row(f"ours: SEDS {o}, {st}", len(rs),
                                  np.mean([r.rmse_mmps for r in rs]),
                                  np.mean([r.e_dot for r in rs]),
                                  np.mean([r.dtwd_mm for r in rs]), extra))
            off = 1 if st == "train" else 4
            pub = np.array([PUBLISHED_SEDS[s][off:off + 3] for s in shapes], dtype=float)
            lines.append(_fmt_row(f"published SEDS, {st}, same shapes", len(rs), *pub.mean(0),
                                  f"median K {np.median([PUBLISHED_SEDS[s][0] for s in shapes]):g}"))
    lines.append("published means over the 26 shapes:")
    for (method, st), vals in PUBLISHED_MEANS.items():
        lines.append(_fmt_row(f"  {method}, {st}", 26, *vals))
    if per_shape:
        for o in sorted({r.objective for r in results}):
            rs = [r for r in results if r.objective == o and r.set == "test"]
            if not rs:
                continue
            lines += ["", f"per shape, test set, SEDS {o}: ours / published SEDS",
                      f"{'shape':<18} {'K':>7} {'RMSE mm/s':>15} {'e_dot':>15} {'DTWD mm':>17} "
                      f"{'fit s':>7} {'iter':>5} {'points':>6} {'end mm':>7} {'rate/s':>7}  status"]
            for r in rs:
                lines.append(
                    f"{r.shape:<18} {r.n_components:>3}/{r.published_k:<3} "
                    f"{r.rmse_mmps:>7.2f}/{r.published_rmse_mmps:<7.2f} "
                    f"{r.e_dot:>7.3f}/{r.published_e_dot:<7.3f} "
                    f"{r.dtwd_mm:>8.0f}/{r.published_dtwd_mm:<8.0f} {r.seconds:>7.1f} "
                    f"{r.iterations:>5d} {r.repro_points:>6d} {r.max_end_distance_mm:>7.2f} "
                    f"{r.max_rate_per_s:>7.0f}  {r.status}")
            if worst:
                for name, a, b in (("RMSE", "rmse_mmps", "published_rmse_mmps"),
                                   ("e_dot", "e_dot", "published_e_dot"),
                                   ("DTWD", "dtwd_mm", "published_dtwd_mm")):
                    ratio = sorted(rs, key=lambda r: -getattr(r, a) / getattr(r, b))[:worst]
                    lines.append(f"worst {name} ratio: " + ", ".join(
                        f"{r.shape} {getattr(r, a) / getattr(r, b):.2f}x" for r in ratio))
    return "\n".join(lines) + "\n"
