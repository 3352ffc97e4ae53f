"""Fuzz campaign (issue 30's kind): every input a user can give, each case classified.

Not part of the test suite: a script that runs a few hundred cases on the current code and
prints a table of counts by class. Areas: model files, demonstration files, field files, every
command's options, ``--out``, named pipes and devices as inputs, the Python API, signals during
each command, concurrent runs on one ``--out``.

Each case ends in one class:

OK                   a clean run (with outputs that mean something), or a clear error: exit
                     code 1 or 2 and no traceback (a ``ValueError``/``TypeError``/project
                     error raised by seds_casadi's own code, from the API)
TRACEBACK            a traceback on the command line, or an exception from the API that is not
                     a project error or escaped from inside a library
SILENTLY_WRONG       input with no meaning accepted, an output that is NaN or missing, an
                     interrupted run that exits other than 130 or writes outputs as complete
HANG                 not finished within the case's timeout (or an interrupt not obeyed in 2 s)
CRASH                death by a signal, or an exit code that is neither 0, 1, 2 nor 130
LEFT_BEHIND          temporary files, the run lock, files in TMPDIR or processes left
TEMPNAME_IN_MESSAGE  a message that names a temporary file

Run (one core, so that other work is not disturbed)::

    taskset -c 1 python benchmarks/fuzz_reliability.py [--only AREA,...] [--match SUBSTRING]

``--sweep N`` adds N signal cases per command at random moments of its run (area
``signal-sweep``, ``--seed`` for others): ``--only signal-sweep --sweep 20`` is the interrupt
stress test.

The failing cases' details go to ``/tmp/fuzz_reliability/failures.txt`` (``--report``).
Python API cases run in a worker process that is restarted after a hang or a crash.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
import traceback
import zipfile
from dataclasses import dataclass, field

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CLASSES = ("OK", "TRACEBACK", "SILENTLY_WRONG", "HANG", "CRASH", "LEFT_BEHIND",
           "TEMPNAME_IN_MESSAGE")
TEMPNAME = re.compile(r"\.tmp-[\w.-]*|\btmp[a-z0-9_]{6,}\b")
WORK = "/tmp/fuzz_reliability"
#: signal cases per command at random moments, and their seed (``--sweep``, ``--seed``)
SWEEP, SWEEP_SEED = 0, 0


# ====================================================================== cases
@dataclass
class Case:
    area: str
    name: str
    kind: str  # "api", "cli", "signal", "concurrent"
    # api: the name of a function of API_CASES and its arguments
    func: str = ""
    args: tuple = ()
    # cli / signal / concurrent
    argv: list = field(default_factory=list)
    setup: object = None  # callable(case_dir) -> dict of placeholders for argv
    expect: str = "either"  # "refuse", "accept", "either"
    outputs: tuple = ()  # files a complete run writes under --out (checked when accepted)
    timeout: float = 120.0
    sig: int = 0
    delay: float = 0.0


CASES: list[Case] = []


def api(area, name, func, *args, expect="either", timeout=120.0):
    CASES.append(Case(area, name, "api", func=func, args=args, expect=expect, timeout=timeout))


def cli(area, name, argv, setup=None, expect="either", outputs=(), timeout=120.0):
    CASES.append(Case(area, name, "cli", argv=list(argv), setup=setup, expect=expect,
                      outputs=tuple(outputs), timeout=timeout))


# ---------------------------------------------------------------- shared inputs (built once)
def base_path(*parts) -> str:
    return os.path.join(WORK, "base", *parts)


def small_demos():
    from seds_casadi import Demonstrations
    from seds_casadi.core import load_lasa

    d = load_lasa("Sshape")
    pos = [p[::20] for p in d.positions[:3]]
    vel = [v[::20] for v in d.velocities[:3]]
    return Demonstrations(pos, velocities=vel)


def build_base() -> None:
    """The inputs the cases start from: small demonstrations (.npz, .csv), a fitted model with
    a strength factor, and the shipped fields."""
    from seds_casadi import SEDS, save_demonstrations

    os.makedirs(base_path(), exist_ok=True)
    d = small_demos()
    save_demonstrations(base_path("demos.npz"), d)
    rows = []
    for i, (p, v) in enumerate(zip(d.positions, d.velocities)):
        for j in range(len(p)):
            rows.append([i, 0.02 * j, *p[j], *v[j]])
    header = "demo,t,x0,x1,v0,v1"
    np.savetxt(base_path("demos.csv"), np.array(rows), delimiter=",", header=header,
               comments="", fmt="%.10g")
    m = SEDS(3, objective="direction", random_state=0, max_iter=200).fit(d).model_
    m.save(base_path("model.npz"))
    m2 = SEDS(3, objective="mse", random_state=0, max_iter=200).fit(d).model_
    m2.save(base_path("model_plain.npz"))


# ====================================================================== API case functions
class Refused(Exception):
    """Not used: API functions raise the library's own exceptions."""


def _model():
    from seds_casadi import StableDS

    return StableDS.load(base_path("model.npz"))


def _finite(a) -> bool:
    return bool(np.all(np.isfinite(np.asarray(a, dtype=float))))


def _check_loaded_model(m, ref_path=None) -> str | None:
    """A model that loaded: finite predictions, and the original's when ``ref_path``."""
    from seds_casadi import StableDS

    X = np.array([[0.0, 0.0], [-10.0, 5.0], [3.0, -2.0], [1e6, -1e6], [-1e100, 1e100],
                  [1e300, 1e300]])[:, :m.n_dims] if m.n_dims == 2 else np.zeros((3, m.n_dims))
    y = m.predict(X)
    if not _finite(y):
        return f"a loaded model predicts non-finite velocities {y}"
    if ref_path is not None:
        ref = StableDS.load(ref_path)
        if ref.n_dims == m.n_dims and not np.allclose(ref.predict(X), y):
            return "a corrupted model file loaded as a different model"
    return None


# ---- model files
def _raw_entries(path) -> dict:
    with np.load(path, allow_pickle=False) as f:
        return {k: f[k] for k in f.files}


def _write_npz(path, entries) -> None:
    with open(path, "wb") as fh:
        np.savez(fh, **entries)


def _rewrite_guarded(path, mutate) -> None:
    """Rewrite the base model with ``mutate(arrays, meta)`` applied and a valid checksum."""
    from seds_casadi.core.model_files import write_guarded

    e = _raw_entries(base_path("model.npz"))
    meta = json.loads(str(e.pop("fit_info")))
    version = int(e.pop("version"))
    kind = str(e.pop("format"))
    e.pop("checksum")
    arrays = dict(e)
    res = mutate(arrays, meta)
    if res is not None:
        arrays, meta = res
    write_guarded(path, kind, version, arrays, meta, meta_key="fit_info",
                  json_default=lambda v: str(v))


def model_bytes(d, how, arg=None) -> str | None:
    from seds_casadi import StableDS

    src = open(base_path("model.npz"), "rb").read()
    path = os.path.join(d, "m.npz")
    rng = np.random.default_rng(hash((how, str(arg))) % 2**32)
    if how == "truncate":
        data = src[:int(len(src) * arg)]
    elif how == "flip":
        b = bytearray(src)
        for i in rng.integers(0, len(b), int(arg)):
            b[i] ^= 1 << int(rng.integers(0, 8))
        data = bytes(b)
    elif how == "garbage":
        data = rng.bytes(int(arg))
    elif how == "empty":
        data = b""
    elif how == "text":
        data = b"not a model\n" * 10
    elif how == "append":
        data = src + rng.bytes(int(arg))
    else:
        raise AssertionError(how)
    open(path, "wb").write(data)
    m = StableDS.load(path)
    return _check_loaded_model(m, base_path("model.npz"))


def _zip_bomb(path, entry, nbytes, header_dtype="<U1", real=None) -> None:
    """An .npz whose ``entry`` decompresses to ``nbytes`` (a consistent .npy header)."""
    e = _raw_entries(base_path("model.npz")) if real is None else real
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for k, v in e.items():
            if k == entry:
                continue
            with z.open(k + ".npy", "w") as fh:
                np.lib.format.write_array(fh, np.asarray(v), allow_pickle=False)
        dt = np.dtype(header_dtype)
        n = nbytes // dt.itemsize
        hdr = {"descr": np.lib.format.dtype_to_descr(dt), "fortran_order": False,
               "shape": (n,)}
        import io
        buf = io.BytesIO()
        np.lib.format.write_array_header_1_0(buf, hdr)
        with z.open(entry + ".npy", "w", force_zip64=True) as fh:
            fh.write(buf.getvalue())
            chunk = b"\0" * (1 << 22)
            left = n * dt.itemsize
            while left > 0:
                fh.write(chunk[:min(left, len(chunk))])
                left -= len(chunk)


def model_bomb(d, entry, nbytes, dtype) -> str | None:
    from seds_casadi import StableDS

    path = os.path.join(d, "m.npz")
    _zip_bomb(path, entry, int(nbytes), dtype)
    t = time.perf_counter()
    m = StableDS.load(path)
    return (f"a zip bomb ({nbytes / 1e6:.0f} MB in {entry!r}) loaded after "
            f"{time.perf_counter() - t:.1f} s: {m}")


