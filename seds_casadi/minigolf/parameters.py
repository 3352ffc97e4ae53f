"""Learners of the hitting parameters g: s -> (alpha, kappa) (paper Section 5, Eq. 2, 15-18).

The situation s is the hole's position relative to the ball in the hitting plane (2-D). Three
learners, chosen by name with :func:`make_model`:

* ``"gpr"``: one Gaussian process per output, squared-exponential kernel with one length scale
  per input dimension plus a noise term, hyperparameters by maximum likelihood (scikit-learn's
  GaussianProcessRegressor); mean and variance of Eq. 17. Length scales are bounded to
  [0.05, 100] times each input's spread in the training set and the noise to a tenth of the
  outputs' variance, so that tiny training sets are not explained as pure noise; inputs that
  do not vary in the training set are left out of the kernel. The prior mean is the training
  outputs' mean by default (``prior_mean="data"``); ``prior_mean="zero"`` is Eq. 17a as
  printed, a zero-mean process that "outputs zero far from the training data" (Section 5.2).
* ``"gmr"``: one joint GMM over (s, alpha, kappa) fitted by k-means then EM (on the data scaled
  to unit variance per dimension, the result in the data's units), and GMR (Eq. 18) with the
  conditional covariance (the outputs' correlation is kept).
* ``"sep_gmr"``: one GMM per output over (s, output), predicted independently.

Parameters are counted as the paper's Table 1 counts them: a GP stores its M training inputs and
outputs and d_in + 2 hyperparameters per output (length scales, signal variance, noise); a GMM
over d dimensions has K + dK + d(d+1)K/2 parameters.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted

from ..core._random import sklearn_random_state
from ..core.gmm import gmr_function, gmr_predict

__all__ = ["GPRModel", "GMRModel", "make_model", "MODELS", "gpr_param_count",
           "gmm_param_count", "GPR_PRIOR_MEANS"]


#: covariance floor of the GMMs, in units of each dimension's variance (the data are scaled
#: to unit variance: a floor at 1 % of each dimension's spread; 1e-6 let the two Gaussians of
#: a 10-point data set collapse, measured on the rough flat field, benchmarks/README.md)
REG_COVAR = 1e-4
#: the prior means of :class:`GPRModel`: the training outputs' mean, or zero (Eq. 17a)
GPR_PRIOR_MEANS = ("data", "zero")


def gpr_param_count(n_train: int, n_inputs: int, n_outputs: int) -> int:
    """Table 1's count for GPR: M d_in + M n_out + n_out (d_in + 2)."""
    return n_train * n_inputs + n_train * n_outputs + n_outputs * (n_inputs + 2)


