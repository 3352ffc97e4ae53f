"""The published LASA protocol (nbfigueroa/ds-opt, 2018): its metrics against hand-computed
answers."""

import numpy as np
import pytest

from seds_casadi.core.metrics import (
    direction_error,
    dtw_distance,
    pointwise_direction_error,
    reproduction_dtw,
    simulate_until_slow,
    velocity_rmse,
)


# ------------------------------------------------------------------ metrics, known answers
def test_dtw_of_two_hand_made_paths():
    # s = (0,0) (1,0) (2,0), t = (0,0) (2,0): cost [[0, 2], [1, 1], [2, 0]];
    # D = [[0, 2], [1, 1], [3, 1]] -> the best warping path costs 0 + 1 + 0 = 1
    s = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    t = np.array([[0.0, 0.0], [2.0, 0.0]])
    assert dtw_distance(s, t) == pytest.approx(1.0, abs=1e-15)
    assert dtw_distance(t, s) == pytest.approx(1.0, abs=1e-15)
    # two sides of a unit square against the diagonal's end points: (0,1) is 1 from either end
    # and the corners match exactly, so the best path costs 1
    sq = np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    diag = np.array([[0.0, 0.0], [1.0, 1.0]])
    assert dtw_distance(sq, diag) == pytest.approx(1.0, abs=1e-15)
    # one point against a path: the sum of its distances to every point of the path (no window)
    p = np.array([[3.0, 4.0]])
    path = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]])
    assert dtw_distance(p, path) == pytest.approx(5.0 + 4.0 + 0.0, abs=1e-15)


def test_pointwise_direction_error_known_answers_and_the_nan_rule():
    F = np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 0.0], [1e-6, 0.0], [np.nan, 1.0], [1.0, 1.0]])
    V = np.array([[0.0, 1.0], [-1.0, 0.0], [1.0, 0.0], [0.0, 1e-6], [1.0, 0.0], [2.0, 0.0]])
    want = [1.0, 2.0, 0.0, 1.0, 0.0, 1.0 - 1.0 / np.sqrt(2.0)]
    # ds-opt's edot_error.m: only an undefined (NaN) cosine counts 0; tiny norms still count
    np.testing.assert_allclose(pointwise_direction_error(F, V, min_norm_product=0.0), want,
                               atol=1e-15)
    # our default threshold drops the 1e-12 norm product too, which is direction_error's rule
    legacy = pointwise_direction_error(F, V)
    assert legacy[3] == 0.0
    assert np.mean(legacy) == pytest.approx(direction_error(F, V), abs=1e-15)
    with pytest.raises(ValueError, match="min_norm_product"):
        pointwise_direction_error(F, V, min_norm_product=-1.0)


def test_velocity_rmse_is_the_mean_of_per_point_roots_not_a_pooled_root():
    # per point sqrt(mean over dims): sqrt((1 + 1) / 2) = 1 and sqrt((9 + 9) / 2) = 3 -> mean 2;
    # a pooled RMSE would be sqrt(5)
    F = np.array([[1.0, 1.0], [3.0, 3.0]])
    assert velocity_rmse(F, np.zeros_like(F)) == pytest.approx(2.0, abs=1e-15)
    assert velocity_rmse(np.array([[3.0, 4.0]]), np.zeros((1, 2))) == pytest.approx(
        np.sqrt(12.5), abs=1e-15)


def test_the_stop_rule_of_the_reproductions_on_a_linear_system():
    # xdot = -x with dt = 0.5: x_i = 0.5**i x_0 and v_i = -0.5**i x_0. From x_0 = 1 the speed is
    # below 0.1 from i = 4 on (0.0625), so v_4..v_7 are the first 4 slow steps: the run stops at
    # i = 7 and keeps x_0..x_7 (x_8 is computed and dropped): 8 points.
    def field(x):
        return -x

    one = simulate_until_slow(field, np.array([[1.0]]), dt=0.5, speed_tol=0.1, max_steps=3000)
    assert one.shape == (8, 1, 1)
    np.testing.assert_allclose(one[:, 0, 0], 0.5 ** np.arange(8), rtol=0, atol=1e-15)
    # all starts together: from 10 the speed is below 0.1 from i = 7 (0.078), so both run to
    # i = 10 (11 points), the slow one included
    two = simulate_until_slow(field, np.array([[1.0], [10.0]]), dt=0.5)
    assert two.shape == (11, 2, 1)
    np.testing.assert_allclose(two[:, 1, 0], 10 * 0.5 ** np.arange(11), atol=1e-14)
    # every component must be slow: (1, 10) stops like the start 10 alone
    assert simulate_until_slow(field, np.array([[1.0, 10.0]]), dt=0.5).shape == (11, 1, 2)
    # the step limit: ds-opt stops once i > i_max - 2, so at most max_steps - 1 points
    assert simulate_until_slow(field, np.array([[10.0]]), dt=0.5, max_steps=6).shape == (5, 1, 1)
    assert simulate_until_slow(lambda x: 0 * x + 1.0, np.zeros((1, 2)),
                               max_steps=3000).shape == (2999, 1, 2)
    # a slow start still takes the 4 steps the rule looks at
    assert simulate_until_slow(field, np.array([[0.01]]), dt=0.5).shape == (4, 1, 1)
    with pytest.raises(ValueError, match="max_steps"):
        simulate_until_slow(field, np.ones((1, 1)), max_steps=4)
    with pytest.raises(ValueError, match="dt"):
        simulate_until_slow(field, np.ones((1, 1)), dt=0.0)


def test_reproduction_dtw_compares_each_reproduction_with_its_whole_reference():
    def field(x):
        return -x

    starts = np.array([[1.0, 0.0], [0.0, 2.0]])
    refs = [np.array([[1.0, 0.0], [0.0, 0.0]]), np.array([[0.0, 2.0], [0.0, 1.0], [0.0, 0.0]])]
    paths = simulate_until_slow(field, starts, dt=0.5)
    want = [dtw_distance(paths[:, 0], refs[0]), dtw_distance(paths[:, 1], refs[1])]
    np.testing.assert_allclose(reproduction_dtw(field, starts, refs, dt=0.5), want, rtol=1e-15)
    with pytest.raises(ValueError, match="one start per reference"):
        reproduction_dtw(field, starts, refs[:1])
