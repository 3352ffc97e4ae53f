"""Choosing the number of Gaussians K by BIC, as SEDS and ds-opt do.

The original SEDS package and the LPV-DS evaluation (nbfigueroa/ds-opt) pick K by the Bayesian
information criterion of a full-covariance GMM fitted by EM to the joint data [x; xdot]: the K
with the lowest BIC, up to a maximum (15 in ds-opt). The SEDS fit itself is not repeated for each
K (that would cost K_max constrained solves); this is the same cheap proxy those packages use.
"""

from __future__ import annotations

import numpy as np

from ._random import sklearn_random_state

__all__ = ["bic_n_components", "MAX_COMPONENTS"]

#: largest K tried by ``n_components="bic"`` (ds-opt's limit)
MAX_COMPONENTS = 15


def bic_n_components(X: np.ndarray, Xdot: np.ndarray, max_components: int = MAX_COMPONENTS,
                     random_state=0) -> tuple[int, np.ndarray]:
    """The K in 1..max_components whose joint GMM on [x; xdot] has the lowest BIC.

    Parameters
    ----------
    X, Xdot : array, shape (n_samples, d)
        Positions and velocities (any consistent units; each is scaled to unit RMS first, as
        the SEDS problem is).
    max_components : int
        Largest K tried; also limited so that every component has at least 2 (d + 1) samples.
    random_state : int, numpy Generator or None

    Returns
    -------
    K : int
    bic : array, shape (K_tried,)
        BIC of K = 1, 2, ... (lower is better).
    """
    from sklearn.mixture import GaussianMixture

    X, Xdot = np.asarray(X, dtype=float), np.asarray(Xdot, dtype=float)
    if X.ndim != 2 or Xdot.shape != X.shape or len(X) < 2:
        raise ValueError(f"X and Xdot must have the same shape (n >= 2, d), got {X.shape} and "
                         f"{Xdot.shape}")
    if int(max_components) < 1:
        raise ValueError(f"max_components must be at least 1, got {max_components}")
    d = X.shape[1]
    Z = np.hstack([X / max(np.sqrt(np.mean(X**2)), 1e-300),
                   Xdot / max(np.sqrt(np.mean(Xdot**2)), 1e-300)])
    k_max = max(1, min(int(max_components), len(X) // (2 * (d + 1))))
    seed = sklearn_random_state(random_state)
    bic = np.array([GaussianMixture(k, covariance_type="full", init_params="kmeans",
                                    reg_covar=1e-6, random_state=seed).fit(Z).bic(Z)
                    for k in range(1, k_max + 1)])
    return int(np.argmin(bic)) + 1, bic
