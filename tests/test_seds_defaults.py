"""SEDS() with no settings (issue 29): the automatic settings and K, the fit report, and bad
settings refused before any solve (issues 29 and 30)."""

import json
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import decaying_spiral_demos
from sklearn.utils._param_validation import InvalidParameterError

from seds_casadi import SEDS, Demonstrations
from seds_casadi.core.model_selection import REPRODUCTION_TOLERANCE, choose_by_reproduction
from seds_casadi.core.report import FitReport, end_offsets, fit_report
from seds_casadi.core.settings import BEST_SETTINGS, CLASSIC_SETTINGS, SEDSSettings, SettingsError


def _settings(**params) -> SEDSSettings:
    return SEDSSettings.from_params(SEDS(**params).get_params(), n_dims=2)


# ------------------------------------------------------------------ the criterion
def test_choose_by_reproduction_known_answer():
    # geometric means: K=2 -> 2.0, K=3 -> 1.0, K=4 -> 1.02 (within 5 %), K=5 failed
    scores = {2: (2.0, 2.0, 2.0), 3: (1.0, 1.0, 1.0), 4: (1.02, 1.02, 1.02), 5: None}
    K, table = choose_by_reproduction(scores)
    assert K == 3
    assert table[5] is None and table[2] == pytest.approx(2.0)
    # the smallest K within the tolerance wins over the best
    K, _ = choose_by_reproduction({4: (1.04, 1.0, 1.0), 6: (1.0, 1.0, 1.0)})
    assert K == 4
    K, _ = choose_by_reproduction({4: (1.2, 1.0, 1.0), 6: (1.0, 1.0, 1.0)})
    assert K == 6
    with pytest.raises(ValueError, match="no candidate"):
        choose_by_reproduction({3: None, 4: (np.nan, 1, 1)})
    with pytest.raises(ValueError, match="tolerance"):
        choose_by_reproduction({3: (1, 1, 1)}, tolerance=0.5)


@settings(max_examples=40, deadline=None)
@given(st.dictionaries(st.integers(1, 12), st.tuples(*[st.floats(1e-3, 1e3)] * 3), min_size=1))
def test_choose_by_reproduction_is_the_smallest_k_within_tolerance(scores):
    K, table = choose_by_reproduction(scores)
    best = min(table.values())
    assert table[K] <= REPRODUCTION_TOLERANCE * best * (1 + 1e-12)
    assert all(table[k] > REPRODUCTION_TOLERANCE * best for k in table if k < K)
    # scale invariance: the units of a metric do not change the choice
    scaled = {k: (1000 * v[0], v[1], 0.001 * v[2]) for k, v in scores.items()}
    assert choose_by_reproduction(scaled)[0] == K


# ------------------------------------------------------------------ the settings' rule
def test_auto_settings_are_the_best_set_and_given_ones_override():
    s = _settings()
    assert s.k_candidates == (4, 7, 10)
    assert s.problem.objective == "mse" and s.problem.init == "pc"
    assert s.problem.gmm == "fixed" and s.problem.lyapunov == "learned"
    assert s.problem.gain_limit == BEST_SETTINGS["gain_limit"]
    assert all(s.choice[k].startswith("auto") for k in BEST_SETTINGS)
    s = _settings(lyapunov="identity", n_components=6)
    assert s.problem.lyapunov == "identity" and s.choice["lyapunov"] == "given"
    assert s.problem.init == "pc" and s.k_candidates is None and s.problem.n_components == 6


@pytest.mark.parametrize("objective", ["direction", "mse"])
def test_a_named_objective_keeps_seds_own_settings(objective):
    # the hitting motion pins objective="direction": the rest stays SEDS's, K stays 5
    s = _settings(objective=objective)
    assert s.problem.objective == objective
    for k, v in CLASSIC_SETTINGS.items():
        if k != "objective":
            assert getattr(s.problem, k) == v
    assert s.problem.n_components == 5 and s.k_candidates is None
    s = _settings(approach_direction=[1.0, 0.0])
    assert s.problem.objective == "direction" and s.problem.gmm == "joint"


