"""Issue 14: SEDS with a learned Lyapunov matrix P, the paper's constrained form, user constraints.

Known answers (a linear system that only a non-identity P certifies), the generalised
certificate against an independent eigenvalue check, the parametrization against the numpy
oracle, tampered files, every constraint of Eq. 10 on the constrained form's result, and the
user's own constraints honoured.
"""

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oracles import linear_flow_demos
from oracles import responsibilities as responsibilities_oracle
from oracles import seds_objective as objective_numpy
from oracles import unpack as unpack_oracle

from seds_casadi import SEDS, Demonstrations, StableDS
from seds_casadi.core.errors import ModelFileError, StabilityError
from seds_casadi.core.lyapunov import estimate_lyapunov
from seds_casadi.core.model_files import checksum
from seds_casadi.core.objectives import SumKernels
from seds_casadi.core.parametrization import (
    MINOR_FLOOR,
    Layout,
    stability_constraints,
    unpack_casadi,
    unpack_numpy,
)
from seds_casadi.core.stable_ds import certify

MARGIN = 1e-3
#: stable (eigenvalues -1, -3) but A + A^T is indefinite: no SEDS (P = I) model is exact
A_TRUE = np.array([[-1.0, 10.0], [0.0, -3.0]])


def _linear_demos(A=A_TRUE, n=4, T=6.0, dt=0.02, seed=0) -> Demonstrations:
    return linear_flow_demos(A, n=n, T=T, dt=dt, seed=seed)


def _joint_model(A, mu, Sx, Q=None):
    """Joint GMM arrays of a one-component linear system (target at the origin)."""
    d = len(mu)
    Q = 1e-2 * np.eye(d) if Q is None else Q
    cov = np.zeros((1, 2 * d, 2 * d))
    cov[0, :d, :d] = Sx
    cov[0, d:, :d] = A @ Sx
    cov[0, :d, d:] = (A @ Sx).T
    cov[0, d:, d:] = A @ Sx @ A.T + Q
    means = np.r_[mu, A @ mu][None]
    return np.ones(1), means, cov


# ------------------------------------------------------------------ parametrization
@settings(max_examples=40, deadline=None)
@given(st.integers(1, 4), st.integers(1, 5), st.integers(0, 2**31 - 1))
def test_learned_p_parametrization_is_stable_for_every_theta(K, d, seed):
    """A_k^T P + P A_k <= -2 m I and P > 0 with trace d, for any theta; numpy oracle agrees."""
    layout = Layout(K, d, with_noise=False, lyapunov="learned")
    theta = 1.5 * np.random.default_rng(seed).standard_normal(layout.size)
    p = unpack_numpy(theta, layout, MARGIN)
    ref = unpack_oracle(theta, layout, MARGIN)
    for key in ("priors", "mu", "Sx", "P"):
        np.testing.assert_allclose(p[key], ref[key], rtol=1e-8, atol=1e-10)
    # A_k = P^-1 S_k: the two solves differ by rounding amplified by cond(P), which a random
    # theta can make 1e9 (seed 713180 for K = 1, d = 5)
    rtol_a = max(1e-8, 1e-15 * np.linalg.cond(ref["P"]))
    np.testing.assert_allclose(p["A"], ref["A"], rtol=rtol_a, atol=1e-10)
    P = p["P"]
    assert np.trace(P) == pytest.approx(d)
    assert np.linalg.eigvalsh(P).min() > 0
    for k in range(K):
        M = p["A"][k].T @ P + P @ p["A"][k]
        assert np.linalg.eigvalsh(M).max() <= -2 * MARGIN * (1 - 1e-6)


@pytest.mark.parametrize("objective", ["direction", "mse", "likelihood"])
def test_learned_p_objective_equals_numpy_reference(objective):
    layout = Layout(2, 2, with_noise=objective == "likelihood", lyapunov="learned")
    rng = np.random.default_rng(3)
    X = rng.standard_normal((30, 2))
    Xd = -X @ np.array([[1.0, -2.0], [0.5, 1.0]]).T + 0.1 * rng.standard_normal((30, 2))
    w = np.linspace(1, 2, 30) if objective == "direction" else np.ones(30)
    speed = np.linalg.norm(Xd, axis=1)
    coef = w / speed if objective == "direction" else np.ones(30)
    k = SumKernels(layout, objective, MARGIN, X, Xd, coef, float(w.sum()), compile=False)
    for _ in range(3):
        theta = 0.5 * rng.standard_normal(layout.size)
        ref = objective_numpy(theta, layout, X, Xd, w, objective, MARGIN)
        assert k.value(theta) == pytest.approx(ref, rel=1e-10, abs=1e-12)


