"""Benchmark: simulated shots per second in batch, and a 100 x 100 (alpha, kappa) success map.

Shots start at the ball region's centre towards the hole; launch speeds and directions vary.
Targets from the issue: >= 50,000 shots/s in batch, a 100 x 100 map in <= 0.5 s.

Usage: python benchmarks/bench_ball.py [--fields flat double_hill arctan rough_flat] [-n 10000]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from seds_casadi.ball import simulate_shots
from seds_casadi.fields import load_field


def shots(field, n, rng):
    r = field.ball_region
    ball = np.array([(r[0] + r[1]) / 2, (r[2] + r[3]) / 2])
    to_hole = field.hole - ball
    base = np.arctan2(to_hole[1], to_hole[0])
    ang = base + np.deg2rad(rng.uniform(-8, 8, n))
    spd = rng.uniform(1.5, 3.0, n)
    return np.tile(ball, (n, 1)), np.column_stack([spd * np.cos(ang), spd * np.sin(ang)])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fields", nargs="+", default=["flat", "double_hill", "arctan", "rough_flat"])
    ap.add_argument("-n", type=int, default=10000)
    ap.add_argument("--dt", type=float, default=0.002)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    print(f"{'field':<12} {'shots':>7} {'seconds':>8} {'shots/s':>9} {'sunk':>6} "
          f"{'map 100x100 s':>14}")
    for name in args.fields:
        f = load_field(name)
        B, V = shots(f, args.n, rng)
        t0 = time.perf_counter()
        res = simulate_shots(f, B, V, dt=args.dt)
        sec = time.perf_counter() - t0
        a, k = np.meshgrid(np.deg2rad(np.linspace(-8, 8, 100)), np.linspace(1.5, 3.0, 100))
        ball = B[0]
        to_hole = f.hole - ball
        base = np.arctan2(to_hole[1], to_hole[0])
        Vm = np.column_stack([k.ravel() * np.cos(base + a.ravel()),
                              k.ravel() * np.sin(base + a.ravel())])
        t0 = time.perf_counter()
        simulate_shots(f, np.tile(ball, (len(Vm), 1)), Vm, dt=args.dt)
        tmap = time.perf_counter() - t0
        print(f"{name:<12} {args.n:>7} {sec:8.2f} {args.n / sec:9.0f} {res.success_rate:6.1%} "
              f"{tmap:14.2f}", flush=True)


if __name__ == "__main__":
    main()