# ------------------------------------------------------------------ refused before any solve
@pytest.fixture
def no_solve(monkeypatch):
    calls = []
    monkeypatch.setattr(SEDS, "_solve", lambda self, *a, **k: calls.append(1) or 1 / 0)
    yield
    assert not calls, "a solve started before the settings were refused"


@pytest.mark.parametrize("params, error, match", [
    (dict(n_components=[]), InvalidParameterError, "n_components"),
    (dict(n_components=[0, 3]), SettingsError, "at least 1"),
    (dict(n_components=[3, 3]), SettingsError, "twice"),
    (dict(n_components=[2.5]), InvalidParameterError, "n_components"),
    (dict(n_components=range(1, 40)), SettingsError, "at most 20"),
    (dict(n_components=[250, 400]), SettingsError, "too few"),
    (dict(max_iter=10**12), InvalidParameterError, "max_iter"),
    (dict(gain_limit=1e-9), InvalidParameterError, "gain_limit"),
    (dict(stability_margin=1e6), InvalidParameterError, "stability_margin"),
    (dict(stability_margin=2.0, gain_limit=1.0), SettingsError, "not below gain_limit"),
    (dict(gmm="fixed", formulation="constrained"), SettingsError,
     "by-construction"),
    (dict(compile="no"), InvalidParameterError, "compile"),
    (dict(require_convergence="yes"), InvalidParameterError, "require_convergence"),
    (dict(solver_options={"max_iter": "abc"}), SettingsError, "IPOPT refused"),
    (dict(solver_options={"not_an_ipopt_option": 1}), SettingsError, "IPOPT refused"),
])
def test_bad_settings_are_refused_before_any_solve(no_solve, params, error, match):
    demos = decaying_spiral_demos()
    with pytest.raises(error, match=match):
        SEDS(**params).fit(demos)


def test_k_choice_needs_time_ordered_demonstrations(no_solve):
    d = decaying_spiral_demos()
    X, Xd, _, _ = d.stacked()
    with pytest.raises(SettingsError, match="no time order"):
        SEDS().fit(X, Xd)


@pytest.mark.parametrize("n_samples, expected", [
    (200, (4, 7, 10)),  # the whole grid
    (50, (4, 7, 9)),    # 10 needs more velocity values than its parameters: 9, the largest
    (30, (4, 5)),       # K supported, joins
    (20, (1, 2, 3)),    # below the grid: its 3 largest supported K
])
def test_the_default_grid_of_k_shrinks_to_what_the_data_support(n_samples, expected):
    # a K is supported with 2 samples per component and one velocity value per parameter
    t = np.linspace(0, 1, n_samples)
    demos = Demonstrations([np.c_[np.cos(3 * t), np.sin(3 * t)] * (1 - t)[:, None]],
                           dt=0.01)
    learner = SEDS()
    settings = learner._settings(demos)
    assert settings.k_candidates == (4, 7, 10)
    assert learner._supported_candidates(demos, settings) == expected


def test_the_default_choice_tries_the_neighbours_of_its_best_k():
    # real fits: the grid 4, 7, 10 first, then K - 1 and K + 1 of the best-scoring K until
    # the best one's neighbours (within 4-10) have all been tried
    demos = decaying_spiral_demos()
    learner = SEDS(random_state=0).fit(demos)
    ch = learner.fit_info_["choice"]
    tried = sorted(ch["candidates"])
    assert {4, 7, 10} <= set(tried) and set(tried) <= set(range(4, 11))
    scores = {K: c["score"] for K, c in ch["candidates"].items() if c.get("score") is not None}
    best = min(scores, key=scores.get)
    assert all(K in tried for K in (best - 1, best + 1) if 4 <= K <= 10)
    assert learner.model_.n_components == ch["n_components"] in tried
    assert ch["range"] == [min(tried), max(tried)]
    assert "neighbours" in ch["rule"]
    # a K the user lists is tried as listed, with no neighbours
    listed = SEDS(n_components=[4, 7], random_state=0).fit(demos).fit_info_["choice"]
    assert sorted(listed["candidates"]) == [4, 7] and "neighbours" not in listed["rule"]