def model_crafted(d, how) -> str | None:
    """A model file with a valid checksum whose arrays are wrong (the checksum does not help:
    the load must re-validate)."""
    from seds_casadi import StableDS

    path = os.path.join(d, "m.npz")

    def mutate(a, meta):
        K = len(a["priors"])
        if how == "priors_nan":
            a["priors"] = a["priors"] * np.nan
        elif how == "priors_inf":
            a["priors"] = a["priors"] + np.inf
        elif how == "priors_negative":
            a["priors"] = -a["priors"]
        elif how == "priors_zero":
            a["priors"] = 0 * a["priors"]
        elif how == "priors_unnormalised":
            a["priors"] = 1e6 * a["priors"]
        elif how == "priors_tiny":
            a["priors"] = 1e-320 * np.ones_like(a["priors"])
        elif how == "means_nan":
            a["means"] = a["means"] * np.nan
        elif how == "means_huge":
            a["means"] = a["means"] * 1e300
        elif how == "cov_nan":
            a["covariances"] = a["covariances"] * np.nan
        elif how == "cov_zero":
            a["covariances"] = 0 * a["covariances"]
        elif how == "cov_negative":
            a["covariances"] = -a["covariances"]
        elif how == "cov_asymmetric":
            c = a["covariances"].copy()
            c[:, 0, -1] += 5.0
            a["covariances"] = c
        elif how == "cov_huge":
            a["covariances"] = a["covariances"] * 1e300
        elif how == "cov_tiny":
            a["covariances"] = a["covariances"] * 1e-300
        elif how == "target_nan":
            a["target"] = a["target"] * np.nan
        elif how == "target_huge":
            a["target"] = a["target"] + 1e308
        elif how == "wrong_shape_means":
            a["means"] = a["means"][:, :1]
        elif how == "wrong_K":
            a["priors"] = np.append(a["priors"], 0.1)
        elif how == "1d_target":
            a["target"] = a["target"][:1]
        elif how == "int_dtype":
            a["priors"] = (a["priors"] * 100).astype(np.int64)
        elif how == "bool_dtype":
            a["priors"] = a["priors"] > 0
        elif how == "complex_dtype":
            a["means"] = a["means"].astype(complex)
        elif how == "string_dtype":
            a["priors"] = np.array(["a"] * K)
        elif how == "float16":
            a["covariances"] = a["covariances"].astype(np.float16)
        elif how == "scalar_priors":
            a["priors"] = np.array(1.0)
        elif how == "lyap_nan":
            a["lyapunov"] = a["lyapunov"] * np.nan if "lyapunov" in a else np.full((2, 2), np.nan)
        elif how == "lyap_indefinite":
            a["lyapunov"] = -np.eye(2)
        elif how == "strength_nan":
            a["strength_means"] = a["strength_means"] * np.nan
        elif how == "strength_radius_zero":
            a["strength_radius"] = np.array([0.0])
        elif how == "strength_log_range_inverted":
            a["strength_log_range"] = a["strength_log_range"][::-1] * 1.0 + np.array([1, -1])
        elif how == "missing_means":
            del a["means"]
        elif how == "missing_strength_radius":
            del a["strength_radius"]
        elif how == "extra_key":
            a["evil"] = np.arange(3)
        elif how == "meta_weird":
            meta.clear()
            meta.update({"status": float("nan"), "objective": [1, 2, {"x": None}]})
        elif how == "meta_deep":
            x = []
            for _ in range(50000):
                x = [x]
            meta["deep"] = x
        elif how == "K_large":
            n = 200_000
            a["priors"] = np.full(n, 1.0 / n)
            a["means"] = np.tile(a["means"][:1], (n, 1))
            a["covariances"] = np.tile(a["covariances"][:1], (n, 1, 1))
        elif how == "dims_large":
            D = 600
            a["priors"] = np.ones(1)
            a["means"] = np.zeros((1, 2 * D))
            a["covariances"] = np.eye(2 * D)[None]
            a["target"] = np.zeros(D)
            a.pop("lyapunov", None)
        else:
            raise AssertionError(how)
        return a, meta

    if how == "meta_deep":
        sys.setrecursionlimit(200000)
        try:
            _rewrite_guarded(path, mutate)
        except RecursionError:
            # json.dumps cannot write it: write the text by hand
            from seds_casadi.core.model_files import checksum
            e = _raw_entries(base_path("model.npz"))
            txt = '{"deep": ' + "[" * 50000 + "]" * 50000 + "}"
            arrays = {k: e[k] for k in e if k not in ("format", "version", "fit_info",
                                                      "checksum")}
            e["fit_info"] = np.array(txt)
            e["checksum"] = np.array(checksum(list(arrays.values()), txt))
            _write_npz(path, e)
        finally:
            sys.setrecursionlimit(1000)
    elif how == "meta_huge_int":  # valid JSON, valid checksum, an int json cannot convert
        sys.set_int_max_str_digits(0)
        try:
            _rewrite_guarded(path, lambda a, meta: (a, {**meta, "n": 10 ** 5000}))
        finally:
            sys.set_int_max_str_digits(4300)
    else:
        _rewrite_guarded(path, mutate)
    m = StableDS.load(path)
    if how in ("extra_key", "meta_weird", "priors_unnormalised", "cov_tiny", "cov_huge"):
        return _check_loaded_model(m)  # may load; must then be a working model
    bad = _check_loaded_model(m)
    return bad or f"a model file with {how} loaded: {m}"


def model_entries(d, how) -> str | None:
    """Raw npz entries (no valid checksum) replaced."""
    from seds_casadi import StableDS

    path = os.path.join(d, "m.npz")
    e = _raw_entries(base_path("model.npz"))
    if how == "version_string":
        e["version"] = np.array("1")
    elif how == "version_huge":
        e["version"] = np.array(10**18)
    elif how == "version_float_nan":
        e["version"] = np.array(np.nan)
    elif how == "version_array":
        e["version"] = np.arange(5)
    elif how == "format_other":
        e["format"] = np.array("seds_casadi.Other")
    elif how == "format_int":
        e["format"] = np.array(3)
    elif how == "checksum_missing":
        del e["checksum"]
    elif how == "checksum_array":
        e["checksum"] = np.zeros(3)
    elif how == "fit_info_not_json":
        e["fit_info"] = np.array("{not json")
    elif how == "fit_info_bytes":
        e["fit_info"] = np.frombuffer(b"\xff\xfe\x00", dtype=np.uint8)
    elif how == "only_version":
        e = {"version": e["version"]}
    elif how == "no_entries":
        e = {}
    elif how == "object_array":
        with open(path, "wb") as fh:
            np.savez(fh, **{**e, "priors": np.array([{"a": 1}], dtype=object)})
        m = StableDS.load(path)
        return f"a pickled entry loaded: {m}"
    else:
        raise AssertionError(how)
    _write_npz(path, e)
    m = StableDS.load(path)
    return _check_loaded_model(m, base_path("model.npz")) or f"{how}: loaded {m}"


def model_huge_header(d, shape) -> str | None:
    """An entry whose header declares a huge shape over a few bytes."""
    from seds_casadi import StableDS

    path = os.path.join(d, "m.npz")
    e = _raw_entries(base_path("model.npz"))
    import io
    with zipfile.ZipFile(path, "w") as z:
        for k, v in e.items():
            buf = io.BytesIO()
            if k == "means":
                np.lib.format.write_array_header_1_0(
                    buf, {"descr": "<f8", "fortran_order": False, "shape": tuple(shape)})
                buf.write(b"\0" * 64)
            else:
                np.lib.format.write_array(buf, np.asarray(v), allow_pickle=False)
            z.writestr(k + ".npy", buf.getvalue())
    m = StableDS.load(path)
    return f"a header declaring {shape} loaded: {m}"


def model_path(d, what) -> str | None:
    from seds_casadi import StableDS

    p = {"dir": d, "missing": os.path.join(d, "nope.npz"), "devzero": "/dev/zero",
         "devurandom": "/dev/urandom", "devnull": "/dev/null"}.get(what)
    if what == "fifo":
        p = os.path.join(d, "fifo.npz")
        os.mkfifo(p)
    if what == "symlink_to_model":
        p = os.path.join(d, "link.npz")
        os.symlink(base_path("model.npz"), p)
        return _check_loaded_model(StableDS.load(p))
    if what == "symlink_loop":
        p = os.path.join(d, "loop.npz")
        os.symlink(p, p)
    m = StableDS.load(p)
    return f"{what} loaded as a model: {m}"


# ---- demonstrations
def _demo_arrays():
    d = small_demos()
    return [np.array(p) for p in d.positions], [np.array(v) for v in d.velocities]


def _check_demos(d, expect_n=None) -> str | None:
    for p in d.positions:
        if not _finite(p):
            return "loaded demonstrations hold non-finite positions"
    for v in d.velocities:
        if not _finite(v):
            return "loaded demonstrations hold non-finite velocities"
    if expect_n is not None and d.n_demos != expect_n:
        return f"{d.n_demos} demonstrations loaded, {expect_n} in the file"
    return None


def demo_npz(d, how, fit=False) -> str | None:
    from seds_casadi import SEDS, load_demonstrations

    P, V = _demo_arrays()
    e = {}
    for i, (p, v) in enumerate(zip(P, V)):
        e[f"pos_{i}"], e[f"vel_{i}"] = p, v
    meaningful = False  # whether the input has a meaning the load must keep
    if how == "nan_pos":
        e["pos_1"] = e["pos_1"].copy()
        e["pos_1"][3, 0] = np.nan
    elif how == "inf_vel":
        e["vel_0"] = e["vel_0"].copy()
        e["vel_0"][5, 1] = np.inf
    elif how == "bool":
        e = {k: v > 0 for k, v in e.items()}
    elif how == "strings":
        e["pos_0"] = e["pos_0"].astype(str)
    elif how == "int":
        e = {k: (100 * v).astype(np.int64) for k, v in e.items()}
        meaningful = True
    elif how == "complex":
        e["pos_0"] = e["pos_0"].astype(complex)
    elif how == "one_sample":
        e = {"pos_0": P[0][:1], "vel_0": V[0][:1]}
    elif how == "two_samples":
        e = {"pos_0": P[0][:2], "vel_0": V[0][:2]}
        meaningful = True
    elif how == "huge":
        e = {k: v * 1e200 for k, v in e.items()}
    elif how == "tiny":
        e = {k: v * 1e-300 for k, v in e.items()}
    elif how == "1d":
        e = {k: v[:, 0] for k, v in e.items()}
    elif how == "7d":
        rng = np.random.default_rng(0)
        e = {}
        for i in range(3):
            p = np.cumsum(rng.normal(size=(40, 7)), axis=0)[::-1].copy()
            p -= p[-1]
            e[f"pos_{i}"] = p
        meaningful = True
    elif how == "3d_array":
        e["pos_0"] = e["pos_0"][None]
    elif how == "empty_arrays":
        e = {k: v[:0] for k, v in e.items()}
    elif how == "no_entries":
        e = {}
    elif how == "only_vel":
        e = {k: v for k, v in e.items() if k.startswith("vel")}
    elif how == "gap_in_numbering":
        e = {"pos_0": P[0], "pos_5": P[1]}
    elif how == "mismatched_vel":
        e["vel_0"] = e["vel_0"][:-3]
    elif how == "mixed_dims":
        e["pos_1"] = np.hstack([e["pos_1"], e["pos_1"][:, :1]])
        e["vel_1"] = np.hstack([e["vel_1"], e["vel_1"][:, :1]])
    elif how == "different_targets":
        e["pos_1"] = e["pos_1"] + 5.0
    elif how == "constant":
        e = {"pos_0": np.zeros((50, 2)), "pos_1": np.zeros((50, 2))}
    elif how == "dt_negative":
        e = {k: v for k, v in e.items() if k.startswith("pos")}
        e["dt"] = np.array(-0.1)
    elif how == "dt_zero":
        e = {k: v for k, v in e.items() if k.startswith("pos")}
        e["dt"] = np.array(0.0)
    elif how == "dt_nan":
        e = {k: v for k, v in e.items() if k.startswith("pos")}
        e["dt"] = np.array(np.nan)
    elif how == "dt_array":
        e = {k: v for k, v in e.items() if k.startswith("pos")}
        e["dt"] = np.arange(3.0)
    elif how == "t_decreasing":
        e = {k: v for k, v in e.items() if k.startswith("pos")}
        for i in range(3):
            e[f"t_{i}"] = -np.arange(len(e[f"pos_{i}"])) * 0.02
    elif how == "t_nan":
        e = {k: v for k, v in e.items() if k.startswith("pos")}
        for i in range(3):
            e[f"t_{i}"] = np.full(len(e[f"pos_{i}"]), np.nan)
    elif how == "t_wrong_length":
        e = {k: v for k, v in e.items() if k.startswith("pos")}
        for i in range(3):
            e[f"t_{i}"] = np.arange(3.0)
    elif how == "target_nan":
        e["target"] = np.array([np.nan, 0.0])
    elif how == "target_wrong_dims":
        e["target"] = np.zeros(5)
    elif how == "shuffled_rows":
        rng = np.random.default_rng(1)
        idx = rng.permutation(len(P[0]))
        e["pos_0"], e["vel_0"] = P[0][idx], V[0][idx]
        meaningful = True  # velocities given: order does not matter for the samples
    elif how == "unknown_keys":
        e["poss_0"] = P[0]
    elif how == "vel_zero":
        e = {k: (0 * v if k.startswith("vel") else v) for k, v in e.items()}
    elif how == "duplicate_samples":
        e = {k: np.repeat(v, 3, axis=0) for k, v in e.items()}
    elif how == "huge_count":
        e = {f"pos_{i}": P[0][:2] for i in range(5000)}
    else:
        raise AssertionError(how)
    path = os.path.join(d, "demos.npz")
    _write_npz(path, e)
    demos = load_demonstrations(path)
    bad = _check_demos(demos)
    if bad:
        return bad
    if fit or meaningful:
        m = SEDS(2, random_state=0, max_iter=40).fit(demos).model_
        x0 = np.array([p[0] for p in demos.positions])
        if not _finite(m.predict(x0)):
            return "a model fitted to these demonstrations predicts NaN"
        return None
    if how in ("int", "two_samples", "7d", "shuffled_rows", "duplicate_samples", "tiny", "1d",
               "unknown_keys", "different_targets"):
        return None
    return f"demonstrations with {how} were loaded: {demos}"


