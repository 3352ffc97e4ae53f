"""Benchmark: SEDS fit time against the dimension d and K on synthetic smooth demonstrations.

Five demonstrations of 200 samples (1,000 in all) per dimension, each a smooth start-to-target
curve with a random bend; direction objective; the default Hessian strategy (``"auto"``: exact up
to 80 parameters, L-BFGS above). ``--cold`` uses an empty kernel cache, so the first fit of each
(d, K) includes compiling its C kernels.

Usage: python benchmarks/bench_seds_scale.py [--dims 2 3 7] [-K 3 5] [--cold]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
import warnings

import numpy as np


def demos(d: int, n_demos: int = 5, n_samples: int = 200, seed: int = 0):
    from seds_casadi import Demonstrations

    rng = np.random.default_rng(seed)
    s = 3 * np.linspace(0, 1, n_samples)[:, None] ** 2 - 2 * np.linspace(0, 1, n_samples)[:, None] ** 3
    pos = [rng.standard_normal(d) * (1 - s) + 0.5 * rng.standard_normal(d) * np.sin(np.pi * s)
           for _ in range(n_demos)]
    return Demonstrations(pos, dt=0.01)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dims", type=int, nargs="+", default=[2, 3, 7])
    ap.add_argument("-K", type=int, nargs="+", default=[3, 5])
    ap.add_argument("--cold", action="store_true", help="empty kernel cache (compile included)")
    args = ap.parse_args()
    if args.cold:
        os.environ["SEDS_CASADI_CACHE"] = tempfile.mkdtemp(prefix="seds_cold_")
    from seds_casadi import SEDS, SolverError

    print(f"{'d':>3} {'K':>3} {'params':>6} {'hessian':>15} {'seconds':>8} {'iter':>5} "
          f"{'mean cos':>8}  status")
    for d in args.dims:
        data = demos(d)
        for K in args.K:
            t0 = time.perf_counter()
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    m = SEDS(K, random_state=0).fit(data).model_
            except SolverError as exc:
                print(f"{d:>3} {K:>3} {'':>6} {'':>15} {time.perf_counter() - t0:8.1f} "
                      f"{'':>5} {'':>8}  SolverError: {str(exc)[:60]}")
                continue
            i = m.fit_info
            print(f"{d:>3} {K:>3} {i['n_parameters']:>6} {i['hessian']:>15} "
                  f"{time.perf_counter() - t0:8.1f} {i['iterations']:>5} {-i['objective']:8.3f}"
                  f"  {i['status']}", flush=True)


if __name__ == "__main__":
    main()
