import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from seds_casadi.core.metrics import direction_error, dtw_distance, swept_error_area, velocity_rmse


def _dtw_reference(s, t):
    n, m = len(s), len(t)
    D = np.full((n + 1, m + 1), np.inf)
    D[0, 0] = 0
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            D[i, j] = np.linalg.norm(s[i - 1] - t[j - 1]) + min(D[i - 1, j], D[i, j - 1],
                                                                D[i - 1, j - 1])
    return D[n, m]


def test_known_answers():
    a = np.array([[1.0, 0.0], [0.0, 2.0]])
    assert velocity_rmse(a, a) == 0.0
    assert velocity_rmse(a, np.zeros_like(a)) == pytest.approx(np.mean([np.sqrt(0.5),
                                                                        np.sqrt(2.0)]))
    assert direction_error(a, 3 * a) == pytest.approx(0.0)
    assert direction_error(a, -a) == pytest.approx(2.0)
    assert direction_error(np.array([[1.0, 0.0]]), np.array([[0.0, 1.0]])) == pytest.approx(1.0)
    assert direction_error(np.zeros((1, 2)), np.ones((1, 2))) == 0.0  # zero norm counts as 0
    s = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    assert dtw_distance(s, s) == 0.0
    assert dtw_distance(s, s + [0.0, 1.0]) == pytest.approx(3.0)
    # two parallel segments 1 apart, length 2: swept area 2
    assert swept_error_area(s + [0.0, 1.0], s) == pytest.approx(2.0)


@settings(max_examples=40, deadline=None)
@given(arrays(np.float64, st.tuples(st.integers(1, 8), st.just(2)), elements=st.floats(-5, 5)),
       arrays(np.float64, st.tuples(st.integers(1, 8), st.just(2)), elements=st.floats(-5, 5)))
def test_dtw_matches_the_textbook_recursion(s, t):
    assert dtw_distance(s, t) == pytest.approx(_dtw_reference(s, t), rel=1e-12, abs=1e-12)


def test_bad_shapes():
    with pytest.raises(ValueError, match="shape mismatch"):
        velocity_rmse(np.zeros((2, 2)), np.zeros((3, 2)))
    with pytest.raises(ValueError, match="dimension mismatch"):
        dtw_distance(np.zeros((2, 2)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="2-D"):
        swept_error_area(np.zeros((2, 3)), np.zeros((2, 3)))