def test_constrained_objective_is_eq5_as_written():
    """Constrained form: f(x) = sum_k h^k (mu_xdot^k + A_k (x - mu_x^k)), against numpy."""
    layout = Layout(2, 2, with_noise=False, formulation="constrained")
    rng = np.random.default_rng(4)
    X = rng.standard_normal((25, 2))
    Xd = rng.standard_normal((25, 2))
    k = SumKernels(layout, "mse", MARGIN, X, Xd, np.ones(25), 25.0, compile=False)
    theta = 0.4 * rng.standard_normal(layout.size)
    for kk in range(2):  # raw priors must be positive
        s = layout.slices(kk)
        theta[s["pi"]] = [0.3, 0.6][kk]
    th = ca.SX.sym("t", layout.size)
    p = unpack_casadi(th, layout, MARGIN)
    ev = ca.Function("e", [th], [*p["mu"], *p["mud"], *p["A"], *[L @ L.T for L in p["L"]]])
    vals = [np.asarray(v) for v in ev(theta)]
    mu, mud, A, Sx = vals[0:2], vals[2:4], vals[4:6], vals[6:8]
    pri = np.array([0.3, 0.6])
    h = responsibilities_oracle(X, pri / pri.sum(), np.hstack(mu).T, np.stack(Sx))
    # the raw priors enter the log-likelihood unnormalised; the posterior normalises them away
    F = sum(h[:, [j]] * (mud[j].T + (X - mu[j].T) @ A[j].T) for j in range(2))
    ref = float(np.mean(np.sum((F - Xd) ** 2, axis=1)))
    assert k.value(theta) == pytest.approx(ref, rel=1e-10)


# ------------------------------------------------------------------ the certificate
@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_generalised_certificate_against_an_independent_eigenvalue_check(seed):
    rng = np.random.default_rng(seed)
    d = int(rng.integers(2, 4))
    A = rng.standard_normal((d, d)) * 2 - np.eye(d)
    R = rng.standard_normal((d, d))
    P = R @ R.T + 0.1 * np.eye(d)
    mu = rng.standard_normal(d)
    priors, means, cov = _joint_model(A, mu, np.eye(d))
    # independent: eigenvalues of the symmetric matrix from its characteristic polynomial
    M = A.T @ P + P @ A
    stable = np.roots(np.poly(M)).real.max() < 0
    if stable:
        cert = certify(priors, means, cov, np.zeros(d), lyapunov=P)
        assert cert["max_eig_lyapunov"] < 0
    else:
        with pytest.raises(StabilityError, match="A_k\\^T P \\+ P A_k"):
            certify(priors, means, cov, np.zeros(d), lyapunov=P)


def test_certificate_refuses_a_p_that_is_not_positive_definite():
    priors, means, cov = _joint_model(-np.eye(2), np.ones(2), np.eye(2))
    with pytest.raises(StabilityError, match="positive definite"):
        certify(priors, means, cov, np.zeros(2), lyapunov=np.diag([1.0, -1.0]))
    with pytest.raises(StabilityError, match="shape"):
        certify(priors, means, cov, np.zeros(2), lyapunov=np.eye(3))


def test_estimate_lyapunov_finds_a_p_that_the_linear_system_decreases():
    demos = _linear_demos()
    X, Xd, _, _ = demos.stacked()
    P = estimate_lyapunov(X, Xd)
    assert np.trace(P) == pytest.approx(2.0)
    frac_up_I = np.mean(np.sum(X * Xd, axis=1) > 0)
    frac_up_P = np.mean(np.einsum("ni,ij,nj->n", X, P, Xd) > 0)
    assert frac_up_I > 0.05  # the identity is violated on part of the data
    assert frac_up_P < 0.5 * frac_up_I


# ------------------------------------------------------------------ known answer: the learner
@pytest.fixture(scope="module")
def linear_fits():
    demos = _linear_demos()
    plain = SEDS(1, objective="mse", random_state=0).fit(demos).model_
    learned = SEDS(1, objective="mse", random_state=0, lyapunov="learned").fit(demos).model_
    return demos, plain, learned


def test_learned_p_fits_what_seds_cannot_and_is_certified(linear_fits):
    demos, plain, learned = linear_fits
    X, Xd, _, _ = demos.stacked()
    err_plain = np.sqrt(np.mean((plain.predict(X) - Xd) ** 2))
    err_learned = np.sqrt(np.mean((learned.predict(X) - Xd) ** 2))
    assert err_learned < 0.05 * np.sqrt(np.mean(Xd**2))
    assert err_learned < 0.2 * err_plain
    np.testing.assert_allclose(learned.A[0], A_TRUE, atol=0.15)
    P = learned.lyapunov_matrix
    assert not np.allclose(P, np.eye(2), atol=0.1)
    assert np.linalg.eigvalsh(learned.A[0].T @ P + P @ learned.A[0]).max() < 0
    assert learned.certificate["max_eig_sym_A"] > 0  # P = I would not certify it
    assert learned.fit_info["lyapunov"] == "learned"
    np.testing.assert_allclose(plain.lyapunov_matrix, np.eye(2))