def gmm_param_count(n_components: int, n_dims: int) -> int:
    """Parameters of a GMM: K + d K + d (d + 1) K / 2 (priors, means, covariances)."""
    return n_components * (1 + n_dims + n_dims * (n_dims + 1) // 2)


def _check_xy(S, Y, min_samples: int, what: str):
    S = np.atleast_2d(np.asarray(S, dtype=float))
    Y = np.asarray(Y, dtype=float)
    if Y.ndim == 1:
        Y = Y[:, None]
    if S.shape[0] != Y.shape[0]:
        raise ValueError(f"{S.shape[0]} situations for {Y.shape[0]} outputs")
    if not (np.all(np.isfinite(S)) and np.all(np.isfinite(Y))):
        raise ValueError("training data contain NaN or infinite values")
    if S.shape[0] < min_samples:
        raise ValueError(f"{what} needs at least {min_samples} training points, got {S.shape[0]}")
    return S, Y


class GPRModel(RegressorMixin, BaseEstimator):
    """GPR per output (Eq. 17), squared-exponential kernel with per-dimension length scales.

    A scikit-learn estimator: ``clone``, ``get_params``/``set_params``, ``GridSearchCV`` and
    ``cross_val_score`` work; ``score`` is R^2 over the outputs.

    Parameters
    ----------
    n_restarts : int, default 5
        Restarts of the marginal-likelihood optimiser (from random hyperparameters within the
        bounds). With 2, the angle's GP stopped in a worse optimum (log marginal likelihood
        12.9 against 33.2: a length scale of 2 cm) in 2 of 20 repetitions of arctan's "28
        equally spaced" set, and those repetitions sank 30-40 % instead of 100 %.
    random_state : int, numpy Generator or None, default 0
    prior_mean : {"data", "zero"}, default "data"
        The process's mean before the data: ``"data"``, the training outputs' mean (the
        outputs are centred and scaled to unit variance before the fit); ``"zero"``, zero, as
        Eq. 17a is printed, g(s*) = K(s*, S) (K(S, S) + sigma_n I)^-1 alpha, so that far from
        the training data the prediction returns to 0 (the outputs are only scaled, by their
        root mean square, which leaves the mean at zero). Table 1's ``"paper"`` protocol uses
        ``"zero"``. The signal variance and the noise are bounded relative to the outputs'
        scale either way.

    Attributes
    ----------
    gps_ : list of sklearn GaussianProcessRegressor
        One per output, on the outputs divided by ``y_scale_``.
    y_scale_ : array, shape (n_out,)
        The outputs' scale the processes were fitted in (1 with ``prior_mean="data"``: the
        regressor normalises them itself).
    active_ : array of int
        Inputs that vary in the training set (the others are left out of the kernel).
    n_params_ : int
        Parameter count as in the paper's Table 1.
    """

    name = "gpr"

    def __init__(self, n_restarts: int = 5, random_state=0, prior_mean: str = "data") -> None:
        self.n_restarts = n_restarts
        self.random_state = random_state
        self.prior_mean = prior_mean

    def fit(self, S, Y) -> GPRModel:
        """Fit on situations S (M, d_in) and outputs Y (M, n_out); returns self."""
        import warnings

        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

        if int(self.n_restarts) < 0:
            raise ValueError(f"n_restarts must be >= 0, got {self.n_restarts}")
        if self.prior_mean not in GPR_PRIOR_MEANS:
            raise ValueError(f"prior_mean must be one of {', '.join(GPR_PRIOR_MEANS)}, got "
                             f"{self.prior_mean!r}")
        S, Y = _check_xy(S, Y, 2, "GPR")
        zero = self.prior_mean == "zero"
        d = S.shape[1]
        # inputs that do not vary in the training set carry no information (e.g. the distance
        # to the hole when only its sideways position changes): leave them out of the kernel
        spread = np.ptp(S, axis=0)
        active = np.flatnonzero(spread > 1e-9 * max(1.0, float(spread.max())))
        if active.size == 0:
            raise ValueError("GPR: all training situations are the same point")
        scale = spread[active]
        seed = sklearn_random_state(self.random_state)
        gps = []
        # "zero": the outputs divided by their root mean square (the mean stays at zero, the
        # bounds below keep their meaning); "data": the regressor centres and scales them
        y_scale = (np.sqrt(np.mean(Y**2, axis=0)) if zero else np.ones(Y.shape[1]))
        y_scale = np.where(y_scale > 0, y_scale, 1.0)
        for j in range(Y.shape[1]):
            kernel = (ConstantKernel(1.0, (1e-2, 1e2))
                      * RBF(length_scale=scale, length_scale_bounds=(0.05 * scale.min(),
                                                                     100 * scale.max()))
                      + WhiteKernel(1e-4, (1e-8, 1e-1)))
            gp = GaussianProcessRegressor(kernel=kernel, normalize_y=not zero,
                                          n_restarts_optimizer=int(self.n_restarts),
                                          random_state=seed)
            with warnings.catch_warnings():  # bound warnings on tiny training sets
                warnings.simplefilter("ignore")
                gp.fit(S[:, active], Y[:, j] / y_scale[j])
            gps.append(gp)
        self.active_, self.gps_, self.y_scale_ = active, gps, y_scale
        self.n_params_ = gpr_param_count(S.shape[0], d, Y.shape[1])
        self.n_inputs_ = self.n_features_in_ = d
        return self

    def predict(self, S, return_var: bool = False):
        """Mean (n, n_out) and, with ``return_var``, the predictive variance (n, n_out)."""
        check_is_fitted(self, "gps_")
        S = _check_s(S, self.n_inputs_)[:, self.active_]
        out = [gp.predict(S, return_std=True) for gp in self.gps_]
        mean = np.column_stack([m for m, _ in out]) * self.y_scale_
        if not return_var:
            return mean
        return mean, np.column_stack([s**2 for _, s in out]) * self.y_scale_**2


class GMRModel(RegressorMixin, BaseEstimator):
    """GMR on a joint GMM over (s, outputs) (Eq. 18), or one GMM per output (``separate``).

    A scikit-learn estimator: ``GridSearchCV(GMRModel(), {"n_components": [1, 2, 3]})`` picks K.

    Parameters
    ----------
    n_components : int, default 3
    separate : bool, default False
        One GMM per output (the paper's "sep. GMR") instead of one joint GMM.
    random_state : int, numpy Generator or None, default 0

    Attributes
    ----------
    gmms_ : list of (output columns, sklearn GaussianMixture)
    n_params_ : int
        Parameter count as in the paper's Table 1.
    """

    def __init__(self, n_components: int = 3, separate: bool = False, random_state=0) -> None:
        self.n_components = n_components
        self.separate = separate
        self.random_state = random_state

    @property
    def name(self) -> str:
        """Registry name: ``"sep_gmr"`` or ``"gmr"``."""
        return "sep_gmr" if self.separate else "gmr"

    def fit(self, S, Y) -> GMRModel:
        """Fit by k-means then EM on situations S (M, d_in) and outputs Y (M, n_out)."""
        from sklearn.mixture import GaussianMixture

        K = self.n_components
        if isinstance(K, bool) or not isinstance(K, (int, np.integer)) or K < 1:
            raise ValueError(f"n_components must be an integer >= 1, got {K!r}")
        S, Y = _check_xy(S, Y, K + 1, f"GMR with {K} components")
        d = S.shape[1]
        groups = [[j] for j in range(Y.shape[1])] if self.separate else [list(range(Y.shape[1]))]
        seed = sklearn_random_state(self.random_state)
        gmms, functions = [], []
        for cols in groups:
            data = np.column_stack([S, Y[:, cols]])
            gm = _fit_standardised(GaussianMixture(int(K), covariance_type="full",
                                                   init_params="kmeans", reg_covar=REG_COVAR,
                                                   random_state=seed), data)
            gmms.append((cols, gm))
            # GMR (Eq. 18) of this GMM, built once: core.gmm defines it in CasADi
            functions.append(gmr_function(gm.weights_, gm.means_, gm.covariances_,
                                          list(range(d)), list(range(d, d + len(cols))),
                                          with_cov=True))
        self.gmms_, self._functions = gmms, functions
        self.n_inputs_ = self.n_features_in_ = d
        self.n_outputs_ = Y.shape[1]
        self.n_params_ = sum(gmm_param_count(int(K), d + len(c)) for c, _ in gmms)
        return self

    def predict(self, S, return_var: bool = False):
        """Mean (n, n_out) and, with ``return_var``, the conditional variance (n, n_out)."""
        check_is_fitted(self, "gmms_")
        S = _check_s(S, self.n_inputs_)
        d = self.n_inputs_
        mean = np.empty((len(S), self.n_outputs_))
        var = np.empty_like(mean)
        for (cols, gm), f in zip(self.gmms_, self._functions):
            m, c = gmr_predict(S, gm.weights_, gm.means_, gm.covariances_, np.arange(d),
                               np.arange(d, d + len(cols)), return_cov=True, function=f)
            mean[:, cols] = m
            var[:, cols] = np.diagonal(c, axis1=1, axis2=2)
        return (mean, var) if return_var else mean

    def __getstate__(self) -> dict:  # the GMR Functions are rebuilt from gmms_ after unpickling
        state = dict(self.__dict__)
        state.pop("_functions", None)
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        if "gmms_" in state:
            d = state["n_inputs_"]
            self._functions = [gmr_function(gm.weights_, gm.means_, gm.covariances_,
                                            list(range(d)), list(range(d, d + len(c))), True)
                               for c, gm in state["gmms_"]]


def _fit_standardised(gm, data: np.ndarray):
    """Fit ``gm`` (k-means, then EM) on the columns of ``data`` scaled to zero mean and unit
    variance, and return it with its parameters in the data's own units.

    Situations [m], angles [deg] and gains differ in scale by two orders of magnitude: on the
    raw data k-means clusters by the angle alone and one ``reg_covar`` for all dimensions
    swamps the gain's small variances (joint GMR then predicted the gain worse than the
    separate GMMs). Scaled, both act alike on every dimension; the model is the same family.
    """
    mu = data.mean(axis=0)
    sd = data.std(axis=0)
    sd = np.where(sd > 0, sd, 1.0)
    gm.fit((data - mu) / sd)
    gm.means_ = gm.means_ * sd + mu
    gm.covariances_ = gm.covariances_ * np.outer(sd, sd)
    chol = np.linalg.cholesky(gm.covariances_)
    gm.precisions_cholesky_ = np.transpose(np.linalg.inv(chol), (0, 2, 1))
    gm.precisions_ = gm.precisions_cholesky_ @ np.transpose(gm.precisions_cholesky_, (0, 2, 1))
    return gm


def _check_s(S, n_inputs: int) -> np.ndarray:
    S = np.atleast_2d(np.asarray(S, dtype=float))
    if S.ndim != 2 or S.shape[1] != n_inputs:
        raise ValueError(f"situations must have shape (n, {n_inputs}), got {S.shape}")
    if not np.all(np.isfinite(S)):
        raise ValueError("situations contain NaN or infinite values")
    return S


MODELS = {
    "gpr": lambda **kw: GPRModel(**kw),
    "gmr": lambda **kw: GMRModel(separate=False, **kw),
    "sep_gmr": lambda **kw: GMRModel(separate=True, **kw),
}


def make_model(name: str, **kwargs):
    """A hitting-parameter learner by name: ``"gpr"``, ``"gmr"`` or ``"sep_gmr"``."""
    if name not in MODELS:
        raise ValueError(f"unknown hitting-parameter model {name!r}; valid: {', '.join(MODELS)}")
    return MODELS[name](**kwargs)
