"""Robots (URDF against DH tables, Jacobians, dynamics) and the 500 Hz swing controller."""

import os

import casadi as ca
import numpy as np
import oracles
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from seds_casadi.motion import HittingMotionLearner, load_hitting_demos, rotation_z
from seds_casadi.robots import (
    SwingController,
    default_base,
    face_orientation,
    gravity_ratio,
    orientation_error,
    place_head,
    simulate_swing,
)
from seds_casadi.robots.club import Club
from seds_casadi.robots.models import load_robot, robot_names
from seds_casadi.robots.orientation import log3_sx, orientation_error_sx
from seds_casadi.robots.urdf import (
    KATANA_ORIGINS,
    KATANA_TOOL,
    ROBOTS_FOLDER,
    WAM_DH,
    katana_urdf,
    wam_urdf,
)

pytestmark = pytest.mark.slow

RNG = np.random.default_rng(7)


@pytest.fixture(scope="module")
def motion():
    return HittingMotionLearner(n_components=3).fit(load_hitting_demos()).motion_


def _T(R=np.eye(3), p=(0, 0, 0)):
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _rpy(r, p, y):
    cy, sy, cp, sp = np.cos(y), np.sin(y), np.cos(p), np.sin(p)
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1.0]])
    return Rz @ Ry @ _rx(r)


def _random_q(r):
    return RNG.uniform(r.lower, r.upper)


def test_shipped_urdfs_are_the_generated_ones():
    with open(os.path.join(ROBOTS_FOLDER, "wam7.urdf")) as fh:
        assert fh.read() == wam_urdf()
    with open(os.path.join(ROBOTS_FOLDER, "katana_6m180.urdf")) as fh:
        assert fh.read() == katana_urdf()


def test_wam_forward_kinematics_matches_the_dh_table():
    r = load_robot("wam")
    fl = r.model.getFrameId("wam_flange")
    for _ in range(20):
        q = _random_q(r)
        T = _T(p=(0, 0, 0.346))
        for (alpha, a, d), qi in zip(WAM_DH, q):
            T = T @ _T(_rz(qi)) @ _T(p=(0, 0, d)) @ _T(p=(a, 0, 0)) @ _T(_rx(alpha))
        T = T @ _T(_rx(np.pi / 2))  # tool plate
        pin.framesForwardKinematics(r.model, r.data, q)
        M = r.data.oMf[fl]
        np.testing.assert_allclose(M.translation, T[:3, 3], atol=1e-8)
        np.testing.assert_allclose(M.rotation, T[:3, :3], atol=1e-8)


def test_katana_forward_kinematics_matches_the_joint_origins():
    r = load_robot("katana")
    fl = r.model.getFrameId("katana_flange")
    for _ in range(20):
        q = _random_q(r)
        T = np.eye(4)
        for (xyz, rpy), qi in zip(KATANA_ORIGINS, q):
            T = T @ _T(_rpy(*rpy), xyz) @ _T(_rz(qi))
        T = T @ _T(_rpy(*KATANA_TOOL[1]), KATANA_TOOL[0])
        pin.framesForwardKinematics(r.model, r.data, q)
        np.testing.assert_allclose(r.data.oMf[fl].translation, T[:3, 3], atol=1e-8)
        np.testing.assert_allclose(r.data.oMf[fl].rotation, T[:3, :3], atol=1e-8)


@pytest.mark.parametrize("name", ["wam", "katana", "panda", "ur5"])
def test_head_jacobian_matches_finite_differences(name):
    r = load_robot(name, base=(0.2, -0.1, 0.05, 0.7))
    for _ in range(3):
        q = _random_q(r)
        J = r.head_jacobian(q)
        x0, R0 = r.head_pose(q)
        eps = 1e-7
        for i in range(r.nv):
            dq = np.zeros(r.nv)
            dq[i] = eps
            x1, R1 = r.head_pose(q + dq)
            np.testing.assert_allclose((x1 - x0) / eps, J[:3, i], atol=1e-5)
            W = (R1 @ R0.T - np.eye(3)) / eps  # skew(omega)
            np.testing.assert_allclose([W[2, 1], W[0, 2], W[1, 0]], J[3:, i], atol=1e-5)


@pytest.mark.parametrize("name", ["wam", "katana", "panda"])
def test_rnea_and_aba_are_inverse(name):
    r = load_robot(name)
    for _ in range(5):
        q, qd = _random_q(r), RNG.normal(size=r.nv)
        qdd = RNG.normal(size=r.nv)
        tau = pin.rnea(r.model, r.data, q, qd, qdd)
        np.testing.assert_allclose(pin.aba(r.model, r.data, q, qd, tau), qdd, atol=1e-8)


