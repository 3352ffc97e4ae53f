"""The strength factor v(x) > 0: Gaussian mixture regression of the speed on the position
(paper Eq. 12), in the log domain and saturated beyond the demonstrated speeds.

Eq. 12 is written once, as a CasADi expression (:func:`strength_sx`, on the GMR of
:func:`seds_casadi.core.gmm.gmr_sx`, with the saturation of :func:`saturate_sx`);
:class:`StrengthFactor` evaluates it numerically over many points at once. Two models are built
on it: the hitting DS (Eq. 14, :mod:`seds_casadi.motion.hitting`) and a point-to-point model
fitted with the direction objective, which moves along its certified streamlines at the
demonstrated speeds (``SEDS(speed_calibration="strength")``, :class:`StableDS`).
:class:`StrengthFactorLearner` fits it, scikit-learn style.

Positivity of v (paper footnote 4): the GMR is done on log-speed, v(x) = exp(E[log v | x]),
which is positive everywhere by construction and equals Eq. 12 applied to log v. GMR
extrapolates linearly, so outside the demonstrated range of log-speeds [lo, hi] the prediction is
saturated smoothly (C1, ``hi + log2 tanh((g - hi) / log2)`` above, likewise below): v stays
between half the slowest and twice the fastest demonstrated speed, and is exactly the GMR of
Eq. 12 (in log v) inside the range.

Far from the data (beyond :data:`FAR_FACTOR` times its extent) the GMR is evaluated at the point
pulled radially back to that distance, as :meth:`StableDS.gains_velocity_sx` does for Eq. 6: the
Gaussians' exponents overflow from about 1e154 times the components' spread (inf - inf, NaN),
while v there is already saturated or constant along the ray. So v is finite and positive for
every finite x, and unchanged within that distance.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin

from ..codegen import batch_evaluate
from ._random import sklearn_random_state
from .gmm import gmr_sx

__all__ = ["StrengthFactor", "StrengthFactorLearner", "strength_sx", "saturate_sx"]


def as_points(X, d: int, name: str = "X") -> tuple[np.ndarray, bool]:
    """``X`` as finite rows of shape (n, d), and whether it was one point of shape (d,)."""
    X = np.asarray(X, dtype=float)
    single = X.ndim == 1
    X2 = np.atleast_2d(X)
    if X2.ndim != 2 or X2.shape[1] != d:
        raise ValueError(f"{name} must have shape (n, {d}) or ({d},), got {X.shape}")
    if not np.all(np.isfinite(X2)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return X2, single

_LOG2 = float(np.log(2.0))
#: beyond this many times the data's extent the GMR is evaluated at that distance
#: (:func:`strength_sx`; the same rule as :data:`seds_casadi.core.stable_ds.FAR_FACTOR`)
FAR_FACTOR = 1e6


def pull_back_sx(x, centre: np.ndarray, radius: float) -> ca.SX:
    """``x`` itself within max-norm distance ``radius`` of ``centre``; beyond it, the point
    pulled radially back to that distance (no overflow, no 0/0).

    Parameters
    ----------
    x : casadi.SX, shape (d, 1)
    centre : array, shape (d,)
    radius : float, > 0

    Returns
    -------
    casadi.SX, shape (d, 1)
    """
    c = ca.DM(np.asarray(centre, dtype=float))
    e = x - c
    far = ca.mmax(ca.fabs(e))
    return ca.if_else(far > radius, c + (radius / ca.fmax(far, radius)) * e, x)


def far_radius(means: np.ndarray, covariances: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre of a GMM's means and :data:`FAR_FACTOR` times its extent (the largest distance of
    a mean from that centre plus the component's standard deviation).

    Parameters
    ----------
    means : array, shape (K, d)
    covariances : array, shape (K, d, d)

    Returns
    -------
    centre : array, shape (d,)
    radius : float
    """
    centre = np.mean(means, axis=0)
    ext = max(float(np.linalg.norm(m - centre) + np.sqrt(max(np.trace(S), 0.0)))
              for m, S in zip(means, covariances))
    return centre, FAR_FACTOR * max(ext, 1e-300)


def saturate_sx(g, log_range) -> ca.SX:
    """Identity on the demonstrated range [lo, hi] of log v; beyond it, a C1 tanh saturation that
    never goes more than log 2 past the range (no saturation unless both ends are finite)."""
    lo, hi = float(log_range[0]), float(log_range[1])
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return g
    m = _LOG2
    return ca.if_else(g > hi, hi + m * ca.tanh((g - hi) / m),
                      ca.if_else(g < lo, lo + m * ca.tanh((g - lo) / m), g))


def strength_sx(x, priors, means, covariances, log_range=(-np.inf, np.inf)) -> ca.SX:
    """Eq. 12 (in log v, saturated) as SX: v(x) = exp(sat(E[log v | x])), finite for every
    finite x (beyond :data:`FAR_FACTOR` times the data's extent, taken at that distance).

    Parameters
    ----------
    x : casadi.SX, shape (d, 1)
    priors, means, covariances : the joint GMM over (x, log v)
        Shapes (K,), (K, d+1), (K, d+1, d+1).
    log_range : (float, float)
        Demonstrated range of log v (:func:`saturate_sx`).

    Returns
    -------
    casadi.SX, scalar
    """
    means, covariances = np.asarray(means, dtype=float), np.asarray(covariances, dtype=float)
    d = means.shape[1] - 1
    centre, radius = far_radius(means[:, :d], covariances[:, :d, :d])
    logv = gmr_sx(pull_back_sx(x, centre, radius), priors, means, covariances, np.arange(d), [d])
    return ca.exp(saturate_sx(logv, log_range))


