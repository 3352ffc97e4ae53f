"""codegen.column_sum: a sum over columns compiled as a vectorised C loop, against CasADi."""

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from seds_casadi.codegen import UnsupportedOperation, compiler_available
from seds_casadi.codegen.column_sum import LANES, ColumnSum, column_sum_source

pytestmark = pytest.mark.skipif(compiler_available() is None, reason="no C compiler")


def _function():
    """Shared p (3), per column u (2) and a weight w; two outputs, one a 2 x 2 matrix, with
    the math functions the SEDS kernels use (exp, log, sqrt) and a division."""
    p, u, w = ca.SX.sym("p", 3), ca.SX.sym("u", 2), ca.SX.sym("w")
    s = ca.exp(p[0] * u[0]) + ca.log(1 + u[1] ** 2) / (1 + p[1] ** 2)
    M = ca.vertcat(ca.horzcat(s * p[2], ca.sqrt(1 + u[0] ** 2)), ca.horzcat(u[1], -s))
    return ca.Function("f", [p, u, w], [w * s, w * M])


def _reference(f, p, U):
    m = f.map(U.shape[1])
    out = m(p, U[:2], U[2:])
    return [_sum_columns(np.asarray(o), f.size_out(j)) for j, o in enumerate(out)]


def _sum_columns(block, shape):
    """A map's output is the columns' outputs side by side: sum those blocks."""
    r, c = shape
    return block.reshape(r, -1, c).sum(axis=1)


@settings(max_examples=25, deadline=None)
@given(st.integers(1, 700), st.integers(1, 3), st.integers(0, 2**31 - 1))
def test_the_sum_equals_casadis_map_for_any_size_and_threads(n, threads, seed):
    rng = np.random.default_rng(seed)
    U = np.vstack([rng.standard_normal((2, n)), rng.uniform(0.1, 2.0, (1, n))])
    f = _function()
    p = rng.standard_normal(3)
    got = ColumnSum(f, U, pad_row=2, threads=threads)(p)
    for g, r in zip(got, _reference(f, p, U)):
        assert g.shape == r.shape
        np.testing.assert_allclose(g, r, rtol=1e-12, atol=1e-12)


def test_known_answer_and_the_lanes():
    # f = w * u: the sum is the weighted column sum, whatever the padding to the lanes
    p, u, w = ca.SX.sym("p", 1), ca.SX.sym("u", 1), ca.SX.sym("w")
    f = ca.Function("lin", [p, u, w], [w * u * p])
    n = 4 * LANES + 3
    U = np.vstack([np.arange(n, dtype=float)[None], np.ones((1, n))])
    assert ColumnSum(f, U, pad_row=1)(np.array([2.0]))[0][0, 0] == 2.0 * n * (n - 1) / 2
    assert "#pragma omp simd" in column_sum_source(f, "lin")


def test_bad_input_is_refused_by_name():
    f = _function()
    U = np.ones((3, 10))
    with pytest.raises(ValueError, match="U must have shape"):
        ColumnSum(f, np.ones((2, 10)), pad_row=1)
    cs = ColumnSum(f, U, pad_row=2)
    with pytest.raises(ValueError, match="p has 2 entries"):
        cs(np.ones(2))
    x, z = ca.MX.sym("x", 2), ca.MX.sym("z", 2)
    with pytest.raises(UnsupportedOperation, match="SX Function"):
        column_sum_source(ca.Function("m", [x, z], [x + z]), "m")
    y, v = ca.SX.sym("y", 2), ca.SX.sym("v", 2)
    sparse = ca.Function("s", [y, v], [ca.diag(y + v)])
    with pytest.raises(UnsupportedOperation, match="sparse"):
        column_sum_source(sparse, "s")
