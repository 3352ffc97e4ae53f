"""The CasADi objective and its exact derivatives against an independent numpy implementation."""

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import seds_objective as objective_numpy
from oracles import unpack as unpack_oracle

from seds_casadi import SEDS
from seds_casadi.codegen import compiler_available
from seds_casadi.core.objectives import SumKernels
from seds_casadi.core.parametrization import Layout, unpack_casadi, unpack_numpy
from seds_casadi.core.settings import OBJECTIVES

MARGIN = 1e-3


def _data(seed, n=25, d=2):
    rng = np.random.default_rng(seed)
    X = rng.standard_normal((n, d))
    Xd = -X + 0.3 * rng.standard_normal((n, d))
    Xd[0] = 0.0  # a sample at rest must contribute 0 to the direction objective
    w = rng.uniform(0.5, 2.0, n)
    return X, Xd, w


def _kernels(layout, objective, X, Xd, w, compile=False):
    speed = np.linalg.norm(Xd, axis=1)
    if objective == "direction":
        coef = np.where(speed > 0, w / np.where(speed > 0, speed, 1), 0)
        norm = w.sum()
    else:
        coef, norm = np.ones(len(X)), float(len(X))
    return SumKernels(layout, objective, MARGIN, X, Xd, coef, norm, compile=compile)


@pytest.mark.parametrize("objective", OBJECTIVES)
@pytest.mark.parametrize("K,d", [(1, 2), (3, 2), (2, 3)])
def test_casadi_objective_equals_numpy_reference(objective, K, d):
    layout = Layout(K, d, with_noise=objective == "likelihood")
    X, Xd, w = _data(K * 10 + d, d=d)
    w_used = w if objective == "direction" else np.ones(len(X))
    k = _kernels(layout, objective, X, Xd, w)
    rng = np.random.default_rng(7)
    for _ in range(5):
        theta = 0.5 * rng.standard_normal(layout.size)
        ref = objective_numpy(theta, layout, X, Xd, w_used, objective, MARGIN)
        assert k.value(theta) == pytest.approx(ref, rel=1e-10, abs=1e-12)
        assert float(k.casadi_function()(theta)) == pytest.approx(ref, rel=1e-10, abs=1e-12)


@pytest.mark.parametrize("objective", OBJECTIVES)
def test_exact_gradient_and_hessian_against_finite_differences(objective):
    layout = Layout(2, 2, with_noise=objective == "likelihood")
    X, Xd, w = _data(1)
    w_used = w if objective == "direction" else np.ones(len(X))
    k = _kernels(layout, objective, X, Xd, w)
    theta = 0.3 * np.random.default_rng(2).standard_normal(layout.size)
    h = 1e-6
    eye = np.eye(layout.size)
    fd_grad = np.array([(objective_numpy(theta + h * e, layout, X, Xd, w_used, objective, MARGIN)
                         - objective_numpy(theta - h * e, layout, X, Xd, w_used, objective,
                                           MARGIN)) / (2 * h) for e in eye])
    np.testing.assert_allclose(k.gradient(theta), fd_grad, rtol=1e-5, atol=1e-7)
    fd_hess = np.array([(k.gradient(theta + h * e) - k.gradient(theta - h * e)) / (2 * h)
                        for e in eye])
    H = k.hessian(theta)
    np.testing.assert_allclose(H, H.T, atol=1e-12)
    np.testing.assert_allclose(H, fd_hess, rtol=1e-4, atol=1e-6)


def test_compiled_kernels_agree_with_the_virtual_machine():
    layout = Layout(2, 2, with_noise=False)
    X, Xd, w = _data(4)
    vm = _kernels(layout, "direction", X, Xd, w, compile=False)
    cc = _kernels(layout, "direction", X, Xd, w, compile=True)
    theta = 0.2 * np.random.default_rng(0).standard_normal(layout.size)
    assert cc.value(theta) == pytest.approx(vm.value(theta), rel=1e-12)
    np.testing.assert_allclose(cc.gradient(theta), vm.gradient(theta), rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(cc.hessian(theta), vm.hessian(theta), rtol=1e-9, atol=1e-12)


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 4), st.integers(1, 5), st.integers(0, 2**31 - 1))
def test_every_parameter_vector_is_a_stable_model(K, d, seed):
    """Eq. 10 holds by construction: for any theta, (b)-(e) are satisfied (numpy side)."""
    layout = Layout(K, d, with_noise=True)
    theta = 2.0 * np.random.default_rng(seed).standard_normal(layout.size)
    p = unpack_numpy(theta, layout, MARGIN)
    ref = unpack_oracle(theta, layout, MARGIN)
    for key in ref:
        np.testing.assert_allclose(p[key], ref[key], rtol=1e-10, atol=1e-12)
    assert np.all(p["priors"] > 0) and np.sum(p["priors"]) == pytest.approx(1.0)
    for k in range(K):
        assert np.linalg.eigvalsh(p["A"][k] + p["A"][k].T).max() <= -2 * MARGIN * (1 - 1e-9)
        assert np.linalg.eigvalsh(p["Sx"][k]).min() > 0
        assert np.linalg.eigvalsh(p["Q"][k]).min() > 0


