"""Benchmark: SEDS fit time on LASA, and a SciPy baseline on the same problem, side by side.

Part 1 fits the direction objective at the default number of Gaussians (K=5) on LASA shapes with
100 samples per demonstration and prints the time of each fit, the median, and e_dot on the
training data. The first fit of a given (K, d, objective) compiles the kernels (cached on disk
afterwards); that one-off cost is printed separately.

Part 2 solves the *same* problem (same parametrization, data, scaling, bounds and start) with
``scipy.optimize.minimize(method="SLSQP")`` and finite-difference gradients on the numpy objective,
as a Python user without this library would, and prints the speed ratio and both objectives.

Usage: python benchmarks/bench_seds_fit.py [--shapes Angle CShape ...] [--baseline-shapes ...]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from oracles import seds_objective as objective_numpy  # noqa: E402  (a plain numpy objective)
from scipy.optimize import minimize

from seds_casadi import SEDS, ConvergenceWarning
from seds_casadi.core.datasets import LASA_SINGLE_SHAPES, load_lasa
from seds_casadi.core.metrics import direction_error


def fit_times(shapes, K, n_samples):
    rows = []
    for s in shapes:
        demos = load_lasa(s, n_samples=n_samples)
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            m = SEDS(K, objective="direction", random_state=0).fit(demos).model_
        sec = time.perf_counter() - t0
        X, V = np.concatenate(demos.positions), np.concatenate(demos.velocities)
        rows.append((s, sec, m.fit_info["iterations"], direction_error(m.predict(X), V),
                     m.fit_info["status"]))
        print(f"  {s:<18} {sec:6.2f} s  {m.fit_info['iterations']:4d} it  "
              f"e_dot {rows[-1][3]:.4f}  {m.fit_info['status']}", flush=True)
    return rows


def baseline(shape, K, n_samples, objective):
    demos = load_lasa(shape, n_samples=n_samples)
    seds = SEDS(K, objective=objective, random_state=0)
    prob = seds.build_problem(demos)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        model = seds.fit(demos).model_
    t_ours = time.perf_counter() - t0
    J_ours = model.fit_info["objective"]

    def f(th):
        return objective_numpy(th, prob.layout, prob.X, prob.Xd, prob.weights, objective,
                               prob.margin)

    bounds = list(zip(np.where(np.isfinite(prob.lbx), prob.lbx, None),
                      np.where(np.isfinite(prob.ubx), prob.ubx, None)))
    t0 = time.perf_counter()
    res = minimize(f, prob.theta0, method="SLSQP", bounds=bounds,
                   options={"maxiter": 1000, "ftol": 1e-10})
    t_scipy = time.perf_counter() - t0
    return t_ours, J_ours, t_scipy, float(res.fun), int(res.nit)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shapes", nargs="+", default=list(LASA_SINGLE_SHAPES))
    ap.add_argument("--baseline-shapes", nargs="+", default=["Angle", "CShape", "GShape"])
    ap.add_argument("-K", type=int, default=5)
    ap.add_argument("--samples", type=int, default=100)
    ap.add_argument("--skip-baseline", action="store_true", help="only part 1")
    args = ap.parse_args()

    print(f"Part 1: direction objective, K={args.K}, {args.samples} samples per demonstration")
    t0 = time.perf_counter()
    warm = load_lasa("Angle", n_samples=args.samples)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        SEDS(args.K, random_state=0).fit(warm)
    print(f"  first fit incl. kernel compilation (or cache load): {time.perf_counter() - t0:.2f} s")
    rows = fit_times(args.shapes, args.K, args.samples)
    secs = np.array([r[1] for r in rows])
    print(f"  median fit time {np.median(secs):.2f} s over {len(rows)} shapes "
          f"(mean {secs.mean():.2f} s, max {secs.max():.2f} s)")
    named = [r for r in rows if r[0] in ("Angle", "CShape", "GShape")]
    if named:
        print("  e_dot on training data: " + ", ".join(f"{r[0]} {r[3]:.4f}" for r in named)
              + f"; mean {np.mean([r[3] for r in named]):.4f}")

    if args.skip_baseline:
        return
    print("\nPart 2: same problem, SciPy SLSQP with finite-difference gradients (same start)")
    print(f"  {'shape':<10} {'objective':<10} {'ours s':>8} {'scipy s':>8} {'ratio':>7} "
          f"{'J ours':>12} {'J scipy':>12}")
    for s in args.baseline_shapes:
        for obj in ("direction", "mse"):
            t_o, J_o, t_s, J_s, _ = baseline(s, args.K, args.samples, obj)
            print(f"  {s:<10} {obj:<10} {t_o:8.2f} {t_s:8.2f} {t_s / t_o:7.1f} {J_o:12.6f} "
                  f"{J_s:12.6f}{'' if J_o <= J_s + 1e-6 * abs(J_s) else '  (scipy lower)'}",
                  flush=True)


if __name__ == "__main__":
    main()