def test_club_inertia_and_head_frame():
    c = Club(0.5, 0.1, 0.3)
    inert = c.inertia()
    assert inert.mass == pytest.approx(0.4)
    assert inert.lever[2] == pytest.approx((0.1 * 0.25 + 0.3 * 0.5) / 0.4)
    r = load_robot("wam", club=c)
    fl = r.model.getFrameId("wam_flange")
    q = _random_q(r)
    pin.framesForwardKinematics(r.model, r.data, q)
    head = r.data.oMf[r.head_frame]
    flange = r.data.oMf[fl]
    # the head is 0.5 m along the flange's z axis; its x axis (face normal) is the flange's x
    np.testing.assert_allclose(head.translation, flange.translation + 0.5 * flange.rotation[:, 2],
                               atol=1e-8)
    np.testing.assert_allclose(head.rotation[:, 0], flange.rotation[:, 0], atol=1e-8)
    # the club's mass is carried by the last link
    bare = pin.buildModelFromUrdf(os.path.join(ROBOTS_FOLDER, "wam7.urdf"))
    assert sum(i.mass for i in r.model.inertias) == pytest.approx(
        sum(i.mass for i in bare.inertias) + 0.4)


def test_every_known_robot_loads_with_its_club():
    for name in robot_names():
        r = load_robot(name)
        assert r.nv == r.model.nq and r.nv >= 5
        x, R = r.head_pose(r.q_home)
        assert np.all(np.isfinite(x)) and np.allclose(R.T @ R, np.eye(3))


def _fig7_cases(motion):
    """Ball moved sideways (Fig. 7a) and three holes (Fig. 7b): (ball, alpha) pairs, alpha
    turning the default hit psi* towards the hole."""
    psi = motion.hitting_direction
    out = []
    for dy in (0.0, -0.09, -0.18):
        ball = np.array([0.0, dy, 0.02135])
        for hole_y in (-0.3, 0.0, 0.3):
            s = np.array([2.4, hole_y]) - ball[:2]
            out.append((ball, float(np.arctan2(s[1], s[0]) - np.arctan2(psi[1], psi[0]))))
    return out


@pytest.mark.parametrize("name,kappa,cases", [("wam", 1.0, slice(0, 9, 2)),
                                              ("katana", 0.4, slice(1, 9, 2))])
def test_swings_hit_with_the_commanded_velocity(name, kappa, cases, motion):
    r = load_robot(name, base=default_base(name))
    for ball, alpha in _fig7_cases(motion)[cases]:
        res = simulate_swing(r, motion, ball, alpha, kappa)
        assert res.hit, (name, ball, alpha)
        assert res.direction_error_deg <= 2.0, (name, ball, alpha, res.direction_error_deg)
        assert res.speed_error <= 0.05, (name, ball, alpha, res.speed_error)
        assert res.limits_ok
        # after the hit the resting mode slows the club down, still moving forwards
        v_end = np.linalg.norm(res.head[-1] - res.head[-2]) / (res.t[-1] - res.t[-2])
        assert v_end < 0.5 * np.linalg.norm(res.hit_velocity)
        i = np.searchsorted(res.t, res.hit_time)
        psi = res.commanded / np.linalg.norm(res.commanded)
        assert (res.head[-1] - res.head[i]) @ psi > 0.02
        if name == "wam":
            assert res.peak_torque_ratio <= 1.0 + 1e-9
        else:
            # the Katana's published efforts cannot even hold it against gravity
            assert gravity_ratio(r, r.q_home) > 1


def test_example_robot_data_arm_swings_with_the_same_controller(motion):
    r = load_robot("panda", base=(0.0, 0.55, 0.0, -np.pi / 2))
    res = simulate_swing(r, motion, np.array([0.0, 0.0, 0.02135]), 0.05, 1.0)
    assert res.hit and res.direction_error_deg <= 2.0 and res.speed_error <= 0.05
    assert res.limits_ok and res.peak_torque_ratio <= 1.0 + 1e-9


def test_hitting_parameters_follow_a_hole_moved_mid_swing(motion):
    # Fig. 8b: the hole moves during the swing; alpha is recomputed every tick from the
    # situation, without re-planning, and the hit goes where the moved hole asks
    r = load_robot("wam", base=default_base("wam"))
    ball = np.array([0.0, 0.0, 0.02135])
    psi = motion.hitting_direction
    seen = []

    def aim(t, b, h):
        seen.append(h[1])
        return np.arctan2(h[1] - b[1], h[0] - b[0]) - np.arctan2(psi[1], psi[0]), 1.0

    res = simulate_swing(r, motion, ball, hole=[2.4, 0.0], params=aim,
                         perturb=[{"t": 0.15, "hole": [2.4, -0.3]}])
    assert res.hit and seen[0] == 0.0 and seen[-1] == -0.3
    v = res.hit_velocity
    to_hole = np.array([2.4, -0.3]) - ball[:2]
    angle = np.degrees(np.arccos(v[:2] @ to_hole / np.linalg.norm(v[:2]) / np.linalg.norm(to_hole)))
    assert angle < 2.0


