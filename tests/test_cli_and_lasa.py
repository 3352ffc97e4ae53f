"""The command line (through the installed console script) and the LASA benchmark runner."""

import csv
import logging
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from seds_casadi import StableDS, save_demonstrations
from seds_casadi.app.cli import build_parser, command_logging
from seds_casadi.app.lasa import CSV_COLUMNS, evaluate_shape, run_lasa
from seds_casadi.core.datasets import LASA_SHAPES, LASA_SINGLE_SHAPES, load_lasa

pytestmark = pytest.mark.slow


def _cli():
    exe = shutil.which("seds-casadi")
    if exe is None:  # not installed as a console script: fall back to the module
        return [sys.executable, "-m", "seds_casadi"]
    return [exe]


def test_all_lasa_shapes_load_offline():
    assert len(LASA_SHAPES) == 30 and len(LASA_SINGLE_SHAPES) == 26
    for name in LASA_SHAPES:
        d = load_lasa(name)
        assert d.n_demos == 7 and d.n_dims == 2
        assert all(950 <= len(p) <= 1000 for p in d.positions)
    with pytest.raises(ValueError, match="unknown LASA shape"):
        load_lasa("Circle")


def test_evaluate_shape_split_protocol_scores_held_out_demos(tmp_path):
    r = evaluate_shape("GShape", objective="direction", protocol="split", n_components=2,
                       n_samples=30, figure_path=str(tmp_path / "g.png"))
    assert r.e_dot < 0.2 and r.rmse > 0 and r.dtwd > 0 and r.iterations > 0
    assert (tmp_path / "g.png").stat().st_size > 1000


def test_cli_fit_writes_a_loadable_model_and_figure(tmp_path, spiral_demos):
    demo_file = tmp_path / "demos.npz"
    save_demonstrations(demo_file, spiral_demos)
    out = tmp_path / "out"
    res = subprocess.run(_cli() + ["fit", str(demo_file), "-K", "2", "--objective", "mse",
                                   "--out", str(out)], capture_output=True, text=True,
                         timeout=600)
    assert res.returncode == 0, res.stderr
    model = StableDS.load(out / "model.npz")
    assert model.n_components == 2
    assert (out / "streamlines.png").stat().st_size > 1000
    assert '"status"' in res.stdout


def test_cli_fit_with_a_learned_lyapunov_matrix_and_a_gain_limit(tmp_path, spiral_demos):
    demo_file = tmp_path / "demos.npz"
    save_demonstrations(demo_file, spiral_demos)
    out = tmp_path / "out"
    res = subprocess.run(_cli() + ["fit", str(demo_file), "-K", "2", "--objective", "mse",
                                   "--lyapunov", "learned", "--gain-limit", "10",
                                   "--init", "lpv", "--out", str(out)], capture_output=True, text=True,
                         timeout=600)
    assert res.returncode == 0, res.stderr
    model = StableDS.load(out / "model.npz")
    assert model.fit_info["lyapunov"] == "learned"
    assert model.fit_info["init"] == "lpv"
    P = model.lyapunov_matrix
    assert np.trace(P) == pytest.approx(2.0)
    for A in model.A:
        assert np.linalg.eigvalsh(A.T @ P + P @ A).max() < 0


