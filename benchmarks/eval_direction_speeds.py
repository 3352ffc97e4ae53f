"""Direction objective (Eq. 9): does the returned model move at the demonstrated speeds? (issue 13)

For every LASA shape, SEDS with the direction objective (default K, 100 samples per
demonstration) is fitted with each speed calibration of the learner (``speed_calibration``:
"median", the default, and "least-squares", the former default) in the same run. Printed per
shape and calibration: the median over the demonstrations' samples of the speed ratio
|f(x_i)| / |xdot_i| (target: within [0.8, 1.25]) with its 10th and 90th percentiles, and whether
every reproduction from a demonstration's start reaches the target (within 1 % of the shape's
extent) in at most 3x that demonstration's duration (RK4, 500 steps per duration).

Usage::

    python benchmarks/eval_direction_speeds.py [--shapes Angle CShape ...] [-K 5]
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

from seds_casadi import SEDS
from seds_casadi.core import load_lasa
from seds_casadi.core.datasets import LASA_SHAPES, load_lasa_raw


def evaluate(shape: str, K: int, calibration: str, n_samples: int = 100) -> dict:
    demos = load_lasa(shape, n_samples=n_samples)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        model = SEDS(K, objective="direction", random_state=0,
                     speed_calibration=calibration).fit(demos).model_
        seconds = time.perf_counter() - t0
    X = np.concatenate(demos.positions)
    V = np.concatenate(demos.velocities)
    nf, nv = np.linalg.norm(model.predict(X), axis=1), np.linalg.norm(V, axis=1)
    moving = nv > 1e-9 * nv.max()
    ratio = nf[moving] / nv[moving]
    extent = float(np.max(X.max(0) - X.min(0)))
    reached = []
    raw, _, dt_raw = load_lasa_raw(shape)
    for p, full in zip(demos.positions, raw):
        duration = dt_raw * (len(full) - 1)
        dt = duration / 500
        _, info = model.rollout(p[0], dt=dt, max_steps=int(np.ceil(3 * duration / dt)),
                                tol=0.01 * extent, return_info=True, warn=False)
        reached.append(bool(info["converged"][0]))
    return {"median": float(np.median(ratio)), "p10": float(np.percentile(ratio, 10)),
            "p90": float(np.percentile(ratio, 90)), "reached": sum(reached),
            "demos": len(reached), "seconds": seconds}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shapes", nargs="+", default=list(LASA_SHAPES))
    ap.add_argument("-K", type=int, default=5)
    ap.add_argument("--calibrations", nargs="+", default=["median", "least-squares"])
    a = ap.parse_args(argv)
    rows = {c: [] for c in a.calibrations}
    print(f"{'shape':<20} " + " | ".join(f"{c + ': ratio (p10-p90) reached':<40}"
                                          for c in a.calibrations))
    for s in a.shapes:
        cells = []
        for c in a.calibrations:
            r = evaluate(s, a.K, c)
            rows[c].append(r)
            cells.append(f"{r['median']:5.2f} ({r['p10']:.2f}-{r['p90']:.2f}) "
                         f"{r['reached']}/{r['demos']} {r['seconds']:5.1f} s".ljust(40))
        print(f"{s:<20} " + " | ".join(cells), flush=True)
    for c in a.calibrations:
        rs = rows[c]
        med = np.array([r["median"] for r in rs])
        inside = int(np.sum((med >= 0.8) & (med <= 1.25)))
        allreach = sum(r["reached"] == r["demos"] for r in rs)
        print(f"{c}: median ratio within [0.8, 1.25] on {inside}/{len(rs)} shapes (range "
              f"{med.min():.2f}-{med.max():.2f}); every reproduction reached the target in 3x "
              f"the duration on {allreach}/{len(rs)} shapes "
              f"({sum(r['reached'] for r in rs)}/{sum(r['demos'] for r in rs)} reproductions); "
              f"median fit {np.median([r['seconds'] for r in rs]):.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
