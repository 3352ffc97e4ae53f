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
import subprocess
import sys
import time

import casadi as ca
import numpy as np
import pytest

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
