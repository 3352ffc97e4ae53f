"""Issue 30 (reliability), the classes not covered by ``tests/test_reliability_30.py``; each
test fails on the code before its fix.

3 no wait that never ends: a hanging compiler is stopped (no progress, or the size-bound
  timeout) and the caller falls back to CasADi's virtual machine;
4 numerical functions stay finite for every finite input (the strength factor far away);
6 values with no meaning are refused: boolean demonstrations, unordered times, a field with two
  friction laws, slopes and steps no ball model can follow;
7 nothing left behind: a figure's temporary file after a kill, the run lock after SIGHUP;
8 a cached library swapped with another (with their records) is rebuilt, not loaded.
"""

import logging
import os
import signal
import subprocess
import sys
import time

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_reliability_30c import _plain_model

from seds_casadi.codegen import compile_functions, compiler_available
from seds_casadi.codegen.cache import CompileError, shared_library

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
needs_cc = pytest.mark.skipif(compiler_available() is None, reason="no C compiler")


def _env(**extra) -> dict:
    return dict(os.environ, MPLBACKEND="Agg",
                PYTHONPATH=os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")]), **extra)


# ---------------------------------------------------------------- class 3: a hanging compiler

def _script(tmp_path, name: str, body: str) -> str:
    path = tmp_path / name
    path.write_text("#!/bin/bash\n" + body + "\n")
    path.chmod(0o755)
    return str(path)


def _no_process_left(marker: str) -> None:
    time.sleep(0.2)
    left = subprocess.run(["pgrep", "-f", marker], capture_output=True, text=True).stdout
    assert left.strip() == "", "a compiler process was left running"


@needs_cc
def test_a_hanging_compiler_is_stopped_and_the_functions_fall_back(tmp_path, monkeypatch,
                                                                  caplog):
    """A compiler that never returns (blocked on a lock, a network file system ...): the build
    is killed at the timeout (here set to 2 s by the environment; by default 60 s plus 120 s per
    MB of C) and the functions come back uncompiled, with a warning."""
    marker = "1000.271"
    monkeypatch.setenv("CC", _script(tmp_path, "hang_cc", f"exec sleep {marker}"))
    monkeypatch.setenv("SEDS_CASADI_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("SEDS_CASADI_COMPILE_TIMEOUT", "2")
    x = ca.SX.sym("x", 2)
    f = ca.Function("hang_probe", [x], [3 * x])
    t0 = time.perf_counter()
    with caplog.at_level(logging.WARNING, logger="seds_casadi.codegen"):
        out = compile_functions([f])
    elapsed = time.perf_counter() - t0
    assert out[0] is f and 1.5 < elapsed < 8, elapsed
    assert "longer than 2 s" in caplog.text and "virtual machine" in caplog.text
    _no_process_left(f"sleep {marker}")


@needs_cc
def test_a_compiler_that_makes_no_progress_is_stopped_before_the_timeout(tmp_path,
                                                                        monkeypatch):
    """No CPU time used by the compiler's processes for the stall window: it hangs, whatever
    the timeout; a compiler busy for longer than the window is left to finish."""
    marker = "1000.314"
    gcc = compiler_available()
    monkeypatch.setenv("SEDS_CASADI_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("CC", _script(tmp_path, "hang_cc", f"exec sleep {marker}"))
    t0 = time.perf_counter()
    with pytest.raises(CompileError, match="no progress"):
        shared_library(b"double f(double x) { return x; }\n", "stall", timeout=600, stall=1.0)
    assert time.perf_counter() - t0 < 5
    _no_process_left(f"sleep {marker}")
    # busy for 2.5 s (2.5 stall windows) before it compiles: not a hang
    monkeypatch.setenv("CC", _script(
        tmp_path, "busy_cc",
        f"end=$(( $(date +%s%N) + 2500000000 )); while [ $(date +%s%N) -lt $end ]; do :; done\n"
        f'exec {gcc} "$@"'))
    lib = shared_library(b"double g(double x) { return 2 * x; }\n", "busy", stall=1.0)
    assert os.path.getsize(lib) > 0


# ------------------------------------------------------ class 8: swapped libraries in the cache

_PROBE = """
import casadi as ca, numpy as np
from seds_casadi.codegen import compile_functions
x = ca.SX.sym("x", 2)
out = []
for name, scale in (("swap_a", 2.0), ("swap_b", 3.0)):
    f = ca.Function(name, [x], [ca.sin(x) * scale])
    g = compile_functions([f])[0]
    out.append(f"{g is not f}:{float(np.asarray(g([0.3, 0.7]))[1, 0]):.12f}")
print(" ".join(out))
"""


@needs_cc
def test_two_cached_libraries_swapped_with_their_records_are_rebuilt(tmp_path):
    """Swapping two libraries together with their ``.sha256`` files left each matching its
    record, and every later fit failed with "undefined symbol" until the cache was cleared: the
    record now names the library it belongs to."""
    cache = tmp_path / "cache"

    def run() -> str:
        res = subprocess.run([sys.executable, "-c", _PROBE], env=_env(SEDS_CASADI_CACHE=str(cache)),
                             capture_output=True, text=True, timeout=120)
        assert res.returncode == 0, res.stderr[-2000:]
        return res.stdout.strip()

    want = f"True:{2 * np.sin(0.7):.12f} True:{3 * np.sin(0.7):.12f}"
    assert run() == want
    a, b = sorted(p for p in cache.iterdir() if p.suffix == ".so")
    data_a, data_b = a.read_bytes(), b.read_bytes()
    for suffix in ("", ".sha256"):
        pa, pb = f"{a}{suffix}", f"{b}{suffix}"
        os.rename(pa, pa + ".x")
        os.rename(pb, pa)
        os.rename(pa + ".x", pb)
    assert a.read_bytes() == data_b
    assert run() == want
    assert a.read_bytes() == data_a and b.read_bytes() == data_b  # rebuilt in place


# --------------------------------------- class 4: finite for every finite input (far away)

def _strength_model():
    """A certified 2-D model of two components (test_reliability_30c's ``_plain_model``),
    without and with a two-component strength factor over (x, log v)."""
    from seds_casadi import StableDS
    from seds_casadi.core.strength import StrengthFactor

    plain = _plain_model()
    sf_means = np.array([[1.0, 0.5, np.log(0.8)], [-0.5, 1.5, np.log(0.3)]])
    sf_covs = np.array([[[0.09, 0.0, 0.02], [0.0, 0.09, -0.01], [0.02, -0.01, 0.05]],
                        [[0.25, 0.05, 0.0], [0.05, 0.25, 0.03], [0.0, 0.03, 0.08]]])
    strength = StrengthFactor([0.6, 0.4], sf_means, sf_covs, log_range=(np.log(0.2), np.log(1.0)))
    with_v = StableDS(plain.priors, plain.means, plain.covariances, plain.target,
                      strength=strength, strength_radius=0.05)
    return plain, with_v


_FINITE = st.floats(min_value=-1.7e308, max_value=1.7e308, allow_nan=False)


@settings(max_examples=150, deadline=None)
@given(st.lists(_FINITE, min_size=2, max_size=2), st.sampled_from([1.0, 1e-150, 1e150]))
def test_the_strength_model_is_finite_for_every_finite_point(xy, scale):
    """v(x), f_v(x) and Eq. 8's h(x) are finite everywhere: NaN came from |x| ~ 1e155 on
    (inf - inf in the Gaussians' exponents, rho = inf / inf)."""
    plain, model = _MODELS
    with np.errstate(over="ignore"):
        x = np.clip(np.asarray(xy) * scale, -1.7e308, 1.7e308)
    v = model.strength(x)
    assert np.isfinite(v) and 0.1 - 1e-12 <= v <= 2.0 + 1e-12  # half the slowest, twice the fastest
    f = model.predict(x)
    assert np.all(np.isfinite(f)) and np.linalg.norm(f) <= v * (1 + 1e-9)
    h = _FIELD(x)
    assert np.all(np.isfinite(h)) and abs(np.linalg.norm(h) - 1) < 1e-9
    if np.max(np.abs(x - model.target)) > 1e-6:  # f_v points along f (the same streamlines)
        g = plain.predict(x)
        if np.all(np.isfinite(g)) and np.max(np.abs(g)) > 0:
            g = g / np.max(np.abs(g))
            cos = np.dot(f, g) / (np.linalg.norm(f) * np.linalg.norm(g))
            assert cos > 1 - 1e-9


def test_the_far_rule_leaves_the_model_unchanged_near_the_data_and_is_continuous():
    """Within 1e6 times the data's extent: the numpy oracle of Eq. 12 and of f_v; beyond it the
    value at the pulled-back point, which joins it continuously."""
    from oracles import strength_factor, strength_model_velocity

    _, model = _MODELS
    sf = model.strength
    X = np.random.default_rng(3).normal(size=(200, 2)) * np.array([[1.0], [30.0]]).repeat(100, 0)
    np.testing.assert_allclose(model.strength(X), strength_factor(
        X, sf.priors, sf.means, sf.covariances, sf.log_range), rtol=1e-12)
    np.testing.assert_allclose(model.predict(X), strength_model_velocity(X, model),
                               rtol=1e-9, atol=1e-12)
    u = np.array([0.6, -0.8])
    for r in (1e5, 1e7, 1e100, 1e300):  # along a ray the value settles (x* is 0.5 off the ray)
        np.testing.assert_allclose(model.predict(u * r), model.predict(u * 1e7), rtol=1e-4)


def test_a_rollout_from_far_away_runs_or_says_it_overflows():
    """A strength model moves at most twice its fastest speed: from 1e300 it runs (finite
    distances in its warning); a plain model whose velocity overflows (at 1.7e308) stops with a
    message that says so (it failed with "x0 contains NaN or infinite values")."""
    from seds_casadi.core.errors import ConvergenceWarning

    _, model = _MODELS
    with pytest.warns(ConvergenceWarning, match=r"did not reach the target .* 1\.41e\+300 away"):
        path = model.rollout(np.array([1e300, 1e300]), dt=0.01, max_steps=5)
    assert path.shape == (6, 2) and np.all(np.isfinite(path))
    plain, _ = _MODELS
    with pytest.raises(ValueError, match=r"start\(s\) \[1\] left the range of floating-point"):
        plain.rollout(np.array([[1.0, 1.0], [1.7e308, -1.7e308]]), dt=0.01, max_steps=5,
                      warn=False)


def _field():
    from seds_casadi.motion.target_field import TargetField

    return TargetField(_MODELS[0])


_MODELS = _strength_model()
_FIELD = _field()


# ------------------------------------------- class 6: values with no meaning are refused

def test_boolean_demonstrations_are_refused():
    from seds_casadi import Demonstrations

    mask = np.array([[True, False], [False, True], [True, True], [False, False]])
    with pytest.raises(TypeError, match=r"positions\[0\]: boolean values"):
        Demonstrations([mask], dt=0.1)
    with pytest.raises(TypeError, match=r"velocities\[0\]: boolean values"):
        Demonstrations([mask.astype(float)], velocities=[mask])
    with pytest.raises(TypeError, match="X: boolean values"):
        Demonstrations.from_samples(mask, mask.astype(float))


_CSV = "demo,t,x0,x1{v}\n" + "".join(
    f"0,{t},{x},{x}{{v{i}}}\n" for i, (t, x) in enumerate([(0.0, 1.0), (0.1, 0.6), (0.2, 0.3),
                                                            (0.3, 0.0)]))


@pytest.mark.parametrize("velocities", [False, True])
def test_a_csv_whose_rows_are_out_of_time_order_is_refused(tmp_path, velocities):
    """With velocity columns the ``t`` column was never read: shuffled rows were fitted as
    given (the direction objective's phase and the trimming read the row order)."""
    from seds_casadi import load_demonstrations

    vel = {f"v{i}": (",-4,-4" if velocities else "") for i in range(4)}
    text = _CSV.format(v=",v0,v1" if velocities else "", **vel)
    ok = tmp_path / "ok.csv"
    ok.write_text(text)
    assert load_demonstrations(ok).n_samples == 4
    lines = text.splitlines()
    lines[2], lines[3] = lines[3], lines[2]  # the samples at t = 0.1 and 0.2 swapped
    bad = tmp_path / "shuffled.csv"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=r"shuffled.csv: line 4: t = 0.1 does not come after "
                                         r"t = 0.2 .* time order"):
        load_demonstrations(bad)


def _field_spec(**changes) -> dict:
    import json

    from seds_casadi.minigolf.fields import FIELDS_FOLDER

    with open(os.path.join(FIELDS_FOLDER, "flat.json")) as fh:
        spec = json.load(fh)
    spec.update(changes)
    return spec


@pytest.mark.parametrize("surface, match", [
    ({"shape": "plane", "slope_x": 1e6, "slope_y": 0.0}, r"rises 1e\+06 m per metre"),
    ({"shape": "plane", "slope_x": 8.0, "slope_y": 8.0}, r"rises 11.3 m per metre"),
    # steps 0.1 mm and 0.1 um wide, centred between the 1 cm grid's lines (the grid saw them
    # nearly flat: 2 /m and 1e-5 /m, against the 47 /m of the ball's radius)
    ({"shape": "arctan", "height": 0.002, "steepness": 1e4, "y0": 0.005},
     r"radius of 0.0121 mm near \(-0.300, 0.005\)"),
    ({"shape": "arctan", "height": 1e-5, "steepness": 1e7, "y0": 0.005}, "radius of 2.42e-06 mm"),
    # a step 5 mm wide, gentle enough (slope 0.51) but curved 66 /m
    ({"shape": "arctan", "height": 0.004, "steepness": 200, "y0": 0.005}, r"radius of 15.\d mm"),
    ({"shape": "hills", "hills": [{"x": 1.005, "y": 0.005, "height": 1e-4, "width": 1e-4}]},
     r"curves with a radius of 0.1 mm near \(1.005, 0.005\)"),
    ({"shape": "rough", "amplitude": 1e-4, "width": 2e-4, "bumps": 30}, "curves with a radius"),
])
def test_surfaces_no_ball_can_roll_on_are_refused(surface, match):
    """Slopes beyond 84 deg (walls), and steps or bumps curved tighter than the ball however narrow:
    the curvature check sampled a 1 cm grid (and a hill 0.1 mm wide made it allocate 47 GB)."""
    from seds_casadi.minigolf.fields import Field

    t0 = time.perf_counter()
    with pytest.raises(ValueError, match=match):
        Field.from_dict(_field_spec(name="steep", surface=surface), "steep.json")
    assert time.perf_counter() - t0 < 3


def test_the_shipped_fields_keep_their_extremes():
    """The closed-form points add nothing where the grid already saw the extremes (arctan's
    largest curvature is now exact: (2/pi) h s^2 3 sqrt(3) / 8)."""
    from seds_casadi.minigolf.fields import load_field

    arctan = load_field("arctan")
    h, s = 0.05, 4.0
    ext = arctan.surface.extremes(arctan.bounds)
    assert ext["curvature"] == pytest.approx(2 / np.pi * h * s**2 * 3 * np.sqrt(3) / 8, rel=1e-9)
    assert ext["slope"] == pytest.approx(2 / np.pi * h * s, rel=1e-9)
    hills = load_field("double_hill").surface.extremes(load_field("double_hill").bounds)
    assert 1.5 < hills["curvature"] < 2.0 and 0.1 < hills["slope"] < 0.2


def test_a_field_with_two_surface_speeds_is_refused_and_errors_print_plain_numbers():
    from seds_casadi.minigolf.fields import Field

    with pytest.raises(ValueError, match=r"both 'stimp' \(10\) and 'rolling_resistance' "
                                         r"\(0.07\) given"):
        Field.from_dict(_field_spec(rolling_resistance=0.07), "two.json")
    with pytest.raises(ValueError) as err:
        Field.from_dict(_field_spec(hole={"x": 3.2, "y": 0.0}), "far.json")
    assert str(err.value) == "far.json: hole at [3.2, 0] is outside the field [-0.3, 3, -0.6, 0.6]"
    with pytest.raises(ValueError, match=r"ball_region \[-0.5, 0.3, -0.2, 0.2\] is not inside "
                                         r"the bounds \[-0.3, 3, -0.6, 0.6\]$"):
        Field.from_dict(_field_spec(ball_region=[-0.5, 0.3, -0.2, 0.2]), "region.json")


@pytest.mark.parametrize("argv, match", [
    (["play", "--replay", "0"], "argument --replay: must be at least 1, got 0"),
    (["lasa", "--samples", "0"], "argument --samples: must be at least 2, got 0"),
    (["lasa", "--samples", "x"], "argument --samples: expected a whole number, got 'x'"),
])
def test_counts_that_mean_nothing_are_refused_on_the_command_line(tmp_path, capsys, argv, match):
    """``--replay 0`` wrote nothing, ``lasa --samples 0`` meant "all", silently."""
    from seds_casadi.app.cli import main

    with pytest.raises(SystemExit) as exc:
        main([*argv, "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    assert match in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------- class 7: nothing left behind

_SAVE_BIG = """
import sys
from seds_casadi.app.plotting import pyplot, save_figure
plt = pyplot()
fig, ax = plt.subplots(figsize=(60, 60))
ax.plot(range(100000))
print("saving", flush=True)
save_figure(fig, sys.argv[1], dpi=150)
"""


def test_a_figure_killed_while_saving_leaves_nothing_the_next_run_keeps(tmp_path):
    """A run killed while it saves a figure leaves its temporary file (SIGKILL: no clean-up
    can run); its name must be one the next run's sweep removes (it was NAME.tmp-PID.png, and
    the sweep removes only names starting with '.tmp-')."""
    from seds_casadi.app.outdir import LOCK_NAME, output_folder

    out = tmp_path / "out"
    out.mkdir()
    proc = subprocess.Popen([sys.executable, "-c", _SAVE_BIG, str(out / "motion.png")],
                            env=_env(), stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "saving"
        deadline = time.time() + 60
        while time.time() < deadline and proc.poll() is None:
            left = [p.name for p in out.iterdir()]
            if left:
                break
            time.sleep(0.005)
        proc.kill()
        proc.wait()
    finally:
        if proc.poll() is None:
            proc.kill()
    left = sorted(p.name for p in out.iterdir())
    assert left and all(n.startswith(".tmp-") and n.endswith("-motion.png") for n in left), left
    with output_folder(out):  # the next run on the folder
        assert sorted(p.name for p in out.iterdir()) == [LOCK_NAME]
    assert list(out.iterdir()) == []


def test_sighup_ends_a_command_like_ctrl_c_and_removes_the_run_lock(tmp_path):
    """Closing the terminal (SIGHUP) killed the command by default and left the run lock
    (.seds-casadi.lock) in --out; it now ends it like Ctrl-C: exit 130, nothing left."""
    out = tmp_path / "out"
    code = ("import signal; signal.signal(signal.SIGINT, signal.default_int_handler); "
            "import sys; from seds_casadi.app.cli import main; sys.exit(main())")
    proc = subprocess.Popen([sys.executable, "-c", code, "lasa", "--shapes", "Sshape", "Leaf_1",
                             "--objectives", "mse", "--protocols", "all", "-K", "2",
                             "--no-figures", "--out", str(out)],
                            env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lock = out / ".seds-casadi.lock"
    deadline = time.time() + 60
    while not lock.exists() and time.time() < deadline and proc.poll() is None:
        time.sleep(0.01)
    assert lock.exists(), proc.communicate()[1][-2000:]
    time.sleep(0.3)
    t0 = time.perf_counter()
    proc.send_signal(signal.SIGHUP)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err[-2000:]
    assert time.perf_counter() - t0 < 2
    assert "interrupted" in err
    assert not lock.exists() and not (out / "lasa.csv").exists()


# ------------------------------------------------ issue 31: the replay GIF's size and legend

def test_the_replay_gif_is_large_enough_for_a_paper(tmp_path):
    """1000 x 750 pixels (it was 576 x 432), from a replay given as arrays (a straight arm,
    a ball rolling towards the hole)."""
    from PIL import Image

    from seds_casadi.app.replay import REPLAY_COLOURS, Replay, write_replay_gif
    from seds_casadi.minigolf.fields import load_field

    fld = load_field("arctan")
    n = 4
    t = np.linspace(0, 0.3, n)
    chain = np.array([[[0, 0.3, 0], [0, 0.3, 0.5], [0.1, 0.1, 0.5], [0.1, 0.1, 0.05]]] * n)
    ball = np.column_stack([np.linspace(0.1, 1.0, n), np.zeros(n), np.full(n, 0.03)])
    row = {"hole_x_m": fld.hole[0], "hole_y_m": fld.hole[1], "alpha_deg": 0.0, "kappa": 1.0}
    r = Replay(t, chain, chain[:, -2:], ball, 2, 0.1, "gpr shot 0 (missed)", row, fld.name, "wam")
    path = write_replay_gif(r, fld, tmp_path / "r.gif")
    with Image.open(path) as im:
        assert im.size == (1000, 750) and im.n_frames == n
        px = np.asarray(im.convert("RGB")).reshape(-1, 3).astype(int)
    assert np.sum(np.all(np.abs(px - REPLAY_COLOURS["robot"]) <= 40, axis=1)) > 100
    assert [p.name for p in tmp_path.iterdir()] == ["r.gif"]
