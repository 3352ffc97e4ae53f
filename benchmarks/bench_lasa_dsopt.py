"""Benchmark: our SEDS under the published LASA protocol, beside the published figures.

Runs the ds-opt protocol (nbfigueroa/ds-opt ``evaluation-scripts/evaluate_SEDS.m``; see
:mod:`seds_casadi.app.lasa`): the 26 single-pattern shapes, demos 1-4 train and 5-7 test, every
2nd sample, SEDS with the ``mse`` objective, K by BIC on [x; xdot] (ds-opt's elbow rule, up to 15)
or given, and ds-opt's RMSE, e_dot and DTWD. Prints each shape's figures beside the published
SEDS ones, the means beside the published SEDS and LPV-DS means, the worst shapes, and the fit
times (median, the slowest), and writes ``lasa_dsopt.csv`` and ``summary.txt`` to ``--out``.

Usage::

    python benchmarks/bench_lasa_dsopt.py                       # 26 shapes, K by BIC
    python benchmarks/bench_lasa_dsopt.py -K 5 --workers 2      # a fixed K
    python benchmarks/bench_lasa_dsopt.py -K published          # the published runs' K per shape
    python benchmarks/bench_lasa_dsopt.py --shapes Angle CShape -K 3
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from seds_casadi.app.lasa import dsopt_table, run_lasa
from seds_casadi.core.datasets import LASA_SINGLE_SHAPES
from seds_casadi.core.model_selection import BIC_RULES
from seds_casadi.core.settings import OBJECTIVES


def _components(text: str) -> int | str:
    return text if text in ("bic", "published") else int(text)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shapes", nargs="+", default=list(LASA_SINGLE_SHAPES),
                    help="a subset of the 26 single-pattern shapes [all 26]")
    ap.add_argument("-K", "--components", type=_components, default="bic",
                    help="K, 'bic' or 'published' [bic]")
    ap.add_argument("--k-max", type=int, default=15, help="largest K of the BIC search [15]")
    ap.add_argument("--bic-rule", choices=BIC_RULES, default="ds-opt",
                    help="K at the elbow of the BIC curve (ds-opt) or at its minimum [ds-opt]")
    ap.add_argument("--objectives", nargs="+", choices=OBJECTIVES, default=["mse"])
    ap.add_argument("--workers", type=int, default=1, help="local worker processes [1]")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--figures", action="store_true", help="also draw one figure per shape")
    ap.add_argument("--out", default="bench_lasa_dsopt_out", help="output folder")
    a = ap.parse_args(argv)

    t0 = time.perf_counter()
    results = run_lasa(shapes=a.shapes, objectives=a.objectives, protocols=["ds-opt"],
                       n_components=a.components, random_state=a.seed, out_dir=a.out,
                       figures=a.figures, workers=a.workers, k_max=a.k_max,
                       bic_rule=a.bic_rule, progress=False)
    wall = time.perf_counter() - t0
    print(dsopt_table(results))
    test = [r for r in results if r.set == "test"]
    secs = np.array([r.seconds for r in test])
    ks = np.array([r.n_components for r in test])
    slow = sorted(test, key=lambda r: -r.seconds)[:3]
    print(f"fit time over {len(test)} fits: median {np.median(secs):.1f} s, mean "
          f"{secs.mean():.1f} s, max {secs.max():.1f} s; slowest: "
          + ", ".join(f"{r.shape} (K={r.n_components}) {r.seconds:.0f} s" for r in slow))
    if any(r.seconds_k for r in test):
        print(f"BIC search: median {np.median([r.seconds_k for r in test]):.1f} s per shape")
    print(f"K: median {np.median(ks):g}, range {ks.min()}-{ks.max()} ({test[0].k_choice})")
    print(f"wall time {wall / 60:.1f} min with {a.workers} worker(s); wrote "
          f"{os.path.join(a.out, 'lasa_dsopt.csv')}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
