"""Choosing SEDS's settings on held-out demonstrations (leave one demonstration out).

SEDS's optimum depends on choices the data cannot make inside one fit: the objective (Eq. 9 with
its strength factor, Eq. 12, or the mean squared velocity error), the Lyapunov function
(V = |x - x*|^2 or a learned P), K, a gain limit. A lower training objective does not mean a
better model (on LASA the better optimum of two starts was the worse model on the test demos;
``benchmarks/README.md``). :class:`DemoSearchCV` chooses among candidate settings the way a
careful user would: fit on all demonstrations but one, reproduce the one left out from its
start, score it, repeat for each, and refit the best candidate on all of them. The held-out
scores are the three of the published LASA evaluation (ds-opt; :mod:`seds_casadi.core.metrics`):

* ``rmse``: velocity RMSE on the held-out demonstration's samples (units of the velocities),
* ``e_dot``: mean |1 - cos| between model and demonstrated velocities,
* ``dtw``: DTW distance between the reproduction (forward Euler from the held-out start until
  slow, :func:`~seds_casadi.core.metrics.simulate_until_slow`) and the demonstration.

The three have different units, so ``scoring="reproduction"`` (the default) combines them
without weights chosen by us: each candidate's mean over folds divided by the best candidate's,
and the geometric mean of the three ratios (a candidate 10 % worse than the best on every metric
scores -log 1.1). A reproduction that fails (a fold whose fit raised a :class:`SEDSError`)
scores -inf. This is our choice where the literature offers none; a single metric or a callable
can be used instead.

The folds are demonstrations, never samples: samples of one demonstration are strongly
correlated, and a sample-wise split measures interpolation, not generalisation.
"""

from __future__ import annotations

import logging
import time
import warnings

import casadi as ca
import numpy as np
from sklearn.base import BaseEstimator, clone
from sklearn.model_selection import ParameterGrid

from .demonstrations import Demonstrations
from .errors import ConvergenceWarning, SEDSError
from .metrics import pointwise_direction_error, reproduction_dtw, velocity_rmse

__all__ = ["DemoSearchCV", "demo_folds", "held_out_scores", "METRICS", "SCORINGS"]

_LOG = logging.getLogger(__name__)

#: the held-out metrics (lower is better), in the order of the tables
METRICS = ("rmse", "e_dot", "dtw")
#: built-in values of ``scoring``
SCORINGS = ("reproduction",) + METRICS


def demo_folds(n_demos: int, cv="loo") -> list[tuple[list[int], list[int]]]:
    """Train and held-out demonstration indices of each fold.

    Parameters
    ----------
    n_demos : int
        Number of demonstrations (at least 2).
    cv : "loo" or int, default "loo"
        ``"loo"``: each demonstration held out once (n_demos folds). An int k: k folds, the
        demonstrations dealt round-robin (demonstration n in fold n mod k).

    Returns
    -------
    list of (train, test)
    """
    n = int(n_demos)
    if n < 2:
        raise ValueError(f"choosing on held-out demonstrations needs at least 2 of them, got "
                         f"{n}; record more demonstrations or fit one setting directly")
    if isinstance(cv, str):
        if cv != "loo":
            raise ValueError(f"cv must be 'loo' or a number of folds, got {cv!r}")
        k = n
    elif isinstance(cv, bool) or not isinstance(cv, (int, np.integer)):
        raise TypeError(f"cv must be 'loo' or an int, got {type(cv).__name__}")
    else:
        k = int(cv)
        if not 2 <= k <= n:
            raise ValueError(f"cv = {k} folds for {n} demonstrations: use 2..{n}")
    folds = []
    for f in range(k):
        test = [i for i in range(n) if i % k == f]
        folds.append(([i for i in range(n) if i % k != f], test))
    return folds


