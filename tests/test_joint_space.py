"""Issue 13: SEDS in joint space, the shipped putts mapped to the WAM's 7 joints by its IK."""

import warnings

import numpy as np
import pytest

pytest.importorskip("pinocchio")

from seds_casadi import SEDS  # noqa: E402
from seds_casadi.core.metrics import pointwise_direction_error  # noqa: E402
from seds_casadi.motion import load_hitting_demos  # noqa: E402
from seds_casadi.robots import place_robot  # noqa: E402
from seds_casadi.robots.joint_space import joint_space_demos  # noqa: E402


@pytest.fixture(scope="module")
def wam_and_joint_demos():
    robot = place_robot("wam", [0.0, 0.0])
    cart = load_hitting_demos()
    return robot, cart, joint_space_demos(robot, cart)


def test_joint_demos_put_the_club_head_on_the_demonstrations(wam_and_joint_demos):
    robot, cart, joints = wam_and_joint_demos
    assert joints.n_dims == robot.nv == 7
    for p, q in zip(cart.positions, joints.positions):
        head = np.array([robot.head_pose(qi)[0] for qi in q])
        np.testing.assert_allclose(head, p, atol=2e-3)  # IK tolerance 1e-3 m
        assert np.all(q >= robot.lower - 1e-9) and np.all(q <= robot.upper + 1e-9)
        np.testing.assert_allclose(q[-1], joints.target, atol=1e-3)  # all end at q*
        assert np.max(np.abs(np.diff(q, axis=0))) < 0.5  # continuous: no IK branch jumps


@pytest.mark.slow
def test_seds_learns_and_reproduces_the_7d_joint_space_putts(wam_and_joint_demos):
    _, _, joints = wam_and_joint_demos
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = SEDS(3, objective="direction", random_state=0).fit(joints).model_
    assert model.n_dims == 7 and model.certificate["max_eig_lyapunov"] < 0
    X, V = np.concatenate(joints.positions), np.concatenate(joints.velocities)
    assert np.mean(pointwise_direction_error(model.predict(X), V)) < 0.05
    starts = np.stack([p[0] for p in joints.positions])
    _, info = model.rollout(starts, dt=0.01, max_steps=5000, tol=1e-2, return_info=True)
    assert info["converged"].all()


def test_unreachable_demonstrations_name_the_sample(wam_and_joint_demos):
    robot, cart, _ = wam_and_joint_demos
    far = cart.select([0])
    far = type(far)([p + np.array([5.0, 0.0, 0.0]) * (np.arange(len(p))[:, None] == 0)
                     for p in far.positions], dt=0.05, target=far.target)
    with pytest.raises(ValueError, match="demonstration 0, sample 0"):
        joint_space_demos(robot, far)
