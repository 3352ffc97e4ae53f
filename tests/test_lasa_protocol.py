"""The published LASA protocol (nbfigueroa/ds-opt, 2018): its metrics against hand-computed
answers, its data selection, its K choice by BIC, and the ``lasa --protocol ds-opt`` command."""

import csv
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from seds_casadi.app.lasa import (
    DSOPT_COLUMNS,
    PUBLISHED_MEANS,
    PUBLISHED_SEDS,
    DsOptResult,
    dsopt_scores,
    dsopt_sets,
    dsopt_table,
    evaluate_shape,
    evaluate_shape_dsopt,
    run_lasa,
)
from seds_casadi.core.datasets import LASA_SINGLE_SHAPES, load_lasa_raw
from seds_casadi.core.metrics import (
    direction_error,
    dtw_distance,
    pointwise_direction_error,
    reproduction_dtw,
    simulate_until_slow,
    velocity_rmse,
)
from seds_casadi.core.model_selection import choose_k_by_bic, dsopt_elbow_k


# ------------------------------------------------------------------ metrics, known answers
def test_dtw_of_two_hand_made_paths():
    # s = (0,0) (1,0) (2,0), t = (0,0) (2,0): cost [[0, 2], [1, 1], [2, 0]];
    # D = [[0, 2], [1, 1], [3, 1]] -> the best warping path costs 0 + 1 + 0 = 1
    s = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    t = np.array([[0.0, 0.0], [2.0, 0.0]])
    assert dtw_distance(s, t) == pytest.approx(1.0, abs=1e-15)
    assert dtw_distance(t, s) == pytest.approx(1.0, abs=1e-15)
    # two sides of a unit square against the diagonal's end points: (0,1) is 1 from either end
    # and the corners match exactly, so the best path costs 1
    sq = np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    diag = np.array([[0.0, 0.0], [1.0, 1.0]])
    assert dtw_distance(sq, diag) == pytest.approx(1.0, abs=1e-15)
    # one point against a path: the sum of its distances to every point of the path (no window)
    p = np.array([[3.0, 4.0]])
    path = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]])
    assert dtw_distance(p, path) == pytest.approx(5.0 + 4.0 + 0.0, abs=1e-15)


def test_pointwise_direction_error_known_answers_and_the_nan_rule():
    F = np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 0.0], [1e-6, 0.0], [np.nan, 1.0], [1.0, 1.0]])
    V = np.array([[0.0, 1.0], [-1.0, 0.0], [1.0, 0.0], [0.0, 1e-6], [1.0, 0.0], [2.0, 0.0]])
    want = [1.0, 2.0, 0.0, 1.0, 0.0, 1.0 - 1.0 / np.sqrt(2.0)]
    # ds-opt's edot_error.m: only an undefined (NaN) cosine counts 0; tiny norms still count
    np.testing.assert_allclose(pointwise_direction_error(F, V, min_norm_product=0.0), want,
                               atol=1e-15)
    # our default threshold drops the 1e-12 norm product too, which is direction_error's rule
    legacy = pointwise_direction_error(F, V)
    assert legacy[3] == 0.0
    assert np.mean(legacy) == pytest.approx(direction_error(F, V), abs=1e-15)
    with pytest.raises(ValueError, match="min_norm_product"):
        pointwise_direction_error(F, V, min_norm_product=-1.0)


def test_velocity_rmse_is_the_mean_of_per_point_roots_not_a_pooled_root():
    # per point sqrt(mean over dims): sqrt((1 + 1) / 2) = 1 and sqrt((9 + 9) / 2) = 3 -> mean 2;
    # a pooled RMSE would be sqrt(5)
    F = np.array([[1.0, 1.0], [3.0, 3.0]])
    assert velocity_rmse(F, np.zeros_like(F)) == pytest.approx(2.0, abs=1e-15)
    assert velocity_rmse(np.array([[3.0, 4.0]]), np.zeros((1, 2))) == pytest.approx(
        np.sqrt(12.5), abs=1e-15)