def test_cli_fit_with_a_fixed_physically_consistent_gmm(tmp_path, spiral_demos):
    demo_file = tmp_path / "demos.npz"
    save_demonstrations(demo_file, spiral_demos)
    out = tmp_path / "out"
    res = subprocess.run(_cli() + ["fit", str(demo_file), "-K", "3", "--objective", "mse",
                                   "--lyapunov", "learned", "--init", "pc", "--gmm", "fixed",
                                   "--out", str(out)], capture_output=True, text=True,
                         timeout=600)
    assert res.returncode == 0, res.stderr
    model = StableDS.load(out / "model.npz")  # the certificate is re-checked on load
    assert model.fit_info["init"] == "pc" and model.fit_info["gmm"] == "fixed"
    assert model.fit_info["sums"] == "gram"
    bad = subprocess.run(_cli() + ["fit", str(demo_file), "--gmm", "frozen"],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "--gmm" in bad.stderr


def test_cli_fit_chooses_settings_on_held_out_demonstrations(tmp_path, spiral_demos):
    demo_file = tmp_path / "demos.npz"
    save_demonstrations(demo_file, spiral_demos)
    out = tmp_path / "out"
    res = subprocess.run(_cli() + ["fit", str(demo_file), "-K", "2", "--objective", "mse",
                                   "--max-iter", "150", "--choose", "lyapunov=identity,learned",
                                   "--choose", "gain-limit=none,10", "--out", str(out)],
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    model = StableDS.load(out / "model.npz")
    record = model.fit_info["search"]
    assert len(record["candidates"]) == 4
    assert {"lyapunov": "identity", "gain_limit": None} in record["candidates"]
    assert record["best_params"]["lyapunov"] == model.fit_info["lyapunov"]
    assert "rank" in res.stdout and '"chosen"' in res.stdout
    assert "fold" in res.stdout + res.stderr  # the search's progress lines
    bad = subprocess.run(_cli() + ["fit", str(demo_file), "--choose", "lyapunov"],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "NAME=A,B" in bad.stderr
    bad = subprocess.run(_cli() + ["fit", str(demo_file), "--choose", "n_gaussians=2,3"],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "n_gaussians" in bad.stderr


def test_cli_lasa_writes_the_csv_with_the_documented_columns(tmp_path):
    out = tmp_path / "lasa"
    res = subprocess.run(_cli() + ["lasa", "--shapes", "Angle", "--objectives", "direction",
                                   "mse", "--protocols", "all", "-K", "2", "--samples", "25",
                                   "--out", str(out)],
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    with open(out / "lasa.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert tuple(rows[0].keys()) == CSV_COLUMNS
    assert {r["objective"] for r in rows} == {"direction", "mse"}
    assert all(float(r["e_dot"]) < 0.3 for r in rows)
    assert (out / "summary.txt").exists()
    assert os.path.exists(out / "figures" / "Angle_direction.png")


def test_cli_reports_bad_input_clearly(tmp_path):
    res = subprocess.run(_cli() + ["fit", str(tmp_path / "nope.csv")], capture_output=True,
                         text=True, timeout=120)
    assert res.returncode == 2
    assert "no demonstrations file" in res.stderr
    res = subprocess.run(_cli() + ["lasa", "--shapes", "Circle", "--out", str(tmp_path)],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and "unknown LASA shape" in res.stderr
    bad = tmp_path / "nan.csv"
    bad.write_text("demo,t,x0,x1\n0,0,1,nan\n0,1,0,0\n")
    res = subprocess.run(_cli() + ["fit", str(bad)], capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and "NaN" in res.stderr


def test_run_lasa_in_process_pool_matches_serial():
    kw = dict(shapes=["Angle"], objectives=["direction"], protocols=["all"], n_components=2,
              n_samples=20, progress=False, figures=False)
    a = run_lasa(workers=1, **kw)
    b = run_lasa(workers=2, **kw)
    assert a[0].e_dot == pytest.approx(b[0].e_dot, rel=1e-12)
    assert np.isfinite(a[0].dtwd)
    with pytest.raises(ValueError, match="workers"):
        run_lasa(workers=0, **kw)


def test_command_logging_prints_the_commands_progress_plainly(capsys):
    log = logging.getLogger("seds_casadi.app.play")
    with command_logging():
        log.info("teacher: %d good shots on %s", 56, "arctan")
        log.info("table\n  two lines\n")
        # the lower layers' progress (e.g. compiling a kernel) stays out of the output
        logging.getLogger("seds_casadi.codegen.cache").info("compiling ball_steps")
    with command_logging(quiet=True):
        log.info("not with --quiet")
        log.warning("a warning goes to stderr")
    log.info("outside a command: not printed")
    out, err = capsys.readouterr()
    assert out == "teacher: 56 good shots on arctan\ntable\n  two lines\n\n"
    assert err == "a warning goes to stderr\n"
    assert build_parser().parse_args(["play", "--quiet"]).quiet
    assert not build_parser().parse_args(["table1"]).quiet
