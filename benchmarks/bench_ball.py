"""Benchmark: simulated shots per second in batch, and a 100 x 100 (alpha, kappa) success map.

The engines side by side on the same shots: the compiled engine as used by default (backend
"simd" where the step translates: a vectorised C loop, else CasADi's kernel), CasADi's
generated-C kernel (backend "casadi", the previous default), and the numpy reference (a subset
of the shots, since it is slower), with the ratios. Shots start from
random ball positions towards the hole with random speeds and angles.
Targets from the issue: >= 50,000 shots/s in batch, a 100 x 100 map in <= 0.5 s.
Rates are the median of ``--repeats`` runs after a warm-up, the engines alternating.

Usage: python benchmarks/bench_ball.py [--fields flat double_hill arctan rough_flat]
                                       [-n 20000] [--dt 0.01] [--repeats 3]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from seds_casadi.minigolf import Stroke, success_map
from seds_casadi.minigolf.ball import simulate_shots
from seds_casadi.minigolf.ball_kernel import BallKernel, ball_kernel
from seds_casadi.minigolf.fields import load_field


def shots(field, n, rng):
    r = field.ball_region
    B = np.column_stack([rng.uniform(r[0], r[1], n), rng.uniform(r[2], r[3], n)])
    d = field.hole - B
    ang = np.arctan2(d[:, 1], d[:, 0]) + np.deg2rad(rng.uniform(-8, 8, n))
    spd = rng.uniform(1.2, 3.0, n)
    return B, np.column_stack([spd * np.cos(ang), spd * np.sin(ang)])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fields", nargs="+", default=["flat", "double_hill", "arctan", "rough_flat"])
    ap.add_argument("-n", type=int, default=20000)
    ap.add_argument("--n-numpy", type=int, default=2000, help="shots for the numpy engine")
    ap.add_argument("--dt", type=float, default=0.01)
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per engine (median)")
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    stroke = Stroke(np.array([1.0, 0.0, 0.0]), 1.0)
    print(f"{'field':<12} {'backend':>7} {'build s':>7} {'default/s':>10} {'casadi/s':>9} "
          f"{'numpy/s':>8} {'x casadi':>8} {'x numpy':>7} {'sunk':>6} {'agree':>6} "
          f"{'map 100x100 s':>14}")
    for name in args.fields:
        f = load_field(name)
        t0 = time.perf_counter()
        kern = ball_kernel(f, args.dt)  # build/compile (cached on disk after the first time)
        build = time.perf_counter() - t0
        peer = BallKernel(f, args.dt, backend="casadi")
        B, V = shots(f, args.n, rng)
        # warm-up (threads, first touch of the libraries), then the median of --repeats runs
        # of each engine, alternating so that both see the same machine load
        simulate_shots(f, B[:1000], V[:1000], dt=args.dt, engine="compiled")
        peer.run(B[:1000], V[:1000], 20.0)
        t_c, t_k = [], []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            fast = simulate_shots(f, B, V, dt=args.dt, engine="compiled")
            t_c.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            slow = peer.run(B, V, 20.0)
            t_k.append(time.perf_counter() - t0)
        rate_c, rate_k = args.n / np.median(t_c), args.n / np.median(t_k)
        assert np.array_equal(slow.sunk, fast.sunk), "backends disagree"
        m = args.n_numpy
        t0 = time.perf_counter()
        ref = simulate_shots(f, B[:m], V[:m], dt=args.dt, engine="numpy")
        rate_n = m / (time.perf_counter() - t0)
        agree = np.mean(ref.sunk == fast.sunk[:m])
        ball = np.array([(f.ball_region[0] + f.ball_region[1]) / 2, 0.0])
        alphas = np.deg2rad(np.linspace(-30, 30, 100))
        kappas = np.linspace(0.8, 2.4, 100)
        t0 = time.perf_counter()
        success_map(f, stroke, ball, f.hole, alphas, kappas, engine="compiled")
        tmap = time.perf_counter() - t0
        print(f"{name:<12} {kern.backend:>7} {build:7.2f} {rate_c:10.0f} {rate_k:9.0f} "
              f"{rate_n:8.0f} {rate_c / rate_k:8.1f} {rate_c / rate_n:7.1f} "
              f"{fast.success_rate:6.1%} {agree:6.1%} {tmap:14.2f}", flush=True)


if __name__ == "__main__":
    main()
