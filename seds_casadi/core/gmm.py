"""Gaussian mixture helpers in plain numpy: densities, responsibilities and regression (GMR).

All functions are vectorised over samples and numerically stable (log-sum-exp), so they can be
evaluated far from the data without underflow or NaN.
"""

from __future__ import annotations

import numpy as np

__all__ = ["log_gaussian", "responsibilities", "gmr_predict", "responsibilities_casadi",
           "logsumexp_parts_sx"]

_LOG_2PI = float(np.log(2.0 * np.pi))


def log_gaussian(X: np.ndarray, mean: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """Log density of a multivariate normal at many points.

    Parameters
    ----------
    X : array, shape (n_samples, n_dims)
    mean : array, shape (n_dims,)
    cov : array, shape (n_dims, n_dims)
        Symmetric positive definite.

    Returns
    -------
    array, shape (n_samples,)
    """
    L = np.linalg.cholesky(cov)
    diff = (X - mean).T
    z = np.linalg.solve(L, diff) if diff.size else diff
    maha = np.sum(z * z, axis=0)
    logdet = 2.0 * np.sum(np.log(np.diag(L)))
    return -0.5 * (maha + logdet + mean.shape[0] * _LOG_2PI)


def responsibilities(
    X: np.ndarray, priors: np.ndarray, means: np.ndarray, covariances: np.ndarray
) -> np.ndarray:
    """Posterior weights h^k(x) of each component (paper Eq. 6), by log-sum-exp.

    Parameters
    ----------
    X : array, shape (n_samples, n_dims)
    priors : array, shape (n_components,)
    means : array, shape (n_components, n_dims)
    covariances : array, shape (n_components, n_dims, n_dims)

    Returns
    -------
    array, shape (n_samples, n_components)
        Rows sum to one.
    """
    logp = np.stack(
        [np.log(priors[k]) + log_gaussian(X, means[k], covariances[k]) for k in range(len(priors))],
        axis=1,
    )
    logp -= logp.max(axis=1, keepdims=True)
    w = np.exp(logp)
    return w / w.sum(axis=1, keepdims=True)


def gmr_predict(
    X: np.ndarray,
    priors: np.ndarray,
    means: np.ndarray,
    covariances: np.ndarray,
    in_idx: np.ndarray,
    out_idx: np.ndarray,
    return_cov: bool = False,
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Gaussian mixture regression E[y | x] (paper Eq. 5 and 12), optionally with Cov[y | x].

    Parameters
    ----------
    X : array, shape (n_samples, n_in)
    priors, means, covariances : the joint GMM over (x, y)
    in_idx, out_idx : array of int
        Indices of the input and output dimensions in the joint space.
    return_cov : bool
        Also return the conditional covariance (law of total variance over components).

    Returns
    -------
    mean : array, shape (n_samples, n_out)
    cov : array, shape (n_samples, n_out, n_out), only if ``return_cov``
    """
    in_idx = np.asarray(in_idx)
    out_idx = np.asarray(out_idx)
    mu_in = means[:, in_idx]
    cov_in = covariances[:, in_idx][:, :, in_idx]
    h = responsibilities(X, priors, mu_in, cov_in)
    n, K = h.shape
    means_k = np.empty((K, n, len(out_idx)))
    conds = []
    for k in range(K):
        s_oi = covariances[k][np.ix_(out_idx, in_idx)]
        gain = np.linalg.solve(cov_in[k], s_oi.T).T  # Sigma_oi Sigma_ii^-1
        means_k[k] = means[k, out_idx] + (X - mu_in[k]) @ gain.T
        if return_cov:
            conds.append(covariances[k][np.ix_(out_idx, out_idx)] - gain @ s_oi.T)
    mean = np.einsum("nk,kno->no", h, means_k)
    if not return_cov:
        return mean
    cov = np.einsum("nk,kop->nop", h, np.stack(conds))
    dev = means_k - mean[None]
    cov += np.einsum("nk,kno,knp->nop", h, dev, dev)
    return mean, cov


def responsibilities_casadi(x, priors: np.ndarray, means: np.ndarray, covariances: np.ndarray):
    """Posterior weights h^k(x) of Eq. 6 as CasADi SX expressions of a symbolic point x.

    Same log-sum-exp stabilisation as :func:`responsibilities` (numeric GMM, symbolic x).

    Parameters
    ----------
    x : casadi.SX, shape (d, 1)
    priors : array, shape (K,)
    means : array, shape (K, d)
    covariances : array, shape (K, d, d)

    Returns
    -------
    list of casadi.SX
        The K weights, summing to one.
    """
    import casadi as ca

    logp = []
    for k in range(len(priors)):
        L = np.linalg.cholesky(covariances[k])
        z = ca.DM(np.linalg.inv(L)) @ (x - ca.DM(means[k]))
        logp.append(float(np.log(priors[k]) - np.sum(np.log(np.diag(L)))) - 0.5 * ca.sumsqr(z))
    _, e, total = logsumexp_parts_sx(logp)
    return [v / total for v in e]


def logsumexp_parts_sx(logp: list):
    """Stabilised pieces of log-sum-exp over a list of SX terms: (m, [exp(a - m)], sum).

    log sum_k exp(a_k) = m + log(sum); m = max_k a_k keeps every exponential in (0, 1].
    """
    import casadi as ca

    m = logp[0]
    for a in logp[1:]:
        m = ca.fmax(m, a)
    e = [ca.exp(a - m) for a in logp]
    total = e[0]
    for v in e[1:]:
        total = total + v
    return m, e, total
