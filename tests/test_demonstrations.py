import numpy as np
import pytest

from seds_casadi import Demonstrations, load_demonstrations, save_demonstrations

_R = np.random.default_rng(0)


def test_velocities_from_dt_are_exact_for_quadratic_motion():
    t = np.linspace(0, 1, 21)
    pos = np.stack([t**2, 3 * t], axis=1)
    d = Demonstrations([pos], dt=t[1] - t[0], trim_speed=0, target=[1.0, 3.0])
    # second-order central differences are exact for quadratics in the interior
    np.testing.assert_allclose(d.velocities[0][1:-1, 0], 2 * t[1:-1], atol=1e-12)
    np.testing.assert_allclose(d.velocities[0][:, 1], 3.0, atol=1e-12)


def test_velocities_from_time_stamps_with_uneven_steps():
    t = np.array([0.0, 0.1, 0.25, 0.3, 0.5, 0.8])
    pos = np.stack([2 * t, -t], axis=1)
    d = Demonstrations([pos], times=[t], trim_speed=0)
    np.testing.assert_allclose(d.velocities[0], np.tile([2.0, -1.0], (6, 1)), atol=1e-12)


def test_standstill_is_trimmed_and_target_is_mean_of_end_points():
    moving = np.stack([np.linspace(1, 0, 10), np.linspace(2, 0, 10)], axis=1)
    still_start = np.repeat(moving[:1], 5, axis=0)
    still_end = np.repeat(moving[-1:], 5, axis=0)
    a = np.vstack([still_start, moving, still_end])
    b = a + np.array([0.2, 0.0])
    d = Demonstrations([a, b], dt=0.1)
    assert len(d.positions[0]) <= 12  # the 10 moving samples plus at most one standstill each side
    np.testing.assert_allclose(d.target, [0.1, 0.0], atol=1e-12)
    # each demonstration is shifted by its own end point (SEDS's choice)
    for p in d.shifted_positions:
        np.testing.assert_allclose(p[-1], 0.0, atol=1e-12)


def test_given_target_shifts_all_by_it():
    pos = np.stack([np.linspace(1, 0.1, 10), np.zeros(10)], axis=1)
    d = Demonstrations([pos], dt=0.1, target=[0.0, 0.0])
    np.testing.assert_allclose(d.shifted_positions[0], d.positions[0])


def test_stacked_phase_and_subsample_and_select(spiral_demos):
    X, Xd, phase, demo = spiral_demos.stacked()
    assert X.shape == Xd.shape == (spiral_demos.n_samples, 2)
    assert phase.min() == 0.0 and phase.max() == 1.0
    assert set(demo) == {0, 1, 2}
    sub = spiral_demos.subsample(10)
    assert [len(p) for p in sub.positions] == [10, 10, 10]
    np.testing.assert_allclose(sub.positions[0][-1], spiral_demos.positions[0][-1])
    sel = spiral_demos.select([2])
    assert sel.n_demos == 1
    np.testing.assert_allclose(sel.positions[0], spiral_demos.positions[2])
    with pytest.raises(ValueError, match="out of range"):
        spiral_demos.select([5])


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(positions=[]), "empty"),
        (dict(positions=[np.array([[0.0, np.nan], [1.0, 1.0]])], dt=0.1), "NaN or infinite"),
        (dict(positions=[np.array([[0.0, np.inf], [1.0, 1.0]])], dt=0.1), "NaN or infinite"),
        (dict(positions=[np.zeros((1, 2))], dt=0.1), "at least 2"),
        (dict(positions=[_R.random((5, 2)), _R.random((5, 3))], dt=0.1), "dimension"),
        (dict(positions=[np.ones((5, 2))], dt=0.1), "never move"),
        (dict(positions=[_R.random((5, 2))]), "dt="),
        (dict(positions=[_R.random((5, 2))], velocities=[_R.random((4, 2))]), "shape"),
        (dict(positions=[_R.random((5, 2))], dt=-1.0), "dt must be a positive"),
        (dict(positions=[_R.random((5, 2))], dt=0.1, target=[0.0]), "target"),
        (dict(positions=np.zeros((2, 2, 2, 2)), dt=0.1), "shape"),
    ],
)
def test_bad_input_is_rejected_with_a_clear_message(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Demonstrations(**kwargs)


def test_one_still_demo_among_moving_ones_is_named():
    moving = np.stack([np.linspace(1, 0, 10), np.zeros(10)], axis=1)
    with pytest.raises(ValueError, match="demonstration 1 never moves"):
        Demonstrations([moving, np.zeros((10, 2))], dt=0.1)


def test_npz_and_csv_round_trip(tmp_path, spiral_demos):
    path = tmp_path / "demos.npz"
    save_demonstrations(path, spiral_demos)
    back = load_demonstrations(path)
    for a, b in zip(back.positions, spiral_demos.positions):
        np.testing.assert_allclose(a, b)
    np.testing.assert_allclose(back.target, spiral_demos.target)
    # CSV: demo, t, x0, x1 (velocities derived from time stamps)
    rows = ["demo,t,x0,x1"]
    for n, p in enumerate(spiral_demos.positions):
        for i, x in enumerate(p):
            rows.append(f"{n},{0.05 * i},{float(x[0])!r},{float(x[1])!r}")
    csv_path = tmp_path / "demos.csv"
    csv_path.write_text("# a comment\n" + "\n".join(rows) + "\n")
    back = load_demonstrations(csv_path, trim_speed=0)
    assert back.n_demos == 3
    np.testing.assert_allclose(back.positions[1], spiral_demos.positions[1])
    np.testing.assert_allclose(back.velocities[0][5], spiral_demos.velocities[0][5], rtol=0.05)


def test_bad_files(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_demonstrations(tmp_path / "missing.csv")
    bad = tmp_path / "x.csv"
    bad.write_text("demo,time,x0\n0,0,1\n")
    with pytest.raises(ValueError, match="missing column 't'"):
        load_demonstrations(bad)
    bad.write_text("demo,t,x0\n0,0,abc\n")
    with pytest.raises(ValueError, match="not numeric"):
        load_demonstrations(bad)
    junk = tmp_path / "x.npz"
    junk.write_bytes(b"not a zip file")
    with pytest.raises(ValueError, match="not a readable"):
        load_demonstrations(junk)
    other = tmp_path / "x.txt"
    other.write_text("")
    with pytest.raises(ValueError, match="unknown demonstrations format"):
        load_demonstrations(other)


def test_estimated_dt_recovers_the_step_after_subsampling(spiral_demos):
    assert spiral_demos.estimated_dt() == pytest.approx(0.05, rel=0.02)  # linear_demos' dt
    # known answer: constant speed along a line, 41 samples at 0.1 s -> 11 kept, 0.4 s apart
    t = np.linspace(0, 4, 41)[:, None]
    line = Demonstrations([np.hstack([2 - 0.5 * t, t])], velocities=[np.tile([-0.5, 1.0], (41, 1))])
    sub = line.subsample(11)
    assert sub.dt is None
    assert sub.estimated_dt() == pytest.approx(0.4, rel=1e-9)