def test_ball_moved_mid_swing_is_still_hit(motion):
    r = load_robot("wam", base=default_base("wam"))
    ball = np.array([0.0, 0.0, 0.02135])
    res = simulate_swing(r, motion, ball, 0.0, 1.0,
                         perturb=[{"t": 0.2, "ball": ball + np.array([0, -0.04, 0])}])
    assert res.hit and res.direction_error_deg <= 3.0


def test_bad_inputs(tmp_path, motion):
    with pytest.raises(ValueError, match="unknown robot 'r2d2'.*wam, katana"):
        load_robot("r2d2")
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'></robot>")
    with pytest.raises(ValueError, match="failed to load"):
        load_robot(str(bad), flange="a")
    with pytest.raises(ValueError, match="failed to load"):  # no flange: read first
        load_robot(str(bad))
    # without a flange an arm that branches is refused, naming its tips and the remedy
    joint = ("<joint name='{0}' type='revolute'><parent link='base'/><child link='{1}'/>"
             "<axis xyz='0 0 1'/><limit lower='-1' upper='1' effort='10' velocity='1'/>"
             "</joint>")
    link = ("<link name='{0}'><inertial><mass value='1'/><inertia ixx='0.01' ixy='0' ixz='0' "
            "iyy='0.01' iyz='0' izz='0.01'/></inertial></link>")
    fork = tmp_path / "fork.urdf"
    fork.write_text("<robot name='fork'>" + link.format("base") + link.format("l1")
                    + link.format("l2") + joint.format("j1", "l1") + joint.format("j2", "l2")
                    + "</robot>")
    with pytest.raises(ValueError, match=r"branches \(tip joints \['j1', 'j2'\]\).*#LINK"):
        load_robot(str(fork))
    with pytest.raises(ValueError, match="inside the field surface"):
        load_robot("wam", base=(0, 0.5, -0.2, 0))
    from seds_casadi.minigolf.fields import load_field

    hills = load_field("double_hill")
    with pytest.raises(ValueError, match="inside the field surface"):
        load_robot("wam", base=(0.9, 0.22, 0.01, 0), field=hills)  # on top of a hill
    assert load_robot("wam", base=(0.9, 0.22, 0.05, 0), field=hills).base[2] == 0.05
    r = load_robot("katana", base=default_base("katana"))
    with pytest.raises(ValueError, match="beyond the club's reach"):
        simulate_swing(r, motion, np.array([2.0, 0.0, 0.02]))
    with pytest.raises(ValueError, match="period must be positive"):
        SwingController(r, motion, period=0.0)
    with pytest.raises(ValueError, match="cannot place the club head"):
        place_head(r, np.array([0.0, 0.45, 1.5]), np.array([1.0, 0, 0]), restarts=1)


def test_start_is_placed_behind_the_ball_facing_the_hit(motion):
    r = load_robot("wam", base=default_base("wam"))
    target = np.array([-0.3, 0.02, 0.07])
    d = rotation_z(0.1) @ np.array([1.0, 0, 0])
    q = place_head(r, target, d)
    x, R = r.head_pose(q)
    np.testing.assert_allclose(x, target, atol=1e-3)
    assert R[:, 0] @ d > np.cos(np.deg2rad(2))


def test_effective_mass_at_the_face_matches_the_inverse_inertia():
    from seds_casadi.robots.dynamics import effective_mass

    r = load_robot("wam")
    for _ in range(3):
        q = _random_q(r)
        n = RNG.normal(size=3)
        n /= np.linalg.norm(n)
        m = effective_mass(r, q, n)
        Minv = pin.computeMinverse(r.model, r.data, q)
        Minv = np.triu(Minv) + np.triu(Minv, 1).T
        J = r.head_jacobian(q)[:3]
        assert m == pytest.approx(1.0 / (n @ J @ Minv @ J.T @ n), rel=1e-9)
        assert effective_mass(r, q, -n) == pytest.approx(m)
        # a plausible range: above half the head's 0.3 kg, below the whole arm with its club
        assert 0.3 * 0.5 < m < sum(i.mass for i in r.model.inertias)


# ---------------------------------------------------------------- orientation, once in CasADi
def _rotation(axis, angle):
    axis = np.asarray(axis, float)
    return Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).as_matrix()