def demo_csv(d, text, expect_ok=False) -> str | None:
    from seds_casadi import load_demonstrations

    path = os.path.join(d, "demos.csv")
    open(path, "w").write(text)
    demos = load_demonstrations(path)
    bad = _check_demos(demos)
    if bad or expect_ok:
        return bad
    return f"a CSV with no meaning was loaded: {demos}"


def _csv_rows(mod=None, header="demo,t,x0,x1,v0,v1", vel=True) -> str:
    P, V = _demo_arrays()
    lines = [header]
    for i, (p, v) in enumerate(zip(P, V)):
        for j in range(len(p)):
            row = [str(i), f"{0.02 * j:.4f}", *(f"{x:.6g}" for x in p[j])]
            if vel:
                row += [f"{x:.6g}" for x in v[j]]
            lines.append(",".join(row))
    if mod:
        lines = mod(lines)
    return "\n".join(lines) + "\n"


def demo_path(d, what) -> str | None:
    from seds_casadi import load_demonstrations

    p = {"devzero": "/dev/zero", "devurandom": "/dev/urandom", "devnull": "/dev/null",
         "dir": d, "missing": os.path.join(d, "none.csv")}.get(what)
    if what.startswith("fifo"):
        p = os.path.join(d, "x." + what.split("_")[1])
        os.mkfifo(p)
    if what == "huge_sparse_csv":
        p = os.path.join(d, "big.csv")
        with open(p, "wb") as fh:
            fh.truncate(3 * 10**9)
    demos = load_demonstrations(p)
    return f"{what} loaded as demonstrations: {demos}"


# ---- fields
def _field_spec(name="flat"):
    from seds_casadi.minigolf.fields import FIELDS_FOLDER

    with open(os.path.join(FIELDS_FOLDER, name + ".json")) as fh:
        return json.load(fh)


def _set(spec, dotted, value):
    keys = dotted.split(".")
    cur = spec
    for k in keys[:-1]:
        cur = cur.setdefault(k, {})
    if value is DELETE:
        cur.pop(keys[-1], None)
    else:
        cur[keys[-1]] = value


DELETE = "<delete>"


def field_case(d, base, changes, expect_ok=False, raw=None) -> str | None:
    from seds_casadi.minigolf.ball import simulate_shots
    from seds_casadi.minigolf.fields import load_field

    path = os.path.join(d, "f.json")
    if raw is not None:
        open(path, "w").write(raw)
    else:
        spec = _field_spec(base)
        for k, v in changes:
            _set(spec, k, v)
        open(path, "w").write(json.dumps(spec, allow_nan=True))
    f = load_field(path)
    r = f.ball_region
    ball = np.array([[0.5 * (r[0] + r[1]), 0.5 * (r[2] + r[3])]])
    aim = f.hole - ball[0]
    res = simulate_shots(f, ball, 2.0 * aim / np.linalg.norm(aim), max_time=20.0)
    for k in ("final_position", "final_xy", "position"):
        if hasattr(res, k) and not _finite(getattr(res, k)):
            return f"a shot on the accepted field ends at a non-finite position ({k})"
    if expect_ok:
        return None
    return f"a field with {changes or 'this text'} was accepted ({f.name})"


# ---- SEDS settings, solver options, predictions
def seds_fit(d, kwargs, expect_ok=False) -> str | None:
    from seds_casadi import SEDS

    kw = {"random_state": 0, "max_iter": 30}
    kw.update(kwargs)
    m = SEDS(**kw).fit(small_demos()).model_
    y = m.predict(np.array([[0.0, 0.0], [-20.0, 5.0]]))
    if not _finite(y):
        return f"SEDS({kwargs}) fitted a model that predicts {y}"
    if expect_ok:
        return None
    return f"SEDS({kwargs}) was accepted and fitted {m}"


def predict_case(d, which, X, method="predict", kwargs=None, expect_ok=False) -> str | None:
    from seds_casadi import StableDS

    m = StableDS.load(base_path(which))
    X = np.asarray(X) if not isinstance(X, str) else X
    if method == "predict":
        y = m.predict(X)
        big = np.max(np.abs(np.asarray(X, dtype=float)), initial=0.0) >= 1e308
        if np.any(np.isnan(y)) or (not big and not _finite(y)):
            # beyond 1e308 the exact velocity may exceed the largest float: +-inf is then
            # its rounding, NaN never is
            return f"predict({X!r}) = {y}"
        return None if expect_ok else f"predict accepted {X!r}: {y}"
    out = m.rollout(X, **(kwargs or {}))
    traj = out[0] if isinstance(out, tuple) else out
    arrs = traj if isinstance(traj, list) else [traj]
    for a in arrs:
        if not _finite(a):
            return f"rollout({X!r}, {kwargs}) returned non-finite points"
    return None if expect_ok else f"rollout({X!r}, {kwargs}) accepted"


def demonstrations_kwargs(d, kwargs, expect_ok=False) -> str | None:
    from seds_casadi import Demonstrations

    P, V = _demo_arrays()
    demos = Demonstrations(P, **kwargs)
    bad = _check_demos(demos)
    if bad or expect_ok:
        return bad
    return f"Demonstrations({kwargs}) accepted"


API_FUNCS = {f.__name__: f for f in (model_bytes, model_bomb, model_crafted, model_entries,
                                     model_huge_header, model_path, demo_npz, demo_csv,
                                     demo_path, field_case, seds_fit, predict_case,
                                     demonstrations_kwargs)}


def _csv_case(name, text, expect_ok=False):
    api("demo_files", f"csv_{name}", "demo_csv", text, expect_ok)


