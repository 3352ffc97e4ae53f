"""The paper's Table 1: GPR against GMR for the hitting parameters on simulated fields.

Protocol (paper Section 7.2.1), for each field and training-set kind:

1. The teacher's data set (:func:`seds_casadi.teacher.collect_dataset`): 20 situations along
   one input dimension on rough flat and double hill (fixed speed: the models predict alpha),
   56 on arctan (minimal speed: alpha and kappa).
2. A training set of the given kind is drawn: ``random`` (without replacement) or ``equally
   spaced`` (every other point along the line; a checkerboard over the arctan grid).
3. Each model (GPR, GMR, and on arctan the separate GMMs) is fitted on it; RMSE of alpha
   [deg] (and of the hitting speed kappa v* [m/s] on arctan) on the remaining points.
4. Success rate: 30 random situations in the range of the data set's inputs (hole along the
   edge; ball over the grid's box), each model's prediction played on the ball model.
5. Steps 2-4 are repeated (100 times in the paper) and averaged.

Fields of your own follow the protocol of their teacher's strategy. GMMs have 2 Gaussians on
the one-output fields and 3 on arctan: the counts that give Table 1's
"#" column (20; 45 joint, 60 separate). Repetitions are independent tasks with their own seeds
(derived from the run's seed, the field, the training kind and the repetition number), so a
run gives the same numbers on any executor: in this process, local processes or Dask.
"""

from __future__ import annotations

import os
import zlib
from dataclasses import dataclass

import numpy as np

from ..core._io import atomic_csv
from .ball import simulate_shots
from .fields import Field
from .parameters import make_model
from .teacher import HittingDataset

__all__ = ["TRAINING_SETS", "MODELS_BY_STRATEGY", "PAPER_TABLE1", "TABLE1_FIELDS", "CSV_COLUMNS",
           "run_table1", "format_table1", "write_table1_csv", "training_indices",
           "Table1Row"]

TABLE1_FIELDS = ("rough_flat", "double_hill", "arctan")
#: Training sets by the data set's strategy: fixed speed (rough flat, double hill; and any
#: field of your own taught that way) or minimal speed (arctan).
TRAINING_SETS = {
    "fixed_speed": [("5 random", 5, "random"), ("10 random", 10, "random"),
                    ("10 equally spaced", 10, "spaced")],
    "minimal_speed": [("16 random", 16, "random"), ("28 equally spaced", 28, "spaced")],
}
MODELS_BY_STRATEGY = {"fixed_speed": ("gpr", "gmr"), "minimal_speed": ("gpr", "sep_gmr", "gmr")}
N_COMPONENTS = {"fixed_speed": 2, "minimal_speed": 3}
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
    spread = np.ptp(situations, axis=0)
    varying = np.flatnonzero(spread > 1e-9 * max(1.0, spread.max()))
    if len(varying) <= 1:
        order = np.argsort(situations[:, varying[0]] if len(varying) else np.arange(n),
                           kind="stable")
        return np.sort(order[np.round(np.linspace(0, n - 1, size)).astype(int)])
    # a grid: checkerboard of the grid coordinates, thinned or filled to ``size``
    ranks = [np.unique(np.round(situations[:, j], 9), return_inverse=True)[1] for j in varying]
    board = np.flatnonzero((ranks[0] + ranks[1]) % 2 == 0)
    if len(board) >= size:
        return np.sort(board[np.round(np.linspace(0, len(board) - 1, size)).astype(int)])
    rest = np.setdiff1d(np.arange(n), board)
    extra = rest[np.round(np.linspace(0, len(rest) - 1, size - len(board))).astype(int)]
    return np.sort(np.concatenate([board, extra]))


def _test_situations(ds: HittingDataset, n: int, rng: np.random.Generator):
    """Random situations in the range of the data set's inputs: where the data set moved the
    hole, a hole in the range of its holes (ball fixed), else a ball in the box of its balls."""
    hole_spread = np.ptp(ds.hole, axis=0)
    if hole_spread.max() > 0:
        lo, hi = ds.hole.min(axis=0), ds.hole.max(axis=0)
        holes = lo + rng.uniform(size=(n, 2)) * (hi - lo)
        balls = ds.ball[rng.integers(0, len(ds), n)]
    else:
        lo, hi = ds.ball.min(axis=0), ds.ball.max(axis=0)
        balls = lo + rng.uniform(size=(n, 2)) * (hi - lo)
        holes = np.tile(ds.hole[0], (n, 1))
    return balls, holes


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
    balls, holes = _test_situations(ds, N_TEST_SITUATIONS, rng)
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


def run_table1(datasets: dict[str, tuple[Field, HittingDataset]], repetitions: int = 100,
               seed: int = 0, executor=None, progress: bool = False
               ) -> tuple[list[Table1Row], list[Table1Row]]:
    """Run the protocol (module docstring).

    Parameters
    ----------
    datasets : dict
        Field name -> (field, data set); the data set's strategy picks the training sets and
        models (:data:`TRAINING_SETS`, :data:`MODELS_BY_STRATEGY`).
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
        if ds.strategy not in TRAINING_SETS:
            raise ValueError(f"{fname}: no Table 1 protocol for strategy {ds.strategy!r}")
        for ti, (label, size, kind) in enumerate(TRAINING_SETS[ds.strategy]):
            if size >= len(ds):
                raise ValueError(f"{fname}: the data set has {len(ds)} situations, too few for "
                                 f"'{label}' (the teacher dropped {ds.dropped})")
            for rep in range(int(repetitions)):
                tasks.append({"field": fname, "field_spec": field.spec, "dataset": ds,
                              "training": label, "size": size, "kind": kind, "rep": rep,
                              "models": MODELS_BY_STRATEGY[ds.strategy],
                              "n_components": N_COMPONENTS[ds.strategy],
                              "seed": [int(seed), zlib.crc32(fname.encode()), ti, rep]})
    results = (executor.map(_repetition, tasks) if executor is not None
               else map(_repetition, tasks))
    if progress:
        from tqdm.auto import tqdm

        results = tqdm(results, total=len(tasks), desc="Table 1 repetitions", unit="rep")
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
