"""The paper's Table 1: GPR against GMR for the hitting parameters on simulated fields.

Protocol (paper Section 7.2.1), for each field and training-set kind:

1. The teacher's data set (:func:`seds_casadi.minigolf.teacher.collect_dataset`) over the
   situations the field declares: 20 along a one-dimensional situation space (the rough flat
   and double hill fields: the hole moved along the far edge), 56 over a two-dimensional one
   (arctan: the ball over its region). With a fixed speed the models predict alpha, else
   alpha and kappa.
2. A training set of the given kind is drawn: ``random`` (without replacement) or ``equally
   spaced`` (every other point along the line; a checkerboard over a grid). The kinds follow
   the dimension of the situation space: 5 and 10 random and 10 equally spaced points in
   one dimension, 16 random and 28 equally spaced in two.
3. Each model (GPR, GMR, and with two outputs the separate GMMs) is fitted on it; RMSE of alpha
   [deg] (and of the hitting speed kappa v* [m/s] with two outputs) on the remaining points.
4. Success rate: 30 random situations drawn from the field's declaration (the same draw as
   ``seds-casadi play``), each model's prediction played on the ball model.
5. Steps 2-4 are repeated (100 times in the paper) and averaged.

Fields of your own follow the same protocol. GMMs have 2 Gaussians with one output and 3 with
two: the counts that give Table 1's "#" column (20; 45 joint, 60 separate). Repetitions are
independent tasks with their own seeds (derived from the run's seed, the field, the training
kind and the repetition number), so a run gives the same numbers on any executor: in this
process, local processes or Dask.
"""

from __future__ import annotations

import os
import zlib
from dataclasses import dataclass

import numpy as np

from ..core._io import atomic_csv
from ._progress import progress_bar
from .ball import simulate_shots
from .fields import Field
from .hitting_data import HittingDataset
from .parameters import make_model

__all__ = ["TRAINING_SETS", "MODELS_BY_OUTPUTS", "PAPER_TABLE1", "TABLE1_FIELDS", "CSV_COLUMNS",
           "run_table1", "format_table1", "write_table1_csv", "training_indices",
           "Table1Row", "protocol"]

TABLE1_FIELDS = ("rough_flat", "double_hill", "arctan")
#: Training sets (label, size, kind) by the dimension of the field's situation space: one
#: (the hole along a slider: rough flat, double hill) or two (arctan, and the default
#: declaration: the ball anywhere in its region)
TRAINING_SETS = {
    1: [("5 random", 5, "random"), ("10 random", 10, "random"),
        ("10 equally spaced", 10, "spaced")],
    2: [("16 random", 16, "random"), ("28 equally spaced", 28, "spaced")],
}
#: Models compared, by the number of outputs (alpha; or alpha and kappa)
MODELS_BY_OUTPUTS = {1: ("gpr", "gmr"), 2: ("gpr", "sep_gmr", "gmr")}
#: Gaussians of the GMMs, by the number of outputs
N_COMPONENTS = {1: 2, 2: 3}
N_TEST_SITUATIONS = 30
#: columns of ``table1.csv``: the RMSE of the hitting angle [deg] and of the hitting speed
#: kappa v* [m/s] (empty without a speed output), the success rate (a fraction) and the model's
#: number of parameters
CSV_COLUMNS = ("field", "training", "model", "rmse_angle_deg", "rmse_speed_mps", "success_rate",
               "n_params")

#: The paper's Table 1: (field, training, model) -> (rmse_angle [deg], rmse_speed, success, #)
PAPER_TABLE1 = {
    ("rough_flat", "5 random", "gpr"): (1.40, np.nan, 0.54, 19),
    ("rough_flat", "5 random", "gmr"): (0.52, np.nan, 0.64, 20),
    ("rough_flat", "10 random", "gpr"): (0.77, np.nan, 0.59, 34),
    ("rough_flat", "10 random", "gmr"): (0.35, np.nan, 0.79, 20),
    ("rough_flat", "10 equally spaced", "gpr"): (0.15, np.nan, 0.96, 34),
    ("rough_flat", "10 equally spaced", "gmr"): (0.23, np.nan, 0.94, 20),
    ("double_hill", "5 random", "gpr"): (1.60, np.nan, 0.36, 19),
    ("double_hill", "5 random", "gmr"): (0.80, np.nan, 0.43, 20),
    ("double_hill", "10 random", "gpr"): (1.41, np.nan, 0.42, 34),
    ("double_hill", "10 random", "gmr"): (0.35, np.nan, 0.52, 20),
    ("double_hill", "10 equally spaced", "gpr"): (0.18, np.nan, 0.87, 34),
    ("double_hill", "10 equally spaced", "gmr"): (0.27, np.nan, 0.83, 20),
    ("arctan", "16 random", "gpr"): (0.94, 0.02, 0.85, 72),
    ("arctan", "16 random", "sep_gmr"): (1.01, 0.02, 0.86, 60),
    ("arctan", "16 random", "gmr"): (1.01, 0.02, 0.87, 45),
    ("arctan", "28 equally spaced", "gpr"): (0.24, 0.01, 0.96, 120),
    ("arctan", "28 equally spaced", "sep_gmr"): (0.52, 0.02, 0.88, 60),
    ("arctan", "28 equally spaced", "gmr"): (0.95, 0.02, 0.93, 45),
}


