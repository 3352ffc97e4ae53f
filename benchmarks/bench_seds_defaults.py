"""Benchmark (issue 29): what ``SEDS()`` with no settings gives, on LASA and on 3-D / 7-D motions.

Two parts, each printed as a table:

``--lasa`` (default): the ds-opt protocol (:mod:`seds_casadi.app.lasa`: 26 single-pattern
shapes, demos 1-4 train, 5-7 test, every 2nd sample, ds-opt's RMSE, e_dot and DTWD on the test
demos), in one run and alternating shape by shape:

* ``SEDS(random_state=0)`` given only the training demonstrations (the new default: the
  automatic settings and K chosen by :func:`~seds_casadi.core.model_selection.choose_by_reproduction`),
* the old default, ``SEDS(5, objective="direction", lyapunov="identity", init="joint-em",
  gmm="joint", gain_limit=None)`` (``--no-before`` skips it),
* the dsopt LPV-DS peer (``--dsopt-path``, a clone of SunannnSun/dsopt; cvxpy must import, e.g.
  from ``--peer-lib``, a folder added at the end of ``sys.path``) with the published runs' K.

Fit times include the choice of K; every fit single-threaded (``OMP_NUM_THREADS=1`` is set
before numpy loads).

``--own``: 3-D minimum-jerk arcs, 3-D helical approaches and 7-D joint-space reaching motions
of our own (:func:`arcs_3d`, :func:`helix_3d`, :func:`reaching_7d`), fitted with
``SEDS(random_state=0)``; the fit report (:func:`~seds_casadi.core.report.fit_report`) per
demonstration: reached, peak speed ratio.

Usage::

    python benchmarks/bench_seds_defaults.py --dsopt-path /tmp/dsopt --peer-lib /tmp/peerlib
    python benchmarks/bench_seds_defaults.py --own --no-lasa
    python benchmarks/bench_seds_defaults.py --shapes Angle JShape --no-before
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402

from seds_casadi import SEDS, Demonstrations  # noqa: E402
from seds_casadi.app.lasa import PUBLISHED_SEDS, dsopt_scores, dsopt_sets  # noqa: E402
from seds_casadi.core.datasets import LASA_SINGLE_SHAPES  # noqa: E402
from seds_casadi.core.errors import ConvergenceWarning  # noqa: E402

#: the old default (before issue 29), every setting spelt out
BEFORE = dict(n_components=5, objective="direction", lyapunov="identity", init="joint-em",
              gmm="joint", gain_limit=None)
#: published LPV-DS PC-GMM O2 test means (RMSE, e_dot, DTWD), the issue's target
LPV_O2 = (5.19, 0.062, 1749.0)
PUBLISHED_SEDS_MEANS = (6.34, 0.099, 3954.0)


def min_jerk(t: np.ndarray) -> np.ndarray:
    """The minimum-jerk profile s(t) = 10 t^3 - 15 t^4 + 6 t^5 on t in [0, 1]."""
    return 10 * t**3 - 15 * t**4 + 6 * t**5


def arcs_3d(n_demos: int = 5, n_samples: int = 150, duration: float = 1.5, seed: int = 0,
            noise: float = 5e-4) -> Demonstrations:
    """3-D minimum-jerk arcs [m] into the origin: each from its own start (0.3-0.5 m away),
    bulging sideways and up by 0.05-0.12 m, with position noise."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 1, n_samples)
    s = min_jerk(t)
    pos = []
    for _ in range(n_demos):
        r = rng.uniform(0.3, 0.5)
        az, el = rng.uniform(-0.6, 0.6), rng.uniform(0.1, 0.5)
        x0 = r * np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
        side = np.cross(x0, [0, 0, 1.0])
        side /= np.linalg.norm(side)
        bulge = rng.uniform(0.05, 0.12) * side + rng.uniform(0.0, 0.06) * np.array([0, 0, 1.0])
        p = (1 - s)[:, None] * x0 + (np.sin(np.pi * s))[:, None] * bulge
        pos.append(p + noise * rng.standard_normal(p.shape) * (1 - s)[:, None])
    return Demonstrations(pos, dt=duration / (n_samples - 1))


def reaching_7d(n_demos: int = 5, n_samples: int = 200, duration: float = 2.0, seed: int = 1
                ) -> Demonstrations:
    """7-D joint-space reaching [rad]: minimum-jerk from 5 start configurations to a target
    (a WAM-like home), each joint with its own curvature (a via-point bump)."""
    rng = np.random.default_rng(seed)
    target = np.array([0.0, -1.2, 0.0, 2.2, 0.0, 0.3, 0.0])
    t = np.linspace(0, 1, n_samples)
    s = min_jerk(t)
    pos = []
    for _ in range(n_demos):
        q0 = target + rng.uniform(-0.9, 0.9, 7)
        bump = rng.uniform(-0.25, 0.25, 7)
        pos.append(target + (1 - s)[:, None] * (q0 - target)
                   + np.sin(np.pi * s)[:, None] * bump)
    return Demonstrations(pos, dt=duration / (n_samples - 1))


def helix_3d(n_demos: int = 4, n_samples: int = 180, duration: float = 2.0, seed: int = 3
             ) -> Demonstrations:
    """3-D helical approaches [m] into the origin: 1.25 turns about the vertical axis at a
    shrinking radius (0.15-0.25 m at the start) while descending from 0.2-0.35 m, minimum-jerk
    in time (made to test the choice of K: its score is not smooth in K here)."""
    rng = np.random.default_rng(seed)
    s = min_jerk(np.linspace(0, 1, n_samples))
    pos = []
    for _ in range(n_demos):
        r0, phase, z0 = rng.uniform(0.15, 0.25), rng.uniform(0, 2 * np.pi), rng.uniform(0.2, 0.35)
        ang = phase + 2.5 * np.pi * s
        pos.append(np.c_[(1 - s) * r0 * np.cos(ang), (1 - s) * r0 * np.sin(ang), (1 - s) * z0])
    return Demonstrations(pos, dt=duration / (n_samples - 1))