def test_symbolic_and_numeric_unpacking_agree():
    layout = Layout(3, 3, with_noise=False)
    theta = np.random.default_rng(5).standard_normal(layout.size)
    th = ca.SX.sym("th", layout.size)
    sym = unpack_casadi(th, layout, MARGIN)
    A_fun = ca.Function("A", [th], sym["A"])
    Linv_fun = ca.Function("L", [th], sym["Linv"])
    num = unpack_numpy(theta, layout, MARGIN)
    for k in range(3):
        np.testing.assert_allclose(np.asarray(A_fun(theta)[k]), num["A"][k], atol=1e-12)
        Linv = np.asarray(Linv_fun(theta)[k])
        np.testing.assert_allclose(np.linalg.inv(Linv.T @ Linv), num["Sx"][k], rtol=1e-10)


def test_problem_objective_matches_numpy_at_the_initial_guess(spiral_demos):
    prob = SEDS(2, objective="mse", random_state=0, compile=False).build_problem(spiral_demos)
    ref = objective_numpy(prob.theta0, prob.layout, prob.X, prob.Xd, prob.weights, "mse",
                          prob.margin)
    assert float(prob.objective_function(prob.theta0)) == pytest.approx(ref, rel=1e-10)


@pytest.mark.parametrize("objective", OBJECTIVES)
@pytest.mark.parametrize("threads", [2, 3])
def test_threaded_sums_equal_the_serial_ones_and_the_oracle(objective, threads, monkeypatch):
    # 101 samples: padded with zero-weight copies to a multiple of the threads
    layout = Layout(2, 2, with_noise=objective == "likelihood")
    X, Xd, w = _data(5, n=101)
    w_used = w if objective == "direction" else np.ones(len(X))
    monkeypatch.setenv("SEDS_CASADI_THREADS", "1")
    serial = _kernels(layout, objective, X, Xd, w)
    monkeypatch.setenv("SEDS_CASADI_THREADS", str(threads))
    threaded = _kernels(layout, objective, X, Xd, w)
    assert (serial.threads, threaded.threads) == (1, threads)
    theta = 0.4 * np.random.default_rng(3).standard_normal(layout.size)
    ref = objective_numpy(theta, layout, X, Xd, w_used, objective, MARGIN)
    assert threaded.value(theta) == pytest.approx(ref, rel=1e-10, abs=1e-12)
    np.testing.assert_allclose(threaded.gradient(theta), serial.gradient(theta), rtol=1e-10,
                               atol=1e-12)
    np.testing.assert_allclose(threaded.hessian(theta), serial.hessian(theta), rtol=1e-10,
                               atol=1e-12)


