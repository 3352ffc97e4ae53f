"""The game layer (seds_casadi.game): one shot function on real swings (Pinocchio), the ball
model and exudyn; the robot's measured launch; scenes loaded once per process."""

import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytestmark = pytest.mark.slow

pytest.importorskip("pinocchio")

from seds_casadi.game.launch import calibrate_launch  # noqa: E402
from seds_casadi.game.scene import Scene  # noqa: E402
from seds_casadi.game.shot import Shot, play_round, play_shot, swing_launch  # noqa: E402
from seds_casadi.minigolf.ball import RESTITUTION, impact  # noqa: E402
from seds_casadi.minigolf.fields import load_field  # noqa: E402
from seds_casadi.minigolf.stroke import LaunchTable, Stroke  # noqa: E402
from seds_casadi.minigolf.teacher import Teacher  # noqa: E402
from seds_casadi.motion.golf import BALL_MASS  # noqa: E402
from seds_casadi.motion.hitting import HittingMotionLearner  # noqa: E402
from seds_casadi.motion.putting_demos import load_hitting_demos  # noqa: E402
from seds_casadi.robots.dynamics import effective_mass  # noqa: E402

#: shots played by the code before the game layer (app/play.py's play_shot and
#: app/validate.py's _shot, commit e360d10) with the motion fitted as below: the known answers
#: the one shot function must reproduce. (robot, field, ball, hole, alpha [rad], kappa) ->
#: hit, sunk, club direction error [deg], speed error, face error [deg], final position [m]
BEFORE = [
    (("wam", "arctan", (0.2, 0.1), (1.4, 0.0), 0.06981317007977318, 1.4),
     (True, True, 0.031213833533906134, 0.001995848522660326, 0.01622329565387568,
      (1.379167753788367, 0.012231955652375696))),
    (("wam", "flat", (0.2, -0.1), (2.0, 0.2), -0.03490658503988659, 1.0),
     (True, False, 0.02494381042613062, 0.0013674932763414471, 0.006223650621374053,
      (1.6647571272756303, -0.12708460689887877))),
    (("katana", "flat", (0.2, 0.0), (1.5, 0.0), 0.0, 0.8),
     (True, False, 20.301183848109734, 0.2474664043875131, 1.0877331085815276,
      (0.7136356412237499, 0.018247379690901143))),
    (("panda", "double_hill", (0.3, 0.0), (2.4, 0.1), 0.017453292519943295, 1.2),
     (True, False, 0.07721071957057553, 0.0021686988611828717, 0.012095905612249396,
      (2.4681853462816807, 0.19850658084266556))),
]
#: the same code's exudyn check of the first two: sunk in exudyn, final distance between the
#: engines [m]
BEFORE_EXUDYN = [(True, 0.004488601054968111), (False, 0.006141201275169246)]


@pytest.fixture(scope="module")
def motion(tmp_path_factory):
    m = HittingMotionLearner(n_components=3).fit(load_hitting_demos()).motion_
    folder = tmp_path_factory.mktemp("motion") / "motion"
    m.save(str(folder))
    return m, str(folder)


def _scene(motion, robot, field):
    m, folder = motion
    return Scene(robot, load_field(field), m, motion_folder=folder)


