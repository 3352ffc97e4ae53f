"""The paper's Table 1: GPR against GMR for the hitting parameters on simulated fields.

Two protocols, chosen by name (:data:`PROTOCOLS`): ``"paper"`` (the default) as Section 7.2.1
describes it, and ``"grid"``, the protocol of this package before (issues 4 and 15).

``"paper"`` (Section 7.2.1, Fig. 10, Eq. 15-16), for each field and training-set kind, on the
fields as the paper's simulator modelled them (:func:`simulated_field`: a rough surface without
the grass's structure, Section 7.2.2; the caller teaches on them):

1. The teacher's data set as in ``"grid"`` (20 situations along one input dimension, the hole
   moved sideways along the far edge with the speed fixed, on rough flat and double hill; 56
   over the ball's region at the minimal speed on arctan), and around each of its shots the
   **sinking set** (:mod:`seds_casadi.minigolf.sinking`). Each repetition draws its examples
   from the sinking set: the taught parameters plus the noise of Eq. 15 ("the hole being larger
   than the ball"), not the centre of the range.
2. Training sets: on a one-dimensional situation space, 5 and 10 points **at random from a
   range around the centre of the input range** (Fig. 10's black crosses; the middle
   :data:`CENTRE_FRACTION` of it: see below) and 10 equally spaced over the whole range; on
   arctan 16 random and 28 equally spaced over the whole region (the text names the centred
   range for the "initial experiment" on the flat and double hill fields only).
3. RMSE on the remaining examples of the data set (noisy too: the paper's validation data are
   its data set), success on 30 random situations of the whole declared range, played on the
   ball model; models, counts and repetitions as below. GPR is Eq. 17a as printed, a
   zero-mean process (:data:`GPR_PRIOR_MEAN`; ``"grid"`` keeps the training outputs' mean).

The width of the centred range is not given in the text; :data:`CENTRE_FRACTION` = 0.6 (the
middle 12 of the 20 points) follows from two of its statements. "10 random training points" are
drawn from that range, so it holds more than 10 of the 20 points: more than half the range (with
0.6 the 10-point draw leaves out 2 of 12 centred points, 66 possible training sets). And GPR,
which "outputs zero far from the training data", sinks 0.54-0.59 with random points on the
rough flat field where equally spaced ones sink 0.96: about the part of the range the training
points cover, and hardly more with 10 points than with 5.

The examples are redrawn in every repetition (the paper collected one data set), so the means
average over the teacher's noise as well as over the training sets. ``noise_spread`` and
``centre_fraction`` of :func:`run_table1` change the two choices
(``benchmarks/table1_sensitivity.py``).

``"grid"``, for each field and training-set kind:

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
from .parameters import GPR_PRIOR_MEANS, make_model
from .sinking import SinkingSet, sinking_set
from .teacher import Teacher

__all__ = ["TRAINING_SETS", "PAPER_TRAINING_SETS", "PROTOCOLS", "CENTRE_FRACTION",
           "GPR_PRIOR_MEAN",
           "MODELS_BY_OUTPUTS", "PAPER_TABLE1", "TABLE1_FIELDS", "CSV_COLUMNS",
           "run_table1", "format_table1", "write_table1_csv", "training_indices",
           "Table1Row", "protocol", "training_sets", "centred_indices", "paper_conclusions",
           "rows_within", "simulated_field"]

#: The protocols of :func:`run_table1` (module docstring)
PROTOCOLS = ("paper", "grid")
#: ``"paper"``: the random training points of a one-dimensional situation space come from the
#: middle of the input range of this width (a fraction of the range; module docstring)
CENTRE_FRACTION = 0.6
#: GPR's prior mean by protocol (:class:`~seds_casadi.minigolf.parameters.GPRModel`):
#: ``"paper"``, zero, Eq. 17a as printed (no mean term; GPR "outputs zero far from the
#: training data", Section 5.2); ``"grid"``, the training outputs' mean, as before
GPR_PRIOR_MEAN = {"paper": "zero", "grid": "data"}

TABLE1_FIELDS = ("rough_flat", "double_hill", "arctan")
#: Training sets (label, size, kind) by the dimension of the field's situation space: one
#: (the hole along a slider: rough flat, double hill) or two (arctan, and the default
#: declaration: the ball anywhere in its region)
TRAINING_SETS = {
    1: [("5 random", 5, "random"), ("10 random", 10, "random"),
        ("10 equally spaced", 10, "spaced")],
    2: [("16 random", 16, "random"), ("28 equally spaced", 28, "spaced")],
}
#: ``"paper"``: as :data:`TRAINING_SETS`, the random points of the one-dimensional situation
#: spaces drawn from the centred range (kind ``"centred"``)
PAPER_TRAINING_SETS = {
    1: [("5 random", 5, "centred"), ("10 random", 10, "centred"),
        ("10 equally spaced", 10, "spaced")],
    2: TRAINING_SETS[2],
}
#: Models compared, by the number of outputs (alpha; or alpha and kappa)
MODELS_BY_OUTPUTS = {1: ("gpr", "gmr"), 2: ("gpr", "sep_gmr", "gmr")}
#: Gaussians of the GMMs, by the number of outputs
N_COMPONENTS = {1: 2, 2: 3}
N_TEST_SITUATIONS = 30
#: columns of ``table1.csv``: the RMSE of the hitting angle [deg] and of the hitting speed
#: kappa v* [m/s] (empty without a speed output), the success rate (a fraction), the model's
#: number of parameters, the repetitions averaged, and the spread across them: the standard
#: deviation and the 10 % and 90 % quantiles of the success rate, the standard deviation of
#: the angle's RMSE (one repetition's row: 1 and empty)
CSV_COLUMNS = ("field", "training", "model", "rmse_angle_deg", "rmse_speed_mps", "success_rate",
               "n_params", "repetitions", "success_std", "success_q10", "success_q90",
               "rmse_angle_std")

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
    model's number of parameters; the spread across the repetitions (NaN for one repetition's
    row): ``success_std``, ``success_q10``, ``success_q90`` and ``rmse_angle_std``.
    """

    field: str
    training: str
    model: str
    rmse_angle: float
    rmse_speed: float
    success_rate: float
    n_params: int
    repetitions: int = 1
    success_std: float = np.nan
    success_q10: float = np.nan
    success_q90: float = np.nan
    rmse_angle_std: float = np.nan