def test_threads_default_and_a_bad_setting(monkeypatch):
    from seds_casadi.core.objectives import THREADED_MIN_SAMPLES, kernel_threads

    monkeypatch.delenv("SEDS_CASADI_THREADS", raising=False)
    assert kernel_threads(THREADED_MIN_SAMPLES - 1) == 1
    assert 1 <= kernel_threads(10_000) <= 2
    monkeypatch.setenv("SEDS_CASADI_THREADS", "two")
    with pytest.raises(ValueError, match="SEDS_CASADI_THREADS must be a positive integer"):
        kernel_threads(10_000)


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 50_000), st.integers(1, 4))
def test_blocked_sum_layout_covers_the_samples_with_little_padding(n, threads):
    from seds_casadi.core.objectives import BLOCKED_MIN_SAMPLES, sum_layout

    chunk, blocks = sum_layout(n, threads)
    q = -(-n // threads)
    assert chunk * blocks >= q and chunk * blocks - q < chunk
    if q > BLOCKED_MIN_SAMPLES:  # both about sqrt(q): the work buffer is (chunk + blocks) P^2
        assert chunk <= np.sqrt(q) + 1 and blocks <= np.sqrt(q) + 2
    else:
        assert (chunk, blocks) == (q, 1)


def test_hessian_sum_keeps_a_small_work_buffer(monkeypatch):
    """The regression: a serial map with a summed output kept n x P^2 doubles per call."""
    monkeypatch.setenv("SEDS_CASADI_THREADS", "1")
    monkeypatch.setenv("SEDS_CASADI_SIMD", "0")  # CasADi's maps (the vectorised sums: below)
    layout = Layout(3, 2, with_noise=False)
    X, Xd, w = _data(2, n=2000)
    k = _kernels(layout, "mse", X, Xd, w)
    P = layout.size
    assert k._h.sz_w() < 0.1 * 2000 * P * P  # one serial sum: more than 2000 P^2
    one = SumKernels(layout, "mse", MARGIN, X, Xd, np.ones(2000), 2000.0, compile=False,
                     blocked=False)
    assert one._h.sz_w() > 2000 * P * P
    theta = 0.3 * np.random.default_rng(1).standard_normal(P)
    np.testing.assert_allclose(k.hessian(theta), one.hessian(theta), rtol=1e-10, atol=1e-12)
    assert k.value(theta) == pytest.approx(one.value(theta), rel=1e-12)


needs_cc = pytest.mark.skipif(compiler_available() is None, reason="no C compiler")


@needs_cc
@pytest.mark.parametrize("objective", OBJECTIVES)
@pytest.mark.parametrize("threads", [1, 2])
def test_vectorised_sums_equal_casadis_maps_and_the_oracle(objective, threads, monkeypatch):
    """Two implementations of J, grad J and Hess J (codegen.column_sum against CasADi's
    compiled maps), and J against the numpy oracle; 1,003 samples (padded to the lanes and
    threads with zero-weight copies)."""
    layout = Layout(3, 2, with_noise=objective == "likelihood")
    X, Xd, w = _data(8, n=1003)
    w_used = w if objective == "direction" else np.ones(len(X))
    monkeypatch.setenv("SEDS_CASADI_THREADS", str(threads))
    monkeypatch.setenv("SEDS_CASADI_SIMD", "0")
    ref = _kernels(layout, objective, X, Xd, w, compile=True)
    monkeypatch.setenv("SEDS_CASADI_SIMD", "1")
    fast = _kernels(layout, objective, X, Xd, w, compile=True)
    assert (ref.engine, fast.engine) == ("casadi", "simd")
    rng = np.random.default_rng(11)
    for _ in range(3):
        theta = 0.4 * rng.standard_normal(layout.size)
        oracle = objective_numpy(theta, layout, X, Xd, w_used, objective, MARGIN)
        assert fast.value(theta) == pytest.approx(oracle, rel=1e-10, abs=1e-12)
        assert float(fast.casadi_function()(theta)) == pytest.approx(oracle, rel=1e-10,
                                                                     abs=1e-12)
        np.testing.assert_allclose(fast.gradient(theta), ref.gradient(theta), rtol=1e-9,
                                   atol=1e-11)
        H = fast.hessian(theta)
        np.testing.assert_array_equal(H, H.T)
        np.testing.assert_allclose(H, ref.hessian(theta), rtol=1e-9, atol=1e-10)


@needs_cc
def test_a_fit_says_which_sums_it_used(spiral_demos, monkeypatch):
    fast = SEDS(2, objective="mse", random_state=0).fit(spiral_demos).model_
    monkeypatch.setenv("SEDS_CASADI_SIMD", "0")
    slow = SEDS(2, objective="mse", random_state=0).fit(spiral_demos).model_
    assert (fast.fit_info["sums"], slow.fit_info["sums"]) == ("simd", "casadi")
    # the same problem, summed in another order: the same optimum to the solver's precision
    assert fast.fit_info["objective"] == pytest.approx(slow.fit_info["objective"], rel=1e-3)
    con = SEDS(2, objective="mse", random_state=0, formulation="constrained",
               max_iter=50).build_problem(spiral_demos)
    assert con.kernels.engine == "casadi"  # its IPOPT path depends on the order of the sums
