"""SEDS(init="pc", gmm="fixed"): the physically-consistent clustering and the fixed-GMM fit.

The similarity against a per-pair loop written from the PC-GMM paper's definition; a known
answer where only the velocity directions separate two clusters; a fixed-GMM fit keeps its
initial GMM exactly, optimises the dynamics, and is certified.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import decaying_spiral_demos

from seds_casadi import SEDS
from seds_casadi.core.problem import _pc_gmm, gmm_indices, pc_embedding, pc_similarity


def _similarity_loop(X, Xd):
    """s_ij = exp(-l |x_i - x_j|) (1 + cos), l = 1 / (2 sigma^2), sigma^2 = mode / 2, pair by
    pair (the histogram's mode is the centre of its fullest bin, numpy's 'auto' bins)."""
    n = len(X)
    dists = [float(np.sqrt(np.sum((X[i] - X[j]) ** 2))) for i in range(n) for j in range(i + 1, n)]
    counts, edges = np.histogram(dists, bins="auto")
    b = int(np.argmax(counts))
    l_inv = 2.0 * max((edges[b] + edges[b + 1]) / 2, 1e-6 * max(dists)) / 2.0
    S = np.zeros((n, n))
    for i in range(n):
        for j in range(n):
            ni, nj = np.linalg.norm(Xd[i]), np.linalg.norm(Xd[j])
            cos = 0.0 if ni == 0 or nj == 0 else float(Xd[i] @ Xd[j]) / (ni * nj)
            S[i, j] = np.exp(-np.linalg.norm(X[i] - X[j]) / l_inv) * (1.0 + cos)
    return S


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(3, 25), d=st.integers(2, 4))
def test_similarity_matches_the_pairwise_definition(seed, n, d):
    rng = np.random.default_rng(seed)
    X, Xd = rng.normal(size=(n, d)), rng.normal(size=(n, d))
    Xd[0] = 0.0  # a sample at rest: cos = 0 with every other
    S = pc_similarity(X, Xd)
    np.testing.assert_allclose(S, _similarity_loop(X, Xd), rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(S, S.T, rtol=0, atol=0)
    assert np.all(S >= 0) and np.all(S <= 2 + 1e-12)
    np.testing.assert_allclose(np.diag(S)[1:], 2.0, rtol=1e-12)  # itself: same place, cos 1


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(12, 120), d=st.integers(2, 4),
       k=st.integers(1, 5))
def test_embedding_matches_scikit_learns_spectral_embedding(seed, n, d, k):
    """Our step-by-step embedding (Cholesky shift-invert) against scikit-learn's
    ``spectral_embedding``: the same columns (up to rounding) and the same random state after
    it, so each K's k-means starts where SpectralClustering's would."""
    import warnings

    from sklearn.manifold import spectral_embedding
    from sklearn.utils import check_random_state

    rng = np.random.default_rng(seed)
    t = np.linspace(0, 1, n)[:, None]
    X = np.hstack([np.cos(3 * t), np.sin(3 * t), t ** 2, t][:d]) + 0.05 * rng.normal(size=(n, d))
    Xd = np.gradient(X, axis=0) + 0.01 * rng.normal(size=(n, d))
    ours = pc_embedding(X, Xd, k, seed)
    rs = check_random_state(seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        theirs = spectral_embedding(pc_similarity(X, Xd), n_components=k, random_state=rs,
                                    drop_first=False)
    assert ours.maps.shape == (n, k)
    # eigenvectors of (nearly) equal eigenvalues are defined only up to a rotation: compare
    # the spaces they span, and the columns themselves when the spectrum is well separated
    Q1, Q2 = np.linalg.qr(ours.maps)[0], np.linalg.qr(theirs)[0]
    assert np.linalg.norm(Q1 - Q2 @ (Q2.T @ Q1)) < 1e-6
    for a, b in zip(ours.state, rs.get_state()):
        assert np.array_equal(np.asarray(a), np.asarray(b))


@pytest.mark.parametrize("k", [3, 9, 12])
def test_embedding_columns_solve_the_generalised_eigenproblem(k):
    """Each column u is a generalised eigenvector (D - W) u = lambda D u of the similarity W
    without its diagonal (self-similarities are no edges of the graph; degrees D), the
    eigenvalues ascending from 0 (the graph Laplacian's smallest), by ARPACK (k < n) and by
    the dense solve that serves k >= n (here n = 12)."""
    rng = np.random.default_rng(3)
    t = np.linspace(0, 1, 12)[:, None]
    X = np.hstack([np.cos(2 * t), np.sin(2 * t)]) + 0.02 * rng.normal(size=(12, 2))
    Xd = np.gradient(X, axis=0)
    W = pc_similarity(X, Xd)
    np.fill_diagonal(W, 0.0)
    D = np.diag(W.sum(axis=1))
    U = pc_embedding(X, Xd, k, 0).maps
    assert U.shape == (12, min(k, 12))
    lam = np.array([u @ (D - W) @ u / (u @ D @ u) for u in U.T])
    for u, lm in zip(U.T, lam, strict=True):
        np.testing.assert_allclose((D - W) @ u, lm * (D @ u), atol=1e-8 * np.abs(D).max())
    assert lam[0] == pytest.approx(0.0, abs=1e-10) and np.all(np.diff(lam) >= -1e-10)


def test_embedding_equals_scikit_learns_on_a_lasa_shape():
    """On LASA's Angle (1,000 samples, K up to 10) the columns agree to rounding."""
    from sklearn.manifold import spectral_embedding
    from sklearn.utils import check_random_state

    from seds_casadi.app.lasa import dsopt_sets
    from seds_casadi.core.problem import data_scales

    X, Xd, _, _ = dsopt_sets("Angle")["train"].demonstrations().stacked()
    sx, sv = data_scales(X, Xd)
    ours = pc_embedding(X / sx, Xd / sv, 10, 0)
    theirs = spectral_embedding(pc_similarity(X[::2] / sx, Xd[::2] / sv), n_components=10,
                                random_state=check_random_state(0), drop_first=False)
    np.testing.assert_allclose(ours.maps, theirs, atol=1e-10)


def test_clusters_follow_the_direction_where_positions_alone_cannot():
    # two long parallel lanes 0.02 apart, travelled in opposite directions: by position alone
    # the best split of two is across the lanes' length; by the physically-consistent
    # similarity each lane is one cluster (opposite velocities have similarity 0)
    x = np.linspace(-1, 1, 200)
    X = np.r_[np.c_[x, np.zeros_like(x)], np.c_[x, np.full_like(x, 0.02)]]
    Xd = np.r_[np.tile([1.0, 0.0], (200, 1)), np.tile([-1.0, 0.0], (200, 1))]
    w, mu, cov = _pc_gmm(X, Xd, 2, random_state=0, reg=1e-9)
    lanes = sorted(mu[:, 1])
    assert lanes == pytest.approx([0.0, 0.02], abs=1e-9)
    np.testing.assert_allclose(w, 0.5, atol=1e-12)
    assert np.all(cov[:, 1, 1] < 1e-8)  # no cluster straddles the lanes
    from sklearn.mixture import GaussianMixture

    em = GaussianMixture(2, random_state=0).fit(X)
    assert np.ptp(em.means_[:, 0]) > 0.5  # EM on positions cuts across the lanes instead


_spiral_demos = decaying_spiral_demos


@pytest.mark.parametrize("lyapunov", ["identity", "learned"])
def test_fixed_gmm_keeps_the_initial_gmm_and_fits_a_certified_model(lyapunov):
    demos = _spiral_demos()
    learner = SEDS(3, objective="mse", random_state=0, lyapunov=lyapunov, init="pc",
                   gmm="fixed", max_iter=300)
    prob = learner.build_problem(demos)
    idx = gmm_indices(prob.layout)
    np.testing.assert_array_equal(prob.lbx[idx], prob.theta0[idx])
    np.testing.assert_array_equal(prob.ubx[idx], prob.theta0[idx])
    priors0, means0, covs0 = prob.to_model_arrays(prob.theta0)
    model = learner.fit(demos).model_
    assert model.fit_info["gmm"] == "fixed" and model.fit_info["init"] == "pc"
    c = model.certificate
    assert c["max_eig_lyapunov"] < 0 and c["min_eig_cov"] > 0
    d = 2
    np.testing.assert_allclose(model.priors, priors0, rtol=1e-9)
    np.testing.assert_allclose(model.means[:, :d], means0[:, :d], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(model.covariances[:, :d, :d], covs0[:, :d, :d], rtol=1e-9)
    # the start's gains are already the least-squares stable gains for the initial P under
    # this mixing (so, for mse and P = I, the optimum): IPOPT may not make it worse
    assert model.fit_info["objective"] <= model.fit_info["objective_initial"] * (1 + 1e-9)
    # and the model reproduces the spiral's direction
    X, Xd = np.concatenate(demos.positions), np.concatenate(demos.velocities)
    moving = (np.linalg.norm(Xd, axis=1) > 1e-9) & (np.linalg.norm(X, axis=1) > 1e-9)
    X, Xd = X[moving], Xd[moving]
    F = model.predict(X)
    cos = np.sum(F * Xd, 1) / np.linalg.norm(F, axis=1) / np.linalg.norm(Xd, axis=1)
    assert np.median(cos) > 0.95


def test_joint_gmm_moves_the_gmm():
    demos = _spiral_demos()
    learner = SEDS(3, objective="mse", random_state=0, init="pc", max_iter=300)
    prob = learner.build_problem(demos)
    assert np.all(prob.lbx[gmm_indices(prob.layout)] < prob.ubx[gmm_indices(prob.layout)])
    _, means0, _ = prob.to_model_arrays(prob.theta0)
    model = learner.fit(demos).model_
    assert np.abs(model.means[:, :2] - means0[:, :2]).max() > 1e-3


def test_unknown_gmm_is_refused():
    with pytest.raises(ValueError, match="'gmm' parameter of SEDS must be a str among "
                                         "{'joint', 'fixed', 'auto'}. Got 'frozen'"):
        SEDS(2, gmm="frozen").fit(_spiral_demos())


@pytest.mark.parametrize("lyapunov", ["identity", "learned"])
def test_fixed_gmm_mse_statistics_equal_the_sum_over_samples(lyapunov):
    # two implementations of the same J: the (K d)-square statistics (GramKernels) and the
    # per-sample C sums (SumKernels), at random dynamics with the GMM at its fixed values
    from seds_casadi.core.objectives import GramKernels, SumKernels

    demos = _spiral_demos()
    prob = SEDS(3, objective="mse", random_state=0, lyapunov=lyapunov, init="pc",
                gmm="fixed").build_problem(demos)
    assert isinstance(prob.kernels, GramKernels) and prob.hessian == "exact"
    ref = SumKernels(prob.layout, "mse", prob.margin, prob.X, prob.Xd, np.ones(len(prob.X)),
                     float(len(prob.X)))
    rng = np.random.default_rng(1)
    free = np.setdiff1d(np.arange(prob.layout.size), gmm_indices(prob.layout))
    for _ in range(3):
        theta = prob.theta0.copy()
        theta[free] += rng.normal(scale=0.3, size=len(free))
        assert prob.kernels.value(theta) == pytest.approx(ref.value(theta), rel=1e-10)
        np.testing.assert_allclose(prob.kernels.gradient(theta)[free], ref.gradient(theta)[free],
                                   rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(prob.kernels.hessian(theta)[np.ix_(free, free)],
                                   ref.hessian(theta)[np.ix_(free, free)], rtol=1e-7, atol=1e-9)


def test_fixed_gmm_in_7d_on_exactly_linear_data_is_certified():
    # a 7-D linear flow is fitted almost exactly: the joint covariances' velocity block is then
    # A Sigma_x A^T plus a tiny residual, and a floor far below that block was lost to rounding
    # (joint covariance "not positive definite", eigenvalue -3e-11, before the relative floor)
    from oracles import linear_flow_demos

    rng = np.random.default_rng(3)
    M, W = rng.normal(size=(7, 7)), rng.normal(size=(7, 7))
    A = -(M @ M.T / 7 + 0.5 * np.eye(7)) + 0.3 * (W - W.T)
    demos = linear_flow_demos(A, n=4, T=4.0, dt=0.02)
    model = SEDS(4, objective="mse", random_state=0, init="pc", gmm="fixed").fit(demos).model_
    c = model.certificate
    assert c["max_eig_lyapunov"] < 0 and c["min_eig_cov"] > 0
    X = np.concatenate(demos.positions)
    cos = np.sum(model.predict(X) * (X @ A.T), 1) / (
        np.linalg.norm(model.predict(X), axis=1) * np.linalg.norm(X @ A.T, axis=1))
    assert np.median(cos) > 0.95
