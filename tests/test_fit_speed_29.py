"""Issue 29, the default's speed: each fast path against the code it replaces.

* the compiled DTW (``metrics._dtw_kernel``) against numpy's anti-diagonal sweep;
* the reproductions integrated by one CasADi call per chunk of steps
  (``simulate_until_slow`` given a Function) against one Python call per step;
* the LPV start found by the main solver with P's factor held (``SEDSProblem.start_fixed``)
  against LPV-DS's gain problem solved apart (``_stable_gains_lpv``): the same problem.
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
from seds_casadi.core import metrics
from seds_casadi.core.gmm import responsibilities
from seds_casadi.core.parametrization import unpack_numpy
from seds_casadi.core.problem import _stable_gains_lpv, build_problem


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


@pytest.mark.parametrize("substeps", [1, 3])
@pytest.mark.parametrize("max_steps", [3000, 7, 130])
def test_chunked_reproductions_equal_the_step_by_step_loop(spiral_model, substeps, max_steps):
    """Same points, bit for bit, and the same stop: the slow rule (about 300 steps, over two
    chunks of 128), the step limit inside the first chunk (7) and just past it (130)."""
    demos = decaying_spiral_demos()
    starts = np.stack([p[0] for p in demos.positions])
    kw = dict(dt=0.01, speed_tol=0.05, max_steps=max_steps, substeps=substeps)
    loop = metrics.simulate_until_slow(spiral_model.predict, starts, **kw)
    fast = metrics.simulate_until_slow(spiral_model._function(), starts, **kw)
    assert fast.shape == loop.shape
    np.testing.assert_array_equal(fast, loop)
    if max_steps == 3000:
        assert 128 < len(loop) < 2999  # stopped by the slow rule, after a chunk boundary
    else:
        assert len(loop) == max_steps - 1


def test_a_function_of_the_wrong_size_is_refused():
    x = ca.SX.sym("x", 3)
    with pytest.raises(ValueError, match="2 coordinates"):
        metrics.simulate_until_slow(ca.Function("f", [x], [-x]), np.ones((1, 2)))


def test_the_start_found_by_the_main_solver_is_lpv_dss_gain_problem():
    """With the Gram statistics and P held, the main NLP is LPV-DS's gain problem: its optimum
    equals the one :func:`_stable_gains_lpv` finds apart from the same start."""
    demos = decaying_spiral_demos()
    prob = build_problem(demos, SEDS(3, random_state=0)._settings(demos).problem)
    layout = prob.layout
    assert prob.start_fixed is not None
    sl = layout.lyapunov_slice
    np.testing.assert_array_equal(prob.start_fixed, np.arange(sl.start, sl.stop))
    th, J = prob.kernels.nlp_expression()
    solver = ca.nlpsol("lpv_in_main", "ipopt", {"x": th, "f": J},
                       {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes",
                        "ipopt.tol": 1e-12})
    lb, ub = prob.lbx.copy(), prob.ubx.copy()
    lb[prob.start_fixed] = ub[prob.start_fixed] = prob.theta0[prob.start_fixed]
    J_main = float(solver(x0=prob.theta0, lbx=lb, ubx=ub)["f"])

    p0 = unpack_numpy(prob.theta0, layout, prob.margin)
    gamma = responsibilities(prob.X, p0["priors"], p0["mu"], p0["Sx"])
    gains = _stable_gains_lpv(gamma, prob.X, prob.Xd, p0["P"], prob.margin, list(p0["A"]))
    F = np.einsum("nk,kij,nj->ni", gamma, np.array(gains), prob.X)
    J_apart = float(np.mean(np.sum((F - prob.Xd) ** 2, axis=1)))
    assert J_main == pytest.approx(J_apart, rel=1e-5)
    assert J_main < prob.kernels.value(prob.theta0)  # the start gains were improved on


def test_the_default_fit_reports_its_lpv_start():
    model = SEDS(3, random_state=0).fit(decaying_spiral_demos()).model_
    assert model.fit_info["start_iterations"] > 0
    c = model.certificate
    assert c["max_eig_lyapunov"] < 0 and c["min_eig_cov"] > 0
