"""Independent numpy implementations of the package's equations, used only as test oracles.

The package defines each equation once, in CasADi; these re-implementations check it. Also
:func:`linear_flow_demos`, demonstrations sampled from the exact flow of a linear system.
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
    P = np.eye(d)
    if getattr(layout, "lyapunov", "identity") == "learned":  # A_k = P^-1 S_k, P = d M / tr M
        LP = _tril(layout, theta[layout.size - layout.n_tril:])
        M = LP @ LP.T
        P = d * M / np.trace(M)
        A = np.stack([np.linalg.solve(P, A[k]) for k in range(K)])
    out = {"priors": priors, "mu": mu, "Sx": Sx, "A": A, "P": P}
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


# ------------------------------------------------ the hitting motion (Eq. 8, 12, 14)
def target_field(X, ds, hitting_direction, tiny: float = 1e-200):
    """Eq. 8 of a certified StableDS: (h, f), f = sum_k h^k(x) A_k (x - x*), h = f / ||f||
    (psi* where ||f|| <= tiny); shapes (n, d)."""
    d = ds.n_dims
    w = responsibilities(X, ds.priors, ds.means[:, :d], ds.covariances[:, :d, :d])
    F = np.einsum("nk,kij,nj->ni", w, ds.A, X - ds.target)
    nrm = np.linalg.norm(F, axis=1)
    H = np.where(nrm[:, None] > tiny, F / np.maximum(nrm, tiny)[:, None],
                 np.asarray(hitting_direction)[None, :])
    return H, F


def saturate(g, log_range):
    """The C1 tanh saturation of log v beyond the demonstrated range (identity inside)."""
    lo, hi = log_range
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return g
    m = np.log(2.0)
    return np.where(g > hi, hi + m * np.tanh((g - hi) / m),
                    np.where(g < lo, lo + m * np.tanh((g - lo) / m), g))


def strength_factor(X, priors, means, covariances, log_range):
    """Eq. 12 in log v, saturated: v(x) = exp(sat(E[log v | x])), shape (n,)."""
    d = means.shape[1] - 1
    logv = gmr_predict(X, priors, means, covariances, np.arange(d), [d])[:, 0]
    return np.exp(saturate(logv, log_range))


def strength_model_velocity(X, ds) -> np.ndarray:
    """f_v(x) = v(x) rho(x) f(x) / ||f(x)|| of a StableDS with a strength factor (rho: the taper
    ||e|| / sqrt(||e||^2 + r^2)), from its arrays; plain Eq. 5 without one."""
    F = seds_velocity(X, ds.priors, ds.means, ds.covariances)
    if ds.strength is None:
        return F
    sf = ds.strength
    v = strength_factor(X, sf.priors, sf.means, sf.covariances, sf.log_range)
    e = np.linalg.norm(X - ds.target, axis=1)
    rho = e / np.sqrt(e ** 2 + ds.strength_radius ** 2)
    nf = np.linalg.norm(F, axis=1)
    return (v * rho / np.maximum(nf, 1e-200))[:, None] * F


def rotation_z(alpha):
    c, s = np.cos(alpha), np.sin(alpha)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def hitting_ds(X, alpha, kappa, motion):
    """Eq. 14, kappa R_alpha v(R_alpha^T x) h(R_alpha^T x), from a HittingMotion's parameters."""
    R = rotation_z(alpha)
    Y = X @ R  # rows: R^T x
    tf, sf = motion.target_field, motion.strength
    H, _ = target_field(Y, tf.ds, tf.hitting_direction)
    v = strength_factor(Y, sf.priors, sf.means, sf.covariances, sf.log_range)
    return kappa * (v[:, None] * H) @ R.T


# ------------------------------------------------ the club head's orientation
def log3(R):
    """Rotation vector of R (so(3) log), with the limits near 0 and pi."""
    c = np.clip((np.trace(R) - 1) / 2, -1.0, 1.0)
    th = np.arccos(c)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if th < 1e-6:
        return 0.5 * w
    if th > np.pi - 1e-4:
        axis = np.sqrt(np.maximum((np.diag(R) + 1) / 2, 0))
        k = int(np.argmax(axis))
        axis[np.arange(3) != k] = R[k, np.arange(3) != k] / (2 * axis[k])
        return th * axis / np.linalg.norm(axis)
    return th / (2 * np.sin(th)) * w


def orientation_error(R, Rd, full):
    """log(Rd R^T), or the turn about z from R_x's horizontal direction to Rd_x's."""
    if full:
        return log3(Rd @ R.T)
    a = np.arctan2(Rd[1, 0], Rd[0, 0]) - np.arctan2(R[1, 0], R[0, 0])
    return np.array([0.0, 0.0, (a + np.pi) % (2 * np.pi) - np.pi])


def face_orientation(direction):
    """x along the horizontal part of direction (+x if none), z up."""
    d = np.asarray(direction, float).copy()
    d[2] = 0.0
    n = np.linalg.norm(d)
    x = d / n if n > 1e-9 else np.array([1.0, 0, 0])
    z = np.array([0.0, 0.0, 1.0])
    return np.column_stack([x, np.cross(z, x), z])


def linear_flow_demos(A: np.ndarray, n: int = 4, T: float = 6.0, dt: float = 0.02,
                      seed: int = 0):
    """Demonstrations of xdot = A x (target at the origin), from n random unit starts, sampled
    every dt by the exact flow expm(A dt)."""
    from scipy.linalg import expm

    from seds_casadi import Demonstrations

    rng = np.random.default_rng(seed)
    M = expm(A * dt)
    paths = []
    for _ in range(n):
        x = rng.uniform(-1, 1, A.shape[0])
        traj = [x / np.linalg.norm(x)]
        for _ in range(int(T / dt)):
            traj.append(M @ traj[-1])
        paths.append(np.array(traj))
    return Demonstrations(paths, dt=dt, target=np.zeros(A.shape[0]))


def decaying_spiral_demos():
    """Three 2-D demonstrations of a decaying spiral into the origin (200 samples each, 100 mm
    wide), for the LPV and PC initialisations' tests."""
    from seds_casadi import Demonstrations

    t = np.linspace(0, 1, 200)
    demos = []
    for phi in (0.0, 0.5, 1.0):
        r = np.exp(-3 * t)
        a = phi + 4 * t
        demos.append(np.column_stack([r * np.cos(a), r * np.sin(a)]) * 100)
    return Demonstrations([p - p[-1] for p in demos], dt=t[1])
