"""Issue 29 (SEDS() fast enough to be the default): the Gram fit's IPOPT solver and the LPV
start's are built once per process for each (K, d, margin, options), with the data's statistics
as parameters. A cached solver must give exactly the fit a new one gives, on other data."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import random_gmm
from oracles import responsibilities as oracle

from seds_casadi import SEDS
from seds_casadi.core import load_lasa
from seds_casadi.core import objectives as objectives_module
from seds_casadi.core import problem as problem_module
from seds_casadi.core import seds as seds_module


def _clear() -> None:
    seds_module._SOLVERS.clear()
    problem_module._LPV_SOLVERS.clear()
    objectives_module._GRAM.clear()


def _fit(demos, K=4):
    return SEDS(K, random_state=0).fit(demos).model_


@pytest.fixture(scope="module")
def two_shapes():
    return load_lasa("Sshape", n_samples=60), load_lasa("Angle", n_samples=60)


def test_a_cached_solver_gives_the_fit_a_new_one_gives_on_other_data(two_shapes):
    a, b = two_shapes
    _clear()
    new = _fit(b)
    assert new.fit_info["sums"] == "gram"  # the default's objective: the cached path ran
    _clear()
    _fit(a)
    solvers = dict(seds_module._SOLVERS)
    lpv = dict(problem_module._LPV_SOLVERS)
    assert len(solvers) == 1 and len(lpv) == 1
    again = _fit(b)  # Angle on the solvers Sshape built
    assert all(seds_module._SOLVERS[k][0] is v[0] for k, v in solvers.items())  # reused
    assert all(problem_module._LPV_SOLVERS[k][0] is v[0] for k, v in lpv.items())
    assert again.fit_info["iterations"] == new.fit_info["iterations"]
    np.testing.assert_array_equal(again.means, new.means)
    np.testing.assert_array_equal(again.covariances, new.covariances)
    np.testing.assert_array_equal(again.priors, new.priors)
    assert again.fit_info["objective"] == new.fit_info["objective"]


def test_the_parametric_gram_objective_is_the_sum_over_samples(two_shapes):
    """J(theta, p) with this data's statistics as p against the mean squared error summed
    over the samples in numpy, at random theta."""
    from seds_casadi.core.parametrization import Layout, unpack_numpy

    demos = two_shapes[0]
    X, Xd, _, _ = demos.stacked()
    X, Xd = X / np.abs(X).max(), Xd / np.abs(Xd).max()
    rng = np.random.default_rng(3)
    K, d, margin = 3, 2, 1e-3
    layout = Layout(K, d, False, "learned")
    gamma = rng.dirichlet(np.ones(K), len(X))
    kernels = objectives_module.GramKernels(layout, margin, gamma, X, Xd)
    for _ in range(5):
        theta = rng.normal(scale=0.5, size=layout.size)
        A = unpack_numpy(theta, layout, margin)["A"]
        f = sum(gamma[:, k:k + 1] * (X @ A[k].T) for k in range(K))
        expected = np.mean(np.sum((f - Xd) ** 2, axis=1))
        assert kernels.value(theta) == pytest.approx(expected, rel=1e-10)
        assert float(kernels.nlp_objective()(theta)) == pytest.approx(expected, rel=1e-10)


def test_a_solver_in_use_is_not_handed_out_twice():
    """Taken out while it solves: a second taker (another thread) gets none and builds its
    own; put back, it is handed out again."""
    key = ("test", 1)
    entry = (object(), object())
    seds_module._keep_solver(key, entry)
    assert seds_module._take_solver(key) is entry
    assert seds_module._take_solver(key) is None
    seds_module._keep_solver(key, entry)
    assert seds_module._take_solver(key) is entry
    assert seds_module._take_solver(None) is None


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), K=st.integers(1, 8), d=st.integers(1, 7),
       scale=st.floats(0.1, 1e3))
def test_the_cached_responsibilities_are_the_symbolic_ones_and_the_oracles(seed, K, d, scale):
    """responsibilities() evaluates one Function per (K, d) with the GMM's numbers as
    parameters (it built the expression with the numbers as constants at every call, 3.5 ms
    each): the same numbers as responsibilities_sx's Function, and numpy's oracle."""
    import casadi as ca

    from seds_casadi.core.gmm import responsibilities, responsibilities_sx

    rng = np.random.default_rng(seed)
    priors, means, covs = random_gmm(rng, K, d)
    X = rng.standard_normal((30, d)) * scale
    x = ca.SX.sym("x", d)
    f = ca.Function("h", [x], [ca.vertcat(*responsibilities_sx(x, priors, means, covs))])
    got = responsibilities(X, priors, means, covs)
    np.testing.assert_allclose(got, np.asarray(f(X.T)).T, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(got, oracle(X, priors, means, covs), rtol=1e-9, atol=1e-12)


def test_the_clusters_computed_in_the_background_are_those_computed_in_line(two_shapes,
                                                                           monkeypatch):
    """SEDS()'s choice of K with each K's k-means started on a background thread while the K
    before it is fitted (problem.prefetch_labels) and with every k-means in line: the same
    choice and the same model, bit for bit; the background thread ends with the fit."""
    import threading

    demos = two_shapes[1]
    started = []
    original = seds_module.prefetch_labels

    def recording(embedding, Ks):
        started.append(tuple(Ks))
        return original(embedding, Ks)
    monkeypatch.setattr(seds_module, "prefetch_labels", recording)
    ahead = SEDS(n_components=[3, 4, 5], random_state=0).fit(demos).model_
    assert started == [(3, 4, 5)]
    monkeypatch.setattr(seds_module, "prefetch_labels", lambda embedding, Ks: (lambda: None))
    inline = SEDS(n_components=[3, 4, 5], random_state=0).fit(demos).model_
    assert ahead.n_components == inline.n_components
    np.testing.assert_array_equal(ahead.means, inline.means)
    np.testing.assert_array_equal(ahead.covariances, inline.covariances)
    for _ in range(50):
        if not any(t.name.startswith("seds-kmeans") for t in threading.enumerate()):
            break
        threading.Event().wait(0.1)
    assert not any(t.name.startswith("seds-kmeans") for t in threading.enumerate())
