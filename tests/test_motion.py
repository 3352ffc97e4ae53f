"""Hitting motion (issue 3): target field, strength factor, Eq. 14, resting mode, rollouts; the
CasADi expressions of Eq. 8, 12 and 14 against numpy oracles; the scikit-learn learners."""

import casadi as ca
import numpy as np
import oracles
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import clone

from seds_casadi import SEDS, Demonstrations
from seds_casadi.core import StrengthFactor, StrengthFactorLearner
from seds_casadi.motion import (
    HittingMotion,
    HittingMotionLearner,
    Perturbations,
    TargetField,
    approach_paths,
    plane_crossing,
    rotation_z,
    rotation_z_sx,
)
from seds_casadi.motion.putting_demos import generate_putting_demos


@pytest.fixture(scope="module")
def demos():
    return generate_putting_demos(random_state=0)


@pytest.fixture(scope="module")
def motion(demos):
    return HittingMotionLearner(n_components=3, random_state=0).fit(demos).motion_


def test_generated_demos_reach_the_ball_moving_along_x(demos):
    assert demos.n_demos == 7 and demos.n_dims == 3
    for p, v in zip(demos.positions, demos.velocities):
        np.testing.assert_allclose(p[-1], 0.0, atol=1e-12)
        speed = np.linalg.norm(v[-1])
        assert 0.85 < speed < 1.15
        assert v[-1][0] / speed > np.cos(np.deg2rad(5))
        assert p[0][0] < -0.25  # starts behind the ball
        # sampled at 20 Hz: the velocities are the exact derivatives of the positions
        mid = (p[2:] - p[:-2]) / 0.1
        np.testing.assert_allclose(mid[:-1], v[1:-2], atol=0.05)


