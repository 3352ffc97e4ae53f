"""Direction objective (Eq. 9): does the returned model move at the demonstrated speeds? (issue 13)

For every LASA shape, SEDS with the direction objective (default K, 100 samples per
demonstration) is fitted with each speed calibration of the learner (``speed_calibration``:
"strength", the default: a strength factor v(x) along the certified streamlines, Eq. 12;
"median", one factor on the gains; "least-squares", the first default) in the same run. Printed per
shape and calibration: the median over the demonstrations' samples of the speed ratio
|f(x_i)| / |xdot_i| (target: within [0.8, 1.25]) with its 10th and 90th percentiles, and whether
every reproduction from a demonstration's start reaches the target (within 1 % of the shape's
extent) in at most 3x that demonstration's duration (RK4, 500 steps per duration).

Usage::

    python benchmarks/eval_direction_speeds.py [--shapes Angle CShape ...] [-K 5]
    python benchmarks/eval_direction_speeds.py --figure docs/direction_speeds.png --shapes WShape

``--figure PATH`` draws, for the first shape, the reproductions of each calibration over the
demonstrations and the speed along them against time.
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


def figure(shape: str, K: int, calibrations: list[str], path: str,
           n_samples: int = 100) -> None:
    """Reproductions and speed against time, per calibration, for one shape."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    demos = load_lasa(shape, n_samples=n_samples)
    raw, _, dt_raw = load_lasa_raw(shape)
    duration = dt_raw * (len(raw[0]) - 1)
    fig, axes = plt.subplots(2, len(calibrations), figsize=(4.6 * len(calibrations), 7.4),
                             squeeze=False)
    X = np.concatenate(demos.positions)
    extent = float(np.max(X.max(0) - X.min(0)))
    for j, c in enumerate(calibrations):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = SEDS(K, objective="direction", random_state=0,
                         speed_calibration=c).fit(demos).model_
        ax, axs = axes[0, j], axes[1, j]
        for n, (p, v) in enumerate(zip(demos.positions, demos.velocities)):
            t = np.linspace(0.0, duration, len(p))
            ax.plot(p[:, 0], p[:, 1], color="tab:red", lw=1.4,
                    label="demonstrations" if n == 0 else None)
            axs.plot(t, np.linalg.norm(v, axis=1), color="tab:red", lw=1.2,
                     label="demonstrations" if n == 0 else None)
            dt = duration / 500
            repro, info = model.rollout(p[0], dt=dt, max_steps=int(3 * 500), tol=0.01 * extent,
                                       return_info=True, warn=False)
            ax.plot(repro[:, 0], repro[:, 1], color="tab:blue", lw=1.1, ls="--",
                    label="reproductions (3x the duration)" if n == 0 else None)
            ax.plot(*repro[-1], "o", ms=4, color="tab:green" if info["converged"][0] else "k")
            ts = dt * np.arange(len(repro))
            axs.plot(ts, np.linalg.norm(model.predict(repro), axis=1), color="tab:blue",
                     lw=1.0, ls="--", label="reproductions" if n == 0 else None)
        r = evaluate(shape, K, c, n_samples)
        ax.plot(*model.target, "k*", ms=10)
        ax.set_title(f"{shape}, speed_calibration={c!r}\n{r['reached']}/{r['demos']} reach the "
                     "target within 3x the duration", fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        ax.legend(fontsize=7, loc="best")
        axs.axvline(duration, color="0.5", lw=0.8, ls=":")
        axs.set_xlabel("time [s] (dotted: the demonstration's duration)")
        axs.set_ylabel("speed [mm/s]")
        axs.set_title(f"speed ratio model/demo: median {r['median']:.2f}, "
                      f"p10-p90 {r['p10']:.2f}-{r['p90']:.2f}", fontsize=9)
        axs.set_xlim(0, 3 * duration)
        axs.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shapes", nargs="+", default=list(LASA_SHAPES))
    ap.add_argument("-K", type=int, default=5)
    ap.add_argument("--calibrations", nargs="+", default=["strength", "median", "least-squares"])
    ap.add_argument("--figure", default=None, metavar="PATH",
                    help="only draw the first shape's reproductions and speeds to PATH")
    a = ap.parse_args(argv)
    if a.figure:
        figure(a.shapes[0], a.K, a.calibrations[:2], a.figure)
        return 0
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