def held_out_scores(model, demos: Demonstrations, dt: float | None = None,
                    speed_tol: float | None = None, max_steps: int | None = None,
                    start_index: int = 0, return_paths: bool = False,
                    substeps: int | None = None) -> dict:
    """RMSE, e_dot and DTW of a fitted model on demonstrations it has not seen.

    Parameters
    ----------
    model : StableDS, SEDS or callable
        Anything with ``predict``, or the velocity field itself, (n, d) -> (n, d), in the
        caller's coordinates (e.g. a peer's model).
    demos : Demonstrations
        The held-out set (same target as the model).
    dt : float, optional
        Forward-Euler step of the reproductions. Default: the demonstrations' time step
        (:meth:`Demonstrations.estimated_dt`).
    speed_tol : float, optional
        A reproduction stops once every velocity component is below this for 4 steps (the
        LASA evaluation's rule; 0.1 mm/s there). Default: 1e-3 times the fastest demonstrated
        velocity component.
    max_steps : int, optional
        Step limit. Default: three times the longest demonstration's duration.
    start_index : int, default 0
        The reproductions start at this sample of each demonstration (the LASA evaluation
        starts at the 20th, index 19).

    return_paths : bool, default False
        Also return the reproductions under ``"paths"``, shape (steps, demos, d).
    substeps : int, optional
        Sub-steps per step of ``dt`` (:func:`~seds_casadi.core.metrics.simulate_until_slow`).
        Default: 1 forward-Euler step for a plain callable; for a model with ``stiffness()`` (a
        :class:`StableDS` or a fitted :class:`SEDS`) RK4 sub-steps of at most 0.25 / stiffness
        (at most 1,000), the step of the fit report's rollouts
        (:func:`~seds_casadi.core.report.fit_report`), so that a stiff candidate is judged on its
        motion, not on the integrator's error at a coarse data rate. The reproduction is still
        sampled every ``dt``, so candidates are compared on the same DTW. Given explicitly, the
        sub-steps are forward Euler: pass 1 to reproduce a published protocol literally (the
        ds-opt LASA evaluation does).

    Returns
    -------
    dict
        ``rmse``, ``e_dot``, ``dtw`` (each the mean over the demonstrations), ``steps``,
        ``substeps`` and ``peak_speeds`` (each reproduction's largest speed, sub-steps
        included; :func:`~seds_casadi.core.metrics.simulate_until_slow`).
    """
    predict = getattr(model, "predict", model)
    pos = [p + demos.target for p in demos.shifted_positions]
    X, V = np.concatenate(pos), np.concatenate(demos.velocities)
    F = np.asarray(predict(X), dtype=float)
    if dt is None or max_steps is None:
        data_dt = demos.estimated_dt()
        dt = data_dt if dt is None else dt
        if max_steps is None:
            max_steps = int(np.ceil(3 * max(len(p) for p in pos) * data_dt / dt))
    if speed_tol is None:
        speed_tol = 1e-3 * float(np.max(np.abs(V)))
    max_steps = max(int(max_steps), 5)
    method = "euler"
    if substeps is None:
        substeps = reproduction_substeps(model, float(dt))
        method = "rk4" if _rate(model) > 0 else "euler"
    starts = np.stack([p[min(int(start_index), len(p) - 1)] for p in pos])
    dtw, paths, peaks = reproduction_dtw(_field(model, predict, X.shape[1]), starts, pos,
                                         return_paths=True, dt=float(dt),
                                         speed_tol=float(speed_tol), max_steps=max_steps,
                                         window=4, substeps=int(substeps), return_peaks=True,
                                         method=method)
    out = {"rmse": velocity_rmse(F, V),
           "e_dot": float(np.mean(pointwise_direction_error(F, V, min_norm_product=0.0))),
           "dtw": float(np.mean(dtw)), "steps": int(len(paths)), "substeps": int(substeps),
           "peak_speeds": peaks}
    if return_paths:
        out["paths"] = paths
    return out