def test_target_field_is_unit_everywhere_and_finite_at_the_ball(motion):
    tf = motion.target_field
    X = np.random.default_rng(0).standard_normal((200, 3)) * np.logspace(-8, 2, 200)[:, None]
    H = tf(X)
    np.testing.assert_allclose(np.linalg.norm(H, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(tf(np.zeros(3)), motion.hitting_direction)
    assert np.all(np.isfinite(tf(np.full(3, 1e-300))))
    # psi* is the slowest eigenvector of df/dx at the ball, along the demonstrated hit (+x)
    J = tf.jacobian
    lam = tf.eigenvalues[np.argmax(tf.eigenvalues.real)].real
    np.testing.assert_allclose(J @ motion.hitting_direction, lam * motion.hitting_direction,
                               atol=1e-8)
    assert motion.hitting_direction[0] > np.cos(np.deg2rad(10))


def test_strength_factor_is_positive_far_from_the_data(motion, demos):
    X = np.random.default_rng(1).standard_normal((500, 3)) * 50.0
    v = motion.strength(X)
    assert np.all(v > 0) and np.all(np.isfinite(v))
    assert motion.hitting_speed == pytest.approx(
        np.mean([np.linalg.norm(u[-1]) for u in demos.velocities]), rel=0.15)


def test_eq14_equals_a_direct_evaluation(motion):
    rng = np.random.default_rng(2)
    f_ca = motion.to_casadi()
    for _ in range(20):
        a, k = rng.uniform(-np.pi, np.pi), rng.uniform(0.3, 2.0)
        x = rng.uniform(-0.5, 0.3, 3)
        R = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
        y = R.T @ x
        f = motion.target_field.ds.predict(y)
        direct = k * R @ (motion.strength(y) * f / np.linalg.norm(f))
        np.testing.assert_allclose(motion.velocity(x, a, k), direct, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(np.asarray(f_ca(x, a, k)).ravel(), direct, rtol=1e-9,
                                   atol=1e-12)
    X = rng.uniform(-0.5, 0.3, (7, 3))
    V = motion.velocity(X, 0.3, 1.2)
    for x, v in zip(X, V):
        np.testing.assert_allclose(motion.velocity(x, 0.3, 1.2), v)


def test_rollout_hits_with_the_commanded_speed(motion, demos):
    for p in demos.positions:
        r = motion.rollout(p[0], alpha=np.deg2rad(10), kappa=1.3)
        assert r.hit
        assert abs(r.speed_error) < 0.02
        assert np.linalg.norm(r.hit_position) < 0.02
        # after the hit the resting mode brings the club to rest
        assert np.linalg.norm(r.velocities[-1]) < 0.2 * np.linalg.norm(r.hit_velocity)


def test_rollout_follows_a_ball_moved_mid_swing(motion, demos):
    start = demos.positions[0][0]
    moved = np.array([0.0, 0.05, 0.0])
    r = motion.rollout(start, perturb=[{"t": 0.3, "ball": moved}])
    assert r.hit
    assert np.linalg.norm(r.hit_position - moved) < 0.02
    assert r.events and r.events[0]["t"] == 0.3


@pytest.mark.parametrize("mode", ["flat", "arc"])
def test_resting_mode_is_continuous_at_the_hit_and_stable(motion, mode):
    p, v = np.zeros(3), motion.hitting_velocity(0.2, 1.0)
    np.testing.assert_allclose(motion.resting_velocity(p, p, v, mode), v, atol=1e-12)
    A, rest = motion._rest_system(p, v, mode)
    assert np.linalg.eigvalsh(A + A.T).max() < 0
    if mode == "arc":
        assert rest[2] > 0  # the club ends above the ball's height


def test_bad_inputs(motion, demos):
    with pytest.raises(ValueError, match="kappa"):
        motion.velocity(np.zeros(3), 0.0, 0.0)
    with pytest.raises(ValueError, match="kappa"):
        motion.velocity(np.zeros(3), 0.0, -1.0)
    with pytest.raises(ValueError, match="alpha"):
        motion.velocity(np.zeros(3), np.nan, 1.0)
    with pytest.raises(ValueError, match="NaN"):
        motion.rollout([np.nan, 0, 0])
    with pytest.raises(ValueError, match="resting mode"):
        motion.rollout(demos.positions[0][0], rest_mode="stop")
    # demonstrations that stop at the ball: no hitting motion to learn
    s = np.linspace(0, 1, 20)[:, None]
    stop = Demonstrations([-0.4 * (1 - s) ** 2 * np.array([1.0, 0.2, 0.1])],
                          velocities=[0.8 * (1 - s) * np.array([1.0, 0.2, 0.1])],
                          target=np.zeros(3))
    with pytest.raises(ValueError, match="no hitting motion"):
        HittingMotionLearner().fit(stop)
    with pytest.raises(ValueError, match="3-D"):
        HittingMotionLearner().fit(Demonstrations([np.stack([np.linspace(-1, 0, 9)] * 2, 1)],
                                                  dt=0.1, target=np.zeros(2)))
    with pytest.raises(TypeError, match="StableDS"):
        TargetField("not a model")
    with pytest.raises(ValueError, match="positive"):
        StrengthFactorLearner().fit(np.zeros((3, 3)), np.array([1.0, 0.0, 1.0]))


def test_a_spiralling_model_has_no_target_field():
    from conftest import linear_demos

    A = np.array([[-1.0, -3.0], [3.0, -1.0]])
    d = linear_demos(A, np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.3]]), dt=0.05, steps=40)
    ds = SEDS(1, objective="mse", random_state=0).fit(d).model_
    with pytest.raises(ValueError, match="spirals"):
        TargetField(ds)


def test_rotation_is_about_z():
    R = rotation_z(0.7)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(R @ [0, 0, 1.0], [0, 0, 1.0])