def test_the_stop_rule_of_the_reproductions_on_a_linear_system():
    # xdot = -x with dt = 0.5: x_i = 0.5**i x_0 and v_i = -0.5**i x_0. From x_0 = 1 the speed is
    # below 0.1 from i = 4 on (0.0625), so v_4..v_7 are the first 4 slow steps: the run stops at
    # i = 7 and keeps x_0..x_7 (x_8 is computed and dropped): 8 points.
    def field(x):
        return -x

    one = simulate_until_slow(field, np.array([[1.0]]), dt=0.5, speed_tol=0.1, max_steps=3000)
    assert one.shape == (8, 1, 1)
    np.testing.assert_allclose(one[:, 0, 0], 0.5 ** np.arange(8), rtol=0, atol=1e-15)
    # all starts together: from 10 the speed is below 0.1 from i = 7 (0.078), so both run to
    # i = 10 (11 points), the slow one included
    two = simulate_until_slow(field, np.array([[1.0], [10.0]]), dt=0.5)
    assert two.shape == (11, 2, 1)
    np.testing.assert_allclose(two[:, 1, 0], 10 * 0.5 ** np.arange(11), atol=1e-14)
    # every component must be slow: (1, 10) stops like the start 10 alone
    assert simulate_until_slow(field, np.array([[1.0, 10.0]]), dt=0.5).shape == (11, 1, 2)
    # the step limit: ds-opt stops once i > i_max - 2, so at most max_steps - 1 points
    assert simulate_until_slow(field, np.array([[10.0]]), dt=0.5, max_steps=6).shape == (5, 1, 1)
    assert simulate_until_slow(lambda x: 0 * x + 1.0, np.zeros((1, 2)),
                               max_steps=3000).shape == (2999, 1, 2)
    # a slow start still takes the 4 steps the rule looks at
    assert simulate_until_slow(field, np.array([[0.01]]), dt=0.5).shape == (4, 1, 1)
    with pytest.raises(ValueError, match="max_steps"):
        simulate_until_slow(field, np.ones((1, 1)), max_steps=4)
    with pytest.raises(ValueError, match="dt"):
        simulate_until_slow(field, np.ones((1, 1)), dt=0.0)


@settings(max_examples=40, deadline=None)
@given(rate=st.floats(0.1, 80.0), n=st.integers(1, 50), x0=st.floats(-5.0, 5.0))
def test_substeps_are_euler_at_the_finer_step_sampled_at_the_coarse_one(rate, n, x0):
    # xdot = -rate x: each recorded step is n Euler steps of dt / n, x_k = (1 - rate dt / n)^(n k)
    dt = 0.05
    path = simulate_until_slow(lambda x: -rate * x, np.array([[x0]]), dt=dt, speed_tol=1e-3,
                               max_steps=40, substeps=n)[:, 0, 0]
    k = np.arange(len(path))
    np.testing.assert_allclose(path, x0 * (1 - rate * dt / n) ** (n * k), rtol=1e-9, atol=1e-12)
    if n == 1:
        np.testing.assert_array_equal(path, simulate_until_slow(
            lambda x: -rate * x, np.array([[x0]]), dt=dt, speed_tol=1e-3, max_steps=40)[:, 0, 0])


def test_bad_substeps_are_refused():
    with pytest.raises(ValueError, match="substeps"):
        simulate_until_slow(lambda x: -x, np.ones((1, 1)), substeps=0)


def test_reproduction_dtw_compares_each_reproduction_with_its_whole_reference():
    def field(x):
        return -x

    starts = np.array([[1.0, 0.0], [0.0, 2.0]])
    refs = [np.array([[1.0, 0.0], [0.0, 0.0]]), np.array([[0.0, 2.0], [0.0, 1.0], [0.0, 0.0]])]
    paths = simulate_until_slow(field, starts, dt=0.5)
    want = [dtw_distance(paths[:, 0], refs[0]), dtw_distance(paths[:, 1], refs[1])]
    np.testing.assert_allclose(reproduction_dtw(field, starts, refs, dt=0.5), want, rtol=1e-15)
    dtw, got = reproduction_dtw(field, starts, refs, return_paths=True, dt=0.5)
    np.testing.assert_array_equal(got, paths)
    np.testing.assert_allclose(dtw, want, rtol=1e-15)
    with pytest.raises(ValueError, match="one start per reference"):
        reproduction_dtw(field, starts, refs[:1])


