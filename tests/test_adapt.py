"""Self-correction (seds_casadi.game.adapt): the green estimated from observed paths, shots
matched to cross the hole as on the nominal green, worlds checked to be the same course, and
play --world/--adapt end to end (real ball model, real Pinocchio swings)."""

import json
import os
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("pinocchio")

from seds_casadi.game.adapt import (  # noqa: E402
    GREEN_PARAMETERS,
    CorrectedModel,
    Green,
    Observation,
    TiltedSurface,
    World,
    check_world,
    estimate_green,
    hole_passage,
    launch_ceiling,
    launch_limited,
    matching_shots,
    next_situation,
    world_names,
)
from seds_casadi.game.shot import Shot, ShotResult  # noqa: E402
from seds_casadi.minigolf.ball import simulate_shots  # noqa: E402
from seds_casadi.minigolf.fields import Field, load_field  # noqa: E402
from seds_casadi.minigolf.parameters import make_model  # noqa: E402
from seds_casadi.minigolf.stroke import LaunchTable, Stroke  # noqa: E402

#: a robot's launch, made up: 1.5 x the commanded club speed, turned by 0.5 deg
TABLE = LaunchTable(np.deg2rad([-40.0, 40.0]), np.array([0.4, 2.6]), np.full((2, 2), 1.5),
                    np.full((2, 2), np.deg2rad(0.5)), "test arm")
STROKE = Stroke(np.array([1.0, 0.0, 0.0]), 1.0, launch_table=TABLE)


def _observe(world: Field, stroke: Stroke, balls, holes, alphas, kappas) -> list[Observation]:
    """What a camera sees of hits on the world's ball model (paths every 10 ms)."""
    V = stroke.launch_velocity(alphas, kappas)
    res = simulate_shots(world, balls, V, hole=holes, engine="numpy", record_paths=True)
    out = []
    for i in range(len(balls)):
        shot = Shot(balls[i], holes[i], alphas[i], kappas[i])
        r = ShotResult(shot, "ball", True, bool(res.sunk[i]), res.final_position[i],
                       path=res.paths[i], path_time=np.arange(len(res.paths[i])) * 0.01)
        out.append(Observation.from_result(r))
    return out


def _flat(**change) -> Field:
    spec = json.loads(json.dumps(load_field("flat").spec))
    spec.update(change)
    return Field.from_dict(spec)


def test_a_nominal_green_is_the_field_and_tilts_add_a_plane():
    fld = load_field("arctan")
    g = Green(fld, STROKE)
    balls = np.array([[0.1, 0.2], [0.0, -0.3]])
    a, k = np.array([0.1, -0.05]), np.array([1.2, 1.4])
    V = STROKE.launch_velocity(a, k)
    ref = simulate_shots(replace(fld, hole_radius=1e-6), balls, V, engine="numpy")
    assert np.array_equal(g.end_points(balls, a, k), ref.final_position)
    t = TiltedSurface(fld.surface, [0.01, -0.02])
    P = np.array([[0.3, 0.1], [1.0, -0.4]])
    assert np.allclose(t.gradient(P), fld.surface.gradient(P) + [0.01, -0.02])
    assert np.allclose(t.height(P) - fld.surface.height(P), P @ [0.01, -0.02])
    # a green equal to the nominal returns the given shots unchanged, converged
    A, K, ok = matching_shots(g, balls, np.array([[1.4, 0.0]] * 2), a, k)
    assert ok.all() and np.array_equal(A, a) and np.allclose(K, k)


@settings(max_examples=8, deadline=None)
@given(factor=st.floats(0.7, 1.4), tilt=st.floats(-0.012, 0.012))
def test_the_green_is_estimated_from_observed_paths(factor, tilt):
    """Known answer: paths observed on a flat green with another rolling resistance and a
    sideways tilt give back both (within 6 % and 0.2 %), from four shots."""
    nominal = _flat()
    world = replace(nominal, rolling_resistance=nominal.rolling_resistance * factor,
                    surface=TiltedSurface(nominal.surface, [0.0, tilt]))
    balls = np.array([[0.0, 0.0], [0.2, 0.3], [0.1, -0.3], [0.0, 0.2]])
    holes = np.tile(nominal.hole, (4, 1))
    alphas = np.deg2rad([0.0, -8.0, 7.0, -4.0])
    kappas = np.array([1.0, 1.1, 0.9, 1.2])
    obs = _observe(world, STROKE, balls, holes, alphas, kappas)
    g = estimate_green(Green(nominal, STROKE), obs)
    assert np.exp(g.q[0]) == pytest.approx(factor, rel=0.06)
    assert g.q[2] == pytest.approx(tilt, abs=0.002)
    assert len(g.q) == len(GREEN_PARAMETERS)


