"""Issue 29, the default's speed: each fast path against the code it replaces.

* the compiled DTW (``metrics._dtw_kernel``) against numpy's anti-diagonal sweep;
* the reproductions integrated by one CasADi call per chunk of steps
  (``simulate_until_slow`` given a Function) against one Python call per step;
* the peaks of the reproductions (sub-steps included) and the RK4 sub-steps, against the
  step loop and a closed form;

and the choice's new parts: the time scale of a candidate that rushes
(``peak_speed_factor``, ``_time_scaled``), the speed band among near ties, and the choice and
the fit report measuring the same peaks.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import decaying_spiral_demos

from seds_casadi import SEDS
from seds_casadi.codegen.cache import compiler_available
from seds_casadi.core import metrics, model_selection
from seds_casadi.core.model_selection import choose_by_reproduction, peak_speed_factor
from seds_casadi.core.seds import _time_scaled


@settings(max_examples=40, deadline=None, derandomize=True)
@given(seed=st.integers(0, 10_000), n=st.integers(1, 60), m=st.integers(1, 60),
       d=st.integers(1, 7), scale=st.sampled_from([1e-3, 1.0, 1e3]))
def test_the_compiled_dtw_is_numpys(seed, n, m, d, scale):
    rng = np.random.default_rng(seed)
    s, t = scale * rng.normal(size=(n, d)), scale * rng.normal(size=(m, d))
    want = metrics._dtw_numpy(s, t)
    got = metrics.dtw_distance(s, t)
    assert got == pytest.approx(want, rel=1e-12, abs=0.0)


def test_the_dtw_kernel_is_compiled_where_a_compiler_is_and_nan_still_propagates():
    if compiler_available():
        assert metrics._dtw_kernel() is not None
    s = np.array([[0.0, 0.0], [np.nan, 1.0]])
    assert np.isnan(metrics.dtw_distance(s, np.zeros((3, 2))))
    # a known answer through the compiled path (test_lasa_protocol's hand-made paths)
    assert metrics.dtw_distance([[3.0, 4.0]], [[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]]) == 9.0


@pytest.fixture(scope="module")
def spiral_model():
    return SEDS(3, random_state=0).fit(decaying_spiral_demos()).model_


@pytest.mark.parametrize("method", ["euler", "rk4"])
@pytest.mark.parametrize("substeps", [1, 3])
@pytest.mark.parametrize("max_steps", [3000, 7, 130])
def test_chunked_reproductions_equal_the_step_by_step_loop(spiral_model, substeps, max_steps,
                                                           method):
    """Same points and peaks, and the same stop: the slow rule (about 300 steps, over two
    chunks of 128), the step limit inside the first chunk (7) and just past it (130)."""
    demos = decaying_spiral_demos()
    starts = np.stack([p[0] for p in demos.positions])
    kw = dict(dt=0.01, speed_tol=0.05, max_steps=max_steps, substeps=substeps,
              method=method, return_peaks=True)
    loop, peaks = metrics.simulate_until_slow(spiral_model.predict, starts, **kw)
    fast, fast_peaks = metrics.simulate_until_slow(spiral_model._function(), starts, **kw)
    assert fast.shape == loop.shape
    if method == "euler":  # the same operations in the same order
        np.testing.assert_array_equal(fast, loop)
    else:  # CasADi's RK4 sums in its own order
        np.testing.assert_allclose(fast, loop, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(fast_peaks, peaks, rtol=1e-12)
    recorded = np.linalg.norm(spiral_model.predict(loop.reshape(-1, 2)), axis=1)
    assert np.all(peaks >= recorded.reshape(loop.shape[:2]).max(axis=0) - 1e-12)
    if max_steps == 3000:
        assert 128 < len(loop) < 2999  # stopped by the slow rule, after a chunk boundary
    else:
        assert len(loop) == max_steps - 1


@pytest.mark.parametrize("threads", ["1", "2", "3"])
def test_reproductions_on_several_threads_are_the_same_numbers(spiral_model, threads,
                                                               monkeypatch):
    """The starts integrated side by side on CasADi's threads (``map(m, "thread", T)``): bit
    for bit the points and peaks of one thread."""
    demos = decaying_spiral_demos()
    starts = np.stack([p[0] for p in demos.positions])
    kw = dict(dt=0.01, speed_tol=0.05, max_steps=3000, substeps=2, method="rk4",
              return_peaks=True)
    monkeypatch.setenv("SEDS_CASADI_THREADS", "1")
    one, one_peaks = metrics.simulate_until_slow(spiral_model._function(), starts, **kw)
    monkeypatch.setenv("SEDS_CASADI_THREADS", threads)
    assert metrics.reproduction_threads(len(starts)) == min(int(threads), len(starts))
    got, peaks = metrics.simulate_until_slow(spiral_model._function(), starts, **kw)
    np.testing.assert_array_equal(got, one)
    np.testing.assert_array_equal(peaks, one_peaks)


def test_the_dtw_of_reproductions_on_two_threads_is_the_same(spiral_model, monkeypatch):
    demos = decaying_spiral_demos()
    starts = np.stack([p[0] for p in demos.positions])
    kw = dict(dt=0.01, speed_tol=0.05, max_steps=3000, method="rk4")
    out = {}
    for threads in ("1", "2"):
        monkeypatch.setenv("SEDS_CASADI_THREADS", threads)
        out[threads] = metrics.reproduction_dtw(spiral_model._function(), starts,
                                                demos.positions, **kw)
    np.testing.assert_array_equal(out["2"], out["1"])
    assert np.all(out["1"] > 0)


def test_reproduction_threads_refuse_a_setting_with_no_meaning(monkeypatch):
    monkeypatch.setenv("SEDS_CASADI_THREADS", "many")
    with pytest.raises(ValueError, match="SEDS_CASADI_THREADS"):
        metrics.reproduction_threads(4)


def test_a_function_of_the_wrong_size_is_refused():
    x = ca.SX.sym("x", 3)
    with pytest.raises(ValueError, match="2 coordinates"):
        metrics.simulate_until_slow(ca.Function("f", [x], [-x]), np.ones((1, 2)))


def test_rk4_sub_steps_follow_the_closed_form():
    """x' = -a x from 1 with sub-steps of a h = 0.25: RK4 multiplies x by the known factor
    R = 1 - z + z^2/2 - z^3/6 + z^4/24 (z = a h) each sub-step, Euler by 1 - z; RK4 stays within
    2e-5 of exp(-a t), Euler is off by about 3 %; the peak speed is a, at the start."""
    a, dt, n = 10.0, 0.1, 4
    z = a * dt / n

    def field(x):
        return -a * x

    for method, factor in (("rk4", 1 - z + z**2 / 2 - z**3 / 6 + z**4 / 24), ("euler", 1 - z)):
        path, peaks = metrics.simulate_until_slow(field, np.ones((1, 1)), dt=dt, substeps=n,
                                                  speed_tol=1e-3, method=method,
                                                  return_peaks=True)
        k = np.arange(len(path))
        np.testing.assert_allclose(path[:, 0, 0], factor ** (n * k), rtol=1e-12)
        err = np.max(np.abs(path[:, 0, 0] - np.exp(-a * dt * k)))
        assert err < 2e-5 if method == "rk4" else err > 1e-2
        assert peaks[0] == pytest.approx(a)
    with pytest.raises(ValueError, match="'euler' or 'rk4'"):
        metrics.simulate_until_slow(field, np.ones((1, 1)), method="heun")


@pytest.mark.parametrize("ratios, want", [
    ([1.0, 1.1, 0.9], None),                       # in the band
    ([0.6, 0.7], None),                            # too slow: not sped up
    ([1.3, 1.5, 1.4], 1 / np.sqrt(1.3 * 1.5)),      # rushing, spread 1.15: centred
    ([0.85, 1.4], None),                           # spread 1.65: no factor fits the band
    ([0.884, 1.323, 1.265], 1 / np.sqrt(0.884 * 1.323)),  # spread 1.50: fits with 1 % room
    ([0.8, 1.26], None),                           # spread 1.575: fits without room only
    ([], None), ([1.3, np.nan], None), ([1.3, 0.0], None),
])
def test_the_time_scale_of_a_rushing_candidate(ratios, want):
    got = peak_speed_factor(ratios)
    if want is None:
        assert got is None
    else:
        assert got == pytest.approx(want)
        scaled = got * np.asarray(ratios)
        room = model_selection.SPEED_BAND_ROOM
        assert scaled.min() >= 0.8 * room and scaled.max() <= 1.25 / room


def test_a_time_scaled_model_keeps_its_streamlines_and_certificate(spiral_model):
    slow = _time_scaled(spiral_model, 0.8)
    X = np.random.default_rng(0).normal(scale=50.0, size=(200, 2))
    np.testing.assert_allclose(slow.predict(X), 0.8 * spiral_model.predict(X), rtol=1e-9,
                               atol=1e-12)
    assert slow.certificate["max_eig_lyapunov"] < 0
    assert slow.fit_info["time_scale"] == 0.8
    np.testing.assert_allclose(slow.A, 0.8 * spiral_model.A, rtol=1e-12)


def test_near_ties_within_the_speed_band_go_first():
    scores = {4: (1.0, 1.0, 1.0), 5: (1.02, 1.0, 1.0), 6: (0.99, 1.0, 1.0), 7: (2.0, 1, 1)}
    ratios = {4: [1.3, 1.0], 5: [1.0, 1.1], 6: [1.0, 1.0], 7: [1.0, 1.0]}
    K, _ = choose_by_reproduction(scores)
    assert K == 4  # the smallest near tie
    K, table = choose_by_reproduction(scores, speed_ratios=ratios)
    assert K == 5  # 4 rushes (1.3): the smallest near tie within the band
    # no near tie within the band: the penalised scores decide as before
    K, _ = choose_by_reproduction({4: (1, 1, 1), 5: (3, 3, 3)},
                                  speed_ratios={4: [1.3], 5: [1.0]})
    assert K == 4


def test_the_choice_and_the_fit_report_read_the_same_peaks():
    demos = decaying_spiral_demos()
    learner = SEDS(n_components=[3, 4], random_state=0).fit(demos)
    choice = learner.fit_info_["choice"]
    got = choice["candidates"][choice["n_components"]]["peak_speed_ratios"]
    rows = learner.report(demos).rows
    want = [r.peak_speed_reproduction / r.peak_speed_demo for r in rows]
    np.testing.assert_allclose(got, want, rtol=0.01)