# ------------------------------------------------------------------ the protocol's data
def test_the_protocol_takes_demos_1_to_4_and_5_to_7_every_second_sample():
    pos, vel, _ = load_lasa_raw("CShape")
    sets = dsopt_sets("CShape")
    train, test = sets["train"], sets["test"]
    assert train.demos == (1, 2, 3, 4) and test.demos == (5, 6, 7)
    assert [p.shape for p in train.positions] == [(500, 2)] * 4
    assert [p.shape for p in test.positions] == [(500, 2)] * 3
    for k, n in enumerate(train.demos):
        np.testing.assert_array_equal(train.positions[k], pos[n - 1][0::2])
        np.testing.assert_array_equal(train.velocities[k], vel[n - 1][0::2])  # the file's [mm/s]
    for k, n in enumerate(test.demos):
        np.testing.assert_array_equal(test.velocities[k], vel[n - 1][0::2])
        # MATLAB's data_(1:2, 20): the 20th subsampled point, sample 39 (index 38) of the file
        np.testing.assert_array_equal(test.starts[k], pos[n - 1][38])
    demos = train.demonstrations()
    assert demos.n_samples == 2000  # nothing trimmed
    np.testing.assert_array_equal(demos.target, [0.0, 0.0])
    np.testing.assert_array_equal(np.concatenate(demos.shifted_positions),
                                  np.concatenate(train.positions))
    assert sorted(PUBLISHED_SEDS) == sorted(LASA_SINGLE_SHAPES)


def test_dsopt_scores_of_a_linear_system_and_of_a_field_twice_as_fast():
    # demos of xdot = A x sampled exactly: the true field scores RMSE 0 and e_dot 0, and its
    # Euler reproductions stay near the demos; twice the field keeps the directions (e_dot 0)
    # and its RMSE is the mean over points of the root of the mean over dims of v^2
    from scipy.linalg import expm

    from seds_casadi.app.lasa import DsOptSet

    A = np.array([[-1.0, 0.5], [-0.5, -1.0]])
    t = np.arange(500) * 0.01
    P, V = [], []
    for x0 in ([100.0, 0.0], [0.0, 80.0]):
        X = np.array([expm(A * tk) @ x0 for tk in t])
        P.append(X)
        V.append(X @ A.T)
    data = DsOptSet((1, 2), P, V, np.stack([p[19] for p in P]))
    rmse, e_dot, dtwd, paths = dsopt_scores(lambda Y: Y @ A.T, data)
    assert rmse == pytest.approx(0.0, abs=1e-9) and e_dot == pytest.approx(0.0, abs=1e-12)
    assert paths.shape[1:] == (2, 2) and np.isfinite(dtwd) and dtwd > 0
    rmse2, e_dot2, _, _ = dsopt_scores(lambda Y: 2 * Y @ A.T, data)
    Vall = np.concatenate(V)
    assert rmse2 == pytest.approx(np.mean(np.sqrt(np.mean(Vall**2, axis=1))), rel=1e-12)
    assert e_dot2 == pytest.approx(0.0, abs=1e-12)


def test_published_tables_reproduce_the_published_means():
    per_shape = np.array([v[1:] for v in PUBLISHED_SEDS.values()])
    tr, te = per_shape[:, :3].mean(0), per_shape[:, 3:].mean(0)
    half_digit = [0.005, 0.0005, 0.5]  # the published means are quoted to 2, 3 and 0 decimals
    assert np.all(np.abs(te - PUBLISHED_MEANS[("SEDS", "test")]) <= half_digit)
    assert np.all(np.abs(tr - PUBLISHED_MEANS[("SEDS", "train")]) <= half_digit)