@dataclass
class Table1Row:
    """One line of Table 1 (means over repetitions) or of one repetition.

    ``rmse_angle`` is in degrees, ``rmse_speed`` (of the hitting speed kappa v*) in m/s (NaN
    when the models predict the angle only), ``success_rate`` a fraction, ``n_params`` the
    model's number of parameters.
    """

    field: str
    training: str
    model: str
    rmse_angle: float
    rmse_speed: float
    success_rate: float
    n_params: int
    repetitions: int = 1


def training_indices(situations: np.ndarray, size: int, kind: str,
                     rng: np.random.Generator) -> np.ndarray:
    """Indices of a training set: ``"random"`` or ``"spaced"`` (module docstring)."""
    n = len(situations)
    if not 1 <= size < n:
        raise ValueError(f"a training set of {size} from {n} situations leaves no test points; "
                         f"use fewer training points or a larger data set")
    if kind == "random":
        return np.sort(rng.choice(n, size, replace=False))
    if kind != "spaced":
        raise ValueError(f"training kind must be 'random' or 'spaced', got {kind!r}")
    centred = situations - situations.mean(axis=0)
    _, sv, vt = np.linalg.svd(centred, full_matrices=False)
    if sv[-1] <= 1e-9 * max(1.0, sv[0]):
        # along a line (a slider): equally spaced along it, both ends included
        order = np.argsort(centred @ vt[0], kind="stable")
        return np.sort(order[np.round(np.linspace(0, n - 1, size)).astype(int)])
    values = [np.unique(np.round(situations[:, j], 9), return_inverse=True) for j in (0, 1)]
    if len(values[0][0]) * len(values[1][0]) != n:
        return _farthest_points(situations, size)
    # a grid: checkerboard of the grid coordinates, thinned or filled to ``size``
    ranks = [inv for _, inv in values]
    board = np.flatnonzero((ranks[0] + ranks[1]) % 2 == 0)
    if len(board) >= size:
        return np.sort(board[np.round(np.linspace(0, len(board) - 1, size)).astype(int)])
    rest = np.setdiff1d(np.arange(n), board)
    extra = rest[np.round(np.linspace(0, len(rest) - 1, size - len(board))).astype(int)]
    return np.sort(np.concatenate([board, extra]))


def _farthest_points(S: np.ndarray, size: int) -> np.ndarray:
    """``size`` points spread over scattered situations: greedy farthest-point selection in
    coordinates scaled by their spread, from the point nearest the middle."""
    spread = np.ptp(S, axis=0)
    Z = (S - S.mean(axis=0)) / np.where(spread > 0, spread, 1.0)
    chosen = [int(np.argmin(np.sum(Z * Z, axis=1)))]
    d = np.sum((Z - Z[chosen[0]]) ** 2, axis=1)
    while len(chosen) < size:
        j = int(np.argmax(d))
        chosen.append(j)
        d = np.minimum(d, np.sum((Z - Z[j]) ** 2, axis=1))
    return np.sort(chosen)


def _repetition(task: dict) -> list[Table1Row]:
    """One repetition for one field and training kind, all models on the same training set."""
    from threadpoolctl import threadpool_limits

    # the matrices here are tiny: BLAS threads only add overhead (2.7x measured), and with
    # several worker processes they oversubscribe the cores
    with threadpool_limits(1):
        return _repetition_body(task)


def _repetition_body(task: dict) -> list[Table1Row]:
    field = Field.from_dict(task["field_spec"], source=task["field"])
    ds: HittingDataset = task["dataset"]
    rng = np.random.default_rng(task["seed"])
    S, Y = ds.situations, ds.outputs
    idx = training_indices(S, task["size"], task["kind"], rng)
    test = np.setdiff1d(np.arange(len(ds)), idx)
    balls, holes = field.situations.sample(N_TEST_SITUATIONS, rng)
    rows = []
    for name in task["models"]:
        kw = {"random_state": task["rep"]}
        if name != "gpr":
            kw["n_components"] = task["n_components"]
        model = make_model(name, **kw).fit(S[idx], Y[idx])
        pred = model.predict(S[test])
        rmse_a = float(np.sqrt(np.mean((pred[:, 0] - Y[test, 0]) ** 2)))
        rmse_v = (float(np.sqrt(np.mean(((pred[:, 1] - Y[test, 1]) * ds.stroke.speed) ** 2)))
                  if Y.shape[1] > 1 else np.nan)
        P = model.predict(holes - balls)
        alpha = np.deg2rad(P[:, 0])
        kappa = P[:, 1] if Y.shape[1] > 1 else np.full(len(P), ds.kappa[0])
        good = np.isfinite(alpha) & np.isfinite(kappa) & (kappa > 0)
        sunk = np.zeros(len(P), bool)
        if good.any():
            V = ds.stroke.launch_velocity(alpha[good], kappa[good])
            sunk[good] = simulate_shots(field, balls[good], V, hole=holes[good]).sunk
        rows.append(Table1Row(task["field"], task["training"], name, rmse_a, rmse_v,
                              float(sunk.mean()), int(model.n_params_)))
    return rows


