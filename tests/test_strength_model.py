"""A direction-objective model that moves at the demonstrated speeds: the strength factor
(Eq. 12) along the certified streamlines (``SEDS(speed_calibration="strength")``, issue 13)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from seds_casadi import SEDS, StableDS
from seds_casadi.core.datasets import load_lasa, load_lasa_raw
from seds_casadi.core.errors import ConvergenceWarning, ModelFileError
from seds_casadi.core.model_files import checksum
from seds_casadi.core.strength import StrengthFactor, StrengthFactorLearner


@pytest.fixture(scope="module")
def wshape():
    """LASA WShape, K = 5: with one speed factor on the gains ("median") no reproduction from a
    demonstration's start arrived within 3x the demonstration's duration (0/7)."""
    demos = load_lasa("WShape", n_samples=100)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        fit = SEDS(5, objective="direction", random_state=0).fit(demos)
    return demos, fit.model_


def _reach_times(model, demos, shape):
    """Time to reach 1 % of the extent from each demonstration's start, over its duration."""
    X = np.concatenate(demos.positions)
    extent = float(np.max(np.ptp(X, axis=0)))
    _, _, dt_raw = load_lasa_raw(shape)
    duration = dt_raw * 999
    dt = duration / 500
    starts = np.array([p[0] for p in demos.positions])
    _, info = model.rollout(starts, dt=dt, max_steps=1500, tol=0.01 * extent, return_info=True,
                            warn=False)
    return np.where(info["converged"], info["steps"] * dt / duration, np.inf)


def test_strength_model_moves_at_the_demonstrated_speeds_and_arrives(wshape):
    demos, model = wshape
    assert model.strength is not None and model.fit_info["speed_calibration"] == "strength"
    assert model.fit_info["strength_components"] == 5
    X = np.concatenate(demos.positions)
    V = np.concatenate(demos.velocities)
    nv = np.linalg.norm(V, axis=1)
    moving = nv > 1e-9 * nv.max()
    ratio = np.linalg.norm(model.predict(X[moving]), axis=1) / nv[moving]
    assert 0.8 <= np.median(ratio) <= 1.25
    # the speed follows the demonstrations along the path, not only at the median sample
    assert np.percentile(ratio, 10) > 0.5 and np.percentile(ratio, 90) < 2.0
    times = _reach_times(model, demos, "WShape")
    assert np.all(times <= 3.0), times


def test_median_calibration_is_the_plain_gmm_ds_and_stalls_on_wshape(wshape):
    """The known failure the strength factor removes (same data, same start)."""
    demos, strength_model = wshape
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        plain = SEDS(5, objective="direction", random_state=0,
                     speed_calibration="median").fit(demos).model_
    assert plain.strength is None and plain.fit_info["strength_components"] is None
    # the same optimum of Eq. 9 (same gains up to the factor), so the same streamlines
    np.testing.assert_allclose(plain.A, strength_model.A, rtol=1e-9, atol=1e-12)
    assert np.any(_reach_times(plain, demos, "WShape") > 3.0)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000))
def test_same_streamlines_and_lyapunov_decrease_everywhere(wshape, seed):
    """f_v is a positive multiple of f: the direction is f's and V(x) = ||x - x*||^2 falls."""
    _, model = wshape
    rng = np.random.default_rng(seed)
    scale = 10.0 ** rng.uniform(-4, 2.5)
    X = model.target + scale * rng.standard_normal((20, 2))
    Fv = model.predict(X)
    plain = StableDS(model.priors, model.means, model.covariances, model.target)
    F = plain.predict(X)
    cos = np.sum(Fv * F, axis=1) / (np.linalg.norm(Fv, axis=1) * np.linalg.norm(F, axis=1))
    np.testing.assert_allclose(cos, 1.0, atol=1e-9)
    assert np.all(np.sum((X - model.target) * Fv, axis=1) < 0)


def test_velocity_vanishes_at_the_target_and_tapers_linearly(wshape):
    _, model = wshape
    np.testing.assert_array_equal(model.predict(model.target), 0.0)
    u = np.array([0.6, -0.8])
    r = model.strength_radius
    near = np.linalg.norm(model.predict(model.target + np.outer([1e-3, 1e-2], r * u)), axis=1)
    # speed ~ v(x*) ||e|| / r within the taper: ten times closer, ten times slower
    np.testing.assert_allclose(near[1] / near[0], 10.0, rtol=0.05)


def test_euler_at_a_step_below_the_stiffness_reaches_the_target(wshape):
    demos, model = wshape
    rate = model.stiffness()
    assert np.isfinite(rate) and rate > 0
    starts = np.array([p[0] for p in demos.positions])
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConvergenceWarning)  # neither step nor arrival warnings
        paths = model.rollout(starts, dt=1.0 / rate, method="euler", max_steps=20000)
    for p in paths:
        assert np.linalg.norm(p[-1] - model.target) < 1e-3 * np.abs(starts).max()