def test_shipped_hitting_demos_are_the_generator_output():
    from seds_casadi.motion.putting_demos import HITTING_DEMOS_FILE, load_hitting_demos

    shipped = load_hitting_demos()
    made = generate_putting_demos(random_state=0)
    assert shipped.n_demos == 7
    for a, b in zip(shipped.positions, made.positions):
        np.testing.assert_allclose(a, b, atol=1e-12)
    for a, b in zip(shipped.velocities, made.velocities):
        np.testing.assert_allclose(a, b, atol=1e-12)
    assert HITTING_DEMOS_FILE.endswith(".npz")


def test_ball_moved_mid_swing_is_hit_along_the_commanded_direction(motion, demos):
    for dy in (0.05, -0.05):
        moved = np.array([0.0, dy, 0.0])
        r = motion.rollout(demos.positions[3][0], perturb=[{"t": 0.25, "ball": moved}])
        assert r.hit and np.linalg.norm(r.hit_position - moved) < 1e-3
        assert r.direction_error_deg < 5.0


def test_compiled_hitting_ds_matches_numpy(motion):
    fast = motion.compiled()
    rng = np.random.default_rng(4)
    for _ in range(10):
        x, a, k = rng.uniform(-0.4, 0.2, 3), rng.uniform(-0.5, 0.5), rng.uniform(0.5, 1.5)
        np.testing.assert_allclose(fast(x, a, k), motion.velocity(x, a, k), rtol=1e-9,
                                   atol=1e-12)
    with pytest.raises(TypeError, match="arguments"):
        fast(np.zeros(3))


def test_motion_save_and_load_round_trip(motion, tmp_path):
    motion.save(tmp_path / "m")
    back = HittingMotion.load(tmp_path / "m")
    X = np.random.default_rng(3).normal(scale=0.2, size=(25, 3))
    np.testing.assert_allclose(back.velocity(X, 0.3, 1.2), motion.velocity(X, 0.3, 1.2),
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(back.hitting_direction, motion.hitting_direction)
    assert back.hitting_speed == motion.hitting_speed
    (tmp_path / "m" / "strength.npz").write_bytes(b"broken")
    with pytest.raises(ValueError, match="not a readable seds_casadi.StrengthFactor file"):
        HittingMotion.load(tmp_path / "m")


def test_an_edited_or_old_strength_file_is_refused(motion, tmp_path):
    """The strength factor's file is guarded like the SEDS model's: an edit that would make
    v* 150x faster, NaN priors, and a file from before the checksum are all refused."""
    from seds_casadi.core.errors import ModelFileError

    motion.save(tmp_path / "m")
    path = tmp_path / "m" / "strength.npz"
    with np.load(path, allow_pickle=False) as f:
        data = {k: f[k] for k in f.files}
    fast = dict(data, means=data["means"] + np.r_[0, 0, 0, np.log(150.0)])
    np.savez(path, **fast)
    with pytest.raises(ModelFileError, match="checksum mismatch"):
        HittingMotion.load(tmp_path / "m")
    np.savez(path, **dict(data, priors=np.full_like(data["priors"], np.nan)))
    with pytest.raises(ModelFileError, match="'priors' holds NaN"):
        HittingMotion.load(tmp_path / "m")
    old = {k: data[k] for k in ("priors", "means", "covariances", "log_range", "approach",
                                "rest_length")}
    np.savez(path, **old)  # the unguarded layout of earlier versions
    with pytest.raises(ModelFileError, match="missing entries.*save it again"):
        HittingMotion.load(tmp_path / "m")


# ---------------------------------------------------------------- lining up with psi* (issue 3)
@pytest.mark.slow
def test_fifty_random_swings_hit_within_one_degree_and_two_percent(motion, demos):
    """Issue 3's acceptance figures on a fixed seed: starts in the demonstrations' start box,
    alpha in [-30, 30] deg, kappa in [0.5, 1.5]."""
    first = np.array([p[0] for p in demos.positions])
    lo, hi = first.min(axis=0), first.max(axis=0)
    rng = np.random.default_rng(2026)
    for _ in range(50):
        a, k = np.deg2rad(rng.uniform(-30, 30)), rng.uniform(0.5, 1.5)
        r = motion.rollout(rotation_z(a) @ rng.uniform(lo, hi), alpha=a, kappa=k)
        assert r.hit
        assert r.direction_error_deg < 1.0
        assert abs(r.speed_error) < 0.02


def test_probe_equals_rollout(motion, demos):
    starts = np.array([p[0] for p in demos.positions[:3]])
    a, k = np.deg2rad(-12.0), 0.8
    hit, err, serr = motion.probe(starts @ rotation_z(a).T, alpha=a, kappa=k)
    for i, s in enumerate(starts):
        r = motion.rollout(rotation_z(a) @ s, alpha=a, kappa=k)
        assert hit[i] and r.hit
        assert err[i] == pytest.approx(r.direction_error_deg, abs=1e-6)
        assert serr[i] == pytest.approx(r.speed_error, abs=1e-9)
    far = np.array([[5.0, 5.0, 5.0]])  # too far to arrive within 0.1 s
    hit, err, _ = motion.probe(far, max_time=0.1)
    assert not hit[0] and np.isnan(err[0])


def test_approach_paths_are_tangent_to_the_arrival_direction():
    u = np.array([1.0, 0.2, 0.0]) / np.hypot(1.0, 0.2)
    P, V = approach_paths(u, 1.2, length=0.05, order=3.0)
    assert len(P) == 16
    for p, v in zip(P, V):
        np.testing.assert_allclose(p[-1], 0.0)
        np.testing.assert_allclose(v[-1], 1.2 * u)
        np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.2)
        a = -(p[:-1] @ u)
        b = np.linalg.norm(p[:-1] - np.outer(p[:-1] @ u, u), axis=1)
        np.testing.assert_allclose(b, b[0] * (a / a[0]) ** 3, rtol=1e-9)  # b = c a^3
        # each velocity is the path's tangent: compare with the chord to a nearby point
        chord = p[1:-1] - p[:-2]
        cosang = np.sum(chord * v[:-2], 1) / np.linalg.norm(chord, axis=1) / 1.2
        assert np.all(cosang > 0.99)
    with pytest.raises(ValueError, match="order > 1"):
        approach_paths(u, 1.0, order=1.0)
    with pytest.raises(ValueError, match="non-zero"):
        approach_paths(np.zeros(3), 1.0)