# ====================================================================== the case list
def define_cases() -> None:
    # ---------------------------------------------------------------- model files (API)
    for frac in (0.0, 0.1, 0.5, 0.9, 0.99):
        api("model_files", f"truncate_{frac}", "model_bytes", "truncate", frac)
    for n in (1, 3, 10, 100):
        api("model_files", f"flip_{n}_bits", "model_bytes", "flip", n)
    for n in (10, 5000):
        api("model_files", f"garbage_{n}", "model_bytes", "garbage", n)
    api("model_files", "empty", "model_bytes", "empty")
    api("model_files", "text", "model_bytes", "text")
    api("model_files", "append_garbage", "model_bytes", "append", 1000)
    for entry, nbytes, dt in (("version", 2e8, "<U1"), ("fit_info", 6e8, "<U1"),
                              ("means", 7e8, "<f8"), ("evil", 8e8, "<f8"),
                              ("format", 1e8, "<U1"), ("checksum", 1e8, "|S1")):
        api("model_files", f"zip_bomb_{entry}_{nbytes:.0e}", "model_bomb", entry, nbytes, dt)
    for how in ("priors_nan", "priors_inf", "priors_negative", "priors_zero",
                "priors_unnormalised", "priors_tiny", "means_nan", "means_huge", "cov_nan",
                "cov_zero", "cov_negative", "cov_asymmetric", "cov_huge", "cov_tiny",
                "target_nan", "target_huge", "wrong_shape_means", "wrong_K", "1d_target",
                "int_dtype", "bool_dtype", "complex_dtype", "string_dtype", "float16",
                "scalar_priors", "lyap_nan", "lyap_indefinite", "strength_nan",
                "strength_radius_zero", "strength_log_range_inverted", "missing_means",
                "missing_strength_radius", "extra_key", "meta_weird", "meta_deep", "meta_huge_int",
                "K_large",
                "dims_large"):
        api("model_files", f"crafted_{how}", "model_crafted", how)
    for how in ("version_string", "version_huge", "version_float_nan", "version_array",
                "format_other", "format_int", "checksum_missing", "checksum_array",
                "fit_info_not_json", "fit_info_bytes", "only_version", "no_entries",
                "object_array"):
        api("model_files", f"entries_{how}", "model_entries", how)
    for shape in ((10**9, 2), (2**62, 2), (10**5, 10**5), (-1, 2)):
        api("model_files", f"huge_header_{shape}", "model_huge_header", shape)
    for what in ("dir", "missing", "devzero", "devurandom", "devnull", "fifo",
                 "symlink_to_model", "symlink_loop"):
        api("pipes_devices", f"model_{what}", "model_path", what, timeout=30)

    # ---------------------------------------------------------------- demonstration files
    for how in ("nan_pos", "inf_vel", "bool", "strings", "int", "complex", "one_sample",
                "two_samples", "huge", "tiny", "1d", "7d", "3d_array", "empty_arrays",
                "no_entries", "only_vel", "gap_in_numbering", "mismatched_vel", "mixed_dims",
                "different_targets", "constant", "dt_negative", "dt_zero", "dt_nan",
                "dt_array", "t_decreasing", "t_nan", "t_wrong_length", "target_nan",
                "target_wrong_dims", "shuffled_rows", "unknown_keys", "vel_zero",
                "duplicate_samples", "huge_count"):
        api("demo_files", f"npz_{how}", "demo_npz", how)
    for how in ("huge", "tiny", "duplicate_samples", "different_targets"):
        api("demo_files", f"npz_{how}_fit", "demo_npz", how, True)

    def repl(i, old, new):
        return lambda ls: ls[:i] + [ls[i].replace(old, new, 1)] + ls[i + 1:]

    def shuffle(ls):
        rng = np.random.default_rng(3)
        body = ls[1:]
        return [ls[0]] + [body[i] for i in rng.permutation(len(body))]

    _csv_case("good", _csv_rows(), True)
    _csv_case("good_no_vel", _csv_rows(header="demo,t,x0,x1", vel=False), True)
    _csv_case("nan", _csv_rows(lambda ls: ls[:5] + ["0,0.5,nan,1,0,0"] + ls[5:]))
    _csv_case("inf", _csv_rows(lambda ls: ls[:5] + ["0,0.5,inf,1,0,0"] + ls[5:]))
    _csv_case("huge_value", _csv_rows(lambda ls: ls[:5] + ["0,0.5,1e400,1,0,0"] + ls[5:]))
    _csv_case("bool_words", _csv_rows(lambda ls: [ls[0]] + [
        ",".join(["0", f"{i}", "true", "false", "true", "false"]) for i in range(20)]))
    _csv_case("strings", _csv_rows(lambda ls: ls[:3] + ["0,0.1,abc,def,1,2"] + ls[3:]))
    _csv_case("one_sample", "demo,t,x0,x1\n0,0,1,2\n")
    _csv_case("one_sample_per_demo", "demo,t,x0,x1\n0,0,1,2\n1,0,3,4\n")
    _csv_case("shuffled", _csv_rows(shuffle))
    _csv_case("shuffled_no_vel", _csv_rows(shuffle, header="demo,t,x0,x1", vel=False))
    _csv_case("empty", "")
    _csv_case("header_only", "demo,t,x0,x1\n")
    _csv_case("1d", "demo,t,x0\n" + "".join(f"0,{0.1 * i},{5 - i}\n" for i in range(30)), True)
    _csv_case("7d", "demo,t," + ",".join(f"x{i}" for i in range(7)) + "\n" + "".join(
        f"0,{0.1 * i}," + ",".join(str((30 - i) * (j + 1)) for j in range(7)) + "\n"
        for i in range(31)), True)
    _csv_case("ragged", _csv_rows(lambda ls: ls[:4] + ["0,0.1,1"] + ls[4:]))
    _csv_case("extra_column", _csv_rows(repl(0, "v1", "v1,v2")))
    _csv_case("missing_t", _csv_rows(repl(0, "demo,t,", "demo,time,")))
    _csv_case("dup_column", "demo,t,x0,x0\n" + "".join(f"0,{i},{i},{i}\n" for i in range(5)))
    _csv_case("negative_demo_id", _csv_rows(lambda ls: [ls[0]] + [
        "-" + x for x in ls[1:]]), True)  # negative integers are integers
    _csv_case("float_demo_id", _csv_rows(lambda ls: [ls[0]] + [
        x.replace("0,", "0.5,", 1) if x.startswith("0,") else x for x in ls[1:]]))
    _csv_case("non_contiguous", _csv_rows(lambda ls: [ls[0]] + ls[1:10] + ls[-5:] + ls[10:-5]))
    _csv_case("duplicate_t", "demo,t,x0,x1\n" + "".join(f"0,0,{5 - i},{i}\n" for i in range(9)))
    _csv_case("binary_junk", "demo,t,x0,x1\n\x00\x01\x02\xff\n")
    _csv_case("very_long_line", "demo,t,x0,x1\n0,0," + "1" * 200000 + ",1\n")
    _csv_case("bom_and_crlf", "\ufeffdemo,t,x0,x1\r\n" + "".join(
        f"0,{0.1 * i},{5 - i},{i}\r\n" for i in range(9)), True)
    _csv_case("semicolons", "demo;t;x0;x1\n" + "".join(f"0;{i};{i};{i}\n" for i in range(9)))
    _csv_case("comments_only", "# nothing\n# here\n")
    _csv_case("huge_dims", "demo,t," + ",".join(f"x{i}" for i in range(5000)) + "\n" +
              "".join(f"0,{i}," + ",".join("1" for _ in range(5000)) + "\n" for i in range(3)))
    for what in ("devzero", "devurandom", "devnull", "dir", "missing", "fifo_csv", "fifo_npz",
                 "huge_sparse_csv"):
        api("pipes_devices", f"demos_{what}", "demo_path", what, timeout=30)

    # ---------------------------------------------------------------- Demonstrations(...)
    for kw in ({"smoothing": -5}, {"smoothing": 1e6}, {"smoothing": np.nan},
               {"smoothing": "x"}, {"trim_speed": -1}, {"trim_speed": np.inf},
               {"target": [np.nan, 0]}, {"target": [0, 0, 0]}, {"target": "origin"},
               {"dt": 0}, {"dt": -1}, {"dt": np.nan}, {"dt": 1e300}, {"dt": True},
               {"dt": "0.1"}, {"dt": [0.1, 0.2]}):
        api("python_api", f"Demonstrations_{kw}", "demonstrations_kwargs", kw)

    # ---------------------------------------------------------------- fields (API)
    F = "field_files"
    for name, changes in [
        ("hole_radius_negative", [("hole.radius", -0.05)]),
        ("hole_radius_zero", [("hole.radius", 0)]),
        ("hole_radius_huge", [("hole.radius", 1e9)]),
        ("hole_radius_string", [("hole.radius", "big")]),
        ("hole_x_string", [("hole.x", "far")]),
        ("hole_bool", [("hole.x", True)]),
        ("hole_list", [("hole", [2.4, 0.0])]),
        ("hole_outside", [("hole.x", 50.0)]),
        ("name_path", [("name", "../../escaped")]),
        ("name_abs", [("name", "/etc/passwd")]),
        ("name_int", [("name", 5)]),
        ("name_null", [("name", None)]),
        ("name_long", [("name", "a" * 300)]),
        ("name_unicode", [("name", "gr\u00fcn\u200b")]),
        ("stimp_and_rr", [("rolling_resistance", 0.1)]),
        ("stimp_negative", [("stimp", -3)]),
        ("stimp_zero", [("stimp", 0)]),
        ("stimp_huge", [("stimp", 1e308)]),
        ("stimp_string", [("stimp", "fast")]),
        ("stimp_bool", [("stimp", True)]),
        ("stimp_nan", [("stimp", float("nan"))]),
        ("rr_only_string", [("stimp", DELETE), ("rolling_resistance", "x")]),
        ("rr_only_bool", [("stimp", DELETE), ("rolling_resistance", True)]),
        ("rr_only_list", [("stimp", DELETE), ("rolling_resistance", [0.1])]),
        ("rr_only_huge", [("stimp", DELETE), ("rolling_resistance", 1e300)]),
        ("no_speed", [("stimp", DELETE)]),
        ("slope_huge", [("surface.slope_x", 1e6)]),

        ("slope_nan", [("surface.slope_x", float("nan"))]),
        ("slope_string", [("surface.slope_x", "up")]),
        ("surface_unknown", [("surface.shape", "sphere")]),
        ("surface_null", [("surface", None)]),
        ("bounds_inverted", [("bounds", [3.0, -0.3, -0.6, 0.6])]),
        ("bounds_huge", [("bounds", [-1e300, 1e300, -1e300, 1e300])]),
        ("bounds_short", [("bounds", [0, 1])]),
        ("bounds_strings", [("bounds", ["a", "b", "c", "d"])]),
        ("region_outside", [("ball_region", [5, 6, 5, 6])]),
        ("region_point", [("ball_region", [0.1, 0.1, 0.0, 0.0])]),
        ("boundary_bad", [("boundary", "mirrors")]),
        ("restitution_2", [("wall_restitution", 2.0)]),
        ("restitution_string", [("wall_restitution", "bouncy")]),
        ("restitution_bool", [("wall_restitution", True)]),
        ("teacher_unknown", [("teacher.strategy", "magic")]),
        ("teacher_kappa_range_neg", [("teacher.kappa_range", [-1, 2])]),
        ("teacher_kappa_range_inverted", [("teacher.kappa_range", [2, 1])]),
        ("teacher_banks_string", [("teacher.banks", "no")]),
        ("teacher_not_dict", [("teacher", [1, 2])]),
        ("unknown_top_key", [("colour", "green")]),
        ("situations_bad", [("situations", {"ball": {"fixed": [50, 50]}})]),
        ("situations_string", [("situations", "anywhere")]),
    ]:
        api(F, name, "field_case", "flat", changes)
    for name, changes in [
        ("arctan_step_tiny", [("surface.steepness", 1e5)]),
        ("arctan_height_huge", [("surface.height", 100.0)]),

        ("arctan_axis_bad", [("surface.axis", "z")]),
        ("arctan_steepness_nan", [("surface.steepness", float("nan"))]),
    ]:
        api(F, name, "field_case", "arctan", changes)
    for name, changes in [
        ("rough_bumps_huge", [("surface.bumps", 10**8)]),
        ("rough_bumps_negative", [("surface.bumps", -3)]),
        ("rough_width_zero", [("surface.width", 0.0)]),
        ("rough_amplitude_huge", [("surface.amplitude", 5.0)]),
        ("rough_seed_string", [("surface.seed", "x")]),
        ("rough_friction_variation_2", [("surface.friction_variation", 2.0)]),
    ]:
        api(F, name, "field_case", "rough_flat", changes)
    api(F, "flat_unchanged", "field_case", "flat", [], True)
    # within the declared limits (slope up to 10, a step down as well as up)
    api(F, "slope_steep_within_limit", "field_case", "flat", [("surface.slope_x", 5.0)], True)
    api(F, "arctan_height_negative", "field_case", "arctan", [("surface.height", -0.05)], True)
    api(F, "double_hill_unchanged", "field_case", "double_hill", [], True)
    for name, raw in [("empty", ""), ("not_json", "{name: flat"), ("list", "[1, 2, 3]"),
                      ("deep", "[" * 100000 + "]" * 100000), ("null", "null"),
                      ("nan_literal", '{"name": "x", "stimp": NaN}'),
                      ("huge_number", '{"name": "x", "stimp": 1e999999}'),
                      ("huge_int", '{"name": "x", "stimp": ' + "9" * 5000 + "}"),
                      ("binary", "\x00\x01\xff")]:
        api(F, f"raw_{name}", "field_case", "flat", [], False, raw)

    # ---------------------------------------------------------------- SEDS settings (API)
    P = "python_api"
    for kw in ({"n_components": 0}, {"n_components": -2}, {"n_components": 2.5},
               {"n_components": "many"}, {"n_components": True}, {"n_components": 10**6},
               {"objective": "fast"}, {"max_iter": 0}, {"max_iter": -1}, {"max_iter": 10**12},
               {"max_iter": 2.5}, {"tol": -1}, {"tol": np.nan}, {"tol": 0},
               {"stability_margin": -1}, {"stability_margin": 1e6}, {"stability_margin": np.inf},
               {"omega_lower": -1}, {"omega_lower": np.nan}, {"omega_upper": 0},
               {"hessian": "maybe"}, {"compile": "no"}, {"require_convergence": "yes"},
               {"verbose": "loud"}, {"approach_direction": [np.nan, 1]},
               {"approach_direction": [0, 0]}, {"approach_direction": [1, 0, 0]},
               {"approach_ratio": -4}, {"lyapunov": "learned", "formulation": "constrained",
                                        "gmm": "fixed", "init": "joint-em"},
               {"gain_limit": 1e-9},
               {"gain_limit": -1}, {"gain_limit": np.nan}, {"gain_limit": "lots"},
               {"strength_components": 0}, {"strength_components": -1},
               {"random_state": "seed"}, {"random_state": -1}, {"constraints": 5},
               {"constraints": [lambda x: "not an expression"]},
               {"tol_objective_change": -1},
               {"solver_options": {"max_iter": "abc"}}, {"solver_options": {"tol": -1}},
               {"solver_options": {"no_such_option": 1}}, {"solver_options": "fast"},
               {"solver_options": {"print_level": 99}}, {"solver_options": {"max_cpu_time": -1}},
               {"solver_options": {"linear_solver": "ma57"}},
               {"solver_options": {"hessian_approximation": "exact", "tol": np.nan}},
               {"solver_options": {"max_iter": 10**12}}, {"solver_options": {"ipopt": {}}}):
        api(P, f"SEDS_{kw}", "seds_fit", kw)
    # documented combinations: gmm='fixed' keeps init's GMM whatever the init; 'strength' is
    # speed_calibration's default, unused by objective='mse'
    for kw in ({"n_components": 2}, {"objective": "likelihood", "n_components": 2},
               {"gmm": "fixed", "init": "joint-em"},
               {"speed_calibration": "strength", "objective": "mse"},
               {"formulation": "constrained", "n_components": 2, "objective": "mse"}):
        api(P, f"SEDS_valid_{kw}", "seds_fit", kw, True)
    for which in ("model.npz", "model_plain.npz"):
        for name, X in [("1e300", [1e300, 1e300]), ("-1e300", [-1e300, 1e300]),
                        ("1e155", [1e155, -1e155]), ("max", [1.7e308, 1.7e308]),
                        ("nan", [np.nan, 0.0]), ("inf", [np.inf, 0.0]),
                        ("wrong_dims", [1.0, 2.0, 3.0]), ("empty", np.zeros((0, 2))),
                        ("3d", np.zeros((2, 2, 2))), ("strings", ["a", "b"]),
                        ("scalar", 3.0), ("tiny", [1e-320, -1e-320])]:
            ok = name in ("1e300", "-1e300", "1e155", "max", "tiny", "empty")
            api(P, f"predict_{which}_{name}", "predict_case", which, X, "predict", None, ok)
        for name, X, kw, ok in [
                ("far", [1e300, 1e300], {"dt": 0.01, "max_steps": 100}, True),
                ("nan", [np.nan, 0.0], {"dt": 0.01}, False),
                ("dt_zero", [1.0, 1.0], {"dt": 0.0}, False),
                ("dt_negative", [1.0, 1.0], {"dt": -0.1}, False),
                ("dt_nan", [1.0, 1.0], {"dt": np.nan}, False),
                ("dt_huge", [1.0, 1.0], {"dt": 1e300, "max_steps": 10}, True),
                ("max_steps_zero", [1.0, 1.0], {"dt": 0.01, "max_steps": 0}, True),
                ("max_steps_negative", [1.0, 1.0], {"dt": 0.01, "max_steps": -5}, False),
                ("max_steps_float", [1.0, 1.0], {"dt": 0.01, "max_steps": 2.5}, False),
                ("tol_nan", [1.0, 1.0], {"dt": 0.01, "tol": np.nan}, False),
                ("tol_string", [1.0, 1.0], {"dt": 0.01, "tol": "small"}, False),
                ("dt_bool", [1.0, 1.0], {"dt": True}, False),
                ("dt_string", [1.0, 1.0], {"dt": "0.01"}, False),
                ("max_steps_huge", [1.0, 1.0], {"dt": 0.01, "max_steps": 10**12}, True),
                ("tol_negative", [1.0, 1.0], {"dt": 0.01, "tol": -1.0}, False),
                ("method_bad", [1.0, 1.0], {"dt": 0.01, "method": "magic"}, False),
                ("wrong_dims", [1.0, 1.0, 1.0], {"dt": 0.01}, False)]:
            api(P, f"rollout_{which}_{name}", "predict_case", which, X, "rollout", kw, ok)

    # ---------------------------------------------------------------- command line
    C = "cli_options"
    demos = "{base}/demos.npz"
    fit_small = ["fit", demos, "-K", "2", "--max-iter", "30"]
    for opt, vals in [("-K", ["0", "-1", "nan", "1e9", "abc", "2.5", "", "bic"]),
                      ("--max-iter", ["0", "-5", "nan", "1e12", "abc", "10**12"]),
                      ("--dt", ["0", "-1", "nan", "inf", "1e300", "abc"]),
                      ("--seed", ["-1", "nan", "1e30", "abc", "99999999999999999999"]),
                      ("--gain-limit", ["0", "-1", "nan", "1e-12", "inf", "abc"]),
                      ("--objective", ["fast"]), ("--init", ["x"]),
                      ("--choose", ["objective=mse", "nothing", "K=", "n_components=0,1",
                                    "objective=mse,mse", "tol=abc,1"])]:
        for v in vals:
            argv = ["fit", demos, "--max-iter", "30", opt, v]
            if opt != "-K":
                argv += ["-K", "2"]
            cli(C, f"fit {opt} {v!r}", argv, expect="refuse" if opt not in ("--choose",)
                and v not in ("bic",) else "either", outputs=("model.npz",))
    cli(C, "fit valid small", fit_small, expect="accept", outputs=("model.npz",))
    cli(C, "fit --dt on a file with velocities", fit_small + ["--dt", "0.5"],
        outputs=("model.npz",))
    cli(C, "fit no args", ["fit"], expect="refuse")
    cli(C, "fit two files", ["fit", demos, demos], expect="refuse")
    cli(C, "unknown command", ["frobnicate"], expect="refuse")
    cli(C, "no command", [], expect="refuse")
    # --debug asks for the full traceback of an error: a traceback is its answer
    cli(C, "--debug fit missing", ["--debug", "fit", "/nonexistent.npz"], expect="debug")
    for v in ["0", "-1", "1", "abc", "nan", "1e6"]:
        cli(C, f"lasa --samples {v}", ["lasa", "--quick", "--no-figures", "--samples", v],
            expect="either" if v == "1e6" else "refuse", outputs=("lasa.csv",))
    for opt, v in [("--shapes", "NoSuchShape"), ("--shapes", "../Angle"),
                   ("--components", "0"), ("--components", "abc"), ("--k-max", "0"),
                   ("--k-max", "-3"), ("--workers", "0"), ("--workers", "-2"),
                   ("--workers", "100000"), ("--seed", "nan"), ("--dask", "tcp://nowhere:1"),
                   ("--protocols", "magic"), ("--objectives", "fast")]:
        argv = ["lasa", "--no-figures", "--samples", "20", "--shapes", "Angle", opt, v]
        # more workers than shapes: as many as there are shapes (a cap, not a meaningless value)
        cli(C, f"lasa {opt} {v}", argv, expect="either" if v == "100000" else "refuse",
            outputs=("lasa.csv",), timeout=120)
    cli(C, "lasa valid small", ["lasa", "--quick", "--no-figures", "--samples", "20"],
        expect="accept", outputs=("lasa.csv", "summary.txt"))
    for opt, v in [("--repetitions", "0"), ("--repetitions", "-1"), ("--repetitions", "abc"),
                   ("--repetitions", "1e9"), ("--field", "nowhere"), ("--field", "../flat"),
                   ("--field", "/dev/zero"), ("--workers", "0"), ("--demos", "/dev/null"),
                   ("--demos", "/nonexistent.npz"), ("--protocol", "magic"),
                   ("--seed", "abc"), ("--dask", "notanaddress")]:
        argv = ["table1", "--quick", "--no-figures", opt, v]
        cli(C, f"table1 {opt} {v}", argv, expect="refuse", outputs=("table1.csv",))
    for opt, v in [("--shots", "0"), ("--shots", "-3"), ("--shots", "abc"),
                   ("--shots", "1e12"), ("--validate", "-1"), ("--validate", "abc"),
                   ("--robot", "r2d2"), ("--robot", "../wam"), ("--field", "nowhere"),
                   ("--learner", "svm"), ("--train-size", "0"), ("--train-size", "-1"),
                   ("--train-size", "1"), ("--strategies", "0"), ("--strategies", "abc"),
                   ("--replay", "0"), ("--replay", "-1"), ("--adapt", "-1"), ("--adapt", "abc"),
                   ("--world", "nowhere"), ("--world", "/dev/zero"), ("--models", "/nonexistent"),
                   ("--models", "/dev/null"), ("--workers", "0"), ("--seed", "1e400"),
                   ("--demos", "{base}/demos.csv")]:
        argv = ["play", "--quick", "--validate", "0", opt, v]
        exp = "either" if (opt, v) in (("--train-size", "1"), ("--demos", "{base}/demos.csv"),
                                       ("--shots", "1e12")) else "refuse"
        cli(C, f"play {opt} {v}", argv, expect=exp, outputs=("shots.csv", "summary.txt"),
            timeout=180)
    cli(C, "play valid quick", ["play", "--quick", "--validate", "0", "--shots", "1"],
        expect="accept", outputs=("shots.csv", "summary.txt"))
    for opt, v in [("--shots", "0"), ("--shots", "-1"), ("--shots", "abc"),
                   ("--robot", "nobody"), ("--field", "/dev/urandom"), ("--workers", "-1"),
                   ("--seed", "x")]:
        cli(C, f"validate {opt} {v}", ["validate", "--quick", opt, v], expect="refuse",
            outputs=("validation.csv",))
    cli(C, "validate valid quick", ["validate", "--quick", "--shots", "1"], expect="accept",
        outputs=("validation.csv", "report.txt"))

    # ---------------------------------------------------------------- models folder (play)
    M = "model_files"
    for how in ("empty_folder", "truncated_ds", "missing_strength", "garbage_dataset",
                "ds_is_fifo", "ds_is_dir"):
        cli(M, f"play --models {how}", ["play", "--quick", "--validate", "0", "--models",
                                        "{models_" + how + "}"],
            setup=models_setup, expect="refuse", outputs=("shots.csv",), timeout=180)

    # ---------------------------------------------------------------- field files (CLI)
    for name in ("name_path", "stimp_and_rr", "slope_huge", "arctan_step_tiny", "binary"):
        cli("field_files", f"play --field {name}", ["play", "--quick", "--validate", "0",
                                                    "--field", "{field_" + name + "}"],
            setup=field_setup, expect="refuse", outputs=("shots.csv",), timeout=180)
    cli("field_files", "table1 --field name_path", ["table1", "--quick", "--no-figures",
                                                    "--field", "{field_name_path}"],
        setup=field_setup, expect="refuse", outputs=("table1.csv",))

    # ---------------------------------------------------------------- demonstrations (CLI)
    for how in ("nan", "bool", "one_sample", "7d", "1d", "empty", "huge", "shuffled",
                "strings", "fifo", "devzero"):
        cli("demo_files", f"fit {how}", ["fit", "{demo_" + how + "}", "-K", "2",
                                         "--max-iter", "30"],
            setup=demo_setup, expect="either" if how in ("7d", "1d") else "refuse",
            outputs=("model.npz",), timeout=120)
    cli("demo_files", "table1 --demos nan", ["table1", "--quick", "--no-figures",
                                             "--demos", "{demo_nan}"],
        setup=demo_setup, expect="refuse", outputs=("table1.csv",))

    # ---------------------------------------------------------------- --out
    OUT = "out"
    for how in ("is_file", "under_file", "readonly_proc", "symlink_to_dir", "symlink_dangling",
                "symlink_to_file", "existing_results", "existing_tmp_files", "empty_string",
                "dev_null", "long_name", "same_as_input_dir", "dash_name", "locked"):
        cli(OUT, f"fit --out {how}", fit_small, setup=out_setup(how),
            expect={"symlink_to_dir": "accept", "existing_results": "accept",
                    "existing_tmp_files": "accept", "same_as_input_dir": "accept",
                    "dash_name": "either", "empty_string": "either"}.get(how, "refuse"),
            outputs=("model.npz",))
    cli(OUT, "lasa --out is_file", ["lasa", "--quick", "--no-figures", "--samples", "20"],
        setup=out_setup("is_file"), expect="refuse")
    cli(OUT, "play --out under_file", ["play", "--quick"], setup=out_setup("under_file"),
        expect="refuse")
    cli(OUT, "table1 --out readonly", ["table1", "--quick"], setup=out_setup("readonly_proc"),
        expect="refuse")

    # ---------------------------------------------------------------- signals
    S = "signals"
    long_fit = ["fit", "{base}/sshape.npz", "-K", "12", "--formulation", "constrained",
                "--max-iter", "5000"]
    commands = {
        "fit": (long_fit, ("model.npz",), (2.5, 6.0)),
        "lasa": (["lasa", "--quick", "--no-figures"], ("lasa.csv", "summary.txt"), (2.2, 3.5)),
        "table1": (["table1", "--quick", "--no-figures"], ("table1.csv", "table1.txt"),
                   (2.5, 7.0)),
        "play": (["play", "--quick", "--validate", "1"], ("shots.csv", "summary.txt"),
                 (3.0, 8.0)),
        "validate": (["validate", "--quick"], ("validation.csv", "report.txt"), (2.5, 6.0)),
    }
    for cmd, (argv, outs, delays) in commands.items():
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            for delay in delays:
                CASES.append(Case(S, f"{cmd} {sig.name} at {delay}s", "signal", argv=argv,
                                  outputs=outs, sig=sig, delay=delay, setup=sshape_setup,
                                  timeout=180))
    for cmd in ("fit", "play"):
        argv, outs, delays = commands[cmd]
        CASES.append(Case(S, f"{cmd} SIGINT twice at {delays[0]}s", "signal", argv=argv,
                          outputs=outs, sig=-signal.SIGINT, delay=delays[0],
                          setup=sshape_setup, timeout=180))
        CASES.append(Case(S, f"{cmd} SIGINT at 0.3s (startup)", "signal", argv=argv,
                          outputs=outs, sig=signal.SIGINT, delay=0.3, setup=sshape_setup,
                          timeout=180))

    # ------------------------------------------------- signals at random moments (--sweep N)
    # N cases per command, each signal (SIGINT, SIGTERM or SIGHUP) at a moment drawn uniformly
    # over the command's run (its duration measured on 2 cores, quick settings): start-up,
    # CasADi's conversions, IPOPT, exudyn, the writing of results. A signal that arrives after
    # the run ended counts as OK (NOT_REACHED).
    durations = {"fit": 10.0, "lasa": 4.5, "table1": 9.0, "play": 16.0, "validate": 8.0}
    rng = np.random.default_rng(SWEEP_SEED)
    for cmd, (argv, outs, _) in commands.items():
        for _ in range(SWEEP):
            sig = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)[int(rng.integers(3))]
            delay = round(float(rng.uniform(0.05, durations[cmd])), 2)
            CASES.append(Case("signal-sweep", f"{cmd} {sig.name} at {delay}s (random)",
                              "signal", argv=argv, outputs=outs, sig=sig, delay=delay,
                              setup=sshape_setup, timeout=180))

    # ---------------------------------------------------------------- concurrency
    K = "concurrency"
    CASES.append(Case(K, "two fits on one --out", "concurrent",
                      argv=[fit_small, fit_small], outputs=("model.npz",), delay=0.5))
    CASES.append(Case(K, "fit and lasa on one --out", "concurrent",
                      argv=[fit_small, ["lasa", "--quick", "--no-figures", "--samples", "20"]],
                      outputs=("model.npz",), delay=0.5))
    CASES.append(Case(K, "two plays on one --out", "concurrent",
                      argv=[["play", "--quick", "--validate", "0", "--shots", "1"]] * 2,
                      outputs=("shots.csv",), delay=1.0, timeout=240))
    CASES.append(Case(K, "three fits at once", "concurrent",
                      argv=[fit_small] * 3, outputs=("model.npz",), delay=0.0))
    CASES.append(Case(K, "two fits, different --out, same time", "concurrent",
                      argv=[fit_small, fit_small + ["--out", "{case}/other"]],
                      outputs=("model.npz",), delay=0.0))


