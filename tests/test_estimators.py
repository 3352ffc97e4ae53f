"""The scikit-learn convention: clone, get/set_params, model selection of n_components."""

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from sklearn.model_selection import GridSearchCV, GroupKFold, KFold, cross_val_score

from seds_casadi import SEDS, Demonstrations, StableDS
from seds_casadi.minigolf.parameters import GMRModel, GPRModel


@pytest.mark.parametrize("est", [SEDS(3, objective="mse", random_state=1, max_iter=50),
                                 GPRModel(n_restarts=1, random_state=2),
                                 GMRModel(n_components=2, separate=True, random_state=3)])
def test_clone_keeps_every_parameter_and_no_fitted_state(est):
    c = clone(est)
    assert c is not est and c.get_params() == est.get_params()
    assert not any(k.endswith("_") and not k.startswith("_") for k in vars(c))


def test_set_params_takes_effect_in_fit(spiral_demos):
    learner = SEDS(1, objective="mse", random_state=0)
    learner.set_params(n_components=2)
    assert learner.fit(spiral_demos).model_.n_components == 2
    with pytest.raises(ValueError, match="Invalid parameter"):
        learner.set_params(n_component=3)


def test_seds_fit_returns_the_learner_with_a_certified_model(spiral_demos):
    learner = SEDS(2, objective="mse", random_state=0)
    with pytest.raises(NotFittedError, match="fit"):
        learner.predict(np.zeros((1, 2)))
    assert learner.fit(spiral_demos) is learner
    assert isinstance(learner.model_, StableDS)
    assert learner.fit_info_ is learner.model_.fit_info and learner.n_features_in_ == 2
    X = np.concatenate(spiral_demos.positions)
    np.testing.assert_array_equal(learner.predict(X), learner.model_.predict(X))
    assert learner.score(spiral_demos) > 0.99  # a linear spiral: R^2 of the velocities


def test_seds_on_sample_arrays_equals_seds_on_demonstrations(spiral_demos):
    """fit(X, y) with the samples of a Demonstrations (the form model selection passes) is the
    same problem as fit(demos) when the objective does not use the time order."""
    Xs, Xd, _, _ = spiral_demos.stacked()
    a = SEDS(2, objective="mse", random_state=0).fit(spiral_demos).model_
    b = SEDS(2, objective="mse", random_state=0).fit(Xs + spiral_demos.target, Xd,
                                                     target=spiral_demos.target).model_
    np.testing.assert_allclose(a.predict(Xs[:20]), b.predict(Xs[:20]), rtol=1e-6, atol=1e-9)


@pytest.mark.slow
def test_grid_search_picks_seds_components_by_demonstration_folds():
    # two regimes (a fast spiral near the target, a slow drift further out): K=1 cannot fit both
    from scipy.linalg import expm

    rng = np.random.default_rng(0)
    pos, vel = [], []
    for n in range(4):
        x = np.array([3.0, 0.5 + 0.4 * n]) + 0.05 * rng.standard_normal(2)
        P, V = [], []
        for _ in range(60):
            A = np.array([[-0.4, 0.0], [0.0, -0.4]]) if np.linalg.norm(x) > 1.5 else \
                np.array([[-1.0, -3.0], [3.0, -1.0]])
            P.append(x.copy())
            V.append(A @ x)
            x = expm(0.05 * A) @ x
        pos.append(np.array(P))
        vel.append(np.array(V))
    demos = Demonstrations(pos, velocities=vel, target=[0.0, 0.0])
    Xs, Xd, _, groups = demos.stacked()
    search = GridSearchCV(SEDS(objective="mse", random_state=0, max_iter=200),
                          {"n_components": [1, 3]}, cv=GroupKFold(n_splits=2))
    search.fit(Xs, Xd, groups=groups)
    assert search.best_params_ == {"n_components": 3}
    assert search.best_estimator_.model_.certificate  # the refitted model is certified