@pytest.mark.slow
def test_a_badly_lined_up_fit_is_refitted_and_reported(demos):
    # with these demonstrations, SEDS from seed 3 arrives 0.23 deg off at worst and from seed 4
    # 0.003 deg (found by search): asking for 0.1 deg makes the fit try again
    m = HittingMotionLearner(n_components=3, random_state=3,
                             max_direction_error=0.1).fit(demos).motion_
    tries = m.fit_info["tries"]
    assert len(tries) >= 2 and tries[0]["max_direction_error_deg"] > 0.1
    assert tries[m.fit_info["kept"]]["max_direction_error_deg"] <= 0.1
    from seds_casadi.core.errors import ConvergenceWarning

    with pytest.warns(ConvergenceWarning, match="arrives up to"):
        HittingMotionLearner(n_components=3, random_state=3, restarts=1,
                             max_direction_error=0.1).fit(demos)
    with pytest.raises(ValueError, match="restarts"):
        HittingMotionLearner(restarts=0).fit(demos)
    with pytest.raises(ValueError, match="max_direction_error"):
        HittingMotionLearner(max_direction_error=-1.0).fit(demos)


# ---------------------------------------------------------------- one source of truth (issue 12)
@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), log_scale=st.floats(-9.0, 1.0),
       alpha=st.floats(-np.pi, np.pi), kappa=st.floats(0.1, 3.0))