def protocol(field: Field) -> list[tuple[str, int, str]]:
    """The training sets (label, size, kind) of a field: :data:`TRAINING_SETS` for the
    dimension of the situations it declares."""
    return TRAINING_SETS[min(max(field.situations.dim, 1), 2)]


def run_table1(datasets: dict[str, tuple[Field, HittingDataset]], repetitions: int = 100,
               seed: int = 0, executor=None, progress: bool = False
               ) -> tuple[list[Table1Row], list[Table1Row]]:
    """Run the protocol (module docstring).

    Parameters
    ----------
    datasets : dict
        Field name -> (field, data set); the field's situations pick the training sets
        (:func:`protocol`), the data set's outputs the models (:data:`MODELS_BY_OUTPUTS`).
    repetitions : int
    seed : int
    executor : concurrent.futures.Executor, optional
        Where the repetitions run (default: this process).
    progress : bool

    Returns
    -------
    means : list of Table1Row
        One per (field, training, model), averaged over repetitions.
    runs : list of Table1Row
        Every repetition's rows.
    """
    if int(repetitions) < 1:
        raise ValueError(f"repetitions must be at least 1, got {repetitions}")
    tasks = []
    for fname, (field, ds) in datasets.items():
        n_out = ds.outputs.shape[1]
        for ti, (label, size, kind) in enumerate(protocol(field)):
            if size >= len(ds):
                raise ValueError(f"{fname}: the data set has {len(ds)} situations, too few for "
                                 f"'{label}' (the teacher dropped {ds.dropped})")
            for rep in range(int(repetitions)):
                tasks.append({"field": fname, "field_spec": field.spec, "dataset": ds,
                              "training": label, "size": size, "kind": kind, "rep": rep,
                              "models": MODELS_BY_OUTPUTS[n_out],
                              "n_components": N_COMPONENTS[n_out],
                              "seed": [int(seed), zlib.crc32(fname.encode()), ti, rep]})
    results = (executor.map(_repetition, tasks) if executor is not None
               else map(_repetition, tasks))
    results = progress_bar(results, progress, total=len(tasks), desc="Table 1 repetitions",
                           unit="rep")
    runs = [row for rows in results for row in rows]
    means = []
    for key in dict.fromkeys((r.field, r.training, r.model) for r in runs):
        rs = [r for r in runs if (r.field, r.training, r.model) == key]
        means.append(Table1Row(*key, float(np.mean([r.rmse_angle for r in rs])),
                               float(np.mean([r.rmse_speed for r in rs])),
                               float(np.mean([r.success_rate for r in rs])),
                               rs[0].n_params, len(rs)))
    return means, runs


def _fmt(v, spec=".2f"):
    return "-" if v is None or (isinstance(v, float) and np.isnan(v)) else format(v, spec)


def format_table1(rows: list[Table1Row]) -> str:
    """Text table of our numbers beside the paper's."""
    head = (f"{'field':<12} {'training':<18} {'model':<8} {'e_alpha':>7} {'paper':>6} "
            f"{'e_v':>6} {'paper':>6} {'success':>7} {'paper':>6} {'#':>4} {'paper':>5}")
    lines = [head, "-" * len(head)]
    for r in rows:
        p = PAPER_TABLE1.get((r.field, r.training, r.model), (np.nan,) * 4)
        lines.append(f"{r.field:<12} {r.training:<18} {r.model:<8} {_fmt(r.rmse_angle):>7} "
                     f"{_fmt(p[0]):>6} {_fmt(r.rmse_speed, '.3f'):>6} {_fmt(p[1]):>6} "
                     f"{_fmt(r.success_rate):>7} {_fmt(p[2]):>6} {r.n_params:>4d} "
                     f"{_fmt(p[3], 'd') if not np.isnan(p[3]) else '-':>5}")
    lines.append("e_alpha: RMSE of the hitting angle [deg]; e_v: RMSE of the hitting speed "
                 "[m/s]; success: fraction of 30 random situations sunk; #: parameters.")
    return "\n".join(lines) + "\n"


def write_table1_csv(rows: list[Table1Row], path: str | os.PathLike) -> None:
    """Write the rows with the columns :data:`CSV_COLUMNS` (``field, training, model,
    rmse_angle_deg, rmse_speed_mps, success_rate, n_params``; atomically: a partial file never
    appears under the final name; no speed: empty)."""
    atomic_csv(path, CSV_COLUMNS,
               ([r.field, r.training, r.model, r.rmse_angle,
                 "" if np.isnan(r.rmse_speed) else r.rmse_speed, r.success_rate, r.n_params]
                for r in rows))
