"""Independent numpy implementations of the package's equations, used only as test oracles.

The package defines each equation once, in CasADi; these re-implementations check it.
"""

from __future__ import annotations

import numpy as np

_LOG_2PI = float(np.log(2.0 * np.pi))


def log_gaussian(X: np.ndarray, mean: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """Log density of N(mean, cov) at the rows of X (Cholesky)."""
    L = np.linalg.cholesky(cov)
    diff = (X - mean).T
    z = np.linalg.solve(L, diff) if diff.size else diff
    maha = np.sum(z * z, axis=0)
    logdet = 2.0 * np.sum(np.log(np.diag(L)))
    return -0.5 * (maha + logdet + mean.shape[0] * _LOG_2PI)


def responsibilities(X, priors, means, covariances) -> np.ndarray:
    """Eq. 6 by log-sum-exp, shape (n, K)."""
    logp = np.stack([np.log(priors[k]) + log_gaussian(X, means[k], covariances[k])
                     for k in range(len(priors))], axis=1)
    logp -= logp.max(axis=1, keepdims=True)
    w = np.exp(logp)
    return w / w.sum(axis=1, keepdims=True)


def gmr_predict(X, priors, means, covariances, in_idx, out_idx, return_cov=False):
    """GMR mean (and covariance by the law of total variance)."""
    in_idx, out_idx = np.asarray(in_idx), np.asarray(out_idx)
    mu_in = means[:, in_idx]
    cov_in = covariances[:, in_idx][:, :, in_idx]
    h = responsibilities(X, priors, mu_in, cov_in)
    n, K = h.shape
    means_k = np.empty((K, n, len(out_idx)))
    conds = []
    for k in range(K):
        s_oi = covariances[k][np.ix_(out_idx, in_idx)]
        gain = np.linalg.solve(cov_in[k], s_oi.T).T
        means_k[k] = means[k, out_idx] + (X - mu_in[k]) @ gain.T
        conds.append(covariances[k][np.ix_(out_idx, out_idx)] - gain @ s_oi.T)
    mean = np.einsum("nk,kno->no", h, means_k)
    if not return_cov:
        return mean
    cov = np.einsum("nk,kop->nop", h, np.stack(conds))
    dev = means_k - mean[None]
    cov += np.einsum("nk,kno,knp->nop", h, dev, dev)
    return mean, cov


def seds_velocity(X, priors, means, covariances) -> np.ndarray:
    """Eq. 5 of a joint GMM over (x, xdot): f(x) = sum_k h^k(x) (mu_xdot^k + A_k (x - mu_x^k))."""
    d = means.shape[1] // 2
    A = np.stack([np.linalg.solve(c[:d, :d].T, c[d:, :d].T).T for c in covariances])
    h = responsibilities(X, priors, means[:, :d], covariances[:, :d, :d])
    lin = np.einsum("kij,nkj->nki", A, X[:, None, :] - means[None, :, :d])
    return np.einsum("nk,nki->ni", h, lin + means[None, :, d:])


def random_gmm(rng: np.random.Generator, K: int, n: int, spread: float = 1.0):
    """A random GMM with well-conditioned covariances."""
    priors = rng.dirichlet(np.ones(K))
    means = rng.standard_normal((K, n)) * spread
    covs = []
    for _ in range(K):
        M = rng.standard_normal((n, n))
        covs.append(M @ M.T / n + 0.2 * np.eye(n))
    return priors, means, np.stack(covs)


# ------------------------------------------------------------------ SEDS parametrization
DIRECTION_EPS = 1e-8  # as seds_casadi.core.parametrization


def _tril(layout, v):
    M = np.zeros((layout.d, layout.d))
    for (i, j), x in zip(layout.tril, v):
        M[i, j] = np.exp(x) if i == j else x
    return M


def unpack(theta: np.ndarray, layout, margin: float) -> dict:
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
        L = _tril(layout, theta[s["L"]])
        Sx[k] = L @ L.T
        B = _tril(layout, theta[s["B"]])
        W = np.zeros((d, d))
        for (i, j), x in zip(layout.strict, theta[s["W"]]):
            W[i, j] = x
        A[k] = -(B @ B.T + margin * np.eye(d)) + (W - W.T)
        if Q is not None:
            LQ = _tril(layout, theta[s["Q"]])
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


def seds_objective(
    theta: np.ndarray,
    layout,
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
    p = unpack(theta, layout, margin)
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
    raise ValueError(f"unknown objective {objective!r}")