def test_saved_strength_model_round_trips_and_refuses_edits(wshape, tmp_path):
    _, model = wshape
    f = tmp_path / "m.npz"
    model.save(f)
    with np.load(f, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}
    assert int(data["version"]) == 3
    back = StableDS.load(f)
    X = model.target + np.random.default_rng(1).standard_normal((30, 2)) * 20
    np.testing.assert_array_equal(back.predict(X), model.predict(X))
    assert back.strength_radius == model.strength_radius
    # an edited strength GMM with the checksum left: refused as edited
    bad = dict(data, strength_means=data["strength_means"] * 2)
    np.savez(tmp_path / "edited.npz", **bad)
    with pytest.raises(ModelFileError, match="checksum"):
        StableDS.load(tmp_path / "edited.npz")
    # a negative taper radius with the checksum recomputed: refused as inconsistent
    names = ["priors", "means", "covariances", "target", "strength_priors", "strength_means",
             "strength_covariances", "strength_log_range", "strength_radius"]
    bad = dict(data, strength_radius=np.array([-1.0]))
    bad["checksum"] = np.array(checksum([bad[k] for k in names], str(bad["fit_info"])))
    np.savez(tmp_path / "forged.npz", **bad)
    with pytest.raises(ModelFileError, match="strength_radius"):
        StableDS.load(tmp_path / "forged.npz")


def test_learned_p_with_a_strength_factor_is_version_4(tmp_path):
    demos = load_lasa("Angle", n_samples=30)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        model = SEDS(2, objective="direction", random_state=0, lyapunov="learned").fit(demos).model_
    model.save(tmp_path / "m.npz")
    with np.load(tmp_path / "m.npz", allow_pickle=False) as z:
        assert int(z["version"]) == 4 and "lyapunov" in z.files
    back = StableDS.load(tmp_path / "m.npz")
    np.testing.assert_array_equal(back.lyapunov_matrix, model.lyapunov_matrix)
    X = np.concatenate(demos.positions)
    np.testing.assert_array_equal(back.predict(X), model.predict(X))
    P = model.lyapunov_matrix
    E = X[:-1] - model.target
    assert np.all(np.einsum("ni,ij,nj->n", E, P, model.predict(X[:-1]))[
        np.linalg.norm(E, axis=1) > 0] < 0)


def test_other_objectives_have_no_strength_factor():
    demos = load_lasa("Angle", n_samples=20)
    for obj in ("mse", "likelihood"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            m = SEDS(2, objective=obj, random_state=0).fit(demos).model_
        assert m.strength is None and m.fit_info["speed_calibration"] is None


def test_bad_strength_settings_are_refused(wshape):
    _, model = wshape
    args = (model.priors, model.means, model.covariances, model.target)
    with pytest.raises(ValueError, match="strength_radius"):
        StableDS(*args, strength=model.strength)
    with pytest.raises(ValueError, match="strength_radius"):
        StableDS(*args, strength=model.strength, strength_radius=0.0)
    with pytest.raises(ValueError, match="without a strength factor"):
        StableDS(*args, strength_radius=1.0)
    with pytest.raises(TypeError, match="StrengthFactor"):
        StableDS(*args, strength=lambda x: 1.0, strength_radius=1.0)
    sf3 = StrengthFactorLearner().fit(np.random.default_rng(0).standard_normal((40, 3)),
                                      np.exp(np.random.default_rng(1).standard_normal(40))).factor_
    with pytest.raises(ValueError, match="3-D positions"):
        StableDS(*args, strength=sf3, strength_radius=1.0)
    unbounded = StrengthFactor(model.strength.priors, model.strength.means,
                               model.strength.covariances)
    with pytest.raises(ValueError, match="log_range"):
        StableDS(*args, strength=unbounded, strength_radius=1.0)
    for bad in (0, -2, 1.5, True):
        with pytest.raises(ValueError, match="strength_components"):
            SEDS(2, objective="direction", strength_components=bad).fit(load_lasa("Angle", n_samples=10))
    with pytest.raises(ValueError, match="speed_calibration"):
        SEDS(2, objective="direction", speed_calibration="fast").fit(load_lasa("Angle", n_samples=10))


def test_demonstrations_that_hardly_move_get_a_clear_error():
    rng = np.random.default_rng(0)
    X = rng.standard_normal((50, 2))
    V = -X * 1e-3
    V[2:] = 0.0  # two samples move, the rest stand still
    with pytest.raises(ValueError, match="hardly move"):
        SEDS(1, objective="direction", random_state=0).fit(X, V)


def test_taper_radius_rule(wshape):
    """r = 1 % of the extent, or the distance covered at v(x*) in two of the data's steps if
    more (so the taper's rate v(x*)/r stays below half the sampling rate)."""
    demos, model = wshape
    Xs, _, _, _ = demos.stacked()
    extent = float(np.max(np.ptp(Xs, axis=0)))
    v_star = float(model.strength(model.target))
    expected = min(max(0.01 * extent, 2.0 * v_star * demos.estimated_dt()), 0.25 * extent)
    assert model.strength_radius == pytest.approx(expected, rel=1e-12)
    assert v_star / model.strength_radius <= 0.5 / demos.estimated_dt() * (1 + 1e-12)
    # samples without time order have no step: 1 % of the extent
    X = np.concatenate(demos.positions)
    V = np.concatenate(demos.velocities)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        m = SEDS(2, objective="direction", random_state=0, max_iter=50).fit(
            X, V, target=demos.target).model_
    ext = float(np.max(np.ptp(X, axis=0)))
    assert m.strength_radius == pytest.approx(0.01 * ext, rel=1e-12)


def test_time_ordered_tells_trajectories_from_loose_samples(wshape):
    demos, _ = wshape
    assert demos.time_ordered
    X, V = np.concatenate(demos.positions), np.concatenate(demos.velocities)
    from seds_casadi import Demonstrations

    assert not Demonstrations.from_samples(X, V).time_ordered