def test_casadi_eq8_eq12_eq14_equal_the_numpy_oracles(motion, seed, log_scale, alpha, kappa):
    """The CasADi expressions, evaluated as the package does, against numpy re-implementations,
    from a hair's breadth off the ball (1e-9 m) to 10 m away."""
    rng = np.random.default_rng(seed)
    X = rng.standard_normal((16, 3)) * 10.0**log_scale
    tf, sf = motion.target_field, motion.strength
    H, F = oracles.target_field(X, tf.ds, tf.hitting_direction)
    np.testing.assert_allclose(tf(X), H, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(tf.velocity(X), F, rtol=1e-9, atol=1e-300)
    v = oracles.strength_factor(X, sf.priors, sf.means, sf.covariances, sf.log_range)
    np.testing.assert_allclose(sf(X), v, rtol=1e-9)
    np.testing.assert_allclose(motion.velocity(X, alpha, kappa),
                               oracles.hitting_ds(X, alpha, kappa, motion), rtol=1e-9, atol=1e-12)
    # one point at a time (the rollouts' path) gives the same numbers
    np.testing.assert_allclose(motion.velocity(X[0], alpha, kappa),
                               oracles.hitting_ds(X[:1], alpha, kappa, motion)[0], rtol=1e-9,
                               atol=1e-12)


def test_target_field_at_the_ball_is_psi_star_in_casadi_and_the_oracle(motion):
    tf = motion.target_field
    X = np.array([[0.0, 0.0, 0.0], [1e-300, 0.0, 0.0]])
    H, _ = oracles.target_field(X, tf.ds, tf.hitting_direction)
    np.testing.assert_array_equal(tf(X), H)
    np.testing.assert_array_equal(tf(X)[0], motion.hitting_direction)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), K=st.integers(1, 4), far=st.floats(0.1, 100.0),
       saturated=st.booleans())
def test_strength_factor_with_its_saturation_equals_the_oracle(seed, K, far, saturated):
    rng = np.random.default_rng(seed)
    priors, means, covs = oracles.random_gmm(rng, K, 4)
    log_range = ((float(means[:, 3].min()) - 0.1, float(means[:, 3].max()) + 0.1) if saturated
                 else (-np.inf, np.inf))
    sf = StrengthFactor(priors, means, covs, log_range)
    X = rng.standard_normal((30, 3)) * far  # far away GMR extrapolates past both ends
    want = oracles.strength_factor(X, priors, means, covs, log_range)
    np.testing.assert_allclose(sf(X), want, rtol=1e-9)
    if saturated:
        lo, hi = log_range
        assert np.all(np.log(sf(X)) < hi + np.log(2) + 1e-12)
        assert np.all(np.log(sf(X)) > lo - np.log(2) - 1e-12)


def test_rotation_sx_is_rotation_z():
    for a in (-3.0, -0.4, 0.0, 1.2, np.pi):
        np.testing.assert_allclose(np.asarray(ca.DM(rotation_z_sx(a))), rotation_z(a),
                                   atol=1e-15)


def test_eq14_in_casadi_is_built_on_eq8_and_eq12(motion):
    """The Function of Eq. 14 is kappa R v h with the Functions of Eq. 8 and Eq. 12 (the same
    expressions, not copies)."""
    rng = np.random.default_rng(11)
    f14, f8, f12 = motion.to_casadi(), motion.target_field.to_casadi(), motion.strength.to_casadi()
    for _ in range(5):
        x, a, k = rng.uniform(-0.4, 0.2, 3), rng.uniform(-1, 1), rng.uniform(0.5, 1.5)
        R = rotation_z(a)
        y = R.T @ x
        want = k * R @ (float(f12(y)) * np.asarray(f8(y)[0]).ravel())
        np.testing.assert_allclose(np.asarray(f14(x, a, k)).ravel(), want, rtol=1e-12,
                                   atol=1e-15)