def simulated_field(field: Field) -> Field:
    """The field as the paper's simulator modelled it (Section 7.2.2): without the structure of
    the artificial grass.

    The paper's simulated fields ("Model of these fields", RobotToolKit, Section 7.2) left out
    "the dimples on the golf ball and the structure of the artificial grass covering the
    fields", which made its real-robot data sets "more complex" than the simulated ones. A
    ``"rough"`` surface is that structure (small random bumps and a rolling resistance that
    varies from place to place about the field's Stimpmeter value), so it becomes the plane it
    lies on, at the field's Stimpmeter value; every other surface (hills, arctan, planes,
    height maps), and everything else in the file, is kept.

    Parameters
    ----------
    field : Field

    Returns
    -------
    Field
        ``field`` itself when its surface is not ``"rough"``; else the same field (name, hole,
        walls, situations, teacher) on a plane.
    """
    if field.spec["surface"]["shape"] != "rough":
        return field
    spec = dict(field.spec)
    spec["surface"] = {"shape": "plane", "slope_x": 0.0, "slope_y": 0.0}
    return Field.from_dict(spec, source=f"{field.name} (as simulated: no grass structure)")


def centred_indices(situations: np.ndarray, fraction: float = CENTRE_FRACTION) -> np.ndarray:
    """Indices of the situations in the middle ``fraction`` of the input range: in every input
    that varies, within ``fraction / 2`` of the range's width from its midpoint (Fig. 10's
    black crosses come from such a range)."""
    S = np.atleast_2d(np.asarray(situations, float))
    if not (np.isfinite(fraction) and 0 < fraction <= 1):
        raise ValueError(f"the centred range must be a fraction in (0, 1], got {fraction}")
    lo, hi = S.min(axis=0), S.max(axis=0)
    span = hi - lo
    varies = span > 1e-9 * max(1.0, float(span.max()))
    off = np.abs(S - 0.5 * (lo + hi))[:, varies]
    # a relative tolerance: points on the range's edge by construction stay inside
    keep = np.all(off <= (0.5 * fraction * span[varies]) * (1 + 1e-9) + 1e-12, axis=1)
    return np.flatnonzero(keep)