class DemoSearchCV(BaseEstimator):
    """Pick a learner's settings by leave-one-demonstration-out reproduction, then refit.

    scikit-learn's ``GridSearchCV`` for demonstrations: each candidate of ``param_grid`` is
    fitted on all demonstrations but the held-out ones, scored by how its reproductions and
    velocities match them (module docstring), and the best is refitted on every demonstration.

    Parameters
    ----------
    estimator : SEDS
        The learner with the settings common to every candidate (cloned, never fitted itself).
    param_grid : dict or list of dict
        Candidate settings, as ``GridSearchCV``'s (``{"objective": ["mse", "direction"],
        "lyapunov": ["learned"]}`` makes two candidates).
    scoring : {"reproduction", "rmse", "e_dot", "dtw"} or callable, default "reproduction"
        How candidates are compared (higher score is better). A metric name: minus its mean
        over folds. ``"reproduction"``: minus the mean log ratio of the three metrics to the
        best candidate's (module docstring). A callable ``scoring(model, held_out) -> float``
        (higher better) is averaged over folds.
    cv : "loo" or int, default "loo"
        Folds of demonstrations (:func:`demo_folds`).
    refit : bool, default True
        Fit the best candidate on all demonstrations (``best_estimator_``, ``model_``).
    dt, speed_tol, max_steps, start_index, substeps
        The held-out reproductions' settings (:func:`held_out_scores`; by default the data's
        step, with Euler sub-steps for stiff candidates).
    verbose : int, default 0
        1: a progress line per fit (logger ``seds_casadi.core.search``, INFO).

    Attributes
    ----------
    cv_results_ : dict of arrays
        ``params``; for each metric ``mean_<metric>`` and ``split<i>_<metric>``;
        ``mean_test_score``, ``rank_test_score``, ``mean_fit_time`` [s], ``n_failed`` (folds
        whose fit raised) and ``n_unconverged`` (IPOPT stopped at its limits; the model is
        certified and scored all the same).
    best_index_ : int
    best_params_ : dict
    best_score_ : float
    best_estimator_ : SEDS
        Only with ``refit=True``.
    model_ : StableDS
        ``best_estimator_.model_``; its ``fit_info["search"]`` records the candidates' scores.
    """

    def __init__(self, estimator=None, param_grid=None, scoring="reproduction", cv="loo",
                 refit: bool = True, dt: float | None = None, speed_tol: float | None = None,
                 max_steps: int | None = None, start_index: int = 0, verbose: int = 0,
                 substeps: int | None = None) -> None:
        self.estimator = estimator
        self.param_grid = param_grid
        self.scoring = scoring
        self.cv = cv
        self.refit = refit
        self.dt = dt
        self.speed_tol = speed_tol
        self.max_steps = max_steps
        self.start_index = start_index
        self.verbose = verbose
        self.substeps = substeps

    # ------------------------------------------------------------------ fitting
    def _candidates(self) -> list[dict]:
        if self.estimator is None or not hasattr(self.estimator, "fit"):
            raise TypeError("DemoSearchCV needs an estimator, e.g. "
                            "DemoSearchCV(SEDS(4, objective='mse'), param_grid={...})")
        grid = self.param_grid
        if grid is None or (isinstance(grid, dict | list) and len(grid) == 0):
            raise ValueError("param_grid is empty: give the settings to choose from, e.g. "
                             "{'objective': ['mse', 'direction']}")
        cands = list(ParameterGrid(grid))
        valid = set(self.estimator.get_params())
        for c in cands:
            bad = sorted(set(c) - valid)
            if bad:
                raise ValueError(f"param_grid names {bad}, which {type(self.estimator).__name__} "
                                 f"does not have; valid: {', '.join(sorted(valid))}")
        if not (callable(self.scoring) or self.scoring in SCORINGS):
            raise ValueError(f"unknown scoring {self.scoring!r}; valid: {', '.join(SCORINGS)} "
                             "or a callable (model, held_out) -> float")
        return cands

    def fit(self, X, y=None) -> DemoSearchCV:
        """Score every candidate on every fold, choose, and refit.

        Parameters
        ----------
        X : Demonstrations
            Time-ordered demonstrations (at least 2; their reproductions are scored).
        y : None
            Ignored (scikit-learn's signature).
        """
        if not isinstance(X, Demonstrations):
            raise TypeError(f"DemoSearchCV.fit expects a seds_casadi.Demonstrations, got "
                            f"{type(X).__name__}; wrap trajectories with Demonstrations(...)")
        if not X.time_ordered:
            raise ValueError("DemoSearchCV scores reproductions, so the demonstrations must be "
                             "trajectories in time order, not Demonstrations.from_samples")
        cands = self._candidates()
        folds = demo_folds(X.n_demos, self.cv)
        n_c, n_f = len(cands), len(folds)
        metrics = {m: np.full((n_c, n_f), np.inf) for m in METRICS}
        custom = np.full((n_c, n_f), -np.inf)
        seconds = np.zeros((n_c, n_f))
        failed, unconverged, errors = np.zeros(n_c, int), np.zeros(n_c, int), {}
        t_start = time.perf_counter()
        for c, params in enumerate(cands):
            for f, (train, test) in enumerate(folds):
                est = clone(self.estimator).set_params(**params)
                t0 = time.perf_counter()
                try:
                    with warnings.catch_warnings(record=True) as caught:
                        warnings.simplefilter("always", ConvergenceWarning)
                        est.fit(X.select(train))
                    unconverged[c] += any(issubclass(w.category, ConvergenceWarning)
                                          for w in caught)
                except SEDSError as exc:  # a candidate that fails loses; the search goes on
                    failed[c] += 1
                    errors.setdefault(c, f"{type(exc).__name__}: {exc}")
                    seconds[c, f] = time.perf_counter() - t0
                    self._log(c, n_c, f, n_f, params, None, seconds[c, f])
                    continue
                seconds[c, f] = time.perf_counter() - t0
                held = X.select(test)
                s = held_out_scores(est.model_, held, self.dt, self.speed_tol, self.max_steps,
                                    self.start_index, substeps=self.substeps)
                for m in METRICS:
                    metrics[m][c, f] = s[m]
                if callable(self.scoring):
                    custom[c, f] = float(self.scoring(est.model_, held))
                self._log(c, n_c, f, n_f, params, s, seconds[c, f])
        score = self._scores(metrics, custom)
        if not np.any(np.isfinite(score)):
            raise SEDSError("every candidate failed on some fold: " + "; ".join(
                f"{cands[c]}: {e}" for c, e in errors.items()))
        order = np.argsort(-np.where(np.isfinite(score), score, -np.inf), kind="stable")
        rank = np.empty(n_c, int)
        rank[order] = np.arange(1, n_c + 1)
        res: dict = {"params": cands}
        for m in METRICS:
            res[f"mean_{m}"] = metrics[m].mean(axis=1)
            for f in range(n_f):
                res[f"split{f}_{m}"] = metrics[m][:, f]
        res.update(mean_test_score=score, rank_test_score=rank,
                   mean_fit_time=seconds.mean(axis=1), n_failed=failed,
                   n_unconverged=unconverged, errors=[errors.get(c, "") for c in range(n_c)])
        self.cv_results_ = res
        self.best_index_ = int(order[0])
        self.best_params_ = dict(cands[self.best_index_])
        self.best_score_ = float(score[self.best_index_])
        self.n_splits_ = n_f
        self.search_seconds_ = time.perf_counter() - t_start
        if self.refit:
            best = clone(self.estimator).set_params(**self.best_params_)
            self.best_estimator_ = best.fit(X)
            self.best_estimator_.model_.fit_info["search"] = {
                "best_params": {k: _plain(v) for k, v in self.best_params_.items()},
                "candidates": [{k: _plain(v) for k, v in p.items()} for p in cands],
                "mean_test_score": [_finite(v) for v in score],
                **{f"mean_{m}": [_finite(v) for v in res[f"mean_{m}"]] for m in METRICS},
                "folds": n_f, "scoring": self.scoring if isinstance(self.scoring, str)
                else getattr(self.scoring, "__name__", "callable")}
        return self

    def _scores(self, metrics: dict, custom: np.ndarray) -> np.ndarray:
        if callable(self.scoring):
            return custom.mean(axis=1)
        means = {m: metrics[m].mean(axis=1) for m in METRICS}
        if self.scoring in METRICS:
            return -means[self.scoring]
        logs = []
        for m in METRICS:
            v = means[m]
            best = np.min(v[np.isfinite(v)]) if np.any(np.isfinite(v)) else np.inf
            floor = 1e-12 * max(1.0, abs(best)) if np.isfinite(best) else 0.0
            with np.errstate(invalid="ignore", divide="ignore"):
                logs.append(np.log((v + floor) / (best + floor)))
        out = -np.mean(logs, axis=0)
        return np.where(np.isnan(out), -np.inf, out)

    def _log(self, c, n_c, f, n_f, params, s, sec) -> None:
        if not self.verbose:
            return
        what = ("failed" if s is None else
                f"RMSE {s['rmse']:.4g}, e_dot {s['e_dot']:.3f}, DTW {s['dtw']:.4g}")
        _LOG.info("candidate %d/%d %s, fold %d/%d: %s (%.1f s)", c + 1, n_c, params, f + 1, n_f,
                  what, sec)

    # ------------------------------------------------------------------ the chosen model
    def _best(self):
        best = getattr(self, "best_estimator_", None)
        if best is None:
            from sklearn.exceptions import NotFittedError

            raise NotFittedError("DemoSearchCV is not fitted (or was fitted with refit=False): "
                                 "call fit(demos) first")
        return best

    @property
    def model_(self):
        """The chosen, refitted model (a certified :class:`StableDS`)."""
        return self._best().model_

    def predict(self, X) -> np.ndarray:
        """f(x) of the chosen model."""
        return self._best().predict(X)

    def table(self) -> str:
        """The candidates' held-out means, best first, as text."""
        res = self.cv_results_
        lines = [f"{'rank':>4} {'score':>8} {'RMSE':>9} {'e_dot':>7} {'DTW':>9} {'fit s':>6}  "
                 "params"]
        for c in np.argsort(res["rank_test_score"]):
            note = f"  ({res['n_failed'][c]} folds failed)" if res["n_failed"][c] else ""
            lines.append(f"{res['rank_test_score'][c]:>4} {res['mean_test_score'][c] + 0.0:>8.3f} "
                         f"{res['mean_rmse'][c]:>9.4g} {res['mean_e_dot'][c]:>7.3f} "
                         f"{res['mean_dtw'][c]:>9.4g} {res['mean_fit_time'][c]:>6.1f}  "
                         f"{res['params'][c]}{note}")
        return "\n".join(lines)