def test_matched_shots_sink_on_the_true_green():
    """Shots that sink on the nominal arctan field miss on the slower true green; moved onto
    it, they sink there (the world's own ball model with its hole)."""
    nominal = load_field("arctan")
    world = load_field(os.path.join(os.path.dirname(__file__), "..", "fields", "worlds",
                                    "arctan_stimp8.json"))
    from seds_casadi.minigolf.teacher import Teacher

    teacher = Teacher(nominal, STROKE)
    balls, holes = nominal.situations.design(4)
    good = np.array([teacher.good_shot(b, h) for b, h in zip(balls, holes)])
    assert np.all(np.isfinite(good))
    V = STROKE.launch_velocity(good[:, 0], good[:, 1])
    assert not simulate_shots(world, balls, V, hole=holes, engine="numpy").sunk.any()
    q = np.zeros(5)
    q[0] = np.log(world.rolling_resistance / nominal.rolling_resistance)
    A, K, ok = matching_shots(Green(nominal, STROKE, q), balls, holes, good[:, 0], good[:, 1])
    assert ok.all()
    assert np.all(K > good[:, 1])   # a slower green: faster hits
    sunk = simulate_shots(world, balls, STROKE.launch_velocity(A, K), hole=holes,
                          engine="numpy").sunk
    assert sunk.all()
    # the passage the shots were matched to: the same side distance and speed at the hole
    assert np.allclose(hole_passage(Green(nominal, STROKE, q), balls, holes, A, K),
                       hole_passage(Green(nominal, STROKE), balls, holes, *good.T),
                       atol=0.02)


def test_an_arm_whose_swing_saturates_is_not_asked_for_more():
    """Known answer: a launch that grows with the gain up to 1.2 and no further (an arm at its
    joints' speed limits) has its ceiling at 1.2; on a green twice as slow the matched hits
    stay at or below it, do not converge, and are said to be held back by the arm."""
    kappas = np.array([0.4, 0.8, 1.2, 1.6, 2.0, 2.6])
    factor = 1.5 * np.minimum(kappas, 1.2) / kappas
    table = LaunchTable(np.deg2rad([-40.0, 40.0]), kappas, np.tile(factor[:, None], (1, 2)),
                        np.zeros((6, 2)), "saturating arm")
    stroke = Stroke(np.array([1.0, 0.0, 0.0]), 1.0, launch_table=table)
    assert launch_ceiling(stroke) == pytest.approx(1.2)
    assert launch_ceiling(STROKE) == pytest.approx(2.6)   # a launch that keeps growing
    nominal = _flat()
    balls = np.array([[0.0, 0.0], [0.1, 0.2]])
    holes = np.array([[1.5, 0.0], [1.6, 0.1]])   # the hits below pass them on the nominal
    a, k = np.array([0.0, -0.06]), np.array([1.1, 1.1])
    assert np.all(hole_passage(Green(nominal, stroke), balls, holes, a, k)[:, 1] > 0)
    slow = Green(nominal, stroke, [np.log(2.0), 0, 0, 0, 0])
    A, K, ok = matching_shots(slow, balls, holes, a, k)
    assert np.all(K <= 1.2 + 1e-9) and not ok.any()
    assert launch_limited(slow, balls, holes, A, K).all()
    a_roll = 5 / 7 * slow.field.rolling_resistance * 9.81
    from seds_casadi.game.adapt import fastest_launch

    assert fastest_launch(slow) == pytest.approx(1.5 * 1.2)   # the factor at the ceiling
    stops = int(np.sum(hole_passage(slow, balls, holes, A, K)[:, 1]
                       < -2 * a_roll * nominal.hole_radius))
    # a green only a little slower: the arm can serve it, below its ceiling
    A, K, ok = matching_shots(Green(nominal, stroke, [np.log(1.1), 0, 0, 0, 0]), balls, holes,
                              a, k)
    assert ok.all() and np.all(K > k) and np.all(K <= 1.2 + 1e-9)
    # the correction learned on the twice slower green counts the situations held back, and
    # those whose balls stop short even at the arm's fastest hit (the holes 1.5 m away: all)
    from seds_casadi.game.adapt import _learn_correction
    from seds_casadi.minigolf.hitting_data import HittingDataset

    data = HittingDataset("flat", "fixed_speed", balls, holes, a, k, stroke)
    base = make_model("gpr").fit(data.situations, np.rad2deg(a)[:, None])
    model = _learn_correction(CorrectedModel(base, fixed_kappa=1.1), slow, data, 24)
    n_limited, n_all, n_short = model.limited_
    assert (n_all, n_limited, n_short) == (2, 2, stops) and stops == 2   # 0.7 m short


def test_a_world_must_be_the_same_course():
    arctan = load_field("arctan")
    assert "arctan_stimp8" in world_names()
    w = World.load("arctan_stimp8", arctan)
    assert w.field.rolling_resistance > arctan.rolling_resistance and w.engine == "ball"
    assert World.load("exudyn", arctan).engine == "exudyn"
    assert World.load(None, arctan).field is arctan
    with pytest.raises(ValueError, match="another course.*bounds"):
        check_world(load_field("flat"), arctan)
    moved = {**arctan.spec, "name": "moved", "hole": {"x": 1.3, "y": 0.0, "radius": 0.054},
             "situations": {"ball": {"region": [-0.1, 0.3, -0.45, 0.45]},
                            "hole": {"fixed": [1.3, 0.0]}}}
    with pytest.raises(ValueError, match="another course.*hole"):
        check_world(Field.from_dict(moved), arctan)