# ------------------------------------------------------------------ K by BIC
def test_elbow_rule_of_ds_opt_on_hand_made_bic_curves():
    # d1 = [0 -50 -10 -2 -1], d2 = [0 -50 40 8 1]: one peak at K = 3
    assert dsopt_elbow_k([100.0, 50.0, 40.0, 38.0, 37.0]) == 3
    # d2 = [0 -60 40 0 0 35 0]: the maximum (K = 3) is the first peak and the second (K = 6) is
    # within 75 % of it, so K = 6
    assert dsopt_elbow_k([100.0, 40.0, 20.0, 0.0, -20.0, -5.0, 10.0]) == 6
    # second peak at 50 % of the first (d2 = [0 -60 40 0 0 20 0]): the 45 % rule takes it
    assert dsopt_elbow_k([100.0, 40.0, 20.0, 0.0, -20.0, -20.0, -20.0]) == 6
    # second peak at 25 %: stay at the first
    assert dsopt_elbow_k([100.0, 40.0, 20.0, 0.0, -20.0, -30.0, -40.0]) == 3
    # the maximum at the last K is kept
    assert dsopt_elbow_k([100.0, 90.0, 80.0, 70.0, 100.0]) == 5
    with pytest.raises(ValueError, match="finite"):
        dsopt_elbow_k([1.0, np.nan])


def test_choose_k_by_bic_finds_well_separated_clusters():
    rng = np.random.default_rng(0)
    centres = np.array([[0.0, 0.0, 0.0, 0.0], [10.0, 0.0, -5.0, 0.0], [0.0, 10.0, 0.0, 5.0]])
    Z = np.concatenate([c + 0.3 * rng.standard_normal((200, 4)) for c in centres])
    X, V = Z[:, :2], Z[:, 2:]
    assert choose_k_by_bic(X, V, k_max=6, random_state=0, rule="min", n_init=2) == 3
    # the elbow rule takes the K where the fall of the BIC slows most: K = 3 here (second
    # difference 1833), just ahead of K = 4 (1795), so either is a correct reading of the curve
    assert choose_k_by_bic(X, V, k_max=6, random_state=0, rule="ds-opt", n_init=2) in (3, 4)
    with pytest.raises(ValueError, match="valid: ds-opt, min"):
        choose_k_by_bic(X, V, rule="aic")


# ------------------------------------------------------------------ bad input
def test_unknown_protocol_lists_the_valid_ones_and_ds_opt_options_are_checked():
    with pytest.raises(ValueError, match="unknown protocol 'ds_opt'; valid: all, split, ds-opt"):
        run_lasa(shapes=["Angle"], protocols=["ds_opt"], progress=False)
    with pytest.raises(ValueError, match="26 single-pattern shapes"):
        run_lasa(shapes=["Multi_Models_1"], protocols=["ds-opt"], progress=False)
    with pytest.raises(ValueError, match="'bic' and 'published' are for ds-opt"):
        run_lasa(shapes=["Angle"], protocols=["all"], n_components="bic", progress=False)
    with pytest.raises(ValueError, match="'bic' or 'published'"):
        run_lasa(shapes=["Angle"], protocols=["ds-opt"], n_components="aic", progress=False)
    with pytest.raises(ValueError, match="unknown BIC rule"):
        run_lasa(shapes=["Angle"], protocols=["ds-opt"], bic_rule="max", progress=False)
    with pytest.raises(ValueError, match="evaluate_shape_dsopt"):
        evaluate_shape("Angle", protocol="ds-opt")
    with pytest.raises(ValueError, match="unknown shape 'Circle' for the ds-opt protocol"):
        dsopt_sets("Circle")


def test_dsopt_table_sets_ours_beside_the_published_figures():
    pub = PUBLISHED_SEDS["Angle"]
    rows = [DsOptResult("Angle", "mse", st, 2 * pub[o], pub[o + 1], pub[o + 2], 1.0, 10, 5,
                        True, "Solve_Succeeded", "given", 0.0, 400, 0.01, 20.0, pub[o],
                        pub[o + 1], pub[o + 2], pub[0]) for st, o in (("train", 1), ("test", 4))]
    text = dsopt_table(rows)
    assert "ours: SEDS mse, test" in text and "published SEDS, test, same shapes" in text
    assert "LPV-DS PC-GMM O2, test" in text and "5.19" in text
    assert "worst RMSE ratio: Angle 2.00x" in text and "worst DTWD ratio: Angle 1.00x" in text