def _field(model, predict, d: int):
    """The model's CasADi Function x (d,) -> f(x) (d,), the expression its ``predict``
    evaluates (a :class:`StableDS`, or a fitted SEDS's), which
    :func:`~seds_casadi.core.metrics.simulate_until_slow` integrates many steps per call; else
    ``predict`` itself."""
    inner = getattr(model, "model_", model)
    get = getattr(inner, "_function", None)
    if callable(get) and getattr(inner, "predict", None) is not None:
        f = get()
        if (isinstance(f, ca.Function) and f.n_in() == 1 and f.n_out() == 1
                and f.nnz_in(0) == d and f.nnz_out(0) == d):
            return f
    return predict


#: the reproductions' sub-step h keeps h * stiffness at most this (RK4: the fit report's
#: rollouts use the same step, so that both measure the same reproductions; at 1.0 a 20 Hz
#: hitting motion's peak speeds read 0.74-0.94 of what a 1 ms rollout gives)
RK4_STEP_RATE = 0.25


def _rate(model) -> float:
    """The model's stiffness (0 without one)."""
    model = getattr(model, "model_", model)  # a fitted SEDS holds its StableDS
    stiffness = getattr(model, "stiffness", None)
    if not callable(stiffness):
        return 0.0
    rate = float(stiffness())
    return rate if np.isfinite(rate) and rate > 0 else 0.0


def reproduction_substeps(model, dt: float, max_substeps: int = 1000) -> int:
    """RK4 sub-steps that keep dt / n * stiffness <= RK4_STEP_RATE (1 without a stiffness)."""
    rate = _rate(model)
    return int(min(max_substeps, max(1, np.ceil(dt * rate / RK4_STEP_RATE))))


def _finite(v) -> float | None:
    """A float for JSON: None for a failed candidate's infinite score."""
    return float(v) if np.isfinite(v) else None


def _plain(v):
    """A JSON-friendly copy of a parameter value (model files record the search)."""
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, dict | list | tuple | str | int | float | bool) or v is None:
        return v
    return repr(v)