def _cert(model) -> bool:
    c = model.certificate
    return bool(c["max_eig_lyapunov"] < 0 and c["min_eig_cov"] > 0)


def _fit(learner, demos):
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        model = learner.fit(demos).model_
    return model, time.perf_counter() - t0


def run_lasa(shapes, seed: int, before: bool, peer) -> None:
    if peer is not None:  # warm-up: imports and caches
        peer(dsopt_sets(shapes[0])["train"], 4, seed)
    SEDS(6, random_state=seed).fit(dsopt_sets(shapes[0])["train"].demonstrations())
    cols = ["auto"] + (["before"] if before else []) + (["peer"] if peer else [])
    print("ds-opt protocol, test demos; RMSE [mm/s] / e_dot / DTWD [mm], fit s (the choice "
          "included), K")
    rows = {c: [] for c in cols}
    for shape in shapes:
        sets = dsopt_sets(shape)
        train = sets["train"].demonstrations()
        line = f"{shape:<17}"
        for c in cols:
            if c == "peer":
                f, sec, cert = peer(sets["train"], int(PUBLISHED_SEDS[shape][0]), seed)
                K = int(PUBLISHED_SEDS[shape][0])
            else:
                learner = SEDS(random_state=seed) if c == "auto" else SEDS(random_state=seed,
                                                                           **BEFORE)
                model, sec = _fit(learner, train)
                f, cert, K = model.predict, _cert(model), model.n_components
            sc = dsopt_scores(f, sets["test"])[:3]
            rows[c].append((shape, sc, sec, cert, K))
            line += f" | {c}: {sc[0]:6.2f} {sc[1]:6.3f} {sc[2]:7.0f} {sec:5.2f}s K={K}"
            line += "" if cert else " UNCERT"
        print(line, flush=True)
    print()
    for c in cols:
        S = np.array([r[1] for r in rows[c]])
        secs = np.array([r[2] for r in rows[c]])
        over = sum(int(r[1][i] > 1.5 * PUBLISHED_SEDS[r[0]][4 + i]) for r in rows[c]
                   for i in range(3))
        print(f"{c:<7} means {S[:, 0].mean():.2f} / {S[:, 1].mean():.3f} / {S[:, 2].mean():.0f}"
              f", certified {sum(r[3] for r in rows[c])}/{len(S)}, shape-metrics above 1.5x "
              f"published SEDS {over}, fit median {np.median(secs):.2f} s (mean "
              f"{secs.mean():.2f}, max {secs.max():.2f}), K median "
              f"{np.median([r[4] for r in rows[c]]):g}")
    print(f"published LPV-DS PC-GMM O2 {LPV_O2[0]} / {LPV_O2[1]} / {LPV_O2[2]:.0f}; published "
          f"SEDS {PUBLISHED_SEDS_MEANS[0]} / {PUBLISHED_SEDS_MEANS[1]} / "
          f"{PUBLISHED_SEDS_MEANS[2]:.0f}")
    if peer is not None:
        ta = np.array([r[2] for r in rows["auto"]])
        tp = np.array([r[2] for r in rows["peer"]])
        print(f"fit time: median ours {np.median(ta):.2f} s, peer {np.median(tp):.2f} s, ratio "
              f"of medians ours/peer {np.median(ta) / np.median(tp):.2f}")


def run_own(seed: int) -> None:
    for name, demos in (("3-D minimum-jerk arcs", arcs_3d()), ("3-D helical approaches",
                                                                helix_3d()),
                        ("7-D joint-space reaching", reaching_7d())):
        learner = SEDS(random_state=seed)
        model, sec = _fit(learner, demos)
        rep = learner.report(demos)
        print(f"\n{name}: {demos}; SEDS() K = {model.n_components}, {sec:.2f} s, certified "
              f"{_cert(model)}")
        print(rep)
        ratios = [r.speed_ratio for r in rep.rows]
        print(f"summary: reached {sum(r.reached for r in rep.rows)}/{len(rep.rows)}, peak speed "
              f"ratios {min(ratios):.2f}-{max(ratios):.2f}")


def _peer_fitter(path: str, lib: str | None):
    if lib:
        sys.path.append(lib)
    sys.path.insert(0, os.path.join(os.path.dirname(__file__)))
    from bench_dsopt_peer import _fit_peer, _peer_class

    cls = _peer_class(path)
    return lambda train, K, seed: _fit_peer(cls, train, K, seed)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shapes", nargs="+", default=list(LASA_SINGLE_SHAPES))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-lasa", action="store_true", help="skip the LASA part")
    ap.add_argument("--no-before", action="store_true", help="skip the old default")
    ap.add_argument("--own", action="store_true", help="also the 3-D and 7-D motions")
    ap.add_argument("--dsopt-path", default=None, help="a clone of SunannnSun/dsopt [no peer]")
    ap.add_argument("--peer-lib", default=None, help="a folder holding cvxpy (appended to "
                                                     "sys.path)")
    a = ap.parse_args(argv)
    if not a.no_lasa:
        peer = _peer_fitter(a.dsopt_path, a.peer_lib) if a.dsopt_path else None
        run_lasa(a.shapes, a.seed, not a.no_before, peer)
    if a.own:
        run_own(a.seed)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