# ---------------------------------------------------------------- CLI setups
def sshape_setup(d) -> dict:
    p = base_path("sshape.npz")
    if not os.path.exists(p):
        subprocess.run([sys.executable, "-c",
                        "from seds_casadi import save_demonstrations; "
                        "from seds_casadi.core import load_lasa; "
                        f"save_demonstrations({p!r}, load_lasa('Sshape'))"], check=True,
                       env=_env(d))
    return {}


def demo_setup(d) -> dict:
    from seds_casadi import save_demonstrations  # noqa: F401  (checks the import works)

    P, V = _demo_arrays()
    m = {}
    m["demo_nan"] = p = os.path.join(d, "nan.npz")
    P2 = [p_.copy() for p_ in P]
    P2[0][2, 0] = np.nan
    _write_npz(p, {f"pos_{i}": x for i, x in enumerate(P2)})
    m["demo_bool"] = p = os.path.join(d, "bool.npz")
    _write_npz(p, {f"pos_{i}": x > 0 for i, x in enumerate(P)})
    m["demo_one_sample"] = p = os.path.join(d, "one.csv")
    open(p, "w").write("demo,t,x0,x1\n0,0,1,2\n")
    m["demo_7d"] = p = os.path.join(d, "7d.npz")
    rng = np.random.default_rng(0)
    e = {}
    for i in range(3):
        x = np.cumsum(rng.normal(size=(30, 7)), axis=0)[::-1].copy()
        e[f"pos_{i}"] = x - x[-1]
    _write_npz(p, e)
    m["demo_1d"] = p = os.path.join(d, "1d.csv")
    open(p, "w").write("demo,t,x0\n" + "".join(f"{j},{0.1 * i},{(5 - i) * (j + 1)}\n"
                                                for j in range(2) for i in range(6)))
    m["demo_empty"] = p = os.path.join(d, "empty.csv")
    open(p, "w").write("")
    m["demo_huge"] = p = os.path.join(d, "huge.npz")
    _write_npz(p, {f"pos_{i}": x * 1e200 for i, x in enumerate(P)})
    m["demo_shuffled"] = p = os.path.join(d, "shuffled.csv")
    open(p, "w").write(_csv_rows(lambda ls: [ls[0]] + ls[1:][::-1], header="demo,t,x0,x1",
                                 vel=False))
    m["demo_strings"] = p = os.path.join(d, "strings.npz")
    _write_npz(p, {"pos_0": np.array([["a", "b"]] * 5)})
    m["demo_fifo"] = p = os.path.join(d, "fifo.csv")
    os.mkfifo(p)
    m["demo_devzero"] = "/dev/zero"
    return m