# ------------------------------------------------------------------ end to end (real fits)
@pytest.mark.slow
def test_evaluate_shape_dsopt_scores_train_and_test_with_a_certified_model(tmp_path):
    rows = evaluate_shape_dsopt("Angle", n_components=2, figure_path=str(tmp_path / "a.png"))
    assert [r.set for r in rows] == ["train", "test"]
    for r in rows:
        assert r.n_components == 2 and r.certified and r.k_choice == "given"
        assert 0.5 < r.rmse_mmps < 20 and 0 < r.e_dot < 0.2 and 100 < r.dtwd_mm < 10000
        # the reproductions stopped by the slow rule, near the target (at 0.1 mm/s per component)
        assert 4 <= r.repro_points < 2999 and r.max_end_distance_mm < 1.0
        assert r.max_rate_per_s > 0
    assert rows[0].seconds == rows[1].seconds and rows[0].iterations > 0
    assert (tmp_path / "a.png").stat().st_size > 1000
    # K by BIC, kept small here: the search runs on the training set only
    (r_bic, _) = evaluate_shape_dsopt("Angle", n_components="bic", k_max=2)
    assert r_bic.k_choice == "bic:ds-opt" and r_bic.n_components in (1, 2) and r_bic.seconds_k > 0


@pytest.mark.slow
def test_run_lasa_runs_ds_opt_beside_the_other_protocols(tmp_path):
    res = run_lasa(shapes=["Angle"], objectives=["mse"], protocols=["all", "ds-opt"],
                   n_components=2, n_samples=25, out_dir=str(tmp_path), figures=False,
                   progress=False)
    classic = [r for r in res if not isinstance(r, DsOptResult)]
    dsopt = [r for r in res if isinstance(r, DsOptResult)]
    assert [(r.protocol, r.objective) for r in classic] == [("all", "mse")]
    assert [(r.set, r.n_components) for r in dsopt] == [("train", 2), ("test", 2)]
    assert (tmp_path / "lasa.csv").exists() and (tmp_path / "lasa_dsopt.csv").exists()
    summary = (tmp_path / "summary.txt").read_text()
    assert summary.index("unconverged") < summary.index("ds-opt protocol")


def test_run_lasa_split_protocol_scores_the_held_out_demos():
    """Each task runs its own protocol: "split" trains on demos 1-4 and scores 5-7 (it once ran
    "all" under the split label), so its figures are evaluate_shape's split figures."""
    res = run_lasa(shapes=["Angle"], objectives=["mse"], protocols=["all", "split"],
                   n_components=2, n_samples=20, figures=False, progress=False)
    by = {r.protocol: r for r in res}
    assert sorted(by) == ["all", "split"]
    split = evaluate_shape("Angle", "mse", "split", n_components=2, n_samples=20)
    assert by["split"].rmse == pytest.approx(split.rmse, rel=1e-9)
    assert by["split"].rmse != pytest.approx(by["all"].rmse, rel=1e-6)


@pytest.mark.slow
def test_cli_lasa_protocol_ds_opt_writes_the_csv_with_units(tmp_path):
    out = tmp_path / "dsopt"
    res = subprocess.run([sys.executable, "-m", "seds_casadi", "lasa", "--protocol", "ds-opt",
                          "--shapes", "Angle", "-K", "2", "--no-figures", "--out", str(out)],
                         capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stderr
    with open(out / "lasa_dsopt.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert tuple(rows[0].keys()) == DSOPT_COLUMNS
    assert [(r["shape"], r["objective"], r["set"]) for r in rows] == [
        ("Angle", "mse", "train"), ("Angle", "mse", "test")]
    assert all(r["n_components"] == "2" and r["certified"] == "True" for r in rows)
    assert float(rows[1]["published_rmse_mmps"]) == PUBLISHED_SEDS["Angle"][4]
    assert not (out / "lasa.csv").exists()
    assert "published SEDS, test, same shapes" in res.stdout
    assert "LPV-DS PC-GMM O2, test" in (out / "summary.txt").read_text()
    bad = subprocess.run([sys.executable, "-m", "seds_casadi", "lasa", "--protocol", "dsopt",
                          "--out", str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "invalid choice" in bad.stderr
    assert all(name in bad.stderr for name in ("all", "split", "ds-opt"))
    bad = subprocess.run([sys.executable, "-m", "seds_casadi", "lasa", "--protocol", "all",
                          "-K", "bic", "--shapes", "Angle", "--out", str(tmp_path)],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "are for ds-opt" in bad.stderr
