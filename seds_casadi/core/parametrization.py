"""How the SEDS parameters are laid out in the optimisation vector, and the numpy side of it.

The constraints of Eq. 10 are satisfied *by construction* (the issue lets us choose; we choose
this because it makes every IPOPT iterate a stable model and the problem smooth):

* (d), (e) priors: ``pi = softmax(l)`` with the last logit fixed to 0 (so pi_k in (0, 1), sum 1);
* (c) ``Sigma_x^k = L_k L_k^T`` with ``L_k`` lower triangular and ``diag(L_k) = exp(.)`` > 0;
* (b) ``A_k = Sigma_xdotx^k (Sigma_x^k)^-1 = -(B_k B_k^T + m I) + (W_k - W_k^T)``, with ``B_k`` lower
  triangular (positive diagonal), ``W_k`` strictly lower triangular and ``m > 0`` the stability
  margin, so ``A_k + A_k^T = -2 (B_k B_k^T + m I)`` is negative definite. Every matrix whose
  symmetric part is negative definite (with that margin) has this form, so nothing is lost;
* (a) ``mu_xdot^k = A_k (mu_x^k - x*)``, i.e. each component's linear model vanishes at x*;
* (c) the rest of the joint covariance, ``Sigma_xdot^k = A_k Sigma_x^k A_k^T + Q_k``, ``Q_k`` positive
  definite (optimised for the likelihood objective, estimated from residuals otherwise).

All quantities are in the *scaled attractor frame*: x* at the origin, positions divided by one
scalar ``sx`` and velocities by one scalar ``sv``. A scalar scaling keeps A_k + A_k^T < 0 (a
per-axis scaling would not), so the certificate holds in the caller's units too.

The parametrization is defined once, in CasADi (:func:`unpack_casadi`); :func:`unpack_numpy`
evaluates it. The objectives are in :mod:`seds_casadi.core.objectives`; an independent numpy
implementation of both (a test oracle and the SciPy baseline's objective) is in ``tests/oracles.py``.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

__all__ = ["Layout", "unpack_casadi", "unpack_numpy", "OBJECTIVES"]

OBJECTIVES = ("direction", "mse", "likelihood")
#: smoothing of the model speed in the cosine of Eq. 9 (scaled units), avoids 0/0 at ||f|| = 0
DIRECTION_EPS = 1e-8


class Layout:
    """Index map of the optimisation vector theta for K components in dimension d.

    Parameters
    ----------
    n_components : int
    n_dims : int
    with_noise : bool
        Include the Cholesky factors of Q_k (the likelihood objective needs them).
    """

    def __init__(self, n_components: int, n_dims: int, with_noise: bool) -> None:
        self.K = int(n_components)
        self.d = int(n_dims)
        self.with_noise = bool(with_noise)
        d = self.d
        self.tril = np.array([(i, j) for i in range(d) for j in range(i + 1)], dtype=int)
        self.strict = np.array([(i, j) for i in range(d) for j in range(i)], dtype=int).reshape(-1, 2)
        self.n_tril = len(self.tril)
        self.n_strict = len(self.strict)
        per = d + 2 * self.n_tril + self.n_strict + (self.n_tril if with_noise else 0)
        self.per_component = per
        self.n_logits = self.K - 1
        self.size = self.n_logits + self.K * per

    def slices(self, k: int) -> dict[str, slice]:
        """Slices of component k's blocks in theta: mu, L, B, W (and Q)."""
        o = self.n_logits + k * self.per_component
        out = {}
        for name, n in (("mu", self.d), ("L", self.n_tril), ("B", self.n_tril), ("W", self.n_strict)):
            out[name] = slice(o, o + n)
            o += n
        if self.with_noise:
            out["Q"] = slice(o, o + self.n_tril)
        return out

    def pack_tril(self, M: np.ndarray) -> np.ndarray:
        """Packed entries of a lower-triangular M with positive diagonal (log on the diagonal):
        the inverse of how :func:`unpack_casadi` builds L, B and L_Q."""
        return np.array([np.log(M[i, j]) if i == j else M[i, j] for i, j in self.tril])


def _tril_sx(v: ca.SX, layout: Layout) -> ca.SX:
    M = ca.SX.zeros(layout.d, layout.d)
    for idx, (i, j) in enumerate(layout.tril):
        M[i, j] = ca.exp(v[idx]) if i == j else v[idx]
    return M


