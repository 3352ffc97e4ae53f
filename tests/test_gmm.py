"""numpy GMM helpers against scipy and closed forms."""

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from seds_casadi.core.gmm import gmr_predict, log_gaussian, responsibilities


def test_log_gaussian_matches_scipy():
    rng = np.random.default_rng(0)
    M = rng.standard_normal((3, 3))
    cov = M @ M.T + 0.5 * np.eye(3)
    mean = rng.standard_normal(3)
    X = rng.standard_normal((20, 3)) * 3
    np.testing.assert_allclose(log_gaussian(X, mean, cov),
                               multivariate_normal(mean, cov).logpdf(X), rtol=1e-12)


def test_responsibilities_are_finite_far_away_and_sum_to_one():
    priors = np.array([0.3, 0.7])
    means = np.array([[0.0, 0.0], [1.0, 0.0]])
    covs = np.stack([np.eye(2), 0.1 * np.eye(2)])
    h = responsibilities(np.array([[1e6, 0.0], [0.5, 0.0]]), priors, means, covs)
    assert np.all(np.isfinite(h))
    np.testing.assert_allclose(h.sum(axis=1), 1.0)
    assert h[0, 0] == pytest.approx(1.0)  # the wider Gaussian wins far away


def test_gmr_with_one_gaussian_is_the_gaussian_conditional():
    # joint N([mx, my], [[sxx, sxy], [sxy, syy]]): E[y|x] = my + sxy/sxx (x - mx),
    # Var[y|x] = syy - sxy^2/sxx
    mean = np.array([[1.0, 2.0]])
    cov = np.array([[[2.0, 0.6], [0.6, 1.0]]])
    X = np.array([[0.0], [1.0], [3.0]])
    mu, var = gmr_predict(X, np.array([1.0]), mean, cov, [0], [1], return_cov=True)
    np.testing.assert_allclose(mu[:, 0], 2.0 + 0.3 * (X[:, 0] - 1.0))
    np.testing.assert_allclose(var[:, 0, 0], 1.0 - 0.36 / 2.0)


def test_gmr_variance_includes_the_spread_between_components():
    # two components with the same input distribution: E = mean of outputs, Var adds the spread
    means = np.array([[0.0, -1.0], [0.0, 1.0]])
    covs = np.stack([np.diag([1.0, 0.25])] * 2)
    mu, var = gmr_predict(np.zeros((1, 1)), np.array([0.5, 0.5]), means, covs, [0], [1],
                          return_cov=True)
    assert mu[0, 0] == pytest.approx(0.0)
    assert var[0, 0, 0] == pytest.approx(0.25 + 1.0)