def test_a_user_constraint_that_is_no_expression_is_a_clear_error():
    with pytest.raises(TypeError, match="CasADi expression"):
        SEDS(3, objective="mse", constraints=lambda m: [("x", 0, 1)]).fit(
            decaying_spiral_demos())


# ------------------------------------------------------------------ a real choice and report
@pytest.fixture(scope="module")
def auto_fit():
    demos = decaying_spiral_demos()
    learner = SEDS(n_components=[2, 3, 4], random_state=0).fit(demos)
    return learner, demos


def test_the_choice_is_recorded_and_follows_the_criterion(auto_fit):
    learner, _ = auto_fit
    ch = learner.fit_info_["choice"]
    assert learner.model_.n_components == ch["n_components"] in (2, 3, 4)
    scores = {K: c["score"] for K, c in ch["candidates"].items()}
    best = min(scores.values())
    assert scores[ch["n_components"]] <= REPRODUCTION_TOLERANCE * best
    assert all(scores[K] > REPRODUCTION_TOLERANCE * best for K in scores
               if K < ch["n_components"])
    assert ch["settings"]["objective"].startswith("auto")
    assert ch["range"] == [2, 4]
    cert = learner.model_.certificate
    assert cert["max_eig_lyapunov"] < 0


def test_report_reproduces_each_demonstration(auto_fit, tmp_path):
    learner, demos = auto_fit
    rep = learner.report(demos)
    assert isinstance(rep, FitReport) and len(rep.rows) == demos.n_demos
    assert rep.all_reached
    for r in rep.rows:
        # the demonstration's own figures, computed here independently
        v = demos.velocities[r.demo - 1]
        assert r.peak_speed_demo == pytest.approx(np.linalg.norm(v, axis=1).max())
        assert r.duration_demo == pytest.approx((len(v) - 1) * demos.estimated_dt())
        assert 0.5 < r.speed_ratio < 2.0 and r.rmse >= 0 and 0 <= r.e_dot <= 2
    text = str(rep)
    assert "reach the target" in text and f"{demos.n_demos}/{demos.n_demos}" in text
    rep.save(tmp_path / "r.json")
    assert json.loads((tmp_path / "r.json").read_text())["all_reached"] is True
    if learner.fit_info_["choice"]["at_edge"]:
        assert any("edge of the range" in w for w in rep.warnings)


@pytest.mark.parametrize("factor", [0.4, 1.0, 2.5])
def test_report_warns_about_reproductions_too_fast_or_too_slow(auto_fit, factor):
    """The same paths run c times as fast (_time_scaled): every ratio scales by c, and the
    warnings follow the ratios, above OVERSHOOT or below UNDERSHOOT, demonstration by
    demonstration."""
    from seds_casadi.core.report import OVERSHOOT, UNDERSHOOT
    from seds_casadi.core.seds import _time_scaled

    learner, demos = auto_fit
    base = learner.report(demos)
    rep = fit_report(_time_scaled(learner.model_, factor), demos)
    for r0, r in zip(base.rows, rep.rows, strict=True):
        assert r.speed_ratio == pytest.approx(factor * r0.speed_ratio, rel=0.02)
        fast = any(f"demonstration {r.demo} peaks at {r.speed_ratio:.2f}" in w
                   for w in rep.warnings)
        slow = any(f"demonstration {r.demo} peaks at only" in w for w in rep.warnings)
        assert fast == (r.speed_ratio > OVERSHOOT)
        assert slow == (r.speed_ratio < UNDERSHOOT)
    if factor != 1.0:  # the fit's ratios are near 1 (0.98-1.01): with 0.4 or 2.5 all warn
        assert sum("peaks at" in w for w in rep.warnings) == demos.n_demos
    with pytest.raises(ValueError, match="undershoot"):
        fit_report(learner.model_, demos, undershoot=1.2)


