"""Choosing SEDS's settings on held-out demonstrations (seds_casadi.core.search).

Known answers: the held-out scores of a linear model with a closed-form error; a search between
P = I and a learned P on a system only a non-identity P certifies must choose the learned P.
Properties of the folds over random sizes; a candidate whose every fit fails loses and is
reported; bad input is refused by name.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import linear_flow_demos
from sklearn.exceptions import NotFittedError

from seds_casadi import SEDS, Demonstrations, StableDS
from seds_casadi.core.errors import SEDSError
from seds_casadi.core.metrics import reproduction_dtw
from seds_casadi.core.search import DemoSearchCV, demo_folds, held_out_scores

#: stable (eigenvalues -1, -3) but A + A^T is indefinite: only a learned P certifies it exactly
A_TRUE = np.array([[-1.0, 10.0], [0.0, -3.0]])


def _linear_demos(A=A_TRUE, n=4, T=6.0, dt=0.02, seed=0) -> Demonstrations:
    return linear_flow_demos(A, n=n, T=T, dt=dt, seed=seed)


def _linear_model(A, d=2) -> StableDS:
    """A one-component GMM DS with f(x) = A x exactly (target at the origin)."""
    Sx = np.eye(d)
    cov = np.zeros((1, 2 * d, 2 * d))
    cov[0, :d, :d] = Sx
    cov[0, d:, :d] = A @ Sx
    cov[0, :d, d:] = (A @ Sx).T
    cov[0, d:, d:] = A @ Sx @ A.T + 1e-2 * np.eye(d)
    return StableDS(np.ones(1), np.zeros((1, 2 * d)), cov, np.zeros(d))


# ------------------------------------------------------------------ folds
@settings(max_examples=60, deadline=None)
@given(n=st.integers(2, 30), data=st.data())
def test_folds_hold_each_demonstration_out_exactly_once(n, data):
    cv = data.draw(st.one_of(st.just("loo"), st.integers(2, n)))
    folds = demo_folds(n, cv)
    assert len(folds) == (n if cv == "loo" else cv)
    held = sorted(i for _, test in folds for i in test)
    assert held == list(range(n))
    for train, test in folds:
        assert test and train
        assert sorted(train + test) == list(range(n))


@pytest.mark.parametrize("n, cv, err, match", [
    (1, "loo", ValueError, "at least 2"),
    (4, 5, ValueError, "2..4"),
    (4, 1, ValueError, "2..4"),
    (4, "kfold", ValueError, "'loo'"),
    (4, 2.5, TypeError, "int"),
])
def test_bad_folds_are_refused(n, cv, err, match):
    with pytest.raises(err, match=match):
        demo_folds(n, cv)


# ------------------------------------------------------------------ held-out scores
def test_held_out_scores_of_an_exact_and_a_doubled_model():
    demos = _linear_demos(A=np.array([[-1.0, 0.5], [-0.5, -1.0]]), n=3, T=4.0)
    A = np.array([[-1.0, 0.5], [-0.5, -1.0]])
    X = np.concatenate(demos.positions)
    # the demonstrations' velocities are finite differences, so compare with the same
    V = np.concatenate(demos.velocities)
    exact = held_out_scores(_linear_model(A), demos)
    np.testing.assert_allclose(exact["rmse"],
                               np.mean(np.sqrt(np.mean((X @ A.T - V) ** 2, axis=1))), rtol=1e-9)
    doubled = held_out_scores(_linear_model(2 * A), demos)
    np.testing.assert_allclose(doubled["rmse"],
                               np.mean(np.sqrt(np.mean((2 * X @ A.T - V) ** 2, axis=1))),
                               rtol=1e-9)
    cos = np.sum((X @ A.T) * V, axis=1) / np.linalg.norm(X @ A.T, axis=1) / np.linalg.norm(V,
                                                                                          axis=1)
    np.testing.assert_allclose(exact["e_dot"], np.mean(np.abs(1 - cos)), atol=1e-12)
    # the same directions at twice the speed: same e_dot, a reproduction of twice the pace
    np.testing.assert_allclose(doubled["e_dot"], exact["e_dot"], atol=1e-12)
    assert exact["rmse"] < 0.05 * doubled["rmse"]
    # a field turned by 30 degrees: e_dot near 1 - cos 30 deg, a reproduction off the path
    c, s_ = np.cos(np.pi / 6), np.sin(np.pi / 6)
    turned = held_out_scores(_linear_model(np.array([[c, -s_], [s_, c]]) @ A), demos)
    assert turned["e_dot"] == pytest.approx(1 - c, abs=0.01)
    assert turned["dtw"] > 5 * exact["dtw"]
    # the DTW is the LASA evaluation's, from each start at the data's step until slow, with RK4
    # sub-steps of at most 0.25 / stiffness in between (the fit report's step)
    dt = demos.estimated_dt()
    V_max = np.abs(V).max()
    T = max(len(p) for p in demos.positions)
    sub = int(np.ceil(dt * np.abs(np.linalg.eigvals(A)).max() / 0.25))
    assert exact["substeps"] == sub
    ref = reproduction_dtw(_linear_model(A).predict, np.stack([p[0] for p in demos.positions]),
                           demos.positions, dt=dt, speed_tol=1e-3 * V_max,
                           max_steps=int(np.ceil(3 * T)), window=4, substeps=sub,
                           method="rk4")
    np.testing.assert_allclose(exact["dtw"], ref.mean(), rtol=1e-9)
    # given explicitly, the sub-steps are the protocol's forward Euler
    literal = reproduction_dtw(_linear_model(A).predict,
                               np.stack([p[0] for p in demos.positions]), demos.positions,
                               dt=dt, speed_tol=1e-3 * V_max, max_steps=int(np.ceil(3 * T)),
                               window=4)
    np.testing.assert_allclose(held_out_scores(_linear_model(A), demos, substeps=1)["dtw"],
                               literal.mean(), rtol=1e-12)
    assert exact["steps"] >= 5


def test_a_stiff_model_on_coarse_data_is_judged_on_its_motion_not_on_eulers_overshoot():
    # rates 60 and 40 /s sampled at 20 Hz: explicit Euler at the data's step multiplies the error
    # by |1 - 60 * 0.05| = 2 per step and diverges; the exact model must still score as exact
    A = np.diag([-60.0, -40.0])
    demos = _linear_demos(A=A, n=3, T=0.5, dt=0.05)
    model = _linear_model(A)
    auto = held_out_scores(model, demos)
    assert auto["substeps"] == 12  # ceil(0.05 * 60 / 0.25)
    literal = held_out_scores(model, demos, substeps=1)
    assert literal["substeps"] == 1
    assert not np.isfinite(literal["dtw"]) or literal["dtw"] > 1e3
    # the reproduction at dt / 12 (RK4) follows the exact flow: a DTW far below the extent
    assert auto["dtw"] < 0.5
    assert auto["rmse"] == literal["rmse"] and auto["e_dot"] == literal["e_dot"]
    # a plain callable has no stiffness: the data's step, literally
    assert held_out_scores(model.predict, demos)["substeps"] == 1


# ------------------------------------------------------------------ the search
@pytest.fixture(scope="module")
def lyapunov_search():
    demos = _linear_demos(n=3)
    search = DemoSearchCV(SEDS(1, objective="mse", random_state=0, max_iter=200),
                          {"lyapunov": ["identity", "learned"]}).fit(demos)
    return demos, search


def test_search_chooses_the_learned_p_where_only_it_fits(lyapunov_search):
    demos, search = lyapunov_search
    res = search.cv_results_
    assert search.best_params_ == {"lyapunov": "learned"}
    assert list(res["rank_test_score"]) == [2, 1]
    assert res["mean_rmse"][1] < 0.3 * res["mean_rmse"][0]
    assert search.best_score_ == pytest.approx(0.0)  # the best of every metric
    assert res["mean_test_score"][0] < 0
    # the refit is on every demonstration and certified with its P
    m = search.model_
    assert m.fit_info["lyapunov"] == "learned"
    assert m.fit_info["search"]["best_params"] == {"lyapunov": "learned"}
    P = m.lyapunov_matrix
    assert np.linalg.eigvalsh(m.A[0].T @ P + P @ m.A[0]).max() < 0
    X = np.concatenate(demos.positions)
    np.testing.assert_allclose(search.predict(X), m.predict(X))
    for m_name in ("rmse", "e_dot", "dtw"):
        split = np.stack([res[f"split{f}_{m_name}"] for f in range(3)], axis=1)
        np.testing.assert_allclose(res[f"mean_{m_name}"], split.mean(axis=1))
    assert "learned" in search.table().splitlines()[1]


def test_searched_model_saves_and_loads_with_its_record(lyapunov_search, tmp_path):
    _, search = lyapunov_search
    path = tmp_path / "m.npz"
    search.model_.save(path)
    back = StableDS.load(path)
    assert back.fit_info["search"]["candidates"] == [{"lyapunov": "identity"},
                                                     {"lyapunov": "learned"}]


def test_single_metric_and_callable_scorings_agree_with_the_table(lyapunov_search):
    demos, base = lyapunov_search
    by_dtw = DemoSearchCV(base.estimator, base.param_grid, scoring="dtw", refit=False).fit(demos)
    np.testing.assert_allclose(by_dtw.cv_results_["mean_test_score"],
                               -base.cv_results_["mean_dtw"])
    seen = []

    def neg_rmse(model, held):
        seen.append(held.n_demos)
        return -held_out_scores(model, held)["rmse"]

    by_call = DemoSearchCV(base.estimator, base.param_grid, scoring=neg_rmse, cv=3,
                           refit=False).fit(demos)
    np.testing.assert_allclose(by_call.cv_results_["mean_test_score"],
                               -base.cv_results_["mean_rmse"])
    assert seen == [1] * 6
    with pytest.raises(NotFittedError, match="refit=False"):
        _ = by_call.model_


def test_a_candidate_that_always_fails_loses_and_is_reported():
    demos = _linear_demos(A=np.array([[-1.0, 0.5], [-0.5, -1.0]]), n=3, T=3.0)

    def impossible(model):  # a positive diagonal gain contradicts A_k + A_k^T < 0
        return [(model["A"][0][0, 0], 1.0, np.inf)]

    search = DemoSearchCV(SEDS(1, objective="mse", random_state=0, max_iter=100),
                          [{"constraints": [impossible]}, {"constraints": [None]}],
                          refit=False).fit(demos)
    res = search.cv_results_
    assert list(res["n_failed"]) == [3, 0]
    assert res["errors"][0] and not res["errors"][1]
    assert search.best_index_ == 1
    assert res["mean_test_score"][0] == -np.inf
    assert "3 folds failed" in search.table()
    with pytest.raises(SEDSError, match="every candidate failed"):
        DemoSearchCV(SEDS(1, objective="mse", max_iter=100),
                     {"constraints": [impossible]}).fit(demos)


@pytest.mark.parametrize("make, err, match", [
    (lambda: DemoSearchCV(None, {"lyapunov": ["learned"]}), TypeError, "needs an estimator"),
    (lambda: DemoSearchCV(SEDS(1), {}), ValueError, "param_grid is empty"),
    (lambda: DemoSearchCV(SEDS(1), {"n_gaussians": [2]}), ValueError, "n_gaussians"),
    (lambda: DemoSearchCV(SEDS(1), {"n_components": [1]}, scoring="r2"), ValueError,
     "unknown scoring"),
])
def test_bad_searches_are_refused_before_any_fit(make, err, match):
    with pytest.raises(err, match=match):
        make().fit(_linear_demos(n=2, T=1.0))


def test_bad_data_is_refused():
    search = DemoSearchCV(SEDS(1), {"n_components": [1]})
    demos = _linear_demos(n=2, T=1.0)
    with pytest.raises(TypeError, match="Demonstrations"):
        search.fit(np.concatenate(demos.positions))
    X, V, _, _ = demos.stacked()
    with pytest.raises(ValueError, match="time order"):
        search.fit(Demonstrations.from_samples(X, V))
    with pytest.raises(ValueError, match="at least 2"):
        search.fit(demos.select([0]))