def test_learned_model_converges_and_its_target_field_is_unit(linear_fits):
    _, _, learned = linear_fits
    from seds_casadi.motion.target_field import TargetField

    path, info = learned.rollout(np.array([0.8, -0.6]), dt=0.01, return_info=True)
    assert info["converged"].all()
    tf = TargetField(learned)
    H = tf(np.random.default_rng(0).uniform(-1, 1, (20, 2)))
    np.testing.assert_allclose(np.linalg.norm(H, axis=1), 1.0, atol=1e-9)


def test_saved_learned_model_keeps_p_and_refuses_a_tampered_one(linear_fits, tmp_path):
    _, _, learned = linear_fits
    f = tmp_path / "m.npz"
    learned.save(f)
    back = StableDS.load(f)
    np.testing.assert_array_equal(back.lyapunov_matrix, learned.lyapunov_matrix)
    with np.load(f, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}
    assert int(data["version"]) == 2
    # P edited, checksum left: refused as edited
    bad = dict(data, lyapunov=np.eye(2))
    np.savez(tmp_path / "edited.npz", **bad)
    with pytest.raises(ModelFileError, match="checksum"):
        StableDS.load(tmp_path / "edited.npz")
    # P edited and the checksum recomputed: the certificate refuses it
    names = ["priors", "means", "covariances", "target", "lyapunov"]
    bad["checksum"] = np.array(checksum([bad[k] for k in names], str(bad["fit_info"])))
    np.savez(tmp_path / "forged.npz", **bad)
    with pytest.raises(StabilityError):
        StableDS.load(tmp_path / "forged.npz")


def test_identity_models_still_write_version_1(tmp_path, linear_fits):
    _, plain, _ = linear_fits
    plain.save(tmp_path / "p.npz")
    with np.load(tmp_path / "p.npz", allow_pickle=False) as z:
        assert int(z["version"]) == 1 and "lyapunov" not in z.files
    np.testing.assert_allclose(StableDS.load(tmp_path / "p.npz").lyapunov_matrix, np.eye(2))


# ------------------------------------------------------------------ the constrained form
@pytest.mark.parametrize("lyapunov", ["identity", "learned"])
def test_constrained_form_returns_a_model_satisfying_eq10(lyapunov):
    demos = _linear_demos(A=np.array([[-1.0, 2.0], [-1.0, -1.5]]), n=3)
    learner = SEDS(2, objective="mse", random_state=0, formulation="constrained",
                   lyapunov=lyapunov, max_iter=300).fit(demos)
    m = learner.model_
    info = m.fit_info
    assert info["formulation"] == "constrained"
    assert info["constraint_violation"] < 1e-8
    d, P = 2, m.lyapunov_matrix
    assert np.all(m.priors > 0) and m.priors.sum() == pytest.approx(1.0, abs=1e-12)  # (d), (e)
    for k in range(m.n_components):
        Sx = m.covariances[k, :d, :d]
        assert np.linalg.eigvalsh(m.covariances[k]).min() > 0                       # (c)
        A = m.covariances[k, d:, :d] @ np.linalg.inv(Sx)
        assert np.linalg.eigvalsh(A.T @ P + P @ A).max() < -2 * MARGIN * 0.99      # (b)
        resid = m.means[k, d:] - A @ (m.means[k, :d] - m.target)                     # (a)
        assert np.linalg.norm(resid) < 1e-8 * max(1.0, np.linalg.norm(m.means[k, d:]))
    assert learner.score(demos) > 0.95


def test_stability_constraints_are_the_leading_minors():
    layout = Layout(1, 2, with_noise=False, formulation="constrained")
    g, lbg, ubg = stability_constraints(layout, MARGIN)
    theta = np.zeros(layout.size)
    s = layout.slices(0)
    A = np.array([[-1.0, 3.0], [0.0, -1.0]])  # A + A^T indefinite
    theta[s["pi"]], theta[s["A"]], theta[s["mu"]] = 1.0, A.ravel(), [0.5, 0.2]
    theta[s["mud"]] = A @ np.array([0.5, 0.2])
    v = np.asarray(g(theta)).ravel()
    M = -(A + A.T) - 2 * MARGIN * np.eye(2)
    np.testing.assert_allclose(v[:2], [M[0, 0], np.linalg.det(M)], rtol=1e-12)
    assert v[1] < MINOR_FLOOR  # violated: the minor is negative
    np.testing.assert_allclose(v[2:], 0.0, atol=1e-15)  # (a) and (e) hold here
    assert lbg[0] == MINOR_FLOOR and np.isinf(ubg[0])