@settings(max_examples=60, deadline=None)
@given(axis=st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(
           lambda a: np.linalg.norm(a) > 1e-3),
       angle=st.one_of(st.floats(0.0, np.pi), st.floats(0.0, 1e-5),
                       st.floats(np.pi - 1e-3, np.pi)),
       seed=st.integers(0, 2**31 - 1))
def test_orientation_error_equals_the_oracle(axis, angle, seed):
    """log(Rd R^T) in CasADi (with its limits at 0 and pi) against numpy, R = E^T Rd for a
    random Rd and an error rotation E of any angle."""
    Rd = Rotation.random(random_state=seed).as_matrix()
    E = _rotation(axis, angle)
    R = E.T @ Rd
    e = orientation_error(R, Rd, True)
    want = oracles.orientation_error(R, Rd, True)
    if angle < np.pi - 1e-3:
        np.testing.assert_allclose(e, want, atol=1e-9)
    else:  # arccos is ill-conditioned at pi (1e-16 in the trace: 1e-8 in the angle)
        np.testing.assert_allclose(e, want, atol=1e-6)
    # the vector rotates R onto Rd (at pi either sign of the axis does); within 1e-4 rad of pi
    # the axis is read from the diagonal, which assumes the symmetry of a turn by exactly pi
    np.testing.assert_allclose(Rotation.from_rotvec(e).as_matrix() @ R, Rd,
                               atol=1e-8 if angle < np.pi - 1e-3 else 1e-3)
    np.testing.assert_allclose(orientation_error(R, Rd, False),
                               oracles.orientation_error(R, Rd, False), atol=1e-12)


def test_orientation_error_in_the_tick_is_the_same_expression():
    """The symbolic error (what the compiled tick inlines) evaluates to the numeric one."""
    rng = np.random.default_rng(3)
    R_, Rd_ = ca.SX.sym("R", 3, 3), ca.SX.sym("Rd", 3, 3)
    f = ca.Function("e", [R_, Rd_], [orientation_error_sx(R_, Rd_, True), log3_sx(R_)])
    for _ in range(10):
        R, Rd = (Rotation.random(random_state=rng.integers(2**31)).as_matrix() for _ in range(2))
        e, lg = f(R, Rd)
        np.testing.assert_allclose(np.asarray(e).ravel(), orientation_error(R, Rd, True),
                                   atol=1e-15)
        np.testing.assert_allclose(np.asarray(lg).ravel(), oracles.log3(R), atol=1e-8)
    np.testing.assert_allclose(orientation_error(np.eye(3), np.eye(3), True), 0.0)


@pytest.mark.parametrize("d", [[1.0, 0.2, 0.3], [-0.3, 0.5, 0.0], [0.0, 0.0, 1.0],
                               [1e-12, 0.0, -1.0], [0.0, -2.0, 0.5]])
def test_face_orientation_equals_the_oracle(d):
    R = face_orientation(d)
    np.testing.assert_allclose(R, oracles.face_orientation(d), atol=1e-15)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-15)


def test_swing_refuses_an_unknown_perturbation(motion):
    r = load_robot("wam", base=default_base("wam"))
    with pytest.raises(ValueError, match=r"unknown perturbation key\(s\) \['kappa'\]"):
        simulate_swing(r, motion, np.array([0.0, 0.0, 0.02135]),
                       perturb=[{"t": 0.1, "kappa": 1.2}])


def test_controllers_with_the_same_arm_and_settings_share_one_compiled_tick(motion):
    from seds_casadi.robots.controller import Gains, _compiled_tick, tick_function

    a = SwingController(load_robot("wam", base=(0.0, 0.5, 0.0, -np.pi / 2)), motion)
    b = SwingController(load_robot("wam", base=(1.0, -0.2, 0.1, 0.3)), motion)  # another place
    assert _compiled_tick(a) is _compiled_tick(b)
    other = [SwingController(load_robot("wam"), motion, gains=Gains(kp=90.0)),
             SwingController(load_robot("panda"), motion),
             SwingController(load_robot("wam"), motion, period=0.004),
             SwingController(load_robot("wam"), motion, cartesian_speed_limit=None)]
    ticks = {id(_compiled_tick(c)) for c in other} | {id(_compiled_tick(a))}
    assert len(ticks) == 5
    # the shared tick computes what a tick built for this controller computes
    fresh = tick_function(b)
    z = RNG.standard_normal(fresh.size1_in(0))
    np.testing.assert_allclose(np.asarray(_compiled_tick(b)(z)), np.asarray(fresh(z)),
                               rtol=1e-9, atol=1e-9)
