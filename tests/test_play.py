"""The main job end to end: `seds-casadi play --quick` through the installed console script."""

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from seds_casadi.app.play import PlayConfig, play
from seds_casadi.app.shot_table import SHOT_COLUMNS

pytestmark = pytest.mark.slow

SCRIPT = Path(sys.executable).parent / "seds-casadi"


def _run(*args, timeout=600):
    exe = [str(SCRIPT)] if SCRIPT.exists() else [sys.executable, "-m", "seds_casadi"]
    return subprocess.run(exe + list(args), capture_output=True, text=True, timeout=timeout,
                          env=dict(os.environ, MPLBACKEND="Agg"))


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("play") / "out"
    r = _run("play", "--quick", "--replay", "--out", str(out))
    assert r.returncode == 0, r.stderr[-3000:]
    return out, r


def test_play_quick_writes_shots_summary_figures_and_models(quick_run):
    out, r = quick_run
    assert SCRIPT.exists()  # the console script itself was run
    with open(out / "shots.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert tuple(rows[0]) == SHOT_COLUMNS
    # every column with a unit names it; the hitting angle is in degrees like the learners'
    assert SHOT_COLUMNS == ("method", "shot", "ball_x_m", "ball_y_m", "hole_x_m", "hole_y_m",
                            "alpha_deg", "kappa", "hit", "sunk", "direction_error_deg",
                            "speed_error", "launch_direction_error_deg", "within_limits",
                            "final_x_m", "final_y_m", "sunk_exudyn", "strategy", "miss",
                            "miss_reason", "phase", "adapt_shots")
    assert {row["method"] for row in rows} == {"gpr", "gmr"} and len(rows) == 6
    assert {(row["phase"], row["adapt_shots"]) for row in rows} == {("test", "0")}
    for row in rows:
        assert row["hit"] in ("True", "False") and row["sunk"] in ("True", "False")
        assert -0.45 <= float(row["ball_y_m"]) <= 0.45
    # on arctan the ball is hit across the slope: angles of degrees, not fractions of a radian
    assert max(abs(float(row["alpha_deg"])) for row in rows) > 2.0
    # every shot the robot hit came within 2 deg and 5 % of the commanded velocity
    hit = [row for row in rows if row["hit"] == "True"]
    assert hit and all(float(row["direction_error_deg"]) < 2 for row in hit)
    assert all(abs(float(row["speed_error"])) < 0.05 for row in hit)
    # the ball leaves within 1 deg of the commanded direction (the face), within the limits
    assert all(float(row["launch_direction_error_deg"]) < 1 for row in hit)
    assert all(row["within_limits"] == "True" for row in rows)
    assert "launch direction (face) error max" in (out / "summary.txt").read_text()
    assert sum(row["sunk_exudyn"] != "" for row in rows) == 1
    summary = (out / "summary.txt").read_text()
    assert "gpr:" in summary and "time per stage" in summary
    for name in ("shots.png", "motion.png", "hitting_parameters.png"):
        assert (out / name).stat().st_size > 1000
    assert (out / "models" / "motion" / "stable_ds.npz").exists()
    assert (out / "models" / "dataset_arctan.npz").exists()
    # --replay (N = 1): the page of the first learner's first shot and its GIF
    page = (out / "replay.html").read_text(encoding="utf-8")
    assert "gpr shot 0" in page and "arctan" in page
    assert (out / "replay_gpr_0.gif").stat().st_size > 10000
    assert not list(out.glob("replay_gmr_*.gif")) and "replay" in summary


def test_play_reuses_saved_models(quick_run, tmp_path):
    out, _ = quick_run
    r = _run("play", "--quick", "--models", str(out / "models"), "--out", str(tmp_path / "b"),
             "--validate", "0")
    assert r.returncode == 0, r.stderr[-3000:]
    assert "reused the hitting motion" in r.stdout and "teacher:" not in r.stdout
    assert (tmp_path / "b" / "shots.csv").exists()


def test_play_bad_input_is_a_clear_error(tmp_path):
    r = _run("play", "--quick", "--robot", "r2d2", "--out", str(tmp_path / "x"))
    assert r.returncode == 2 and "unknown robot 'r2d2'" in r.stderr
    r = _run("play", "--quick", "--models", str(tmp_path / "none"), "--out",
             str(tmp_path / "y"))
    assert r.returncode == 2 and "no motion" in r.stderr
    r = _run("play", "--quick", "--field", "moon", "--out", str(tmp_path / "z"))
    assert r.returncode == 2 and "no field 'moon'" in r.stderr


def test_play_draws_its_shots_from_the_fields_declared_situations(tmp_path):
    # a field of one's own with the ball fixed and the hole on a slider: every shot played is
    # one of those situations (not a ball anywhere in the ball region, as before)
    ridge = Path(__file__).resolve().parent / "fields" / "ridge.json"
    res = play(PlayConfig(field=str(ridge), quick=True, learners=("gpr",), validate_shots=0,
                          out=str(tmp_path / "r"), progress=False, train_size=10))
    rows = res["rows"]
    assert len(rows) == 3 and all(r["hit"] for r in rows)
    assert all((r["ball_x_m"], r["ball_y_m"]) == (0.1, 0.0) for r in rows)
    assert all(r["hole_x_m"] == pytest.approx(2.1) and -0.4 <= r["hole_y_m"] <= 0.4
               for r in rows)
    assert res["success"]["gpr"] >= 2 / 3


def test_play_with_several_strategies_names_each_shots_strategy(tmp_path):
    # the paper's Section 8 extension: several strategies explored and clustered, one model
    # per strategy, the most promising played; the ridge's 20 situations keep it short
    ridge = Path(__file__).resolve().parent / "fields" / "ridge.json"
    out = tmp_path / "s"
    r = _run("play", "--quick", "--field", str(ridge), "--strategies", "2", "--learner", "gpr",
             "--validate", "0", "--out", str(out))
    assert r.returncode == 0, r.stderr[-3000:]
    assert "2 strategies on ridge" in r.stdout and "strategy 0: direct" in r.stdout
    with open(out / "shots.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 3 and all(row["strategy"] in ("0", "1") for row in rows)
    assert (out / "strategies.png").stat().st_size > 1000
    assert (out / "models" / "strategies_ridge.npz").exists()
    assert "strategy" in (out / "summary.txt").read_text()
    # the saved strategies are reused
    r = _run("play", "--quick", "--field", str(ridge), "--strategies", "2", "--learner", "gpr",
             "--validate", "0", "--models", str(out / "models"), "--out", str(tmp_path / "t"))
    assert r.returncode == 0 and "reused 2 strategies" in r.stdout


def test_declared_situations_the_robot_cannot_reach_are_named_before_teaching(tmp_path):
    # a sinkhole 1 m deep in the middle of the ball region: the WAM beside the ball cannot
    # put its club there; play says so (which ball positions, what to change) and stops
    spec = json.loads((Path(__file__).resolve().parents[1] / "fields" / "flat.json").read_text())
    spec["surface"] = {"shape": "hills",
                       "hills": [{"x": 0.1, "y": 0.0, "height": -1.0, "width": 0.15}]}
    path = tmp_path / "sinkhole.json"
    path.write_text(json.dumps(spec))
    with pytest.raises(ValueError, match=r"the wam cannot play 1 of 9 declared ball positions "
                                         r"on flat: ball \[0.1, 0.0\].*Declare situations it "
                                         r"can reach") as err:
        play(PlayConfig(field=str(path), quick=True, out=str(tmp_path / "o"),
                        progress=False))
    assert "cannot place the club head" in str(err.value)
    assert not (tmp_path / "o" / "models" / "dataset_flat.npz").exists()


def test_play_config_checks_its_values_and_takes_overrides():
    cfg = PlayConfig(robot="katana", quick=True, out="x", learners=["gmr"])
    assert cfg.learners == ("gmr",) and cfg.shots == 20
    assert cfg.effective().shots == 3 and cfg.effective().validate_shots == 1
    assert PlayConfig(shots=np.int64(5)).shots == 5
    with pytest.raises(ValueError, match="unknown learner 'svm'"):
        PlayConfig(learners=("gpr", "svm"))
    with pytest.raises(ValueError, match="shots must be at least 1, got 0"):
        PlayConfig(shots=0)
    with pytest.raises(ValueError, match="shots must be a whole number"):
        PlayConfig(shots=2.5)
    with pytest.raises(ValueError, match="validate_shots must be at least 0"):
        PlayConfig(validate_shots=-1)
    with pytest.raises(ValueError, match="workers must be at least 1"):
        PlayConfig(workers=0)
    with pytest.raises(ValueError, match="at least one learner"):
        PlayConfig(learners=())
    assert PlayConfig(strategies="3").strategies == 3
    assert PlayConfig(strategies="auto").strategies == "auto"
    with pytest.raises(ValueError, match="strategies must be 'auto' or a whole number"):
        PlayConfig(strategies="some")
    with pytest.raises(ValueError, match="strategies must be at least 1"):
        PlayConfig(strategies=0)
    with pytest.raises(ValueError, match="leave it out with strategies"):
        PlayConfig(strategies="auto", train_size=10)
    # overrides are checked before any work
    with pytest.raises(TypeError, match="no setting 'robots'; valid: robot, field"):
        play(robots="wam")
    with pytest.raises(TypeError, match="config must be a PlayConfig"):
        play("wam")
    with pytest.raises(ValueError, match="unknown robot 'r2d2'"):
        play(PlayConfig(robot="r2d2"), out="unused")
