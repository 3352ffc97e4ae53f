"""Gaussian mixtures: responsibilities (Eq. 6) and Gaussian mixture regression (Eq. 5, 12).

Each formula is written once, as a CasADi SX expression of a symbolic point
(:func:`responsibilities_sx`, :func:`gmr_sx`); :func:`gmr_function` wraps it in a
``casadi.Function`` and :func:`responsibilities` / :func:`gmr_predict` evaluate it numerically over
many points at once (CasADi's map over columns, no Python loop). The same expressions are used for
code generation (the hitting motion, the controller), so numbers and symbols cannot drift apart.

The responsibilities are stabilised by log-sum-exp, so they stay finite and sum to one far from
the data. A plain numpy implementation is kept in the tests as an oracle.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..codegen import batch_evaluate

#: cap of the squared Mahalanobis distance in the responsibilities (below the largest float)
MAX_SQUARED_DISTANCE = 1e300

__all__ = ["responsibilities", "responsibilities_sx", "gmr_sx", "gmr_function", "gmr_predict",
           "logsumexp_parts_sx"]


def logsumexp_parts_sx(logp: list):
    """Stabilised pieces of log-sum-exp over a list of SX terms: (m, [exp(a - m)], sum).

    log sum_k exp(a_k) = m + log(sum); m = max_k a_k keeps every exponential in (0, 1].
    """
    m = logp[0]
    for a in logp[1:]:
        m = ca.fmax(m, a)
    e = [ca.exp(a - m) for a in logp]
    total = e[0]
    for v in e[1:]:
        total = total + v
    return m, e, total


def _check_gmm(priors, means, covariances) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    priors = np.asarray(priors, dtype=float).ravel()
    means = np.atleast_2d(np.asarray(means, dtype=float))
    covariances = np.asarray(covariances, dtype=float)
    K, n = means.shape
    if priors.shape != (K,) or covariances.shape != (K, n, n):
        raise ValueError(f"inconsistent GMM shapes: priors {priors.shape}, means {means.shape}, "
                         f"covariances {covariances.shape}; expected ({K},), ({K}, n), ({K}, n, n)")
    return priors, means, covariances


def responsibilities_sx(x, priors, means, covariances) -> list:
    """Posterior weights h^k(x) of each component (paper Eq. 6) as SX expressions.

    h^k(x) = pi_k N(x; mu_k, Sigma_k) / sum_i pi_i N(x; mu_i, Sigma_i), by log-sum-exp.

    Parameters
    ----------
    x : casadi.SX, shape (n_dims, 1)
        Symbolic point.
    priors : array, shape (n_components,)
    means : array, shape (n_components, n_dims)
    covariances : array, shape (n_components, n_dims, n_dims)
        Symmetric positive definite.

    Returns
    -------
    list of casadi.SX
        The K weights, summing to one.
    """
    priors, means, covariances = _check_gmm(priors, means, covariances)
    log_c, inv_chol = _gaussian_constants(priors, covariances)
    return _weights_sx(x, [float(c) for c in log_c], [ca.DM(m) for m in means],
                       [ca.DM(w) for w in inv_chol])


def _gaussian_constants(priors, covariances) -> tuple[np.ndarray, np.ndarray]:
    """log pi_k - log det L_k and L_k^-1 (Sigma_k = L_k L_k^T) of each component."""
    L = np.linalg.cholesky(covariances)
    log_c = np.log(priors) - np.sum(np.log(np.diagonal(L, axis1=1, axis2=2)), axis=1)
    return log_c, np.linalg.inv(L)


def _weights_sx(x, log_c, means, inv_chol) -> list:
    """h^k(x) from each component's log pi_k - log det L_k, mean and L_k^-1 (numbers or
    symbols): the one expression of Eq. 6 that :func:`responsibilities_sx` (constants) and
    :func:`responsibilities` (parameters, one Function per K and d) build."""
    logp = []
    for k in range(len(log_c)):
        z = inv_chol[k] @ (x - means[k])
        # the squared Mahalanobis distance capped below inf: beyond ~1e154 standard deviations
        # from every component it would overflow, every log-density be -inf and log-sum-exp
        # give NaN (-inf - -inf); capped, the weights stay finite and sum to one
        q = ca.fmin(ca.sumsqr(z), MAX_SQUARED_DISTANCE)
        logp.append(log_c[k] - 0.5 * q)
    _, e, total = logsumexp_parts_sx(logp)
    return [v / total for v in e]


#: :func:`responsibilities`' Functions by (K, d): the GMM's numbers are parameters
_WEIGHTS: dict = {}


def _weights_function(K: int, d: int) -> ca.Function:
    """h(x, log_c, means, inverse factors) for K components in d dimensions (cached)."""
    f = _WEIGHTS.get((K, d))
    if f is None:
        x, c = ca.SX.sym("x", d), ca.SX.sym("c", K)
        mu, W = ca.SX.sym("mu", d, K), ca.SX.sym("W", d * d, K)
        h = _weights_sx(x, [c[k] for k in range(K)], [mu[:, k] for k in range(K)],
                        [ca.reshape(W[:, k], d, d) for k in range(K)])
        f = _WEIGHTS[(K, d)] = ca.Function("h", [x, c, mu, W], [ca.vertcat(*h)])
    return f


def gmr_sx(x, priors, means, covariances, in_idx, out_idx, with_cov: bool = False):
    """Gaussian mixture regression E[y | x] (paper Eq. 5 and 12) as SX, optionally Cov[y | x].

    E[y | x] = sum_k h^k(x) (mu_y^k + Sigma_yx^k (Sigma_x^k)^-1 (x - mu_x^k)); the covariance is the
    law of total variance over the components.

    Parameters
    ----------
    x : casadi.SX, shape (n_in, 1)
    priors, means, covariances : the joint GMM over (x, y)
        Shapes (K,), (K, n), (K, n, n).
    in_idx, out_idx : sequences of int
        Indices of the input and output dimensions in the joint space.
    with_cov : bool
        Also return the conditional covariance.

    Returns
    -------
    mean : casadi.SX, shape (n_out, 1)
    cov : casadi.SX, shape (n_out, n_out), only if ``with_cov``
    """
    priors, means, covariances = _check_gmm(priors, means, covariances)
    i, o = np.asarray(in_idx, dtype=int), np.asarray(out_idx, dtype=int)
    h = responsibilities_sx(x, priors, means[:, i], covariances[:, i][:, :, i])
    mean_k, cond_k = [], []
    for k in range(len(priors)):
        s_oi = covariances[k][np.ix_(o, i)]
        gain = np.linalg.solve(covariances[k][np.ix_(i, i)], s_oi.T).T  # Sigma_oi Sigma_ii^-1
        mean_k.append(ca.DM(means[k, o]) + ca.DM(gain) @ (x - ca.DM(means[k, i])))
        cond_k.append(covariances[k][np.ix_(o, o)] - gain @ s_oi.T)
    mean = sum((h[k] * mean_k[k] for k in range(1, len(h))), h[0] * mean_k[0])
    if not with_cov:
        return mean
    cov = ca.SX.zeros(len(o), len(o))
    for k in range(len(h)):
        dev = mean_k[k] - mean
        cov = cov + h[k] * (ca.DM(cond_k[k]) + dev @ dev.T)
    return mean, cov


def gmr_function(priors, means, covariances, in_idx, out_idx, with_cov: bool = False,
                 name: str = "gmr") -> ca.Function:
    """:func:`gmr_sx` as a ``casadi.Function`` x (n_in,) -> mean (n_out,) [, cov (n_out^2,)].

    The covariance output is the (n_out, n_out) matrix flattened column-major (symmetric, so
    the order does not matter).
    """
    x = ca.SX.sym("x", len(in_idx))
    out = gmr_sx(x, priors, means, covariances, in_idx, out_idx, with_cov)
    if with_cov:
        return ca.Function(name, [x], [out[0], ca.vec(out[1])], ["x"], ["mean", "cov"])
    return ca.Function(name, [x], [out], ["x"], ["mean"])


def _points(X, n_in: int) -> np.ndarray:
    X = np.asarray(X, dtype=float)
    X2 = X.reshape(1, -1) if X.ndim == 1 else X
    if X2.ndim != 2 or X2.shape[1] != n_in:
        raise ValueError(f"X must have shape (n, {n_in}), got {X.shape}")
    return X2


def gmr_predict(X, priors, means, covariances, in_idx, out_idx, return_cov: bool = False,
                function: ca.Function | None = None):
    """Evaluate Gaussian mixture regression (:func:`gmr_sx`) at many points.

    Parameters
    ----------
    X : array, shape (n_samples, n_in)
    priors, means, covariances : the joint GMM over (x, y)
    in_idx, out_idx : sequences of int
    return_cov : bool
        Also return Cov[y | x].
    function : casadi.Function, optional
        A prebuilt :func:`gmr_function` of this GMM (saves rebuilding it on every call).

    Returns
    -------
    mean : array, shape (n_samples, n_out)
    cov : array, shape (n_samples, n_out, n_out), only if ``return_cov``
    """
    X2 = _points(X, len(in_idx))
    f = function or gmr_function(priors, means, covariances, in_idx, out_idx, return_cov)
    if len(X2) == 0:
        n_out = len(out_idx)
        return (np.zeros((0, n_out)), np.zeros((0, n_out, n_out))) if return_cov \
            else np.zeros((0, n_out))
    outs = batch_evaluate(f, X2.T)
    if not return_cov:
        return outs[0]
    n_out = len(out_idx)
    return outs[0], outs[1].reshape(-1, n_out, n_out)


def responsibilities(X, priors, means, covariances) -> np.ndarray:
    """Evaluate the responsibilities h^k(x) of Eq. 6 (:func:`responsibilities_sx`) at many points.

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
    priors, means, covariances = _check_gmm(priors, means, covariances)
    K, d = means.shape
    X2 = _points(X, d)
    if len(X2) == 0:
        return np.zeros((0, K))
    log_c, inv_chol = _gaussian_constants(priors, covariances)
    f = _weights_function(K, d)
    # the GMM's numbers once (CasADi repeats an input given with its own number of columns)
    return batch_evaluate(f, X2.T, log_c[:, None], means.T,
                          inv_chol.transpose(0, 2, 1).reshape(K, d * d).T)[0]
