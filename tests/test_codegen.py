"""The one compile-and-cache helper: verified cache, rebuild of a damaged library, no compiler
left running after a timeout, batched evaluation."""

import os
import subprocess
import sys
import time

import casadi as ca
import numpy as np
import pytest

from seds_casadi.codegen import batch_evaluate, compile_functions, compiler_available
from seds_casadi.codegen.cache import CompileError, _run_compiler

needs_cc = pytest.mark.skipif(compiler_available() is None, reason="no C compiler")

SCRIPT = """
import casadi as ca, numpy as np, sys
from seds_casadi.codegen import compile_functions
x = ca.SX.sym("x", 2)
f = ca.Function("probe_fn_{tag}", [x], [ca.sin(x) * {scale}])
g = compile_functions([f])[0]
print(g is not f, float(np.asarray(g([0.3, 0.7]))[1, 0]))
"""


def _run(tmp_path, tag, scale=2.0):
    env = dict(os.environ, SEDS_CASADI_CACHE=str(tmp_path / "cache"))
    res = subprocess.run([sys.executable, "-c", SCRIPT.format(tag=tag, scale=scale)], env=env,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    compiled, value = res.stdout.split()
    return compiled == "True", float(value)


@needs_cc
@pytest.mark.parametrize("damage", ["truncate", "empty", "garble"])
def test_a_damaged_cached_library_is_rebuilt_not_loaded(tmp_path, damage):
    assert _run(tmp_path, "a") == (True, pytest.approx(2 * np.sin(0.7)))
    libs = [p for p in (tmp_path / "cache").iterdir() if p.suffix == ".so"]
    assert len(libs) == 1 and (tmp_path / "cache" / (libs[0].name + ".sha256")).exists()
    data = libs[0].read_bytes()
    if damage == "truncate":
        libs[0].write_bytes(data[: len(data) // 3])
    elif damage == "empty":
        libs[0].write_bytes(b"")
    else:
        libs[0].write_bytes(data[:100] + bytes(256) + data[356:])
    # loading the damaged file would crash the interpreter (SIGBUS) or fail inside CasADi
    assert _run(tmp_path, "a") == (True, pytest.approx(2 * np.sin(0.7)))
    assert libs[0].read_bytes() == data  # rebuilt to the same bytes


@needs_cc
def test_a_changed_source_never_picks_up_a_stale_library(tmp_path):
    assert _run(tmp_path, "b", 2.0)[1] == pytest.approx(2 * np.sin(0.7))
    assert _run(tmp_path, "b", 3.0)[1] == pytest.approx(3 * np.sin(0.7))


def test_a_compiler_that_times_out_is_killed_with_its_children():
    marker = "31.4159"
    t0 = time.perf_counter()
    with pytest.raises(CompileError, match="longer than"):
        _run_compiler(["sh", "-c", f"sleep {marker} & sleep {marker}"], timeout=0.5)
    assert time.perf_counter() - t0 < 10
    time.sleep(0.2)
    left = subprocess.run(["pgrep", "-f", f"sleep {marker}"], capture_output=True, text=True)
    assert left.stdout.strip() == "", "a compiler process was left running"


def test_a_failing_compiler_reports_its_output():
    with pytest.raises(CompileError, match="no-such-flag"):
        _run_compiler(["sh", "-c", "echo bad option --no-such-flag >&2; exit 1"], timeout=10)


def test_without_a_compiler_the_functions_come_back_unchanged(monkeypatch):
    monkeypatch.setenv("SEDS_CASADI_JIT", "0")
    x = ca.SX.sym("x")
    f = ca.Function("unchanged", [x], [2 * x])
    assert compile_functions([f])[0] is f


def test_batch_evaluate_maps_a_pointwise_function_over_columns():
    x, a = ca.SX.sym("x", 2), ca.SX.sym("a")
    f = ca.Function("f", [x, a], [ca.vertcat(x[0] * a, ca.sin(x[1]), x[0]), ca.dot(x, x)])
    X = np.random.default_rng(0).standard_normal((2, 7))
    out, sq = batch_evaluate(f, X, 2.0)
    np.testing.assert_allclose(out, np.column_stack([2 * X[0], np.sin(X[1]), X[0]]))
    np.testing.assert_allclose(sq[:, 0], np.sum(X**2, axis=0))


def test_a_compiler_never_outlives_the_process_that_started_it():
    """Even a SIGKILL of the Python process (no handler runs) leaves no compiler behind: the
    watchdog that leads the compiler's process group kills the group."""
    marker = "47.1828"
    code = ("from seds_casadi.codegen.cache import _run_compiler\n"
            f"_run_compiler(['sh', '-c', 'sleep {marker} & sleep {marker}'], timeout=600)\n")
    proc = subprocess.Popen([sys.executable, "-c", code])
    try:
        deadline = time.time() + 20
        while time.time() < deadline:  # wait until the fake compiler runs
            if subprocess.run(["pgrep", "-f", f"sleep {marker}"], capture_output=True).stdout:
                break
            time.sleep(0.1)
        else:
            pytest.fail("the fake compiler never started")
        proc.kill()
        proc.wait()
        deadline = time.time() + 5
        while time.time() < deadline:
            left = subprocess.run(["pgrep", "-f", f"sleep {marker}"], capture_output=True,
                                  text=True).stdout.strip()
            if not left:
                break
            time.sleep(0.2)
        assert not left, "the compiler outlived the process that started it"
    finally:
        subprocess.run(["pkill", "-f", f"sleep {marker}"])
