"""Several strategies (the paper's Section 8 extension): exploration, clustering across
situations, the choice of the strategy most likely to succeed, saving, bad input."""

import numpy as np
import pytest
from sklearn.base import clone

from seds_casadi.minigolf import Stroke
from seds_casadi.minigolf.ball import simulate_shots
from seds_casadi.minigolf.fields import load_field
from seds_casadi.minigolf.hitting_data import HittingDataset
from seds_casadi.minigolf.strategies import Strategy, StrategySet, explore, route
from seds_casadi.minigolf.strategy_choice import StrategyChoice

STROKE = Stroke(np.array([0.995, 0.097, -0.003]), 0.99)
SMALL = {"resolution": (151, 41), "alpha_range": (-75.0, 75.0), "kappa_range": (0.8, 2.4)}


@pytest.fixture(scope="module")
def flat_strategies():
    # the flat field with walls: a ball at three places across the ball region, the hole fixed
    f = load_field("flat")
    balls = np.array([[0.1, -0.3], [0.1, 0.0], [0.1, 0.3], [0.2, -0.15], [0.2, 0.15]])
    holes = np.tile(f.hole, (len(balls), 1))
    return f, explore(f, STROKE, balls, holes, n_strategies="auto", min_coverage=0.6, **SMALL)


def test_the_direct_putt_and_the_banks_off_each_side_wall_are_found_on_the_flat_field(
        flat_strategies):
    f, ss = flat_strategies
    routes = [s.routes[0] for s in ss.strategies]
    # one route per strategy, consistent across the situations it covers
    assert all(len(set(s.routes)) == 1 for s in ss.strategies)
    assert {"direct", "left", "right"} <= set(routes)
    direct = ss.strategies[routes.index("direct")]
    # the slowest strategy (label 0) is the direct putt, present everywhere, aimed at the hole
    assert direct.label == 0 and direct.coverage == 1.0 and direct.walls == 0
    aim = STROKE.aim(direct.data.situations)
    np.testing.assert_allclose(direct.data.alpha, aim, atol=np.deg2rad(0.3))
    # every strategy's shots sink, with the walls its route says
    for s in ss.strategies:
        V = STROKE.launch_velocity(s.data.alpha, s.data.kappa)
        r = simulate_shots(f, s.data.ball, V, hole=s.data.hole, engine="numpy")
        assert r.sunk.all() and np.all((r.wall_contacts > 0) == (s.routes[0] != "direct"))
        assert np.all(s.data.labels == s.label) and np.all(s.robustness[s.robustness > 0] <= 1)
    assert route(f, STROKE, [0.1, 0.0], f.hole, direct.data.alpha[1],
                 direct.data.kappa[1]) == "direct"
    # labels run by mean speed
    speeds = [s.data.kappa.mean() for s in ss.strategies]
    assert speeds == sorted(speeds)


def test_strategy_sets_round_trip_and_combine(tmp_path, flat_strategies):
    _, ss = flat_strategies
    ss.save(tmp_path / "s.npz")
    back = StrategySet.load(tmp_path / "s.npz")
    assert len(back) == len(ss) and back.describe() == ss.describe()
    for a, b in zip(ss.strategies, back.strategies):
        np.testing.assert_allclose(a.data.alpha, b.data.alpha, atol=1e-12)
        np.testing.assert_array_equal(a.robustness, b.robustness)
        assert a.routes == b.routes
    data = ss.dataset()
    assert len(data) == sum(len(s.data) for s in ss.strategies)
    assert sorted(set(data.labels)) == [s.label for s in ss.strategies]
    (tmp_path / "bad.npz").write_bytes(b"no")
    with pytest.raises(ValueError, match="not a readable seds_casadi.StrategySet file"):
        StrategySet.load(tmp_path / "bad.npz")


def _synthetic(n=12):
    """Two strategies along a line of situations: strategy 1 exists only where s_y > 0 and
    is more robust there; strategy 0 exists everywhere."""
    y = np.linspace(-0.4, 0.4, n)
    balls = np.tile([0.1, 0.0], (n, 1))
    holes = np.column_stack([np.full(n, 2.4), y])
    rob0 = np.full(n, 0.6)
    rob1 = np.where(y > 0, 0.95, 0.0)

    def data(idx, alpha, kappa, label):
        return HittingDataset("flat", "centre", balls[idx], holes[idx], alpha, kappa, STROKE,
                              labels=np.full(len(idx), label))

    i0, i1 = np.arange(n), np.flatnonzero(y > 0)
    s0 = Strategy(0, 0, data(i0, 0.1 * y[i0], np.full(n, 1.4), 0), rob0, ["direct"] * n)
    s1 = Strategy(1, 1, data(i1, 0.6 - y[i1], np.full(len(i1), 1.9), 1), rob1,
                  ["left"] * len(i1))
    return StrategySet("flat", balls, holes, [s0, s1], STROKE, {"max_jump": 2.0})


def test_the_choice_plays_the_strategy_most_likely_to_succeed():
    ss = _synthetic()
    choice = StrategyChoice("gpr").fit(ss)
    S = np.column_stack([np.full(6, 2.3), [-0.35, -0.2, -0.1, 0.15, 0.25, 0.35]])
    out, labels, chances = choice.predict(S, return_choice=True)
    np.testing.assert_array_equal(labels, [0, 0, 0, 1, 1, 1])
    assert chances.shape == (6, 2) and np.all((chances >= 0) & (chances <= 1))
    # the chosen strategy's own model gives the hitting parameters
    np.testing.assert_allclose(out[3:], choice.predict_strategy(S[3:], 1))
    np.testing.assert_allclose(out[:3], choice.predict_strategy(S[:3], 0))
    np.testing.assert_allclose(out[3:, 1], 1.9, atol=1e-3)
    np.testing.assert_allclose(out[:3, 0], np.rad2deg(0.1 * S[:3, 1]), atol=0.05)  # deg
    gmr = StrategyChoice("gmr", n_components=1).fit(ss)
    assert gmr.predict(S).shape == (6, 2)
    # a scikit-learn estimator (one way to fit, issue 27): clone is unfitted, same parameters
    twin = clone(gmr)
    assert twin.get_params() == {"learner": "gmr", "n_components": 1, "random_state": 0}
    assert not hasattr(twin, "models_")
    np.testing.assert_array_equal(twin.fit(ss).predict(S), gmr.predict(S))


def test_bad_input_is_a_clear_error(flat_strategies):
    f, _ = flat_strategies
    b, h = np.array([[0.1, 0.0]]), np.array([f.hole])
    with pytest.raises(ValueError, match="'auto' or an integer >= 1"):
        explore(f, STROKE, b, h, n_strategies=0)
    with pytest.raises(ValueError, match="'auto' or an integer"):
        explore(f, STROKE, b, h, n_strategies="many")
    with pytest.raises(ValueError, match="min_coverage"):
        explore(f, STROKE, b, h, min_coverage=1.5)
    with pytest.raises(ValueError, match="ball region"):
        explore(f, STROKE, [[2.0, 0.0]], h)
    # too slow to reach the hole at all: no strategy, and the message says what to change
    with pytest.raises(ValueError, match="no strategy sinks the ball in 50% of the 1 "
                                         "situations on flat.*widen the ranges"):
        explore(f, STROKE, b, h, kappa_range=(0.3, 0.6), resolution=(31, 9))
    with pytest.raises(ValueError, match="StrategySet"):
        StrategyChoice().fit([])