def training_indices(situations: np.ndarray, size: int, kind: str,
                     rng: np.random.Generator,
                     centre_fraction: float = CENTRE_FRACTION) -> np.ndarray:
    """Indices of a training set: ``"random"`` (over the whole data set), ``"centred"`` (at
    random from the middle ``centre_fraction`` of the input range, :func:`centred_indices`) or
    ``"spaced"`` (module docstring)."""
    n = len(situations)
    if not 1 <= size < n:
        raise ValueError(f"a training set of {size} from {n} situations leaves no test points; "
                         f"use fewer training points or a larger data set")
    if kind == "random":
        return np.sort(rng.choice(n, size, replace=False))
    if kind == "centred":
        pool = centred_indices(situations, centre_fraction)
        if len(pool) < size:
            raise ValueError(f"the middle {centre_fraction:g} of the input range holds "
                             f"{len(pool)} of {n} situations, too few for {size} training "
                             f"points; widen the centred range or use fewer points")
        return np.sort(rng.choice(pool, size, replace=False))
    if kind != "spaced":
        raise ValueError(f"training kind must be 'random', 'centred' or 'spaced', got {kind!r}")
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
    sinking: SinkingSet | None = task.get("sinking")
    if sinking is not None:
        # the paper's noisy examples (Eq. 15): this repetition's draw from the sinking set
        Y = sinking.draw(rng, task["noise_spread"])[:, :Y.shape[1]]
    idx = training_indices(S, task["size"], task["kind"], rng, task["centre_fraction"])
    test = np.setdiff1d(np.arange(len(ds)), idx)
    balls, holes = field.situations.sample(N_TEST_SITUATIONS, rng)
    rows = []
    for name in task["models"]:
        kw = {"random_state": task["rep"]}
        if name != "gpr":
            kw["n_components"] = task["n_components"]
        else:
            kw["prior_mean"] = task["gpr_prior_mean"]
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
    """The training sets (label, size, kind) of a field under the ``"grid"`` protocol:
    :data:`TRAINING_SETS` for the dimension of the situations it declares."""
    return TRAINING_SETS[min(max(field.situations.dim, 1), 2)]


def training_sets(field: Field, name: str = "paper") -> list[tuple[str, int, str]]:
    """The training sets (label, size, kind) of a field under the protocol ``name``
    (:data:`PROTOCOLS`): :data:`PAPER_TRAINING_SETS` or :data:`TRAINING_SETS`."""
    _check_protocol(name)
    if name == "grid":
        return protocol(field)
    return PAPER_TRAINING_SETS[min(max(field.situations.dim, 1), 2)]


def _check_protocol(name: str) -> None:
    if name not in PROTOCOLS:
        raise ValueError(f"unknown Table 1 protocol {name!r}; valid: {', '.join(PROTOCOLS)}")


