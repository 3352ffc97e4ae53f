"""Benchmark (issue 13): our SEDS against the dsopt LPV-DS peer, same data, same process.

The peer is SunannnSun/dsopt (``dsopt_class.py``, convex: P by a cvxpy problem on the
components' mean directions, then every A_k by a semidefinite program with
A_k^T P + P A_k <= -1e-3 I). It needs a GMM's responsibilities: as in LPV-DS with EM-GMM, a
full-covariance GMM on the positions (scikit-learn, same K, same seed), its posterior as the
mixing function. Both fit the training set of the ds-opt LASA protocol
(:func:`seds_casadi.app.lasa.dsopt_sets`: demos 1-4, every 2nd sample) and are scored the same
way on the test set (demos 5-7: ds-opt's RMSE, e_dot, DTWD). The peer's models are checked
against its own condition (P > 0 and every A_k^T P + P A_k < 0); ours are certified by the fit.

Times: our fit is SEDS's ``fit`` with warm caches (one untimed fit first, so the compiled
problem is on disk); the peer's is GMM + P + A. Both single-threaded on the same machine,
alternating shape by shape.

The peer is not shipped (it has no licence file): clone it and install cvxpy::

    git clone https://github.com/SunannnSun/dsopt /tmp/dsopt && pip install cvxpy
    python benchmarks/bench_dsopt_peer.py --dsopt-path /tmp/dsopt            # 26 shapes, K = 4
    python benchmarks/bench_dsopt_peer.py --dsopt-path /tmp/dsopt --shapes Angle CShape -K 3
    python benchmarks/bench_dsopt_peer.py --dsopt-path /tmp/dsopt -K 6 --ours pc-fixed
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import sys
import time
import warnings

import numpy as np

from seds_casadi import SEDS
from seds_casadi.app.lasa import dsopt_scores, dsopt_sets
from seds_casadi.core.datasets import LASA_SINGLE_SHAPES
from seds_casadi.core.errors import ConvergenceWarning


def _peer_class(path: str):
    if not os.path.isfile(os.path.join(path, "dsopt_class.py")):
        raise SystemExit(f"error: no dsopt_class.py in {path!r}: clone "
                         "https://github.com/SunannnSun/dsopt and pass its folder as --dsopt-path")
    try:
        import cvxpy  # noqa: F401
    except ImportError:
        raise SystemExit("error: the peer needs cvxpy: pip install cvxpy") from None
    sys.path.insert(0, path)
    from dsopt_class import dsopt_class

    return dsopt_class


def _fit_peer(dsopt_class, train, K: int, seed: int):
    """GMM on the positions, then the peer's P and A; returns (predict, seconds, certified)."""
    from sklearn.mixture import GaussianMixture

    X, V = np.concatenate(train.positions), np.concatenate(train.velocities)
    t0 = time.perf_counter()
    gmm = GaussianMixture(K, covariance_type="full", random_state=seed).fit(X)
    gamma = gmm.predict_proba(X).T
    ds = dsopt_class(X, V, np.zeros((1, X.shape[1])), gamma, gamma.argmax(axis=0))
    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # cvxpy's "may be inaccurate": counted
        A = np.asarray(ds.begin())
    seconds = time.perf_counter() - t0
    P = np.asarray(ds.P)
    certified = bool(np.linalg.eigvalsh(P).min() > 0 and all(
        np.linalg.eigvalsh(Ak.T @ P + P @ Ak).max() < 0 for Ak in A))

    def predict(Y):
        Y = np.atleast_2d(Y)
        g = gmm.predict_proba(Y)
        return np.einsum("nk,kij,nj->ni", g, A, Y)

    return predict, seconds, certified


#: our learner's settings, by ``--ours``: SEDS as published (joint EM, joint fit, P = I), or a
#: physically-consistent GMM kept fixed with a learned P (LPV-DS's split in our NLP)
OURS = {"seds": {},
        "pc-fixed": {"lyapunov": "learned", "gain_limit": 10.0, "init": "pc", "gmm": "fixed"}}


def _fit_ours(train, K: int, seed: int, ours: str = "seds"):
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        model = SEDS(K, objective="mse", random_state=seed,
                     **OURS[ours]).fit(train.demonstrations()).model_
    seconds = time.perf_counter() - t0
    c = model.certificate
    return model.predict, seconds, bool(c["max_eig_lyapunov"] < 0 and c["min_eig_cov"] > 0)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dsopt-path", required=True, help="a checkout of SunannnSun/dsopt")
    ap.add_argument("--shapes", nargs="+", default=list(LASA_SINGLE_SHAPES))
    ap.add_argument("-K", type=int, default=4, help="components, both methods [4]")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--ours", choices=list(OURS), default="seds",
                    help="our learner's settings: SEDS (P = I, joint fit), or init='pc', "
                         "gmm='fixed' with a learned P and gain_limit=10 [seds]")
    a = ap.parse_args(argv)
    dsopt_class = _peer_class(a.dsopt_path)
    # warm-up: the compiled SEDS problem for this K lands in the cache, cvxpy imports
    _fit_ours(dsopt_sets(a.shapes[0])["train"], a.K, a.seed, a.ours)
    _fit_peer(dsopt_class, dsopt_sets(a.shapes[0])["train"], a.K, a.seed)
    rows = []
    print(f"ds-opt protocol, test demos, K = {a.K}, ours = {a.ours}; "
          "RMSE [mm/s] / e_dot / DTWD [mm], fit s")
    print(f"{'shape':<17} {'SEDS (ours)':>27} {'s':>6} {'cert':>4} | {'dsopt peer':>27} "
          f"{'s':>6} {'cert':>4} | peer/ours")
    for shape in a.shapes:
        sets = dsopt_sets(shape)
        f_o, t_o, c_o = _fit_ours(sets["train"], a.K, a.seed, a.ours)
        f_p, t_p, c_p = _fit_peer(dsopt_class, sets["train"], a.K, a.seed)
        s_o, s_p = dsopt_scores(f_o, sets["test"])[:3], dsopt_scores(f_p, sets["test"])[:3]
        rows.append((shape, s_o, t_o, c_o, s_p, t_p, c_p))
        print(f"{shape:<17} {s_o[0]:8.2f} {s_o[1]:7.3f} {s_o[2]:10.0f} {t_o:6.2f} {c_o!s:>4} | "
              f"{s_p[0]:8.2f} {s_p[1]:7.3f} {s_p[2]:10.0f} {t_p:6.2f} {c_p!s:>4} | "
              f"{t_p / t_o:5.2f}", flush=True)
    so = np.array([r[1] for r in rows])
    sp = np.array([r[4] for r in rows])
    to, tp = np.array([r[2] for r in rows]), np.array([r[5] for r in rows])
    print(f"\nmeans over {len(rows)} shapes: ours RMSE {so[:, 0].mean():.2f}, e_dot "
          f"{so[:, 1].mean():.3f}, DTWD {so[:, 2].mean():.0f}, certified "
          f"{sum(r[3] for r in rows)}/{len(rows)}; peer RMSE {sp[:, 0].mean():.2f}, e_dot "
          f"{sp[:, 1].mean():.3f}, DTWD {sp[:, 2].mean():.0f}, its own condition holds "
          f"{sum(r[6] for r in rows)}/{len(rows)}")
    print(f"fit time median: ours {np.median(to):.2f} s, peer {np.median(tp):.2f} s; "
          f"median of per-shape ratios peer/ours {np.median(tp / to):.2f} "
          f"(ours {'faster' if np.median(tp / to) > 1 else 'slower'})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