def test_the_correction_starts_at_the_taught_model_and_shots_spread_out():
    rng = np.random.default_rng(1)
    S = rng.uniform([1.0, -0.5], [1.6, 0.5], (30, 2))
    Y = np.column_stack([10 * S[:, 1], 1 + 0.2 * S[:, 0]])
    base = make_model("gpr").fit(S, Y)
    m = CorrectedModel(base)
    assert np.allclose(m.predict(S), base.predict(S))
    m.fit_correction(S[:1], [[2.0, np.log(1.1)]])   # one shot: a constant correction
    assert np.allclose(m.predict(S[5:7]), base.predict(S[5:7]) * [1, 1.1] + [2.0, 0])
    m.fit_correction(S[:6], np.tile([2.0, np.log(1.1)], (6, 1)))
    assert np.allclose(m.correction(S[10:12]), [2.0, np.log(1.1)], atol=1e-3)
    with pytest.raises(ValueError, match="fixed_kappa"):
        CorrectedModel(make_model("gpr").fit(S, Y[:, :1])).predict(S)
    cand = (np.zeros((50, 2)), rng.uniform(0, 1, (50, 2)))
    first = next_situation(cand, np.zeros((0, 2)), np.ones(2))
    second = next_situation(cand, cand[1][[first]], np.ones(2))
    d = np.linalg.norm(cand[1] - cand[1][first], axis=1)
    assert d[second] == pytest.approx(d.max())


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "seds_casadi", "play", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=120)


def test_bad_adaptation_requests_are_one_line_errors_before_any_work(tmp_path):
    for args, words in ((["--world", "arctan_stimp8"], "--world needs --field"),
                        (["--field", "arctan", "--adapt", "-1"], "--adapt"),
                        (["--field", "arctan", "--world", "flat"], "another course")):
        r = _cli(*args, "--out", str(tmp_path / "o"), cwd=tmp_path)
        assert r.returncode != 0
        assert words in r.stderr and "Traceback" not in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1
        assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_play_corrects_itself_on_a_tilted_green(tmp_path):
    """End to end: taught on flat, played on flat tilted 1 % sideways; the round before the
    correction and after 6 adaptation shots; the tilt is found."""
    from seds_casadi.app.play import play

    res = play(field="flat", world="flat_tilted", adapt=6, shots=8, learners=("gpr",),
               validate_shots=0, out=str(tmp_path), progress=False, seed=3)
    rows = res["all_rows"]
    phases = [(r["phase"], r["adapt_shots"]) for r in rows]
    assert phases.count(("adapt", 0)) == 1 and sum(p == "adapt" for p, _ in phases) == 6
    assert phases.count(("test", 0)) == 8 and phases.count(("test", 6)) == 8
    before = np.mean([r["sunk"] for r in rows if r["phase"] == "test" and r["adapt_shots"] == 0])
    after = res["success"]["gpr"]
    assert after >= 0.85 and after > before
    green = res["adaptations"]["gpr"].green
    assert green.q[2] == pytest.approx(0.01, abs=0.003)
    text = (tmp_path / "summary.txt").read_text()
    assert "before the correction (--adapt 0): gpr" in text and "after 6 adaptation shots" in text
    assert (tmp_path / "adaptation.png").stat().st_size > 10_000
    header = (tmp_path / "shots.csv").read_text().splitlines()[0]
    assert header.endswith("phase,adapt_shots")


def test_a_path_passes_the_hole_at_a_side_distance_and_speed():
    """Known answers of path_passage: a straight roll at 1 m/s beside the hole, and one that
    stops short; and a residual is zero before any shot and constant after one."""
    from seds_casadi.game.adapt import PassageResidual, path_passage

    t = np.arange(0, 3.0, 0.01)
    path = np.column_stack([t * 1.0, np.full_like(t, -0.01)])   # 1 cm right of the hole
    off, v2 = path_passage(path, t, [1.5, 0.0], 0.5)
    assert off == pytest.approx(0.01) and v2 == pytest.approx(1.0)
    short = path[t <= 1.2]
    off, v2 = path_passage(short, t[t <= 1.2], [1.5, 0.0], 0.5)
    # short: measured against the line from the start to the hole (where it stopped, not its
    # last heading, which wanders on an uneven green)
    line = np.array([1.5, 0.0]) - short[0]
    u = line / np.linalg.norm(line)
    d = np.array([1.5, 0.0]) - short[-1]
    assert v2 == pytest.approx(-2 * 0.5 * (d @ u))
    assert off == pytest.approx(u[0] * d[1] - u[1] * d[0])
    assert 0.0079 < off < 0.0081   # the hole 1 cm left of the path, less the line's slope
    r = PassageResidual()
    assert np.array_equal(r(np.zeros((3, 2))), np.zeros((3, 2)))