def field_setup(d) -> dict:
    m = {}
    for name, base, changes, raw in [
            ("name_path", "flat", [("name", "../../escaped")], None),
            ("stimp_and_rr", "flat", [("rolling_resistance", 0.1)], None),
            ("slope_huge", "flat", [("surface.slope_x", 1e6)], None),
            ("arctan_step_tiny", "arctan", [("surface.steepness", 1e5)], None),
            ("binary", "flat", [], "\x00\xff")]:
        p = os.path.join(d, name + ".json")
        if raw is None:
            spec = _field_spec(base)
            for k, v in changes:
                _set(spec, k, v)
            raw = json.dumps(spec)
        open(p, "w").write(raw)
        m["field_" + name] = p
    return m


def models_setup(d) -> dict:
    src = os.path.join(WORK, "base", "play_models")
    m = {}
    for how in ("empty_folder", "truncated_ds", "missing_strength", "garbage_dataset",
                "ds_is_fifo", "ds_is_dir"):
        dst = os.path.join(d, how)
        if how == "empty_folder":
            os.makedirs(dst)
        else:
            shutil.copytree(src, dst)
        ds = os.path.join(dst, "motion", "stable_ds.npz")
        if how == "truncated_ds":
            b = open(ds, "rb").read()
            open(ds, "wb").write(b[:len(b) // 2])
        elif how == "missing_strength":
            os.unlink(os.path.join(dst, "motion", "strength.npz"))
        elif how == "garbage_dataset":
            for f in os.listdir(dst):
                if f.startswith("dataset_"):
                    open(os.path.join(dst, f), "wb").write(os.urandom(3000))
        elif how == "ds_is_fifo":
            os.unlink(ds)
            os.mkfifo(ds)
        elif how == "ds_is_dir":
            os.unlink(ds)
            os.mkdir(ds)
        m["models_" + how] = dst
    return m


def out_setup(how):
    def setup(d) -> dict:
        out = os.path.join(d, "out")
        if how == "is_file":
            open(out, "w").write("x")
        elif how == "under_file":
            open(os.path.join(d, "f"), "w").write("x")
            out = os.path.join(d, "f", "out")
        elif how == "readonly_proc":
            out = "/proc/fuzz_out"
        elif how == "symlink_to_dir":
            os.makedirs(os.path.join(d, "real"))
            os.symlink(os.path.join(d, "real"), out)
        elif how == "symlink_dangling":
            os.symlink(os.path.join(d, "nowhere"), out)
        elif how == "symlink_to_file":
            open(os.path.join(d, "f"), "w").write("x")
            os.symlink(os.path.join(d, "f"), out)
        elif how == "existing_results":
            os.makedirs(out)
            open(os.path.join(out, "model.npz"), "w").write("old")
            open(os.path.join(out, "notes.txt"), "w").write("mine")
        elif how == "existing_tmp_files":
            os.makedirs(out)
            open(os.path.join(out, ".tmp-abc123"), "w").write("old")
            open(os.path.join(out, "streamlines.tmp-999.png"), "w").write("old")
        elif how == "empty_string":
            out = ""
        elif how == "dev_null":
            out = "/dev/null"
        elif how == "long_name":
            out = os.path.join(d, "x" * 300)
        elif how == "same_as_input_dir":
            out = d
        elif how == "dash_name":
            out = os.path.join(d, "-weird name with spaces")
        elif how == "locked":
            os.makedirs(out)
            # hold the lock from a process that outlives the setup, for 20 s
            script = ("import fcntl, os, sys, time; fd = os.open(sys.argv[1], os.O_RDWR | "
                      "os.O_CREAT); fcntl.flock(fd, fcntl.LOCK_EX); print('locked', "
                      "flush=True); time.sleep(20)")
            p = subprocess.Popen([sys.executable, "-c", script,
                                  os.path.join(out, ".seds-casadi.lock")],
                                 stdout=subprocess.PIPE, text=True)
            p.stdout.readline()
            return {"out": out, "holder": p}
        return {"out": out}
    return setup


# ====================================================================== running
@dataclass
class Result:
    case: Case
    cls: str
    detail: str
    seconds: float


def _env(d) -> dict:
    tmp = os.path.join(d, "_tmpdir")
    os.makedirs(tmp, exist_ok=True)
    env = dict(os.environ, MPLBACKEND="Agg", TMPDIR=tmp, PYTHONUNBUFFERED="1",
               PYTHONPATH=ROOT)
    return env


def _preexec():
    # as a terminal's shell starts a command: SIGINT and SIGHUP at their defaults
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGHUP, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM, signal.SIGHUP})