def run_table1(datasets: dict[str, tuple[Field, HittingDataset]], repetitions: int = 100,
               seed: int = 0, executor=None, progress: bool = False, protocol: str = "paper",
               sinking: dict[str, SinkingSet] | None = None, noise_spread: float = 1.0,
               centre_fraction: float = CENTRE_FRACTION, gpr_prior_mean: str | None = None
               ) -> tuple[list[Table1Row], list[Table1Row]]:
    """Run a protocol (module docstring).

    Parameters
    ----------
    datasets : dict
        Field name -> (field, data set); the field's situations pick the training sets
        (:func:`training_sets`), the data set's outputs the models
        (:data:`MODELS_BY_OUTPUTS`).
    repetitions : int
    seed : int
    executor : concurrent.futures.Executor, optional
        Where the repetitions run (default: this process).
    progress : bool
    protocol : {"paper", "grid"}, default "paper"
        ``"paper"``: noisy examples from the sinking set (Eq. 15) and random points from the
        centred range; ``"grid"``: the teacher's shots as they are and random points from the
        whole data set.
    sinking : dict, optional
        ``"paper"``: field name -> the sinking set of its data set
        (:func:`~seds_casadi.minigolf.sinking.sinking_set`); measured here when left out.
    noise_spread : float, default 1
        ``"paper"``: the examples are drawn uniformly over this middle fraction of each
        sinking interval (1: anywhere in it, the default; 0: its middle, no noise;
        :meth:`~seds_casadi.minigolf.sinking.SinkingSet.draw`).
    centre_fraction : float, default :data:`CENTRE_FRACTION`
        ``"paper"``: the width of the centred range the random training points of a
        one-dimensional situation space come from (a fraction of the input range).
    gpr_prior_mean : {"zero", "data"}, optional
        GPR's prior mean (:class:`~seds_casadi.minigolf.parameters.GPRModel`); default:
        :data:`GPR_PRIOR_MEAN` of the protocol (``"paper"``: zero, Eq. 17a as printed;
        ``"grid"``: the training outputs' mean, as before issue 33).

    Returns
    -------
    means : list of Table1Row
        One per (field, training, model), averaged over repetitions.
    runs : list of Table1Row
        Every repetition's rows.
    """
    if int(repetitions) < 1:
        raise ValueError(f"repetitions must be at least 1, got {repetitions}")
    _check_protocol(protocol)
    if not (np.isfinite(noise_spread) and 0 <= noise_spread <= 1):
        raise ValueError(f"noise_spread must be in [0, 1], got {noise_spread}")
    if not (np.isfinite(centre_fraction) and 0 < centre_fraction <= 1):
        raise ValueError(f"centre_fraction must be in (0, 1], got {centre_fraction}")
    prior_mean = GPR_PRIOR_MEAN[protocol] if gpr_prior_mean is None else gpr_prior_mean
    if prior_mean not in GPR_PRIOR_MEANS:
        raise ValueError(f"gpr_prior_mean must be one of {', '.join(GPR_PRIOR_MEANS)}, got "
                         f"{prior_mean!r}")
    sinking = dict(sinking or {})
    tasks = []
    for fname, (field, ds) in datasets.items():
        for label, size, kind in training_sets(field, protocol):
            if size >= len(ds):
                raise ValueError(f"{fname}: the data set has {len(ds)} situations, too few for "
                                 f"'{label}' (the teacher dropped {ds.dropped})")
            pool = len(centred_indices(ds.situations, centre_fraction))
            if kind == "centred" and pool < size:
                raise ValueError(f"{fname}: the middle {centre_fraction:g} of the input range "
                                 f"holds {pool} situations, too few for '{label}'; widen "
                                 f"centre_fraction")
    for fname, (field, ds) in datasets.items():
        n_out = ds.outputs.shape[1]
        noise = None
        if protocol == "paper":
            noise = sinking.get(fname)
            if noise is None:
                noise = sinking_set(Teacher(field, ds.stroke, ds.strategy), ds)
            if len(noise) != len(ds):
                raise ValueError(f"{fname}: the sinking set has {len(noise)} situations, the "
                                 f"data set {len(ds)}")
        for ti, (label, size, kind) in enumerate(training_sets(field, protocol)):
            for rep in range(int(repetitions)):
                tasks.append({"field": fname, "field_spec": field.spec, "dataset": ds,
                              "training": label, "size": size, "kind": kind, "rep": rep,
                              "models": MODELS_BY_OUTPUTS[n_out],
                              "n_components": N_COMPONENTS[n_out], "sinking": noise,
                              "noise_spread": float(noise_spread),
                              "centre_fraction": float(centre_fraction),
                              "gpr_prior_mean": prior_mean,
                              "seed": [int(seed), zlib.crc32(fname.encode()), ti, rep]})
    results = (executor.map(_repetition, tasks) if executor is not None
               else map(_repetition, tasks))
    results = progress_bar(results, progress, total=len(tasks), desc="Table 1 repetitions",
                           unit="rep")
    runs = [row for rows in results for row in rows]
    means = []
    for key in dict.fromkeys((r.field, r.training, r.model) for r in runs):
        rs = [r for r in runs if (r.field, r.training, r.model) == key]
        success = np.array([r.success_rate for r in rs])
        angle = np.array([r.rmse_angle for r in rs])
        means.append(Table1Row(*key, float(angle.mean()),
                               float(np.mean([r.rmse_speed for r in rs])),
                               float(success.mean()), rs[0].n_params, len(rs),
                               float(success.std(ddof=1)) if len(rs) > 1 else np.nan,
                               float(np.quantile(success, 0.1)),
                               float(np.quantile(success, 0.9)),
                               float(angle.std(ddof=1)) if len(rs) > 1 else np.nan))
    return means, runs