class StrengthFactor:
    """v(x) > 0 by GMR on (position, log speed) (Eq. 12, in the log domain; footnote 4).

    A fitted value with no ``fit`` of its own: learn one with :class:`StrengthFactorLearner`
    (``StrengthFactorLearner(n_components=2).fit(positions, speeds).factor_``). Its parameters
    are plain arrays, so saving it is saving them.

    Parameters
    ----------
    priors, means, covariances : the joint GMM over (x, log v), shapes (K,), (K, d+1),
        (K, d+1, d+1).
    log_range : (float, float)
        Demonstrated range of log v beyond which it saturates (infinite: no saturation).
    """

    def __init__(self, priors, means, covariances, log_range=(-np.inf, np.inf)) -> None:
        self.priors = np.asarray(priors, dtype=float)
        self.means = np.asarray(means, dtype=float)
        self.covariances = np.asarray(covariances, dtype=float)
        self.n_dims = self.means.shape[1] - 1
        self.log_range = (float(log_range[0]), float(log_range[1]))

    def sx(self, x) -> ca.SX:
        """v(x) of Eq. 12 as SX (:func:`strength_sx`), for building larger expressions."""
        return strength_sx(x, self.priors, self.means, self.covariances, self.log_range)

    def to_casadi(self, name: str = "strength_factor") -> ca.Function:
        """Eq. 12 as a CasADi Function x (d,) -> v (scalar)."""
        x = ca.SX.sym("x", self.n_dims)
        return ca.Function(name, [x], [self.sx(x)], ["x"], ["v"])

    def __getstate__(self) -> dict:  # the cached CasADi Function is rebuilt after unpickling
        state = dict(self.__dict__)
        state.pop("_f", None)
        return state

    def __call__(self, X) -> np.ndarray:
        """v at points X, shape (n, d) -> (n,), or (d,) -> float."""
        X2, single = as_points(X, self.n_dims)
        if len(X2) == 0:
            return np.zeros(0)
        f = self.__dict__.get("_f")
        if f is None:
            f = self.__dict__["_f"] = self.to_casadi()
        v = batch_evaluate(f, X2.T)[0][:, 0]
        return float(v[0]) if single else v


class StrengthFactorLearner(RegressorMixin, BaseEstimator):
    """Learns a :class:`StrengthFactor` from positions and speeds (scikit-learn estimator).

    Parameters
    ----------
    n_components : int, default 2
        Gaussians of the joint GMM over (x, log v) (the paper used 2).
    random_state : int, RandomState or None, default 0
        Seed of scikit-learn's k-means + EM.
    reg_covar : float, default 1e-6
        Added to the covariances' diagonals (scikit-learn's ``GaussianMixture``).

    Attributes
    ----------
    factor_ : StrengthFactor
        The fitted strength factor.
    n_features_in_ : int
        d, the dimension of the positions.
    """

    def __init__(self, n_components: int = 2, random_state=0, reg_covar: float = 1e-6) -> None:
        self.n_components = n_components
        self.random_state = random_state
        self.reg_covar = reg_covar

    def fit(self, X, y) -> StrengthFactorLearner:
        """Fit the joint GMM over (position, log speed) by k-means + EM.

        Parameters
        ----------
        X : array, shape (n, d)
            Positions.
        y : array, shape (n,)
            Speeds there, all positive.

        Returns
        -------
        self
        """
        from sklearn.mixture import GaussianMixture

        K = self.n_components
        if isinstance(K, bool) or not isinstance(K, (int, np.integer)) or K < 1:
            raise ValueError(f"n_components must be a positive integer, got {K!r}")
        if not (np.isfinite(self.reg_covar) and self.reg_covar >= 0):
            raise ValueError(f"reg_covar must be >= 0, got {self.reg_covar}")
        X = np.asarray(X, dtype=float)
        if X.ndim != 2:
            raise ValueError(f"positions must have shape (n, d), got {X.shape}")
        X, _ = as_points(X, X.shape[1], "positions")
        speeds = np.asarray(y, dtype=float).ravel()
        if np.any(~np.isfinite(speeds)) or np.any(speeds <= 0):
            raise ValueError("speeds for the strength factor must be positive and finite")
        if len(speeds) != len(X) or len(X) < K:
            raise ValueError(f"need one speed per position and at least n_components={K} "
                             f"samples, got {len(X)} positions and {len(speeds)} speeds")
        data = np.column_stack([X, np.log(speeds)])
        gm = GaussianMixture(n_components=int(K), covariance_type="full",
                             reg_covar=float(self.reg_covar),
                             random_state=sklearn_random_state(self.random_state)).fit(data)
        self.factor_ = StrengthFactor(gm.weights_, gm.means_, gm.covariances_,
                                      log_range=(float(np.log(speeds.min())),
                                                 float(np.log(speeds.max()))))
        self.n_features_in_ = X.shape[1]
        return self

    def predict(self, X) -> np.ndarray:
        """v at points X, shape (n, d) -> (n,) (:class:`StrengthFactor`)."""
        from sklearn.utils.validation import check_is_fitted

        check_is_fitted(self, "factor_")
        return self.factor_(X)