def _exe() -> list[str]:
    exe = os.path.join(os.path.dirname(sys.executable), "seds-casadi")
    return [exe] if os.path.exists(exe) else [sys.executable, "-m", "seds_casadi"]


def _session_procs(sid: int) -> list[str]:
    out = subprocess.run(["ps", "-eo", "pid,sid,stat,args"], capture_output=True,
                         text=True).stdout.splitlines()[1:]
    res = []
    for line in out:
        parts = line.split(None, 3)
        if len(parts) >= 3 and parts[1] == str(sid) and not parts[2].startswith("Z"):
            res.append(line.strip())
    return res


def _leftovers(d, out) -> list[str]:
    found = []
    for root, dirs, files in os.walk(d):
        if "/_tmpdir" in root + "/" and root.endswith("_tmpdir"):
            pass
        for f in files + dirs:
            p = os.path.join(root, f)
            rel = os.path.relpath(p, d)
            if rel.startswith("_tmpdir" + os.sep):
                found.append(f"in TMPDIR: {rel}")
            elif (f.startswith(".tmp-") or ".tmp-" in f) and "existing_tmp" not in d:
                found.append(f"temporary file {rel}")
            elif f == ".seds-casadi.lock":
                found.append(f"lock file {rel}")
    if out and os.path.isdir(out) and out.startswith(d):
        for f in os.listdir(out):
            if f.startswith(".tmp-") or ".tmp-" in f:
                found.append(f"temporary file in --out: {f}")
    return sorted(set(found))


def _has_traceback(text: str) -> bool:
    return "Traceback (most recent call last)" in text


def _check_outputs(out, outputs) -> str | None:
    for f in outputs:
        p = os.path.join(out, f)
        if not os.path.exists(p):
            return f"exit 0 but {f} is missing"
        if f.endswith(".csv"):
            txt = open(p).read().lower()
            if re.search(r"(^|,)\s*(nan|inf|-inf)\s*(,|$)", txt, re.M):
                return f"{f} holds NaN/inf"
        if f == "model.npz":
            r = subprocess.run([sys.executable, "-c",
                                "import sys, numpy as np; from seds_casadi import StableDS; "
                                "m = StableDS.load(sys.argv[1]); "
                                "y = m.predict(np.zeros((1, m.n_dims))); "
                                "sys.exit(0 if np.all(np.isfinite(y)) else 3)", p],
                               capture_output=True, text=True, env=_env(os.path.dirname(out)))
            if r.returncode != 0:
                return f"model.npz does not load or predicts NaN: {r.stderr[-300:]}"
    return None


def _start(argv, d, out) -> subprocess.Popen:
    cmd = _exe() + list(argv) + (["--out", out] if out is not None and "--out" not in argv
                                 else [])
    log = open(os.path.join(d, f"_log_{time.monotonic_ns()}.txt"), "w+")
    p = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, cwd=d, env=_env(d),
                         start_new_session=True, preexec_fn=_preexec)
    p.log = log
    return p


def _output(p) -> str:
    p.log.flush()
    p.log.seek(0)
    text = p.log.read()
    p.log.close()
    os.unlink(p.log.name)
    return text


def _wait(p, timeout) -> bool:
    try:
        p.wait(timeout)
        return True
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        return False


def _fill(argv, m) -> list[str]:
    return [a.format(**m) if "{" in a else a for a in argv]


def _classify_exit(rc, text, expect, out, outputs) -> tuple[str, str]:
    last = text.strip().splitlines()[-3:] if text.strip() else [""]
    if rc < 0:
        return "CRASH", f"killed by signal {-rc}; {last}"
    if expect == "debug":
        return ("OK", "refused with --debug's traceback") if rc in (1, 2) and \
            _has_traceback(text) else ("SILENTLY_WRONG", f"--debug: exit {rc}: {text[-500:]}")
    if _has_traceback(text):
        return "TRACEBACK", text[-2500:]
    if TEMPNAME.search(text):
        return "TEMPNAME_IN_MESSAGE", TEMPNAME.search(text).group(0) + ": " + text[-800:]
    if rc in (1, 2):
        if expect == "accept":
            return "SILENTLY_WRONG", f"exit {rc} for a valid run: {text[-800:]}"
        if not text.strip():
            return "SILENTLY_WRONG", f"exit {rc} with no message"
        return "OK", f"refused (exit {rc}): {last[-1][:200]}"
    if rc == 0:
        if expect == "refuse":
            return "SILENTLY_WRONG", f"accepted (exit 0): {text[-800:]}"
        bad = _check_outputs(out, outputs)
        if bad:
            return "SILENTLY_WRONG", bad
        return "OK", "ran"
    return "CRASH", f"exit code {rc}: {text[-800:]}"


def run_cli(case: Case, d: str) -> tuple[str, str]:
    m = {"base": base_path(), "case": d}
    out = os.path.join(d, "out")
    holder = None
    if case.setup:
        extra = case.setup(d)
        holder = extra.pop("holder", None)
        out = extra.pop("out", out)
        m.update(extra)
    argv = _fill(case.argv, m)
    try:
        p = _start(argv, d, out)
        finished = _wait(p, case.timeout)
        text = _output(p)
    finally:
        if holder is not None:  # the other run: its lock file is its own, not this run's
            holder.kill()
            holder.wait()
            os.unlink(os.path.join(out, ".seds-casadi.lock"))
    if not finished:
        return "HANG", f"not finished in {case.timeout} s: {text[-1500:]}"
    cls, detail = _classify_exit(p.returncode, text, case.expect, out, case.outputs)
    procs = _session_procs(p.pid)
    left = _leftovers(d, out)
    if cls == "OK" and (procs or left):
        return "LEFT_BEHIND", f"{procs} {left}; run: {detail}"
    return cls, detail


def run_signal(case: Case, d: str) -> tuple[str, str]:
    m = {"base": base_path(), "case": d}
    if case.setup:
        m.update(case.setup(d))
    out = os.path.join(d, "out")
    argv = _fill(case.argv, m)
    p = _start(argv, d, out)
    time.sleep(case.delay)
    if p.poll() is not None:
        text = _output(p)
        return "OK", (f"NOT_REACHED: ended (exit {p.returncode}) before the signal at "
                      f"{case.delay} s; {text[-300:]}")
    sig = abs(case.sig)
    t_sig = time.time()
    os.killpg(p.pid, sig)
    if case.sig < 0:  # twice
        time.sleep(0.15)
        try:
            os.killpg(p.pid, sig)
        except ProcessLookupError:
            pass
    t0 = time.perf_counter()
    finished = _wait(p, 10.0)
    elapsed = time.perf_counter() - t0
    text = _output(p)
    if not finished:
        return "HANG", f"still running 10 s after {signal.Signals(sig).name}: {text[-1500:]}"
    rc = p.returncode
    if rc < 0:
        return "CRASH", f"died of signal {-rc} after {signal.Signals(sig).name}: {text[-800:]}"
    if _has_traceback(text):
        return "TRACEBACK", text[-2500:]
    if TEMPNAME.search(text):
        return "TEMPNAME_IN_MESSAGE", text[-800:]
    if rc == 0:
        # the signal arrived once the work was done (its results written before it, the
        # process ending: signals are then ignored), or it was lost (results written after)
        late = [f for f in case.outputs if not os.path.exists(os.path.join(out, f))
                or os.path.getmtime(os.path.join(out, f)) >= t_sig]
        return ("SILENTLY_WRONG" if late else "OK",
                f"exit 0 after {signal.Signals(sig).name}"
                + (f", written after it or missing: {late}" if late else
                   ", every result written before it") + f": {text[-600:]}")
    if rc != 130:
        return "SILENTLY_WRONG", f"exit {rc} (not 130) after the signal: {text[-800:]}"
    if elapsed > 2.0:
        return "HANG", f"exit 130 only {elapsed:.2f} s after the signal"
    written = [f for f in case.outputs if os.path.exists(os.path.join(out, f))
               and os.path.getmtime(os.path.join(out, f)) >= t_sig - 0.01]
    if written:
        return "SILENTLY_WRONG", f"written after the signal as complete: {written}"
    time.sleep(0.2)
    procs = _session_procs(p.pid)
    left = _leftovers(d, out)
    if procs or left:
        return "LEFT_BEHIND", f"{procs} {left}"
    return "OK", f"exit 130 in {elapsed:.2f} s"


