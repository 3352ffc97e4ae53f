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

The objective functions in CasADi live in :mod:`seds_casadi.seds`; an independent numpy
implementation of the same objectives (used in tests and as the SciPy baseline) is here.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Layout", "unpack_numpy", "objective_numpy", "OBJECTIVES"]

OBJECTIVES = ("direction", "mse", "likelihood")
_LOG_2PI = float(np.log(2.0 * np.pi))
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

    # numpy conversions --------------------------------------------------------
    def tril_numpy(self, v: np.ndarray) -> np.ndarray:
        """Lower-triangular matrix from its packed entries, diagonal through exp."""
        M = np.zeros((self.d, self.d))
        for (i, j), x in zip(self.tril, v):
            M[i, j] = np.exp(x) if i == j else x
        return M

    def pack_tril(self, M: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`tril_numpy` (M lower triangular, positive diagonal)."""
        return np.array([np.log(M[i, j]) if i == j else M[i, j] for i, j in self.tril])


def unpack_numpy(theta: np.ndarray, layout: Layout, margin: float) -> dict[str, np.ndarray]:
    """Model arrays (scaled attractor frame) from theta, in numpy.

    Returns
    -------
    dict with ``priors`` (K,), ``mu`` (K, d), ``Sx`` (K, d, d), ``A`` (K, d, d), and ``Q`` (K, d, d)
    when the layout has noise factors.
    """
    K, d = layout.K, layout.d
    logits = np.r_[theta[: layout.n_logits], 0.0]
    logits = logits - logits.max()
    priors = np.exp(logits) / np.exp(logits).sum()
    mu = np.empty((K, d))
    Sx = np.empty((K, d, d))
    A = np.empty((K, d, d))
    Q = np.empty((K, d, d)) if layout.with_noise else None
    for k in range(K):
        s = layout.slices(k)
        mu[k] = theta[s["mu"]]
        L = layout.tril_numpy(theta[s["L"]])
        Sx[k] = L @ L.T
        B = layout.tril_numpy(theta[s["B"]])
        W = np.zeros((d, d))
        for (i, j), x in zip(layout.strict, theta[s["W"]]):
            W[i, j] = x
        A[k] = -(B @ B.T + margin * np.eye(d)) + (W - W.T)
        if Q is not None:
            LQ = layout.tril_numpy(theta[s["Q"]])
            Q[k] = LQ @ LQ.T
    out = {"priors": priors, "mu": mu, "Sx": Sx, "A": A}
    if Q is not None:
        out["Q"] = Q
    return out


def _log_gauss_rows(X: np.ndarray, mean: np.ndarray, cov: np.ndarray) -> np.ndarray:
    # an implementation independent of gmm.log_gaussian: explicit inverse and slogdet
    diff = X - mean
    inv = np.linalg.inv(cov)
    _, logdet = np.linalg.slogdet(cov)
    return -0.5 * (np.einsum("ni,ij,nj->n", diff, inv, diff) + logdet + X.shape[1] * _LOG_2PI)


def objective_numpy(
    theta: np.ndarray,
    layout: Layout,
    X: np.ndarray,
    Xd: np.ndarray,
    weights: np.ndarray,
    objective: str,
    margin: float,
) -> float:
    """The SEDS objective in numpy (reference for the CasADi version and the SciPy baseline).

    Parameters
    ----------
    theta : array, shape (layout.size,)
    X, Xd : array, shape (n, d)
        Scaled positions (attractor at the origin) and velocities.
    weights : array, shape (n,)
        Per-sample weights (Eq. 11 for ``"direction"``; ones otherwise).
    objective : {"direction", "mse", "likelihood"}
    margin : float
        Stability margin m of the parametrization.

    Returns
    -------
    float
        ``"direction"``: Eq. 9 normalised by the weight sum,
        -sum_i w_i cos(xdot_i, f(x_i)) / sum_i w_i; ``"mse"``: mean_i ||f(x_i) - xdot_i||^2;
        ``"likelihood"``: -mean_i log p(x_i, xdot_i).
    """
    p = unpack_numpy(theta, layout, margin)
    K = layout.K
    logp = np.stack(
        [np.log(p["priors"][k]) + _log_gauss_rows(X, p["mu"][k], p["Sx"][k]) for k in range(K)],
        axis=1,
    )
    if objective == "likelihood":
        for k in range(K):
            logp[:, k] += _log_gauss_rows(Xd - X @ p["A"][k].T, np.zeros(layout.d), p["Q"][k])
        m = logp.max(axis=1, keepdims=True)
        ll = m[:, 0] + np.log(np.exp(logp - m).sum(axis=1))
        return float(-np.mean(ll))
    h = np.exp(logp - logp.max(axis=1, keepdims=True))
    h /= h.sum(axis=1, keepdims=True)
    f = np.einsum("nk,kij,nj->ni", h, p["A"], X)
    if objective == "mse":
        return float(np.mean(np.sum((f - Xd) ** 2, axis=1)))
    if objective == "direction":
        num = np.sum(f * Xd, axis=1)
        den = np.linalg.norm(Xd, axis=1) * np.sqrt(np.sum(f * f, axis=1) + DIRECTION_EPS)
        valid = np.linalg.norm(Xd, axis=1) > 0
        cos = np.where(valid, num / np.where(valid, den, 1.0), 0.0)
        return float(-np.sum(weights * cos) / np.sum(weights))
    raise ValueError(f"unknown objective {objective!r}; valid: {', '.join(OBJECTIVES)}")