def _tril_inverse_sx(L: ca.SX, d: int) -> ca.SX:
    """Inverse of a lower-triangular matrix by forward substitution (small explicit graph)."""
    inv = ca.SX.zeros(d, d)
    for j in range(d):
        inv[j, j] = 1.0 / L[j, j]
        for i in range(j + 1, d):
            acc = 0
            for m in range(j, i):
                acc += L[i, m] * inv[m, j]
            inv[i, j] = -acc / L[i, i]
    return inv


def unpack_casadi(theta: ca.SX, layout: Layout, margin: float) -> dict:
    """Model pieces from theta as SX: the one definition of the parametrization (module docstring).

    Returns a dict of lists over components: ``logpi``, ``mu``, ``L`` (Cholesky factor of
    Sigma_x), ``Linv`` (its inverse), ``logdet`` (log |Sigma_x|), ``A``, and ``LQ``, ``LQinv``,
    ``logdetQ`` with noise factors.
    """
    K, d = layout.K, layout.d
    logits = ca.vertcat(theta[: layout.n_logits], 0)
    top = ca.mmax(logits)
    lse = ca.log(ca.sum1(ca.exp(logits - top))) + top
    out = {k: [] for k in ("logpi", "mu", "L", "Linv", "logdet", "A", "LQ", "LQinv", "logdetQ")}
    diag_pos = [idx for idx, (i, j) in enumerate(layout.tril) if i == j]
    for k in range(K):
        s = layout.slices(k)
        out["logpi"].append(logits[k] - lse)
        out["mu"].append(theta[s["mu"]])
        Lv = theta[s["L"]]
        L = _tril_sx(Lv, layout)
        out["L"].append(L)
        out["Linv"].append(_tril_inverse_sx(L, d))
        out["logdet"].append(2 * sum(Lv[i] for i in diag_pos))
        B = _tril_sx(theta[s["B"]], layout)
        W = ca.SX.zeros(d, d)
        for idx, (i, j) in enumerate(layout.strict):
            W[i, j] = theta[s["W"]][idx]
        out["A"].append(-(B @ B.T + margin * ca.SX.eye(d)) + (W - W.T))
        if layout.with_noise:
            Qv = theta[s["Q"]]
            LQ = _tril_sx(Qv, layout)
            out["LQ"].append(LQ)
            out["LQinv"].append(_tril_inverse_sx(LQ, d))
            out["logdetQ"].append(2 * sum(Qv[i] for i in diag_pos))
    return out


@functools.lru_cache(maxsize=64)
def _unpack_function(K: int, d: int, with_noise: bool, margin: float) -> ca.Function:
    layout = Layout(K, d, with_noise)
    theta = ca.SX.sym("theta", layout.size)
    p = unpack_casadi(theta, layout, margin)
    outs = [ca.vertcat(*p["logpi"]), *p["mu"], *p["L"], *p["A"]]
    if with_noise:
        outs += p["LQ"]
    return ca.Function("unpack", [theta], outs)


def unpack_numpy(theta: np.ndarray, layout: Layout, margin: float) -> dict[str, np.ndarray]:
    """Numerical values of :func:`unpack_casadi`: model arrays (scaled attractor frame) from theta.

    Returns
    -------
    dict with ``priors`` (K,), ``mu`` (K, d), ``Sx`` (K, d, d), ``A`` (K, d, d), and ``Q`` (K, d, d)
    when the layout has noise factors.
    """
    K, d = layout.K, layout.d
    f = _unpack_function(K, d, layout.with_noise, float(margin))
    out = [np.asarray(v) for v in f(np.asarray(theta, dtype=float))]
    L = np.stack(out[1 + K: 1 + 2 * K])
    res = {"priors": np.exp(out[0].ravel()), "mu": np.stack([v.ravel() for v in out[1: 1 + K]]),
           "Sx": L @ np.transpose(L, (0, 2, 1)), "A": np.stack(out[1 + 2 * K: 1 + 3 * K])}
    if layout.with_noise:
        LQ = np.stack(out[1 + 3 * K:])
        res["Q"] = LQ @ np.transpose(LQ, (0, 2, 1))
    return res
