"""Real IPOPT solves: constraint satisfaction, stability, accuracy, persistence, bad input."""

import warnings

import casadi as ca
import numpy as np
import pytest

from seds_casadi import (
    SEDS,
    ConvergenceWarning,
    Demonstrations,
    ModelFileError,
    SolverError,
    StabilityError,
    StableDS,
    certify,
)
from seds_casadi.core.datasets import load_lasa
from seds_casadi.core.metrics import direction_error
from seds_casadi.core.settings import OBJECTIVES


def _assert_certified(model: StableDS):
    d = model.n_dims
    cert = certify(model.priors, model.means, model.covariances, model.target)
    assert cert["max_eig_sym_A"] < 0
    assert cert["min_eig_cov"] > 0
    for k in range(model.n_components):
        assert np.linalg.eigvalsh(model.A[k] + model.A[k].T).max() < 0          # (b)
        assert np.linalg.eigvalsh(model.covariances[k]).min() > 0               # (c)
        A = model.covariances[k, d:, :d] @ np.linalg.inv(model.covariances[k, :d, :d])
        np.testing.assert_allclose(A, model.A[k], rtol=1e-7, atol=1e-9 * np.abs(A).max())
        resid = model.means[k, d:] + A @ (model.target - model.means[k, :d])      # (a)
        assert np.linalg.norm(resid) < 1e-8 * max(1.0, np.linalg.norm(model.means[k, d:]))
    assert np.all((model.priors > 0) & (model.priors <= 1))                      # (d)
    assert np.sum(model.priors) == pytest.approx(1.0, abs=1e-12)                 # (e)
    np.testing.assert_allclose(model.predict(model.target), 0.0, atol=1e-10)     # f(x*) = 0


@pytest.fixture(scope="module")
def fitted(spiral_demos, curved_demos_3d):
    """One fit per (data set, objective), shared by the tests of this module."""
    lasa = load_lasa("Angle", n_samples=25)
    out = {}
    for name, demos in (("spiral", spiral_demos), ("curved3d", curved_demos_3d), ("angle", lasa)):
        for obj in OBJECTIVES:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ConvergenceWarning)
                out[name, obj] = SEDS(2, objective=obj, random_state=0).fit(demos).model_
    return out


@pytest.mark.parametrize("data", ["spiral", "curved3d", "angle"])
@pytest.mark.parametrize("objective", OBJECTIVES)
def test_constraints_hold_after_fitting(fitted, data, objective):
    model = fitted[data, objective]
    _assert_certified(model)
    info = model.fit_info
    for key in ("status", "iterations", "objective", "seconds"):
        assert key in info
    assert info["iterations"] > 0
    # IPOPT does not end worse than the k-means + EM start (up to its own tolerance)
    assert info["objective"] <= info["objective_initial"] + 1e-6 * max(1.0, abs(info["objective"]))


@pytest.mark.parametrize("data", ["spiral", "curved3d", "angle"])
def test_rollouts_from_far_away_converge_to_the_target(fitted, data):
    model = fitted[data, "direction"]
    rng = np.random.default_rng(11)
    d = model.n_dims
    scale = 50 * max(1.0, float(np.abs(model.means[:, :d] - model.target).max()))
    starts = model.target + scale * rng.standard_normal((12, d))
    # f grows at most linearly, so a step small against 1/||A|| is stable for RK4 (and against
    # the taper's rate for a strength model, whose speed far away is bounded)
    dt = min(0.5 / max(np.linalg.norm(A, 2) for A in model.A), 1.0 / model.stiffness())
    trajs = model.rollout(starts, dt=dt, max_steps=200000, tol=1e-3 * scale)
    for tr in trajs:
        assert np.all(np.isfinite(tr))
        assert np.linalg.norm(tr[-1] - model.target) < 1e-3 * scale


def test_known_linear_system_is_recovered(spiral_demos):
    """Data from xdot = A x with A stable: a one-Gaussian MSE fit recovers A."""
    model = SEDS(1, objective="mse", random_state=0).fit(spiral_demos).model_
    np.testing.assert_allclose(model.A[0], [[-1.0, -2.0], [2.0, -1.0]], atol=1e-3)
    assert model.fit_info["objective"] < 1e-6