# ---------------------------------------------------------------- hit detection, perturbations
def test_plane_crossing_one_step_and_many_agree():
    rng = np.random.default_rng(5)
    target, psi = np.array([0.1, -0.2, 0.0]), rotation_z(0.3) @ np.array([1.0, 0.0, 0.0])
    before = target + rng.normal(scale=0.02, size=(200, 3))
    after = before + 0.01 * psi + rng.normal(scale=0.002, size=(200, 3))
    hit, lam, point = plane_crossing(before, after, target, psi, 0.02)
    assert 0 < hit.sum() < 200
    for i in range(200):
        h1, l1, p1 = plane_crossing(before[i], after[i], target, psi, 0.02)
        assert bool(h1) == hit[i]  # the same reading (to rounding: BLAS sums rows its own way)
        assert float(l1) == pytest.approx(lam[i], rel=1e-12, abs=1e-15)
        np.testing.assert_allclose(p1, point[i], rtol=1e-13, atol=1e-16)
        s0, s1 = (before[i] - target) @ psi, (after[i] - target) @ psi
        if hit[i]:  # the crossing point is on the plane, within the radius
            assert s0 < 0 <= s1 and abs((point[i] - target) @ psi) < 1e-15
            assert np.linalg.norm(point[i] - target) <= 0.02
    # a step away from the ball, or past it outside the radius, is no hit
    assert not plane_crossing(target + 0.01 * psi, target + 0.02 * psi, target, psi, 0.02)[0]
    side = target + np.array([0.0, 0.0, 0.5])
    assert not plane_crossing(side - 0.01 * psi, side + 0.01 * psi, target, psi, 0.02)[0]


def test_perturbations_are_handed_out_in_time_order_and_checked():
    ev = Perturbations([{"t": 0.3, "ball": [1, 0, 0]}, {"t": 0.1, "alpha": 0.2}],
                       ("ball", "alpha"))
    assert ev.due(0.0) == []
    assert ev.due(0.1) == [{"t": 0.1, "alpha": 0.2}]
    assert ev.due(0.2) == []
    assert [e["t"] for e in ev.due(1.0)] == [0.3]
    assert [e["t"] for e in ev.applied] == [0.1, 0.3]
    with pytest.raises(ValueError, match="finite time"):
        Perturbations([{"ball": [0, 0, 0]}], ("ball",))
    with pytest.raises(ValueError, match="finite time"):
        Perturbations([{"t": np.nan}], ("ball",))
    with pytest.raises(ValueError, match=r"unknown perturbation key\(s\) \['hole'\].*valid: t, ball"):
        Perturbations([{"t": 0.1, "hole": [1, 0]}], ("ball",))


def test_rollout_refuses_an_unknown_perturbation(motion, demos):
    with pytest.raises(ValueError, match="unknown perturbation"):
        motion.rollout(demos.positions[0][0], perturb=[{"t": 0.1, "wind": [2.4, 0.0]}])


def test_rollout_and_swing_call_params_with_time_ball_and_hole(motion, demos):
    """One callback signature: params(t, ball, hole) -> (alpha [rad], kappa), in the motion's
    rollout as in the robot's swing; a hole moved mid-swing reaches the callback."""
    seen = []

    def params(t, ball, hole):
        seen.append((t, None if hole is None else hole[1]))
        return 0.05, 1.0

    motion.rollout(demos.positions[0][0], params=params, hole=[2.4, 0.0],
                   perturb=[{"t": 0.1, "hole": [2.4, 0.3]}])
    assert seen[0] == (0.0, 0.0) and seen[-1][1] == pytest.approx(0.3)
    assert all(b >= a for (a, _), (b, _) in zip(seen, seen[1:]))


def test_a_kappa_change_mid_swing_takes_effect(motion, demos):
    r = motion.rollout(demos.positions[0][0], perturb=[{"t": 0.1, "kappa": 1.4}])
    assert r.hit and r.commanded_speed == pytest.approx(1.4 * motion.hitting_speed)
    assert abs(r.speed_error) < 0.02