# ------------------------------------------------------------------ user constraints
def test_user_constraints_are_honoured():
    demos = _linear_demos(A=np.array([[-1.0, 0.5], [-0.5, -1.0]]), n=3)

    def slow_x(model):  # every component's gain along x at most -2 (true: -1)
        return [(A[0, 0], -np.inf, -2.0) for A in model["A"]]

    free = SEDS(1, objective="mse", random_state=0).fit(demos).model_
    held = SEDS(1, objective="mse", random_state=0, constraints=slow_x).fit(demos).model_
    assert free.A[0][0, 0] > -1.5
    assert held.A[0][0, 0] <= -2.0 + 1e-6
    assert held.fit_info["user_constraint_violation"] <= 1e-6


@pytest.mark.parametrize("bad, match", [
    (lambda m: [(m["A"][0][0, 0], 1.0, 0.0)], "lower <= upper"),
    (lambda m: [m["A"][0][0, 0]], "triple"),
    (lambda m: [], "no constraint"),
    (lambda m: m["nope"], "failed on the model symbols"),
])
def test_bad_user_constraints_get_clear_errors(bad, match):
    demos = _linear_demos(n=2)
    with pytest.raises(ValueError, match=match):
        SEDS(1, objective="mse", constraints=bad).fit(demos)


def test_bad_options_are_refused():
    demos = _linear_demos(n=2)
    with pytest.raises(ValueError, match="lyapunov"):
        SEDS(1, lyapunov="quadratic").fit(demos)
    with pytest.raises(ValueError, match="formulation"):
        SEDS(1, formulation="penalty").fit(demos)
    with pytest.raises(TypeError, match="callable"):
        SEDS(1, constraints=[1, 2]).fit(demos)


@pytest.mark.parametrize("lyapunov", ["identity", "learned"])
def test_gain_limit_bounds_the_stiffness_of_every_component(lyapunov):
    demos = _linear_demos(A=np.array([[-8.0, 3.0], [-3.0, -8.0]]), n=3)
    X, Xd, _, _ = demos.stacked()
    sx = np.sqrt(np.mean(np.sum(X**2, axis=1)) / 2)
    sv = np.sqrt(np.mean(np.sum(Xd**2, axis=1)) / 2)
    g, d = 0.3, 2
    m = SEDS(2, objective="mse", random_state=0, gain_limit=g,
             lyapunov=lyapunov).fit(demos).model_
    free = SEDS(2, objective="mse", random_state=0, lyapunov=lyapunov).fit(demos).model_
    # |B_ij| <= sqrt(g), |W_ij| <= g: ||B B^T|| <= ||B||_F^2, ||W - W^T|| <= 2 ||W||_F
    bound = d * (d + 1) / 2 * g + 2 * np.sqrt(d * (d - 1) / 2) * g + MARGIN
    P = m.lyapunov_matrix
    for A in m.A:
        A_scaled = A * sx / sv
        if lyapunov == "learned":  # A = P^-1 S: ||A|| <= ||P^-1|| ||S||, P of trace d
            assert np.linalg.norm(P @ A_scaled, 2) <= bound * (1 + 1e-6)
        else:
            assert np.linalg.norm(A_scaled, 2) <= bound * (1 + 1e-6)
    assert max(np.linalg.norm(A, 2) for A in free.A) > max(np.linalg.norm(A, 2) for A in m.A)
    with pytest.raises(ValueError, match="gain_limit"):
        SEDS(1, gain_limit=-1.0).fit(demos)


@pytest.mark.slow
def test_hitting_motion_on_a_learned_lyapunov_model(tmp_path):
    """Eq. 8, 12 and 14 work unchanged on a model certified by a learned P, and it saves."""
    from seds_casadi.motion import HittingMotion, HittingMotionLearner, load_hitting_demos

    motion = HittingMotionLearner(n_components=3, seds_params={"lyapunov": "learned"}).fit(
        load_hitting_demos()).motion_
    P = motion.target_field.ds.lyapunov_matrix
    assert not np.allclose(P, np.eye(3))
    swing = motion.rollout(np.array([-0.3, 0.1, 0.05]), alpha=0.2, kappa=1.2)
    assert swing.direction_error_deg < 1.0 and abs(swing.speed_error) < 0.02
    motion.save(tmp_path / "m")
    back = HittingMotion.load(tmp_path / "m")
    np.testing.assert_array_equal(back.target_field.ds.lyapunov_matrix, P)
    x = np.array([[-0.3, 0.1, 0.05], [-0.2, -0.1, 0.02]])
    np.testing.assert_allclose(back.velocity(x, 0.2, 1.2), motion.velocity(x, 0.2, 1.2))
