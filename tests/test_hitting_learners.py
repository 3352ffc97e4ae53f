"""Hitting-parameter learners (Section 5): known functions, variances, Table 1 counts, bad input."""

import numpy as np
import pytest

from seds_casadi.minigolf.parameters import (
    GMRModel,
    GPRModel,
    gmm_param_count,
    gpr_param_count,
    make_model,
)


def _data(n, seed=0, noise=0.0):
    """A smooth 2-output map along one input dimension (the hole moved sideways)."""
    rng = np.random.default_rng(seed)
    y = np.sort(rng.uniform(-0.5, 0.5, n))
    S = np.column_stack([np.full(n, 2.4), y])
    alpha = 0.2 * np.sin(3 * y) + noise * rng.standard_normal(n)
    kappa = 1.0 + 0.3 * y**2 + noise * rng.standard_normal(n)
    return S, np.column_stack([alpha, kappa])


def _truth(S):
    y = S[:, 1]
    return np.column_stack([0.2 * np.sin(3 * y), 1.0 + 0.3 * y**2])


@pytest.mark.parametrize("name", ["gpr", "gmr", "sep_gmr"])
def test_learners_recover_a_known_smooth_function(name):
    S, Y = _data(25)
    kw = {} if name == "gpr" else {"n_components": 4}
    model = make_model(name, **kw).fit(S, Y)
    St = np.column_stack([np.full(50, 2.4), np.linspace(-0.45, 0.45, 50)])
    mean, var = model.predict(St, return_var=True)
    err = np.sqrt(np.mean((mean - _truth(St)) ** 2, axis=0))
    tol = 0.005 if name == "gpr" else 0.03
    assert np.all(err < tol), err
    assert np.all(var >= 0) and mean.shape == var.shape == (50, 2)


def test_gpr_is_uncertain_far_from_the_data_and_sure_at_it():
    S, Y = _data(10)
    gp = GPRModel().fit(S, Y[:, :1])
    _, v_at = gp.predict(S, return_var=True)
    _, v_far = gp.predict(np.array([[2.4, 3.0]]), return_var=True)
    assert v_far[0, 0] > 10 * v_at.max()


def test_zero_mean_gpr_is_eq_17a_as_printed():
    """prior_mean="zero": the prediction is K(s*, S) (K(S, S) + sigma_n I)^-1 alpha with the
    fitted hyperparameters (Eq. 17a, no mean term), in the outputs' own units."""
    S, Y = _data(12, seed=3, noise=0.01)
    Y = Y + np.array([5.0, 0.0])  # an offset that a zero-mean process must carry itself
    gp = GPRModel(prior_mean="zero").fit(S, Y)
    St = np.column_stack([np.full(7, 2.4), np.linspace(-0.7, 0.7, 7)])
    mean, var = gp.predict(St, return_var=True)
    for j, g in enumerate(gp.gps_):
        signal, noise = g.kernel_.k1, g.kernel_.k2.noise_level
        X, Xt = S[:, gp.active_], St[:, gp.active_]
        K = signal(X) + noise * np.eye(len(X))
        want = signal(Xt, X) @ np.linalg.solve(K, Y[:, j] / gp.y_scale_[j]) * gp.y_scale_[j]
        assert np.allclose(mean[:, j], want, atol=1e-8 * np.abs(want).max())
        assert gp.y_scale_[j] == pytest.approx(np.sqrt(np.mean(Y[:, j] ** 2)))
    assert np.all(var > 0)


def test_far_from_the_data_gpr_returns_to_its_prior_mean():
    """Section 5.2: GPR "outputs zero far from the training data" with the zero mean of
    Eq. 17a; with prior_mean="data" it returns to the training outputs' mean instead."""
    S, Y = _data(10, seed=2)
    alpha = 10.0 + Y[:, :1]  # angles about 10 deg, varying by +-0.2
    far = np.array([[2.4, 50.0]])
    zero = GPRModel(prior_mean="zero").fit(S, alpha).predict(far)[0, 0]
    data = GPRModel().fit(S, alpha).predict(far)[0, 0]
    assert abs(zero) < 1e-3
    assert data == pytest.approx(alpha.mean(), abs=1e-3)
    # near the data the two agree
    near = S[:3]
    assert np.allclose(GPRModel(prior_mean="zero").fit(S, alpha).predict(near),
                       GPRModel().fit(S, alpha).predict(near), atol=0.02)