def run_concurrent(case: Case, d: str) -> tuple[str, str]:
    m = {"base": base_path(), "case": d}
    out = os.path.join(d, "out")
    procs = []
    for argv in case.argv:
        procs.append(_start(_fill(argv, m), d, out))
        time.sleep(case.delay)
    texts, codes = [], []
    for p in procs:
        if not _wait(p, case.timeout):
            for q in procs:
                _wait(q, 0.1)
            return "HANG", "a concurrent run did not finish"
        texts.append(_output(p))
        codes.append(p.returncode)
    for t, rc in zip(texts, codes):
        if rc < 0:
            return "CRASH", f"signal {-rc}: {t[-500:]}"
        if _has_traceback(t):
            return "TRACEBACK", t[-2500:]
        if TEMPNAME.search(t):
            return "TEMPNAME_IN_MESSAGE", t[-800:]
        if rc not in (0, 1, 2):
            return "CRASH", f"exit {rc}: {t[-500:]}"
        if rc in (1, 2) and not re.search(r"lock|another run|in use|busy", t, re.I):
            return "SILENTLY_WRONG", f"exit {rc} with a message about something else: {t[-500:]}"
    if 0 not in codes:
        return "SILENTLY_WRONG", f"no run succeeded: {codes} {[t[-200:] for t in texts]}"
    bad = _check_outputs(out, case.outputs)
    if bad:
        return "SILENTLY_WRONG", bad
    left = _leftovers(d, out) + [x for p in procs for x in _session_procs(p.pid)]
    if left:
        return "LEFT_BEHIND", str(left)
    return "OK", f"exit codes {codes}"


# ---------------------------------------------------------------- the API worker
class Worker:
    """A Python process that runs API cases one at a time (restarted after a hang/crash)."""

    def __init__(self) -> None:
        self.p = None

    def start(self) -> None:
        d = os.path.join(WORK, "worker")
        os.makedirs(d, exist_ok=True)
        self.err = open(os.path.join(d, "stderr.txt"), "a")
        self.p = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--worker"],
                                  stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                  stderr=self.err, text=True, env=_env(d),
                                  start_new_session=True, preexec_fn=_preexec)
        line = self.p.stdout.readline()
        assert line.strip() == "ready", line

    def run(self, case: Case, d: str) -> tuple[str, str]:
        if self.p is None or self.p.poll() is not None:
            self.start()
        self.p.stdin.write(json.dumps({"func": case.func, "dir": d,
                                       "args": _encode(case.args)}) + "\n")
        self.p.stdin.flush()
        box = {}
        t = threading.Thread(target=lambda: box.setdefault("line", self.p.stdout.readline()),
                             daemon=True)
        t.start()
        t.join(case.timeout)
        if t.is_alive():
            self.kill()
            return "HANG", f"not finished in {case.timeout} s"
        line = box.get("line", "")
        if not line:
            rc = self.p.wait()
            self.p = None
            return "CRASH", f"the worker died (exit {rc})"
        r = json.loads(line)
        return _classify_api(case, r)

    def kill(self) -> None:
        if self.p is not None:
            try:
                os.killpg(self.p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            self.p.wait()
            self.p = None


def _encode(args):
    def enc(a):
        if isinstance(a, np.ndarray):
            return {"__nd__": a.tolist(), "shape": list(a.shape)}
        if isinstance(a, float) and not np.isfinite(a):
            return {"__f__": repr(a)}
        if isinstance(a, (list, tuple)):
            return [enc(x) for x in a]
        if isinstance(a, dict):
            return {"__d__": [[enc(k), enc(v)] for k, v in a.items()]}
        if callable(a):
            return {"__lambda__": True}
        if isinstance(a, np.floating):
            return enc(float(a))
        return a
    return [enc(a) for a in args]


def _decode(args):
    def dec(a):
        if isinstance(a, dict):
            if "__nd__" in a:
                return np.array(a["__nd__"], dtype=float).reshape(a["shape"])
            if "__f__" in a:
                return float(a["__f__"])
            if "__d__" in a:
                return {dec(k): dec(v) for k, v in a["__d__"]}
            if "__lambda__" in a:
                return lambda x: "not an expression"
        if isinstance(a, list):
            return [dec(x) for x in a]
        return a
    return [dec(a) for a in args]


def _classify_api(case: Case, r: dict) -> tuple[str, str]:
    if r["status"] == "returned":
        if r["problem"]:
            return "SILENTLY_WRONG", r["problem"]
        if case.expect == "refuse":
            return "SILENTLY_WRONG", "accepted"
        return "OK", f"returned ({r['seconds']:.1f} s)"
    msg = r["message"]
    if TEMPNAME.search(msg):
        return "TEMPNAME_IN_MESSAGE", msg
    if not r["project_error"]:
        return "TRACEBACK", f"{r['type']}: {msg[:500]}\n{r['traceback'][-2000:]}"
    if r["seconds"] > 30:
        return "HANG", f"refused only after {r['seconds']:.0f} s: {r['type']}: {msg[:300]}"
    return "OK", f"refused: {r['type']}: {msg[:200]}"


def worker_main() -> None:
    import warnings

    import seds_casadi
    from seds_casadi import SEDSError

    warnings.simplefilter("ignore")
    pkg = os.path.dirname(os.path.abspath(seds_casadi.__file__))
    proto = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    proto.write("ready\n")
    proto.flush()
    for line in sys.stdin:
        job = json.loads(line)
        f = API_FUNCS[job["func"]]
        d = job["dir"]
        os.makedirs(d, exist_ok=True)
        t = time.perf_counter()
        try:
            problem = f(d, *_decode(job["args"]))
            r = {"status": "returned", "problem": problem}
        except Exception as exc:  # noqa: BLE001 - classified
            tb = exc.__traceback__
            frames = []
            while tb is not None:
                frames.append(os.path.abspath(tb.tb_frame.f_code.co_filename))
                tb = tb.tb_next
            where = frames[-1] if frames else ""
            ok_type = isinstance(exc, (ValueError, TypeError, SEDSError, FileNotFoundError))
            ok_where = where.startswith(pkg) or where.endswith(
                os.path.join("utils", "_param_validation.py"))
            r = {"status": "raised", "type": type(exc).__name__, "message": str(exc),
                 "project_error": ok_type and ok_where, "where": where,
                 "traceback": "".join(traceback.format_exception(exc))}
        except BaseException as exc:  # noqa: BLE001 - KeyboardInterrupt, SystemExit...
            r = {"status": "raised", "type": type(exc).__name__, "message": str(exc),
                 "project_error": False, "where": "",
                 "traceback": "".join(traceback.format_exception(exc))}
        r["seconds"] = time.perf_counter() - t
        proto.write(json.dumps(r, default=str) + "\n")
        proto.flush()


# ---------------------------------------------------------------- main
def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--only", help="comma-separated areas")
    ap.add_argument("--match", help="run only cases whose name contains this")
    ap.add_argument("--report", default=os.path.join(WORK, "failures.txt"))
    ap.add_argument("--list", action="store_true")
    ap.add_argument("--sweep", type=int, default=0, metavar="N",
                    help="N more signal cases per command at random moments (area "
                         "signal-sweep)")
    ap.add_argument("--seed", type=int, default=0, help="the sweep's random moments")
    args = ap.parse_args()
    global SWEEP, SWEEP_SEED
    SWEEP, SWEEP_SEED = args.sweep, args.seed
    if args.worker:
        worker_main()
        return 0
    define_cases()
    cases = CASES
    if args.only:
        cases = [c for c in cases if c.area in args.only.split(",")]
    if args.match:
        cases = [c for c in cases if args.match in c.name]
    if args.list:
        for c in cases:
            print(c.area, "|", c.name)
        print(len(cases), "cases")
        return 0
    if os.path.isdir(WORK):
        subprocess.run(["chmod", "-R", "u+w", WORK])
        shutil.rmtree(WORK, ignore_errors=True)
    os.makedirs(base_path())
    t0 = time.perf_counter()
    print(f"{len(cases)} cases; building the base inputs ...", flush=True)
    build_base()
    # (a concurrent case's argv is a list of command lines)
    if any("--models" in " ".join(str(a) for a in c.argv) for c in cases):
        d = base_path("playrun")
        os.makedirs(d)
        p = _start(["play", "--quick", "--validate", "0", "--shots", "1"], d,
                   os.path.join(d, "out"))
        p.wait()
        _output(p)
        shutil.copytree(os.path.join(d, "out", "models"), base_path("play_models"))
    worker = Worker()
    results: list[Result] = []
    try:
        for i, c in enumerate(cases):
            d = os.path.join(WORK, "cases", f"{i:04d}")
            os.makedirs(d)
            t = time.perf_counter()
            try:
                if c.kind == "api":
                    cls, detail = worker.run(c, d)
                elif c.kind == "cli":
                    cls, detail = run_cli(c, d)
                elif c.kind == "signal":
                    cls, detail = run_signal(c, d)
                else:
                    cls, detail = run_concurrent(c, d)
            except Exception:  # noqa: BLE001 - a fault of the campaign itself
                cls, detail = "TRACEBACK", "CAMPAIGN ERROR: " + traceback.format_exc()
            dt = time.perf_counter() - t
            results.append(Result(c, cls, detail, dt))
            mark = "" if cls == "OK" else f"  <-- {cls}"
            print(f"[{i + 1:3d}/{len(cases)}] {dt:6.1f}s {c.area:14s} {c.name[:60]}{mark}",
                  flush=True)
            if cls == "OK":
                shutil.rmtree(d, ignore_errors=True)
    finally:
        worker.kill()
    total = time.perf_counter() - t0
    areas = sorted({r.case.area for r in results})
    print(f"\n{len(results)} cases in {total / 60:.1f} min\n")
    print(f"{'area':16s}" + "".join(f"{c[:9]:>10s}" for c in CLASSES) + f"{'total':>8s}")
    for a in areas + ["ALL"]:
        rs = [r for r in results if a in ("ALL", r.case.area)]
        print(f"{a:16s}" + "".join(f"{sum(r.cls == c for r in rs):10d}" for c in CLASSES)
              + f"{len(rs):8d}")
    not_reached = [r for r in results if r.detail.startswith("NOT_REACHED")]
    if not_reached:
        print(f"\n{len(not_reached)} signal cases ended before their signal (counted OK): "
              + ", ".join(r.case.name for r in not_reached))
    fails = [r for r in results if r.cls != "OK"]
    os.makedirs(os.path.dirname(args.report), exist_ok=True)
    with open(args.report, "w") as fh:
        for r in fails:
            fh.write(f"=== {r.cls} | {r.case.area} | {r.case.name} | {r.seconds:.1f} s\n"
                     f"{r.detail}\n\n")
    with open(os.path.join(os.path.dirname(args.report), "all_cases.txt"), "w") as fh:
        for r in results:
            fh.write(f"{r.cls:20s} {r.case.area:14s} {r.case.name} | {r.seconds:.1f} s | "
                     f"{r.detail[:300]!r}\n")
    print(f"\n{len(fails)} failing cases; details in {args.report}")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
