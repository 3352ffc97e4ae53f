"""GMM/GMR (defined once in CasADi) against a numpy oracle, scipy and closed forms."""

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import gmr_predict as gmr_oracle
from oracles import log_gaussian, random_gmm
from oracles import responsibilities as resp_oracle
from scipy.stats import multivariate_normal

from seds_casadi.core.gmm import gmr_function, gmr_predict, responsibilities, responsibilities_sx


def test_oracle_log_gaussian_matches_scipy():
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


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), K=st.integers(1, 4), n_in=st.integers(1, 3),
       n_out=st.integers(1, 3), scale=st.floats(0.1, 30.0))
def test_casadi_gmr_equals_the_numpy_oracle(seed, K, n_in, n_out, scale):
    rng = np.random.default_rng(seed)
    priors, means, covs = random_gmm(rng, K, n_in + n_out)
    X = rng.standard_normal((40, n_in)) * scale
    i, o = list(range(n_in)), list(range(n_in, n_in + n_out))
    mu, cov = gmr_predict(X, priors, means, covs, i, o, return_cov=True)
    mu_ref, cov_ref = gmr_oracle(X, priors, means, covs, i, o, return_cov=True)
    np.testing.assert_allclose(mu, mu_ref, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(cov, cov_ref, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(responsibilities(X, priors, means[:, i], covs[:, i][:, :, i]),
                               resp_oracle(X, priors, means[:, i], covs[:, i][:, :, i]),
                               rtol=1e-9, atol=1e-12)


def test_the_symbolic_gmr_is_differentiable_and_matches_finite_differences():
    rng = np.random.default_rng(3)
    priors, means, covs = random_gmm(rng, 3, 3)
    f = gmr_function(priors, means, covs, [0, 1], [2])
    x = ca.SX.sym("x", 2)
    J = ca.Function("J", [x], [ca.jacobian(f(x), x)])
    p = np.array([0.3, -0.2])
    eps = 1e-6
    fd = np.array([(float(f(p + eps * e)) - float(f(p - eps * e))) / (2 * eps)
                   for e in np.eye(2)])
    np.testing.assert_allclose(np.asarray(J(p)).ravel(), fd, rtol=1e-6, atol=1e-8)


def test_responsibilities_sx_sum_to_one_symbolically():
    rng = np.random.default_rng(4)
    priors, means, covs = random_gmm(rng, 4, 2)
    x = ca.SX.sym("x", 2)
    s = ca.Function("s", [x], [sum(responsibilities_sx(x, priors, means, covs))])
    for p in rng.standard_normal((10, 2)) * 100:
        assert float(s(p)) == pytest.approx(1.0, abs=1e-12)


def test_bad_shapes_are_clear_errors():
    with pytest.raises(ValueError, match="inconsistent GMM shapes"):
        responsibilities(np.zeros((2, 2)), [0.5, 0.5], np.zeros((2, 2)), np.stack([np.eye(3)] * 2))
    with pytest.raises(ValueError, match=r"shape \(n, 1\)"):
        gmr_predict(np.zeros((2, 2)), [1.0], [[0.0, 0.0]], [np.eye(2)], [0], [1])