def paper_conclusions(rows: list[Table1Row]) -> dict[str, bool | None]:
    """The paper's conclusions from Table 1 (Section 7.2.1), checked on our means.

    Returns
    -------
    dict
        Conclusion -> whether it holds (None when the rows it needs are missing):
        ``"random: GMR >= GPR"`` (rough flat and double hill, 5 and 10 random points),
        ``"spaced: GPR >= GMR"`` (every field's equally spaced rows),
        ``"joint GMM >= separate GMMs"`` (success, every training set with both, and fewer
        parameters).
    """
    by = {(r.field, r.training, r.model): r for r in rows}

    def compare(pairs):
        pairs = [(by[a], by[b]) for a, b in pairs if a in by and b in by]
        return None if not pairs else all(x.success_rate >= y.success_rate for x, y in pairs)

    fields = dict.fromkeys(r.field for r in rows)
    random_pairs = [((f, t, "gmr"), (f, t, "gpr")) for f in ("rough_flat", "double_hill")
                    for t in ("5 random", "10 random")]
    spaced_pairs = [((f, t, "gpr"), (f, t, "gmr")) for f in fields
                    for t in dict.fromkeys(r.training for r in rows if r.field == f)
                    if "spaced" in t]
    joint_pairs = [((r.field, r.training, "gmr"), (r.field, r.training, "sep_gmr"))
                   for r in rows if r.model == "sep_gmr"]
    joint = compare(joint_pairs)
    if joint is not None:
        joint = joint and all(by[a].n_params < by[b].n_params for a, b in joint_pairs)
    return {"random: GMR >= GPR": compare(random_pairs),
            "spaced: GPR >= GMR": compare(spaced_pairs),
            "joint GMM >= separate GMMs": joint}


def _fmt(v, spec=".2f"):
    return "-" if v is None or (isinstance(v, float) and np.isnan(v)) else format(v, spec)


def rows_within(rows: list[Table1Row], tolerance: float = 0.1) -> tuple[int, int]:
    """(rows whose success rate is within ``tolerance`` of the paper's, rows the paper has)."""
    paired = [(r, PAPER_TABLE1[(r.field, r.training, r.model)]) for r in rows
              if (r.field, r.training, r.model) in PAPER_TABLE1]
    close = sum(abs(r.success_rate - p[2]) <= tolerance + 1e-9 for r, p in paired)
    return int(close), len(paired)


def format_table1(rows: list[Table1Row]) -> str:
    """Text table of our numbers beside the paper's, with the spread of the success rate
    across repetitions (standard deviation), the rows within 0.1 of the paper's success and
    the paper's conclusions checked (:func:`paper_conclusions`)."""
    head = (f"{'field':<12} {'training':<18} {'model':<8} {'e_alpha':>7} {'paper':>6} "
            f"{'e_v':>6} {'paper':>6} {'success':>7} {'sd':>5} {'paper':>6} {'#':>4} "
            f"{'paper':>5}")
    lines = [head, "-" * len(head)]
    for r in rows:
        p = PAPER_TABLE1.get((r.field, r.training, r.model), (np.nan,) * 4)
        lines.append(f"{r.field:<12} {r.training:<18} {r.model:<8} {_fmt(r.rmse_angle):>7} "
                     f"{_fmt(p[0]):>6} {_fmt(r.rmse_speed, '.3f'):>6} {_fmt(p[1]):>6} "
                     f"{_fmt(r.success_rate):>7} {_fmt(r.success_std):>5} {_fmt(p[2]):>6} "
                     f"{r.n_params:>4d} {_fmt(p[3], 'd') if not np.isnan(p[3]) else '-':>5}")
    lines.append("e_alpha: RMSE of the hitting angle [deg]; e_v: RMSE of the hitting speed "
                 "[m/s]; success: fraction of 30 random situations sunk (sd: its standard "
                 "deviation across repetitions); #: parameters.")
    close, total = rows_within(rows)
    if total:
        lines.append(f"{close} of {total} rows within 0.1 of the paper's success.")
    checks = [f"{k}: {'holds' if v else 'does not hold'}"
              for k, v in paper_conclusions(rows).items() if v is not None]
    if checks:
        lines.append("The paper's conclusions: " + "; ".join(checks) + ".")
    return "\n".join(lines) + "\n"


def write_table1_csv(rows: list[Table1Row], path: str | os.PathLike) -> None:
    """Write the rows with the columns :data:`CSV_COLUMNS` (``field, training, model,
    rmse_angle_deg, rmse_speed_mps, success_rate, n_params, repetitions, success_std,
    success_q10, success_q90, rmse_angle_std``; atomically: a partial file never appears under
    the final name; a value that does not apply, as the speed of an angle-only model or the
    spread of one repetition: empty)."""

    def cell(v):
        return "" if isinstance(v, float) and np.isnan(v) else v

    atomic_csv(path, CSV_COLUMNS,
               ([r.field, r.training, r.model, r.rmse_angle, cell(r.rmse_speed),
                 r.success_rate, r.n_params, r.repetitions, cell(r.success_std),
                 cell(r.success_q10), cell(r.success_q90), cell(r.rmse_angle_std)]
                for r in rows))
