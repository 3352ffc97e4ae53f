"""exudyn validation: a ball on an inclined mesh, a full shot in both models, bad input, CLI."""

import csv
import subprocess
import sys
import warnings

import numpy as np
import pytest

from seds_casadi.app.validate import VALIDATION_COLUMNS, ValidateConfig, validate
from seds_casadi.minigolf import Stroke
from seds_casadi.minigolf.ball import impact, simulate_shots
from seds_casadi.minigolf.fields import Field, load_field
from seds_casadi.minigolf.teacher import Teacher
from seds_casadi.sim import field_mesh, free_fall, simulate_shot_exudyn

pytestmark = [pytest.mark.slow,
              pytest.mark.filterwarnings("ignore::DeprecationWarning")]
STROKE = Stroke(np.array([0.995, 0.097, -0.003]), 0.99)


def _plane(slope_x, rho=0.0):
    return Field.from_dict(dict(name="incline", surface={"shape": "plane", "slope_x": slope_x},
                                bounds=[-0.3, 3.0, -0.6, 0.6], boundary="walls",
                                hole={"x": 2.7, "y": 0.5, "radius": 0.054},
                                ball_region=[-0.1, 0.3, -0.45, 0.45], rolling_resistance=rho))


def test_ball_rolls_down_an_inclined_mesh_at_five_sevenths_g_sin_theta():
    theta = np.deg2rad(4.0)
    f = _plane(-np.tan(theta))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        shot = simulate_shot_exudyn(f, [0.0, 0.0], [0.05, 0.0, 0.0], max_time=1.2)
    t, x = shot.path[:, 0], shot.path[:, 1]
    keep = t > 0.4  # after the skid
    # distance along the slope s = x / cos(theta); s'' = 5/7 g sin(theta)
    acc = 2 * np.polyfit(t[keep], x[keep] / np.cos(theta), 2)[0]
    assert acc == pytest.approx(5 / 7 * 9.81 * np.sin(theta), rel=0.01)


def test_a_taught_shot_sinks_in_both_models_and_a_miss_ends_in_the_same_place():
    f = load_field("flat")
    ball = np.array([0.1, 0.0])
    alpha, kappa = Teacher(f, STROKE, resolution=(121, 41)).good_shot(ball, f.hole)
    vc = STROKE.club_velocity(alpha, kappa)[0]
    fast = simulate_shots(f, ball[None], impact(vc[None]), engine="numpy")
    ex = simulate_shot_exudyn(f, ball, vc)
    assert fast.sunk[0] and ex.sunk
    # the impact: exudyn's contact against the impact formula
    launch = impact(vc[None])[0]
    assert np.linalg.norm(ex.launch_velocity) == pytest.approx(np.linalg.norm(launch), rel=0.03)
    # a slower shot that stops short: both models stop it within 5 cm of each other
    vc2 = 0.6 * vc
    fast2 = simulate_shots(f, ball[None], impact(vc2[None]), engine="numpy")
    ex2 = simulate_shot_exudyn(f, ball, vc2)
    assert fast2.stopped[0] and ex2.stopped and not ex2.sunk
    assert np.linalg.norm(ex2.final_position - fast2.final_position[0]) < 0.05
    assert ex2.real_time_factor > 0.2


def test_double_hill_shot_follows_the_fast_model():
    f = load_field("double_hill")
    vc = np.array([1.3, 0.1, 0.0])
    fast = simulate_shots(f, [[0.1, 0.0]], impact(vc[None]), engine="numpy")
    ex = simulate_shot_exudyn(f, [0.1, 0.0], vc)
    assert np.linalg.norm(ex.final_position - fast.final_position[0]) < 0.1


@pytest.mark.parametrize("name", ["wam", "katana", "panda"])
def test_kinematic_tree_falls_like_pinocchio(name):
    from seds_casadi.robots.models import load_robot

    r = load_robot(name, base=(0.2, 0.5, 0.1, -1.0))
    q0 = r.q_home + 0.1
    q_ex, q_pin = free_fall(r, q0, duration=0.2)
    assert np.abs(q_ex - q0).max() > 0.05  # it does fall
    np.testing.assert_allclose(q_ex, q_pin, atol=1e-9)


