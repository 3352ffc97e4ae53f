"""A quadratic Lyapunov function V(x) = (x - x*)^T P (x - x*) estimated from data (issue 14).

SEDS certifies stability with P = I: the distance to the target must fall along every trajectory,
so it cannot follow a motion that first moves away from the target. LPV-DS (Figueroa and
Billard, CoRL 2018) learns P first, from the data alone, as the P under which the demonstrated
velocities decrease V the most consistently, then fits the dynamics. Our learner with
``lyapunov="learned"`` optimises P jointly with the GMM (see
:mod:`seds_casadi.core.parametrization`); :func:`estimate_lyapunov` gives it its starting P, the
data-only estimate in the LPV-DS sense:

    min_P  mean_i max(0, cos_P,i)^2 + rho ||P - I||_F^2 / d^2,
    cos_P,i = (x_i - x*)^T P xdot_i / (|x_i - x*| |xdot_i|),

over P = d M / tr(M), M = L L^T (the normalisation of the parametrization), solved by IPOPT
with exact derivatives. The penalty is the part of each sample's velocity that increases V.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

__all__ = ["estimate_lyapunov", "LYAPUNOV_DIAG_RANGE"]

#: bounds on the diagonal of L_P (P = d L L^T / tr(L L^T)); with the off-diagonal bounds of
#: :func:`seds_casadi.core.problem._bounds` they keep P's condition number finite
LYAPUNOV_DIAG_RANGE = (0.05, 20.0)
#: weight of the pull towards P = I (breaks the ties when many P fit the data equally)
REGULARISATION = 1e-3


def estimate_lyapunov(X: np.ndarray, Xd: np.ndarray, max_iter: int = 200) -> np.ndarray:
    """P (symmetric positive definite, trace d) under which the data decrease V most consistently.

    Parameters
    ----------
    X : array, shape (n, d)
        Positions in the attractor frame (x* at the origin).
    Xd : array, shape (n, d)
        Velocities.
    max_iter : int
        IPOPT's iteration limit.

    Returns
    -------
    array, shape (d, d)
        The estimate; the identity when it does not improve on it or IPOPT fails.
    """
    X = np.asarray(X, dtype=float)
    Xd = np.asarray(Xd, dtype=float)
    d = X.shape[1]
    r, v = np.linalg.norm(X, axis=1), np.linalg.norm(Xd, axis=1)
    ok = (r > 1e-12 * max(r.max(), 1e-300)) & (v > 1e-12 * max(v.max(), 1e-300))
    if ok.sum() < d + 1:
        return np.eye(d)
    U, W = X[ok] / r[ok, None], Xd[ok] / v[ok, None]
    Z = np.einsum("ni,nj->nij", U, W).reshape(len(U), d * d)  # cos_i = Z_i . vec(P)
    tril = [(i, j) for i in range(d) for j in range(i + 1)]
    z = ca.SX.sym("z", len(tril))
    L = ca.SX.zeros(d, d)
    for idx, (i, j) in enumerate(tril):
        L[i, j] = ca.exp(z[idx]) if i == j else z[idx]
    P = (d / ca.sumsqr(L)) * (L @ L.T)
    # the samples enter as one matrix product in an MX graph (an SX graph would hold n
    # nodes per sample: 0.15 s to build on 2,000 samples, longer than the solve)
    zm = ca.MX.sym("z", len(tril))
    Pm = ca.Function("P", [z], [P])(zm)
    c = ca.mtimes(ca.DM(Z), ca.reshape(Pm.T, d * d, 1))
    J = ca.sumsqr(ca.fmax(c, 0)) / len(U) + REGULARISATION * ca.sumsqr(Pm - ca.MX.eye(d)) / d**2
    z_sx, z = z, zm
    lo, hi = np.log(LYAPUNOV_DIAG_RANGE[0]), np.log(LYAPUNOV_DIAG_RANGE[1])
    lbx = np.array([lo if i == j else -10.0 for i, j in tril])
    ubx = np.array([hi if i == j else 10.0 for i, j in tril])
    solver = ca.nlpsol("seds_lyapunov", "ipopt", {"x": z, "f": J},
                       {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes",
                        "ipopt.max_iter": int(max_iter), "ipopt.tol": 1e-10})
    Jf = ca.Function("J", [z], [J])
    z0 = np.zeros(len(tril))
    res = solver(x0=z0, lbx=lbx, ubx=ubx)
    zs = np.asarray(res["x"]).ravel()
    if not (np.all(np.isfinite(zs)) and float(Jf(zs)) < float(Jf(z0))):
        return np.eye(d)
    Pn = np.asarray(ca.Function("P", [z_sx], [P])(zs))
    return 0.5 * (Pn + Pn.T)