def test_grid_search_and_cross_val_score_choose_gmr_components():
    rng = np.random.default_rng(1)
    S = np.column_stack([np.full(60, 2.4), rng.uniform(-0.5, 0.5, 60)])
    # a two-branch map: one Gaussian cannot follow it, three can
    Y = np.column_stack([np.where(S[:, 1] > 0, 3.0, -3.0) + 2 * S[:, 1],
                         1.0 + 0.2 * np.abs(S[:, 1])])
    search = GridSearchCV(GMRModel(random_state=0), {"n_components": [1, 3]},
                          cv=KFold(3, shuffle=True, random_state=0)).fit(S, Y)
    assert search.best_params_ == {"n_components": 3}
    scores = cross_val_score(GPRModel(random_state=0), S, Y, cv=3)
    assert scores.shape == (3,) and np.all(np.isfinite(scores))


def test_learners_accept_a_numpy_generator_as_random_state():
    rng = np.random.default_rng(5)
    S = np.column_stack([np.full(20, 2.4), np.linspace(-0.5, 0.5, 20)])
    Y = np.column_stack([S[:, 1], 1 + S[:, 1] ** 2])
    GMRModel(2, random_state=rng).fit(S, Y)
    GPRModel(random_state=rng).fit(S, Y)


def test_bad_parameters_are_refused_in_fit_with_a_clear_message():
    S = np.column_stack([np.full(20, 2.4), np.linspace(-0.5, 0.5, 20)])
    Y = np.column_stack([S[:, 1], 1 + S[:, 1] ** 2])
    bad = GMRModel(n_components=0)  # stored as given
    with pytest.raises(ValueError, match="n_components must be an integer >= 1"):
        bad.fit(S, Y)
    with pytest.raises(ValueError, match=r"shape \(n, 2\)"):
        GMRModel(2).fit(S, Y).predict(np.zeros((3, 3)))


def test_seds_accepts_a_numpy_generator_as_random_state(spiral_demos):
    a = SEDS(2, objective="mse", random_state=np.random.default_rng(7)).fit(spiral_demos).model_
    b = SEDS(2, objective="mse", random_state=np.random.default_rng(7)).fit(spiral_demos).model_
    np.testing.assert_array_equal(a.means, b.means)  # the same Generator state: the same fit


def test_bic_picks_the_number_of_clusters_of_a_known_mixture():
    from seds_casadi.core.model_selection import bic_n_components

    rng = np.random.default_rng(0)
    centres = np.array([[0, 0, 0, 0], [6, 0, -3, 1], [0, 6, 2, -2]], float)
    Z = np.concatenate([c + 0.5 * rng.standard_normal((150, 4)) for c in centres])
    K, bic = bic_n_components(Z[:, :2], Z[:, 2:], max_components=6, random_state=0,
                              rule="min")
    assert K == 3 and len(bic) == 6 and np.argmin(bic) == 2
    K_elbow, bic_e = bic_n_components(Z[:, :2], Z[:, 2:], max_components=6, random_state=0)
    assert K_elbow == 3  # the default: ds-opt's elbow of the same curve
    with pytest.raises(ValueError, match="BIC rule"):
        bic_n_components(Z[:, :2], Z[:, 2:], rule="aic")
    with pytest.raises(ValueError, match="same shape"):
        bic_n_components(Z[:, :2], Z[:10, 2:])


def test_seds_with_bic_components_records_the_scores(spiral_demos):
    learner = SEDS("bic", objective="mse", random_state=0).fit(spiral_demos)
    info = learner.model_.fit_info
    assert learner.n_components == "bic"  # the parameter is left as given
    from seds_casadi.core.model_selection import dsopt_elbow_k

    assert info["n_components"] == learner.model_.n_components == dsopt_elbow_k(info["bic"])
    with pytest.raises(TypeError,
                       match=r"an int in the range \[1, inf\), a str among \{'auto', 'bic'\}"):
        SEDS("aic").fit(spiral_demos)