def test_demonstrations_that_end_apart_are_warned_about():
    d = decaying_spiral_demos()
    pos = [p.copy() for p in d.positions]
    pos[1] = pos[1] + np.array([30.0, 0.0])  # ends 30 mm (about 20 % of the extent) apart
    apart = Demonstrations(pos, dt=d.estimated_dt())
    off, extent = end_offsets(apart)
    assert off.argmax() == 1 and off[1] > 0.05 * extent
    with pytest.warns(UserWarning, match="demonstration 2 ends"):
        learner = SEDS(3, random_state=0).fit(apart)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = fit_report(learner.model_, apart)
    assert any("demonstration 2 ends" in w for w in rep.warnings)
    assert not any("demonstration 1 ends" in w for w in rep.warnings)


def test_speed_penalty_known_answers():
    from seds_casadi.core.model_selection import speed_penalty

    assert speed_penalty([0.8, 1.0, 1.25]) == pytest.approx(1.0)
    assert speed_penalty([2.5]) == pytest.approx(2.0)
    assert speed_penalty([0.4]) == pytest.approx(2.0)  # log-symmetric: 0.8 / 0.4
    assert speed_penalty([1.0, np.nan]) == np.inf
    # a candidate that rushes loses against a slightly worse path at the demonstrated speed
    K, _ = choose_by_reproduction({3: (1.0, 1.0, 1.0), 4: (1.1, 1.1, 1.1)},
                                  speed_ratios={3: [2.0], 4: [1.1]})
    assert K == 4


def test_cli_fit_prints_and_saves_the_report(tmp_path):
    import subprocess
    import sys

    from seds_casadi.core.demo_files import save_demonstrations

    demo_file = tmp_path / "demos.npz"
    save_demonstrations(demo_file, decaying_spiral_demos())
    out = tmp_path / "out"
    res = subprocess.run([sys.executable, "-m", "seds_casadi", "fit", str(demo_file), "-K", "2-3",
                          "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    assert "reproductions reach the target" in res.stdout and "Traceback" not in res.stderr
    rep = json.loads((out / "report.json").read_text())
    assert len(rep["rows"]) == 3 and rep["choice"]["range"] == [2, 3]
    assert (out / "report.png").stat().st_size > 1000 and (out / "report.txt").exists()
    bad = subprocess.run([sys.executable, "-m", "seds_casadi", "fit", str(demo_file), "-K", "0-3",
                          "--out", str(tmp_path / "bad")], capture_output=True, text=True,
                         timeout=300)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr and "at least 1" in bad.stderr


@pytest.mark.parametrize("approach_ratio", [None, 4.0])
def test_the_hitting_motion_keeps_the_settings_it_had(approach_ratio):
    # HittingMotionLearner names its objective, so SEDS's automatic settings resolve to SEDS's
    # own (the defaults before issue 29): the hitting motion of `play` is the same model
    from seds_casadi.core.settings import ProblemSettings
    from seds_casadi.motion.hitting import HittingMotionLearner

    opts = HittingMotionLearner(approach_ratio=approach_ratio)._seds_options(
        np.array([1.0, 0.0, 0.0]))
    s = SEDSSettings.from_params(SEDS(3, random_state=0, **opts).get_params(), n_dims=3)
    assert s.problem == ProblemSettings(3, objective="direction", random_state=0)
    assert s.k_candidates is None and s.speed_calibration == "median"


@pytest.mark.parametrize("smoothing", [-5, 10**6, 2.5, True, "3"])
def test_smoothing_with_no_meaning_is_refused(smoothing):
    d = decaying_spiral_demos()
    with pytest.raises(ValueError, match="smoothing must be a whole number"):
        Demonstrations(d.positions, dt=d.estimated_dt(), smoothing=smoothing)
    Demonstrations(d.positions, dt=d.estimated_dt(), smoothing=5)  # a valid width still works