def test_the_arm_in_exudyn_hits_like_the_pinocchio_swing():
    from seds_casadi.motion.hitting import HittingMotionLearner
    from seds_casadi.motion.putting_demos import load_hitting_demos
    from seds_casadi.robots import default_base, simulate_swing
    from seds_casadi.robots.models import load_robot

    motion = HittingMotionLearner(n_components=3).fit(load_hitting_demos()).motion_
    f = load_field("flat")
    ball = np.array([0.1, 0.0])
    base = np.array(default_base("wam"))
    base[:2] += ball
    robot = load_robot("wam", base=tuple(base))
    stroke = Stroke.from_motion(motion)
    alpha, kappa = Teacher(f, stroke, resolution=(121, 41)).good_shot(ball, f.hole)
    sw = simulate_swing(robot, motion, np.array([0.1, 0.0, 0.02135]), alpha, kappa)
    ex = simulate_shot_exudyn(f, ball, arm={"robot": robot, "motion": motion, "alpha": alpha,
                                            "kappa": kappa})
    assert ex.hit and ex.sunk
    cos = ex.head_velocity @ sw.hit_velocity / (np.linalg.norm(ex.head_velocity)
                                                * np.linalg.norm(sw.hit_velocity))
    assert np.degrees(np.arccos(min(cos, 1.0))) < 0.5
    assert np.linalg.norm(ex.head_velocity) == pytest.approx(np.linalg.norm(sw.hit_velocity),
                                                             rel=0.03)
    fast = simulate_shots(f, ball[None], impact(sw.hit_velocity[None]), engine="numpy")
    assert fast.sunk[0]
    # the impact in exudyn (the whole arm, contact with restitution 0.8, adaptive steps)
    # launches the ball as the impact model predicts from the Pinocchio swing
    launch = impact(sw.hit_velocity[None], face_normal=sw.face_normal[None],
                    club_mass=sw.effective_mass)[0]
    assert np.linalg.norm(ex.launch_velocity) == pytest.approx(np.linalg.norm(launch),
                                                               rel=0.005)
    # a swing far too slow to reach the ball in time is reported as a miss, not a crash
    slow = simulate_shot_exudyn(f, ball, max_time=3.5, arm={
        "robot": robot, "motion": motion, "alpha": alpha, "kappa": 0.03})
    assert not slow.hit and not slow.sunk


def test_mesh_and_bad_input():
    f = load_field("double_hill")
    pts, tri = field_mesh(f, 0.1)
    assert pts.shape[1] == 3 and tri.shape[1] == 3
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    assert np.all(np.cross(b - a, c - a)[:, 2] > 0)  # normals up
    np.testing.assert_allclose(pts[:, 2], f.surface.height(pts[:, :2]))
    with pytest.raises(ValueError, match="larger spacing"):
        field_mesh(f, 0.001)
    with pytest.raises(ValueError, match="never hit"):
        simulate_shot_exudyn(f, [0.1, 0.0], [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="ball region"):
        simulate_shot_exudyn(f, [2.0, 0.0], [1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="must be positive"):
        simulate_shot_exudyn(f, [0.1, 0.0], [1.0, 0.0, 0.0], tolerance=0.0)
    # a shot that runs out of its computing budget is an error naming how far it got, never a
    # truncated result
    with pytest.raises(RuntimeError, match=r"more than 0.05 s of computing and reached only"):
        simulate_shot_exudyn(f, [0.1, 0.0], [1.5, 0.0, 0.0], max_wall_time=0.05)


def test_validate_command_line(tmp_path):
    out = tmp_path / "v"
    r = subprocess.run([sys.executable, "-m", "seds_casadi", "validate", "--shots", "2",
                        "--out", str(out)], capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-2000:]
    with open(out / "validation.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert tuple(rows[0]) == VALIDATION_COLUMNS and len(rows) == 2
    assert VALIDATION_COLUMNS == ("field", "robot", "shot", "sunk_fast", "sunk_exudyn",
                                  "impact_direction_error_deg", "impact_speed_error",
                                  "final_distance_m")
    for row in rows:
        assert row["sunk_fast"] == row["sunk_exudyn"]
        assert float(row["impact_speed_error"]) < 0.1
        assert float(row["final_distance_m"]) < 0.05
    assert (out / "validation.png").stat().st_size > 1000
    assert "sinks agree" in (out / "report.txt").read_text()


def test_validate_config_checks_its_values():
    assert ValidateConfig(field="arctan", shots=3).robot == "wam"
    with pytest.raises(ValueError, match="shots must be at least 1"):
        ValidateConfig(shots=0)
    with pytest.raises(ValueError, match="seed must be a whole number"):
        ValidateConfig(seed="x")
    with pytest.raises(TypeError, match="no setting 'robot_name'"):
        validate(robot_name="wam")