def test_joint_gmr_keeps_the_correlation_of_the_outputs():
    rng = np.random.default_rng(1)
    s = rng.uniform(-1, 1, 200)
    a = s + 0.05 * rng.standard_normal(200)
    k = 2 * a + 0.01 * rng.standard_normal(200)
    S = np.column_stack([2.4 + 0.01 * rng.standard_normal(200), s])
    gm = GMRModel(n_components=1).fit(S, np.column_stack([a, k]))
    _, g = gm.gmms_[0]
    C = g.covariances_[0]
    cov = C[2:, 2:] - C[2:, :2] @ np.linalg.solve(C[:2, :2], C[:2, 2:])  # Cov[(a, k) | s]
    corr = cov[0, 1] / np.sqrt(cov[0, 0] * cov[1, 1])
    assert corr > 0.9


@pytest.mark.parametrize("separate", [False, True])
def test_gmr_does_not_depend_on_the_units_of_its_outputs(separate):
    # the angle in degrees or radians, the gain as a gain or in percent: the same model (the
    # GMM is fitted on data scaled per dimension); once one covariance floor for all
    # dimensions, set by the largest, swamped a small-scale output of the joint GMM
    rng = np.random.default_rng(2)
    S = np.column_stack([rng.uniform(-0.1, 0.3, 40), rng.uniform(-0.45, 0.45, 40)])
    alpha = 30 * np.tanh(3 * S[:, 1]) + rng.normal(0, 0.2, 40)           # deg
    kappa = 1.0 + 0.2 * S[:, 1] ** 2 - 0.1 * S[:, 0] + rng.normal(0, 0.002, 40)
    Q = np.column_stack([rng.uniform(-0.1, 0.3, 50), rng.uniform(-0.45, 0.45, 50)])
    a = GMRModel(3, separate=separate).fit(S, np.column_stack([alpha, kappa]))
    b = GMRModel(3, separate=separate).fit(S, np.column_stack([np.deg2rad(alpha),
                                                               100 * kappa]))
    pa, pb = a.predict(Q), b.predict(Q)
    np.testing.assert_allclose(np.deg2rad(pa[:, 0]), pb[:, 0], rtol=1e-5, atol=1e-8)
    np.testing.assert_allclose(100 * pa[:, 1], pb[:, 1], rtol=1e-5, atol=1e-6)
    # the fitted parameters are in the data's own units
    _, gm = a.gmms_[0]
    assert np.all(gm.means_[:, :2].min(axis=0) > [-0.2, -0.5])
    assert np.all(gm.means_[:, :2].max(axis=0) < [0.4, 0.5])


def test_parameter_counts_match_table_1():
    # rough flat / double hill: s 2-D, angle only; arctan: s 2-D, angle and speed
    assert gpr_param_count(5, 2, 1) == 19 and gpr_param_count(10, 2, 1) == 34
    assert gpr_param_count(16, 2, 2) == 72 and gpr_param_count(28, 2, 2) == 120
    assert gmm_param_count(2, 3) == 20
    assert 2 * gmm_param_count(3, 3) == 60 and gmm_param_count(3, 4) == 45
    S, Y = _data(16)
    assert GPRModel().fit(S, Y).n_params_ == 72
    assert GMRModel(3).fit(S, Y).n_params_ == 45
    assert GMRModel(3, separate=True).fit(S, Y).n_params_ == 60


def test_bad_input():
    S, Y = _data(3)
    with pytest.raises(ValueError, match="at least 4 training points"):
        GMRModel(3).fit(S, Y)
    with pytest.raises(ValueError, match="at least 2"):
        GPRModel().fit(S[:1], Y[:1])
    with pytest.raises(ValueError, match="NaN"):
        GPRModel().fit(np.array([[0.0, np.nan], [1.0, 1.0]]), [1.0, 2.0])
    with pytest.raises(ValueError, match="valid: gpr, gmr, sep_gmr"):
        make_model("svr")
    with pytest.raises(ValueError, match="prior_mean must be one of data, zero"):
        GPRModel(prior_mean="mean").fit(*_data(5))
    with pytest.raises(ValueError, match="situations"):
        GPRModel().fit(S, Y[:2])