@pytest.mark.parametrize("case, expected", BEFORE, ids=[f"{c[0]}-{c[1]}" for c, _ in BEFORE])
def test_the_shot_function_plays_as_the_code_before_it(motion, case, expected):
    robot, field, ball, hole, alpha, kappa = case
    res = play_shot(_scene(motion, robot, field), Shot(ball, hole, alpha, kappa))
    hit, sunk, dir_err, speed_err, face_err, final = expected
    assert (res.hit, res.sunk) == (hit, sunk)
    np.testing.assert_allclose([res.direction_error_deg, abs(res.speed_error),
                                res.launch_direction_error_deg], [dir_err, speed_err, face_err],
                               rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(res.final_position, final, atol=1e-6)
    assert res.within_limits is True
    assert (res.reason == "") == sunk


def test_the_exudyn_engine_plays_as_the_validation_before_it(motion):
    for (case, _), (sunk_ex, dist) in zip(BEFORE[:2], BEFORE_EXUDYN):
        robot, field, ball, hole, alpha, kappa = case
        scene = _scene(motion, robot, field)
        shot = Shot(ball, hole, alpha, kappa)
        fast, ex = play_shot(scene, shot), play_shot(scene, shot, engine="exudyn")
        assert ex.engine == "exudyn" and ex.hit and ex.sunk == sunk_ex
        assert np.linalg.norm(ex.final_position - fast.final_position) == pytest.approx(
            dist, abs=1e-5)
        # the launch of the fast engine is the arm's: within 1 % and 0.5 deg of exudyn's
        assert np.linalg.norm(ex.launch_velocity) == pytest.approx(
            np.linalg.norm(fast.launch_velocity), rel=0.01)


def test_the_launch_is_the_impact_with_the_arms_effective_mass(motion):
    scene = _scene(motion, "panda", "arctan")
    swing, launch = swing_launch(scene, [0.1, 0.0], 0.1, 1.0)
    m_eff = effective_mass(scene.robot_at([0.1, 0.0]), swing.q[np.searchsorted(
        swing.t, swing.hit_time)], swing.face_normal)
    assert m_eff == pytest.approx(swing.effective_mass, rel=0.02)   # the tick after the hit
    # an independent oracle of the flat-face impact: (1 + e) m / (m + m_b) (v . n) n
    n = swing.face_normal / np.linalg.norm(swing.face_normal)
    k = (1 + RESTITUTION) * swing.effective_mass / (swing.effective_mass + BALL_MASS)
    np.testing.assert_allclose(launch, k * (swing.hit_velocity @ n) * n[:2], rtol=1e-12)


def test_the_measured_launch_table_holds_the_arms_own_launch(motion):
    scene = _scene(motion, "ur5", "arctan")
    table = calibrate_launch(scene, (-20, 20), (0.8, 1.2), n_alpha=3, n_kappa=2)
    # at a grid point, the table's launch is the swing's launch (the same definition)
    stroke = scene.with_launch(table).stroke
    ball = scene.field.situations.ball.design(9)[4]
    _, launch = swing_launch(scene, ball, table.alphas[2], table.kappas[0], {"rest_time": 0.0})
    np.testing.assert_allclose(stroke.launch_velocity(table.alphas[2], table.kappas[0])[0],
                               launch, rtol=1e-9)
    # the UR5's effective mass is about 1 kg, not the ideal club's 0.35 kg: a faster launch
    ideal = scene.stroke.launch_velocity(0.0, 1.0)[0]
    assert np.linalg.norm(stroke.launch_velocity(0.0, 1.0)[0]) > 1.05 * np.linalg.norm(ideal)


def test_the_teacher_on_the_arms_launch_teaches_shots_the_arm_sinks(motion):
    # the Panda swings accurately yet missed every arctan shot taught with the ideal club's
    # launch (its effective mass is 0.44 kg, not 0.35): taught on its own launch, it sinks
    scene = _scene(motion, "panda", "arctan")
    scene = scene.with_launch(calibrate_launch(scene, (-40, 40), (0.6, 2.4)))
    balls = np.array([[0.1, -0.3], [0.1, 0.0], [0.2, 0.3]])
    holes = np.tile(scene.field.hole, (3, 1))
    data = Teacher(scene.field, scene.stroke, resolution=(81, 26)).collect(balls, holes)
    shots = [Shot(b, h, a, k) for b, h, a, k in zip(data.ball, data.hole, data.alpha,
                                                      data.kappa)]
    results = play_round(scene, shots)
    assert all(r.sunk for r in results), [r.reason for r in results]


def test_a_miss_says_why(motion):
    scene = _scene(motion, "wam", "flat")
    short = play_shot(scene, Shot([0.2, 0.0], [2.4, 0.0], 0.0, 0.5))
    assert short.hit and not short.sunk and short.reason.startswith("stopped")
    sw = play_shot(scene, short.shot, keep_swing=True).swing    # the signed speed error
    assert short.speed_error == pytest.approx(
        np.linalg.norm(sw.hit_velocity) / np.linalg.norm(sw.commanded) - 1, abs=1e-12)
    assert abs(short.speed_error) == pytest.approx(sw.speed_error, abs=1e-15)
    assert "short by" in short.reason and short.miss == "short"
    long = play_shot(scene, Shot([0.2, 0.0], [1.0, 0.3], 0.0, 1.2))   # aimed beside the hole
    assert not long.sunk and "long by" in long.reason and "m right of the line" in long.reason
    over = play_shot(scene, Shot([0.2, 0.0], [0.45, 0.0], 0.0, 2.0))   # straight, too fast
    assert not over.sunk and over.reason == "crossed the hole too fast to drop"
    assert (long.miss, over.miss) == ("long", "too fast")   # 1.13 m long, 0.71 m beside
    wide = play_shot(scene, Shot([0.2, 0.0], [1.4, 0.0], 0.6, 0.9))   # 34 deg off the line
    assert not wide.sunk and wide.miss == "wide", wide.reason
    far = play_shot(_scene(motion, "z1", "flat"), Shot([0.2, 0.0], [2.4, 0.0], 0.0, 1.0))
    assert not far.hit and far.reason.startswith("the swing could not start")
    assert far.miss == "no swing"


def test_a_scene_travels_as_a_spec_and_loads_once_per_process(motion):
    scene = _scene(motion, "wam", "flat")
    spec = scene.spec()
    assert pickle.loads(pickle.dumps(spec)) == spec and hash(spec) == hash(scene.spec())
    first = spec.load()
    assert spec.load() is first        # the second shot of a worker reuses the scene
    shot = Shot([0.2, -0.1], [2.0, 0.2], -0.03490658503988659, 1.0)
    np.testing.assert_allclose(play_shot(spec, shot).final_position,
                               play_shot(scene, shot).final_position, atol=1e-12)
    with pytest.raises(ValueError, match="save the motion"):
        Scene("wam", scene.field, scene.motion).spec()


def test_a_round_on_worker_processes_equals_the_round_here(motion):
    from seds_casadi.app.executors import open_executor

    scene = _scene(motion, "wam", "arctan")
    shots = [Shot([0.1, y], [1.4, 0.0], a, 1.4, index=i)
             for i, (y, a) in enumerate([(-0.2, 0.1), (0.0, 0.0), (0.2, -0.1)])]
    here = play_round(scene, shots)                 # one ball-model run for the three
    alone = play_round(scene, shots, chunk=1)       # a ball-model run for each
    with open_executor(2) as ex:
        there = play_round(scene, shots, executor=ex, chunk=2)
    for a, b, c in zip(here, there, alone):
        assert (a.shot.index, a.sunk) == (b.shot.index, b.sunk) == (c.shot.index, c.sunk)
        np.testing.assert_allclose(a.final_position, b.final_position, atol=1e-12)
        np.testing.assert_array_equal(a.path, c.path)


def test_bad_shots_and_engines_are_clear_errors(motion):
    with pytest.raises(ValueError, match="kappa"):
        Shot([0, 0], [1, 0], 0.0, 0.0)
    with pytest.raises(ValueError, match="ball"):
        Shot([np.nan, 0], [1, 0], 0.0, 1.0)
    with pytest.raises(ValueError, match="engine"):
        play_shot(_scene(motion, "wam", "flat"), Shot([0.2, 0], [2, 0], 0.0, 1.0), "mujoco")


# ------------------------------------------------------------------ the launch table alone
_GRID = st.lists(st.floats(-1.0, 1.0), min_size=2, max_size=5, unique=True).map(sorted)


@settings(max_examples=40, deadline=None)
@given(_GRID, st.lists(st.floats(0.5, 2.5), min_size=2, max_size=5, unique=True).map(sorted),
       st.floats(-2, 2), st.floats(-2, 2), st.floats(0.5, 2))
def test_a_table_of_an_affine_launch_is_reproduced_exactly_inside(alphas, kappas, ca, ck, c0):
    a, k = np.array(alphas), np.array(kappas)
    if np.min(np.diff(a)) < 1e-3 or np.min(np.diff(k)) < 1e-3:
        return
    f = c0 + 0.1 * ca * a[None, :] + 0.1 * ck * k[:, None] + 1.0
    table = LaunchTable(a, k, f, 0.01 * f)
    rng = np.random.default_rng(0)
    qa, qk = rng.uniform(a[0], a[-1], 20), rng.uniform(k[0], k[-1], 20)
    fa, oa = table.at(qa, qk)
    exact = c0 + 0.1 * ca * qa + 0.1 * ck * qk + 1.0
    np.testing.assert_allclose(fa, exact, atol=1e-9)
    np.testing.assert_allclose(oa, 0.01 * exact, atol=1e-9)


def test_a_table_of_the_ideal_impact_gives_the_ideal_launch():
    stroke = Stroke(np.array([0.995, 0.097, -0.003]), 0.99)
    k = (1 + stroke.restitution) * stroke.club_mass / (stroke.club_mass + BALL_MASS)
    table = LaunchTable(np.array([-1.0, 1.0]), np.array([0.1, 3.0]), np.full((2, 2), k),
                        np.zeros((2, 2)))
    a, kap = np.linspace(-0.5, 0.5, 7), np.linspace(0.6, 2.4, 7)
    np.testing.assert_allclose(stroke.with_launch(table).launch_velocity(a, kap),
                               impact(stroke.club_velocity(a, kap)), rtol=1e-12)
    d = stroke.with_launch(table).to_dict()
    assert Stroke.from_dict(d).launch_table.to_dict() == table.to_dict()


@pytest.mark.parametrize("bad", [
    dict(alphas=[0.0], kappas=[1, 2], f=np.ones((2, 1))),
    dict(alphas=[1.0, 0.0], kappas=[1, 2], f=np.ones((2, 2))),
    dict(alphas=[0.0, 1.0], kappas=[1, 2], f=np.ones((3, 2))),
    dict(alphas=[0.0, 1.0], kappas=[1, 2], f=-np.ones((2, 2))),
    dict(alphas=[0.0, 1.0], kappas=[1, 2], f=np.full((2, 2), np.nan)),
])
def test_a_bad_launch_table_is_refused(bad):
    with pytest.raises(ValueError):
        LaunchTable(np.array(bad["alphas"]), np.array(bad["kappas"]), bad["f"],
                    np.zeros_like(bad["f"]))


def test_the_katana_plays_its_own_green_as_in_the_papers_section_7_1(tmp_path):
    # Fig. 7a: the ball moved along y from 0 to -0.18 m, the hole fixed on the x axis; the
    # Katana's own launch is taught, its swings are checked against its limits and in exudyn
    from seds_casadi.app.play import play

    res = play(robot="katana", field="katana_flat", shots=10, validate_shots=3,
               out=str(tmp_path / "out"), progress=False, cache=False)
    assert res["success"]["gpr"] >= 0.95 and res["success"]["gmr"] >= 0.95
    rows = res["rows"]
    assert all(r["hit"] and r["within_limits"] is True for r in rows)
    assert max(r["direction_error_deg"] for r in rows) < 1.0
    assert max(abs(r["speed_error"]) for r in rows) < 0.02
    checked = [r for r in rows if r["sunk_exudyn"] != ""]
    assert len(checked) == 3 and all(r["sunk_exudyn"] == r["sunk"] for r in checked)


def test_an_arm_that_cannot_follow_the_motion_is_refused_before_teaching(motion):
    from seds_casadi.game.reach import check_swing_accuracy

    check_swing_accuracy(_scene(motion, "wam", "arctan"), 1.0)          # passes
    with pytest.raises(ValueError, match=r"the ur3 does not follow the hitting motion on "
                                         r"arctan at kappa 1.00 .*deg"):
        check_swing_accuracy(_scene(motion, "ur3", "arctan"), 1.0)