def test_direction_objective_fits_directions_better_than_mse():
    demos = load_lasa("Angle", n_samples=40)
    X, V = np.concatenate(demos.positions), np.concatenate(demos.velocities)
    errs = {}
    for obj in ("direction", "mse"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            m = SEDS(3, objective=obj, random_state=0).fit(demos).model_
        errs[obj] = direction_error(m.predict(X), V)
    assert errs["direction"] < errs["mse"]
    assert errs["direction"] < 0.05


def test_fit_is_deterministic_for_a_seed(spiral_demos):
    a = SEDS(2, random_state=3).fit(spiral_demos).model_
    b = SEDS(2, random_state=3).fit(spiral_demos).model_
    np.testing.assert_array_equal(a.means, b.means)
    np.testing.assert_array_equal(a.covariances, b.covariances)


def test_seven_dimensional_joint_space():
    rng = np.random.default_rng(0)
    A = -np.eye(7) + 0.3 * (lambda M: M - M.T)(rng.standard_normal((7, 7)))
    from conftest import linear_demos

    demos = linear_demos(A, rng.standard_normal((2, 7)), dt=0.1, steps=30)
    model = SEDS(1, objective="direction", random_state=0, compile=False).fit(demos).model_
    _assert_certified(model)
    X, V, _, _ = demos.stacked()
    assert direction_error(model.predict(X + demos.target), V) < 1e-3


def test_predict_is_vectorised_finite_everywhere_and_matches_casadi(fitted):
    model = fitted["spiral", "likelihood"]
    X = np.random.default_rng(0).standard_normal((30, 2)) * np.logspace(-3, 4, 30)[:, None]
    F = model.predict(X)
    assert F.shape == (30, 2) and np.all(np.isfinite(F))
    np.testing.assert_allclose(model.predict(X[3]), F[3])
    f = model.to_casadi()
    assert isinstance(f, ca.Function)
    for x, fx in zip(X, F):
        np.testing.assert_allclose(np.asarray(f(x)).ravel(), fx, rtol=1e-9, atol=1e-9)


def test_save_load_round_trip_is_exact(tmp_path, fitted):
    model = fitted["curved3d", "direction"]
    path = tmp_path / "model.npz"
    model.save(path)
    back = StableDS.load(path)
    for attr in ("priors", "means", "covariances", "target", "A"):
        np.testing.assert_array_equal(getattr(back, attr), getattr(model, attr))
    assert back.fit_info["status"] == model.fit_info["status"]
    with np.load(path, allow_pickle=False) as f:  # no pickled objects inside
        assert "checksum" in f.files


def test_tampered_corrupt_and_unstable_files_are_refused(tmp_path, fitted):
    model = fitted["spiral", "mse"]
    path = tmp_path / "m.npz"
    model.save(path)
    with np.load(path, allow_pickle=False) as f:
        data = {k: f[k] for k in f.files}
    # tampered: a mean moved without updating the checksum
    bad = dict(data)
    bad["means"] = data["means"] + 0.1
    np.savez(tmp_path / "tampered.npz", **bad)
    with pytest.raises(ModelFileError, match="checksum"):
        StableDS.load(tmp_path / "tampered.npz")
    # truncated file
    raw = path.read_bytes()
    (tmp_path / "trunc.npz").write_bytes(raw[: len(raw) // 2])
    with pytest.raises(ModelFileError):
        StableDS.load(tmp_path / "trunc.npz")
    # missing entry
    partial = {k: v for k, v in data.items() if k != "covariances"}
    np.savez(tmp_path / "partial.npz", **partial)
    with pytest.raises(ModelFileError, match="missing"):
        StableDS.load(tmp_path / "partial.npz")
    # unstable but with a valid checksum (recomputed as the writer does): re-certification
    # refuses it
    from seds_casadi.core.model_files import checksum

    means, covs = data["means"].copy(), data["covariances"].copy()
    d = 2
    covs[0, d:, :d] *= -1  # flips A_0 to an unstable matrix
    covs[0, :d, d:] *= -1
    means[0, d:] *= -1
    info = str(data["fit_info"])
    bad = dict(data, covariances=covs, means=means,
               checksum=np.array(checksum([data["priors"], means, covs, data["target"]], info)))
    np.savez(tmp_path / "unstable.npz", **bad)
    with pytest.raises(StabilityError, match=r"\(b\)"):
        StableDS.load(tmp_path / "unstable.npz")


def test_certificate_names_each_violated_constraint():
    d = 2
    Sx = np.eye(d)
    A = -np.eye(d)
    cov = np.block([[Sx, (A @ Sx).T], [A @ Sx, A @ Sx @ A.T + 0.1 * np.eye(d)]])
    target = np.zeros(d)
    good_means = np.array([[1.0, 0.0, -1.0, 0.0]])
    StableDS([1.0], good_means, [cov], target)  # passes
    with pytest.raises(StabilityError, match=r"\(e\)"):
        StableDS([0.5], good_means, [cov], target)
    with pytest.raises(StabilityError, match=r"\(d\)"):
        StableDS([-0.5, 1.5], np.repeat(good_means, 2, 0), [cov, cov], target)
    with pytest.raises(StabilityError, match=r"\(a\)"):
        StableDS([1.0], np.array([[1.0, 0.0, 5.0, 0.0]]), [cov], target)
    notpd = cov.copy()
    notpd[d:, d:] = 0.0
    with pytest.raises(StabilityError, match=r"\(c\)"):
        StableDS([1.0], good_means, [notpd], target)
    with pytest.raises(ValueError, match="inconsistent shapes"):
        StableDS([1.0], good_means[:, :3], [cov], target)


def test_iteration_limit_warns_or_raises(spiral_demos):
    with pytest.warns(ConvergenceWarning, match="without converging"):
        m = SEDS(2, objective="mse", random_state=0, max_iter=2).fit(spiral_demos).model_
    _assert_certified(m)
    assert m.fit_info["success"] is False
    with pytest.raises(SolverError, match="Maximum_Iterations_Exceeded"):
        SEDS(2, objective="mse", random_state=0, max_iter=2,
             require_convergence=True).fit(spiral_demos)


@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        (dict(n_components=0), ValueError,
         r"'n_components' parameter of SEDS must be an int in the range \[1, inf\), a str "
         r"among \{'auto', 'bic'\} or a sequence of positive ints .*Got 0"),
        (dict(n_components=2.5), TypeError, "'n_components' parameter of SEDS must be an int"),
        (dict(n_components=2, objective="speed"), ValueError,
         "'objective' parameter of SEDS must be a str among {'direction', 'mse', 'likelihood', "
         "'auto'}"),
        (dict(n_components=2, hessian="bfgs"), ValueError,
         "'hessian' parameter of SEDS must be a str among {'auto', 'exact', 'limited-memory'}"),
        (dict(n_components=2, omega_lower=0.0), ValueError,
         r"'omega_lower' parameter of SEDS must be a float in the range \(0.0, inf\)"),
    ],
)
def test_bad_settings_are_refused_by_fit(kwargs, exc, match, spiral_demos):
    learner = SEDS(**kwargs)  # scikit-learn convention: __init__ only stores
    assert learner.get_params()["n_components"] == kwargs["n_components"]
    with pytest.raises(exc, match=match):
        learner.fit(spiral_demos)


def test_bad_data_for_fit(spiral_demos):
    with pytest.raises(TypeError, match="Demonstrations"):
        SEDS(2).fit(np.zeros((10, 2)))
    with pytest.raises(ValueError, match="one velocity per position"):
        SEDS(2).fit(np.zeros((10, 2)), np.zeros((9, 2)))
    tiny = Demonstrations([np.stack([np.linspace(1, 0, 5), np.zeros(5)], 1)], dt=0.1)
    with pytest.raises(ValueError, match="too few"):
        SEDS(8).fit(tiny)


def test_rollout_and_predict_bad_input(fitted):
    model = fitted["spiral", "mse"]
    with pytest.raises(ValueError, match="NaN"):
        model.predict([np.nan, 0.0])
    with pytest.raises(ValueError, match="shape"):
        model.predict(np.zeros((3, 5)))
    with pytest.raises(ValueError, match="dt must be positive"):
        model.rollout([1.0, 1.0], dt=0.0)


def test_approach_constraint_holds_after_fitting(curved_demos_3d):
    """The optional arrival constraint: u is an eigenvector of J = sum_k h_k(x*) A_k, and the
    symmetric part of J across u is at least `ratio` times faster than the rate along u."""
    from seds_casadi.core.gmm import responsibilities

    u = np.array([1.0, -0.4, 0.2])
    u /= np.linalg.norm(u)
    model = SEDS(2, random_state=0, approach_direction=u,
                 approach_ratio=3.0).fit(curved_demos_3d).model_
    _assert_certified(model)
    # feasible: on some CPUs the exact-Hessian solve stalls 4e-5 outside the constraint and
    # the fit is done again with L-BFGS (fit_info["feasibility_pass"] records the first try)
    assert model.fit_info["constraint_violation"] < 1e-8
    h = responsibilities(model.target[None], model.priors, model.means[:, :3],
                         model.covariances[:, :3, :3])[0]
    J = np.einsum("k,kij->ij", h, model.A)
    lam = -u @ J @ u
    assert lam > 0
    np.testing.assert_allclose(J @ u, -lam * u, atol=1e-6 * np.abs(J).max())
    Q = np.linalg.svd(np.eye(3) - np.outer(u, u))[0][:, :2]
    M = Q.T @ J @ Q
    assert np.linalg.eigvalsh(0.5 * (M + M.T)).max() <= -3.0 * lam * (1 - 1e-6)
    with pytest.raises(ValueError, match="approach_ratio"):
        SEDS(2, approach_direction=u, approach_ratio=0.5).fit(curved_demos_3d)
    with pytest.raises(ValueError, match="approach_direction"):
        SEDS(2, approach_direction=[0.0, 0.0, 0.0]).fit(curved_demos_3d)
    with pytest.raises(ValueError, match="entries"):
        SEDS(2, approach_direction=[1.0, 0.0]).fit(curved_demos_3d)


def test_predict_is_eq5_of_the_joint_gmm_checked_against_a_numpy_oracle(fitted):
    """StableDS.predict (the CasADi expression, cancellation-free form) equals the general form
    of Eq. 5 computed in numpy from the joint GMM, far from and close to the target; with a
    strength factor (the direction objective's default), v(x) rho(x) f(x) / ||f(x)||; and the
    gains' velocity is Eq. 5 in every case."""
    from oracles import seds_velocity, strength_model_velocity

    for (name, obj), model in fitted.items():
        assert (model.strength is not None) == (obj == "direction"), (name, obj)
        rng = np.random.default_rng(0)
        X = model.target + rng.standard_normal((50, model.n_dims)) * np.r_[1e-6, 1.0, 10.0][
            rng.integers(0, 3, 50)][:, None]
        ref = strength_model_velocity(X, model)
        np.testing.assert_allclose(model.predict(X), ref, rtol=1e-6,
                                   atol=1e-9 * np.abs(ref).max(), err_msg=f"{name} {obj}")
        x = ca.SX.sym("x", model.n_dims)
        gains = ca.Function("g", [x], [model.gains_velocity_sx(x)])
        G = np.array([np.asarray(gains(p)).ravel() for p in X])
        F = seds_velocity(X, model.priors, model.means, model.covariances)
        np.testing.assert_allclose(G, F, rtol=1e-6, atol=1e-9 * np.abs(F).max())


def test_rollout_reports_whether_it_reached_the_target(fitted):
    model = fitted["spiral", "mse"]
    starts = np.array([[2.0, 0.5], [1.5, 1.8]])
    paths, info = model.rollout(starts, dt=0.05, return_info=True)
    tol = 1e-3 * np.linalg.norm(starts - model.target, axis=1).max()  # the default
    assert info["converged"].all() and np.all(info["final_distance"] < tol)
    assert [len(p) - 1 for p in paths] == info["steps"].tolist()
    with pytest.warns(ConvergenceWarning, match=r"2 of 2 rollout\(s\) did not reach the target"):
        short, info = model.rollout(starts, dt=0.05, max_steps=3, return_info=True)
    assert not info["converged"].any() and info["steps"].tolist() == [3, 3]
    assert np.all(info["final_distance"] > 0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model.rollout(starts, dt=0.05, max_steps=3, warn=False)  # asked to be quiet


@pytest.mark.filterwarnings("ignore:IPOPT stopped without converging")
def test_demonstrations_moving_away_from_the_target_are_refused_before_solving(spiral_demos):
    reversed_demos = Demonstrations([p[::-1] for p in spiral_demos.positions], dt=0.05,
                                    target=spiral_demos.target)
    with pytest.raises(ValueError, match="run away from the target.*reversed in time"):
        SEDS(2, objective="mse").fit(reversed_demos)
    # samples without order: refused when the velocities clearly point away (radial outflow)
    Xs, _, _, _ = spiral_demos.stacked()
    with pytest.raises(ValueError, match="point away from the target on average"):
        SEDS(2, objective="mse").fit(Xs, Xs.copy())
    # the spiral's own velocities turn by 63 deg: reversed, they point away only mildly
    Xs, Xd, _, _ = spiral_demos.stacked()
    with pytest.warns(ConvergenceWarning, match="point away from the target on average"):
        SEDS(1, objective="mse", random_state=0, max_iter=5).fit(Xs, -Xd)


def test_demonstrations_that_end_far_from_the_target_give_a_warning(spiral_demos):
    # the first part of each spiral, with the target where the full spiral ends
    half = Demonstrations([p[:8] for p in spiral_demos.positions],
                          velocities=[v[:8] for v in spiral_demos.velocities],
                          target=spiral_demos.target)
    with pytest.warns(ConvergenceWarning, match="end more than half their start distance"):
        SEDS(1, objective="mse", random_state=0).fit(half)



@pytest.mark.slow
def test_a_many_component_fit_with_thin_components_is_certified():
    """K = 15 on smooth 3-D demonstrations gives components with ill-conditioned Sigma_x; the
    model still satisfies Eq. 10a to the certificate's 1e-8 (it once failed with 5.8e-8)."""
    rng = np.random.default_rng(11)
    pos = []
    for _ in range(4):
        t = np.linspace(0, 2.0, 120)
        s = 0.5 - 0.5 * np.cos(np.pi * t / 2.0)
        start = np.array([0.4, -0.2, 0.3]) + 0.05 * rng.standard_normal(3)
        pos.append(np.round(start[None] * (1 - s[:, None])
                            + 0.15 * np.sin(np.pi * s)[:, None] * np.array([0, 1, 0.5]), 6))
    demos = Demonstrations(pos, dt=2.0 / 119)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        model = SEDS(15, objective="direction", random_state=0).fit(demos).model_
    assert model.fit_info["hessian"] == "limited-memory"  # 284 parameters: "auto" chose L-BFGS
    certify(model.priors, model.means, model.covariances, model.target)  # (a) to 1e-8
    d = model.n_dims
    conds = [np.linalg.cond(c[:d, :d]) for c in model.covariances]
    assert max(conds) > 1e6  # the case this test is about: thin components
    for k in range(model.n_components):
        assert np.linalg.eigvalsh(model.A[k] + model.A[k].T).max() < 0          # (b)
        assert np.linalg.eigvalsh(model.covariances[k]).min() > 0               # (c)
    assert np.all(model.priors > 0) and np.sum(model.priors) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(model.predict(model.target), 0.0, atol=1e-9)     # f(x*) = 0


@pytest.mark.slow
@pytest.mark.parametrize("shape", ["CShape", "Sshape"])
def test_direction_objective_moves_at_the_demonstrated_speeds(shape):
    """Issue 13: Eq. 9 fixes only directions; the returned model is calibrated so that its speed
    along the demonstrations is the demonstrated one at the median sample (the least-squares
    factor gave 0.02x on CShape), and its reproductions reach the target."""
    from seds_casadi.core import load_lasa

    demos = load_lasa(shape, n_samples=100)
    ratios = {}
    for how in ("median", "least-squares"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m = SEDS(5, objective="direction", random_state=0, speed_calibration=how).fit(demos).model_
        X, V = np.concatenate(demos.positions), np.concatenate(demos.velocities)
        nf, nv = np.linalg.norm(m.predict(X), axis=1), np.linalg.norm(V, axis=1)
        ok = nv > 0
        ratios[how] = float(np.median(nf[ok] / nv[ok]))
        if how == "median":
            _, info = m.rollout(np.stack([p[0] for p in demos.positions]), dt=0.02,
                                max_steps=3000, tol=0.01 * np.ptp(X, axis=0).max(),
                                return_info=True, warn=False)
            assert info["converged"].all()
    assert 0.8 <= ratios["median"] <= 1.25
    assert ratios["least-squares"] < 0.8  # the former calibration, for contrast


def test_predict_is_finite_and_scales_linearly_far_from_the_data(fitted):
    """Issue 18 class 7: NaN at 1e200 before (inf - inf in the Gaussians' exponents). Far away
    the weights depend only on the direction, so f grows linearly with the distance."""
    model = fitted["angle", "mse"]
    u = np.array([0.6, -0.8])
    ref = model.predict(model.target + 1e8 * u) / 1e8
    for s in (1e20, 1e100, 1e200, 1e300):
        f = model.predict(model.target + s * u)
        assert np.all(np.isfinite(f))
        np.testing.assert_allclose(f / s, ref, rtol=1e-6)
    x = ca.SX.sym("x", 2)
    J = ca.Function("J", [x], [ca.jacobian(model.velocity_sx(x), x)])(model.target)
    assert np.all(np.isfinite(np.asarray(J)))


def test_rollout_warns_when_its_step_cannot_follow_the_stiffest_component(fitted):
    model = fitted["angle", "mse"]
    rate = model.stiffness()
    x0 = model.target + np.array([1.0, 0.5])
    with pytest.warns(ConvergenceWarning, match="stiffest component"):
        model.rollout(x0, dt=2.5 / rate, method="euler", max_steps=5)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConvergenceWarning)
        model.rollout(x0, dt=1.0 / rate, method="euler", max_steps=100000)


def test_solver_options_reach_ipopt_and_bad_ones_are_refused():
    demos = load_lasa("Angle", n_samples=15)
    # an option that shows in the result: IPOPT's own iteration limit
    with pytest.warns(ConvergenceWarning, match="without converging"):
        m = SEDS(2, objective="direction", random_state=0,
                 solver_options={"max_iter": 3}).fit(demos).model_
    assert m.fit_info["iterations"] <= 3 and m.fit_info["solver_options"] == {"max_iter": 3}
    _assert_certified(m)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        m = SEDS(2, random_state=0, objective="mse",
                 solver_options={"ipopt.mu_strategy": "adaptive"}).fit(demos).model_
    _assert_certified(m)
    assert m.fit_info["solver_options"] == {"ipopt.mu_strategy": "adaptive"}
    with pytest.raises(ValueError, match="no_such_option"):
        SEDS(2, solver_options={"no_such_option": 1}).fit(demos)
    with pytest.raises(ValueError, match="refused"):
        SEDS(2, solver_options={"mu_strategy": "fastest"}).fit(demos)
    for bad in ("mu_strategy=adaptive", {1: 2}, {"tol": None}, {"tol": True}):
        with pytest.raises(TypeError, match="solver_options"):
            SEDS(2, solver_options=bad).fit(demos)


def test_a_too_coarse_rollout_step_says_what_to_change(spiral_demos):
    """The step warning names method='rk4' only to a user who is not already using it."""
    from seds_casadi import ConvergenceWarning

    model = SEDS(2, objective="direction", random_state=0).fit(spiral_demos).model_
    dt = 10.0 / model.stiffness()
    start = spiral_demos.positions[0][0]
    for method, names_rk4 in (("rk4", False), ("euler", True)):
        with pytest.warns(ConvergenceWarning, match="cannot follow") as rec:
            model.rollout(start, dt=dt, max_steps=5, method=method, warn=True)
        text = " ".join(str(w.message) for w in rec)
        assert ("method='rk4'" in text) is names_rk4