# ---------------------------------------------------------------- scikit-learn convention
def test_strength_factor_learner_follows_scikit_learn(demos):
    X = np.concatenate(demos.positions)
    S = np.concatenate([np.linalg.norm(v, axis=1) for v in demos.velocities])
    keep = S > 1e-3 * S.max()
    X, S = X[keep], S[keep]
    est = StrengthFactorLearner(n_components=2, random_state=0)
    assert est.get_params() == {"n_components": 2, "random_state": 0, "reg_covar": 1e-6}
    twin = clone(est).set_params(n_components=3)
    assert not hasattr(twin, "factor_") and twin.n_components == 3
    est.fit(X, S)
    np.testing.assert_allclose(est.predict(X), StrengthFactorLearner(2, 0).fit(X, S).factor_(X),
                               rtol=1e-12)
    # one way to fit (issue 27): the fitted value has no fit of its own
    assert not hasattr(StrengthFactor, "fit")
    assert twin.fit(X, S).factor_.priors.shape == (3,)
    assert est.factor_.priors.shape == (2,) and est.n_features_in_ == 3
    assert est.score(X, S) > 0.5  # R^2 of the speeds
    with pytest.raises(ValueError, match="n_components"):
        StrengthFactorLearner(n_components=0).fit(X, S)
    with pytest.raises(ValueError, match="one speed per position"):
        StrengthFactorLearner().fit(X, S[:-1])


def test_hitting_motion_learner_follows_scikit_learn(motion, demos):
    est = HittingMotionLearner(n_components=3, random_state=0)
    params = est.get_params()
    assert params["n_components"] == 3 and params["approach_paths"] is True
    assert params["seds_params"] is None and params["restarts"] == 3
    # clone gives an unfitted copy with the same parameters; fitting it gives the same motion as
    # the fixture's learner; the fitted motion has no fit of its own (one way to fit, issue 27)
    assert not hasattr(HittingMotion, "fit")
    twin = clone(est)
    assert not hasattr(twin, "motion_") and twin.get_params() == params
    X = np.random.default_rng(8).normal(scale=0.2, size=(20, 3))
    got = twin.fit(demos).motion_
    np.testing.assert_array_equal(got.velocity(X, 0.2, 1.1), motion.velocity(X, 0.2, 1.1))
    assert twin.fit_info_ == motion.fit_info and twin.n_features_in_ == 3
    # parameters set through set_params take effect in the next fit
    est.set_params(strength_components=1, approach_paths=False, restarts=1,
                   max_direction_error=180.0, rest_length=0.3)
    m = est.fit(demos).motion_
    assert m.strength.priors.shape == (1,)
    assert est.fit_info_["approach_paths"] is False and len(est.fit_info_["tries"]) == 1
    assert m.rest_length == 0.3
    assert not np.allclose(m.target_field.ds.means, motion.target_field.ds.means)
    from seds_casadi.core.errors import ConvergenceWarning

    with pytest.warns(ConvergenceWarning, match="after 1 iterations"):  # reaches SEDS
        est.set_params(seds_params={"max_iter": 1}).fit(demos)
    assert est.motion_.target_field.ds.fit_info["iterations"] == 1
    # random_state may be a Generator: the first seed is drawn from it, restarts follow it
    with pytest.warns(ConvergenceWarning):
        est.set_params(random_state=np.random.default_rng(4), restarts=2).fit(demos)
    seeds = [t["seed"] for t in est.fit_info_["tries"]]
    assert seeds[0] == int(np.random.default_rng(4).integers(2**31 - 1))
    # __init__ only stores; fit validates
    bad = HittingMotionLearner(restarts=0)
    with pytest.raises(ValueError, match="restarts"):
        bad.fit(demos)
    with pytest.raises(TypeError, match="seds_params"):
        HittingMotionLearner(seds_params=[("omega_upper", 3.0)]).fit(demos)
