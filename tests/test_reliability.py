"""Issue 18 (reliability): one test group per class of the outside fuzz, each failing on the
code before the fix (classes 2 and 7 are tested with the ball model and the SEDS core).

1 unguarded files, 3 the kernel cache, 4 Dask, 5 tracebacks instead of ``error:`` lines,
6 silently misread input, 8 signals and concurrency, 9 weaker checks.
"""

import json
import os
import socket
import threading
import time

import numpy as np
import pytest

from seds_casadi import Demonstrations, ModelFileError, StableDS, load_demonstrations
from seds_casadi.app.cli import main
from seds_casadi.app.executors import open_executor
from seds_casadi.core.model_files import checksum
from seds_casadi.minigolf.fields import FIELDS_FOLDER, Field, load_field
from seds_casadi.minigolf.hitting_data import HittingDataset
from seds_casadi.minigolf.stroke import Stroke

STROKE = Stroke(np.array([0.995, 0.097, -0.003]), 0.99)


def _field_spec(name: str) -> dict:
    with open(os.path.join(FIELDS_FOLDER, name + ".json")) as fh:
        return json.load(fh)


def _dataset(n: int = 6) -> HittingDataset:
    rng = np.random.default_rng(0)
    ball = np.column_stack([np.full(n, 0.1), np.linspace(-0.2, 0.2, n)])
    hole = np.tile([2.5, 0.0], (n, 1))
    return HittingDataset("flat", "centre", ball, hole, rng.uniform(-0.1, 0.1, n),
                          rng.uniform(1.0, 1.5, n), STROKE, declared={})


def _rewrite(path, **changes) -> None:
    """Edit entries of an .npz file in place as an outsider would (checksum left as it was)."""
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    data.update(changes)
    np.savez(path, **data)


def _reseal(path) -> None:
    """Recompute a guarded file's checksum after an edit (a forger who knows the format)."""
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    names = [k for k in data if k not in ("format", "version", "meta", "checksum")]
    data["checksum"] = np.array(checksum([data[k] for k in names], str(data["meta"])))
    np.savez(path, **data)


# ------------------------------------------------------------------ 1. unguarded files
def test_dataset_file_is_guarded_against_edits_nan_and_forgery(tmp_path):
    ds = _dataset()
    p = tmp_path / "dataset_flat.npz"
    ds.save(p)
    back = HittingDataset.load(p)
    np.testing.assert_allclose(back.alpha, ds.alpha, atol=1e-15)
    assert back.stroke.speed == ds.stroke.speed
    # v* edited from 0.99 to 147 m/s in the meta: refused by the checksum
    with np.load(p) as z:
        meta = json.loads(str(z["meta"]))
    meta["stroke"]["speed"] = 147.0
    _rewrite(p, meta=np.array(json.dumps(meta)))
    with pytest.raises(ModelFileError, match="checksum"):
        HittingDataset.load(p)
    ds.save(p)
    _rewrite(p, kappa=np.full(len(ds), np.nan))
    with pytest.raises(ModelFileError, match="'kappa' holds NaN"):
        HittingDataset.load(p)
    # a forged file with a valid checksum is still re-validated
    ds.save(p)
    _rewrite(p, kappa=-ds.kappa)
    _reseal(p)
    with pytest.raises(ModelFileError, match="speed gains must be positive"):
        HittingDataset.load(p)


def test_strategy_set_file_is_guarded(tmp_path):
    from seds_casadi.minigolf.strategies import Strategy, StrategySet

    ds = _dataset()
    ss = StrategySet("flat", ds.ball, ds.hole,
                     [Strategy(0, 0, ds.subset(np.arange(len(ds))), np.full(len(ds), 0.5),
                               ["direct"] * len(ds))], STROKE, {"resolution": [5, 5]})
    p = tmp_path / "strategies_flat.npz"
    ss.save(p)
    back = StrategySet.load(p)
    np.testing.assert_allclose(back.strategies[0].data.kappa, ds.kappa)
    _rewrite(p, s0_kappa=ds.kappa * 100)
    with pytest.raises(ModelFileError, match="checksum"):
        StrategySet.load(p)


def test_every_file_a_play_run_reads_is_guarded():
    """The artefacts ``play --models`` reads: each class writes through write_guarded."""
    import inspect

    from seds_casadi.minigolf import hitting_data, strategy_files
    from seds_casadi.motion import hitting

    for mod in (hitting_data, strategy_files, hitting):
        src = inspect.getsource(mod)
        assert "write_guarded" in src and "read_guarded" in src and "np.savez" not in src


# ------------------------------------------------------------------ 3. the kernel cache
def test_an_unwritable_cache_falls_back_instead_of_failing(tmp_path, monkeypatch):
    from seds_casadi.codegen.cache import CompileError, compiler_available, shared_library

    if compiler_available() is None:
        pytest.skip("no C compiler")
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    monkeypatch.setenv("SEDS_CASADI_CACHE", str(blocker))
    with pytest.raises(CompileError, match="SEDS_CASADI_CACHE"):
        shared_library(b"int f(void) { return 1; }", "t")


# ------------------------------------------------------------------ 4. Dask
class _Server:
    """A TCP service on localhost that is not a Dask scheduler (``mode``: "junk" sends random
    bytes, "silent" accepts and says nothing, as a web server waiting for a request)."""

    def __init__(self, mode: str) -> None:
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen()
        self.address = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        self.mode, self.conns = mode, []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                c, _ = self.sock.accept()
            except OSError:
                return
            self.conns.append(c)
            if self.mode == "junk":
                c.sendall(np.random.default_rng(0).bytes(4096))

    def close(self) -> None:
        for c in self.conns:
            c.close()
        self.sock.close()


@pytest.mark.parametrize("mode", ["junk", "silent"])
def test_dask_against_a_service_that_is_not_a_scheduler(mode):
    srv = _Server(mode)
    try:
        t = time.perf_counter()
        with pytest.raises(ValueError, match="--dask .*scheduler"):
            with open_executor(dask=srv.address, timeout=2.0):
                pass
        # the 2 s timeout holds (it was 58 s, or an EiB alloc); the bound leaves room for a
        # loaded machine (6.6 s seen after the suite's Dask tests)
        assert time.perf_counter() - t < 20.0
    finally:
        srv.close()


def test_dask_refused_port_fails_at_once_and_a_real_scheduler_answers():
    from seds_casadi.app.executors import check_scheduler

    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    t = time.perf_counter()
    with pytest.raises(ValueError, match="cannot connect"):
        check_scheduler(f"tcp://127.0.0.1:{port}", 10.0)
    assert time.perf_counter() - t < 2.0
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, processes=False, dashboard_address=None) as c:
        assert check_scheduler(c.scheduler_address, 5.0)["type"] == "Scheduler"
        with open_executor(dask=c.scheduler_address) as ex:
            assert ex.submit(sum, [1, 2]).result() == 3


@pytest.mark.slow
def test_play_checks_its_executor_before_learning(tmp_path):
    pytest.importorskip("pinocchio")
    from seds_casadi.app.play import play

    srv = _Server("silent")
    t = time.perf_counter()
    try:
        with pytest.raises(ValueError, match="--dask"):
            play(quick=True, dask=srv.address, out=str(tmp_path / "p"), progress=False)
    finally:
        srv.close()
    assert time.perf_counter() - t < 20.0  # 10 s timeout; learning alone took 24 s
    assert not (tmp_path / "p" / "models" / "motion").exists()


# ------------------------------------------------------------------ 5. error lines
def _cli(capsys, *args):
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def demo_npz(tmp_path, spiral_demos):
    from seds_casadi import save_demonstrations

    p = tmp_path / "demos.npz"
    save_demonstrations(p, spiral_demos)
    return p


@pytest.mark.parametrize("command", ["fit", "lasa", "table1", "validate", "play"])
@pytest.mark.parametrize("where", ["file", "under_file"])
def test_unusable_out_is_an_error_line_for_every_command(tmp_path, capsys, demo_npz, command,
                                                         where):
    blocker = tmp_path / "blocker"
    blocker.write_text("x")
    out = blocker if where == "file" else blocker / "sub"
    args = [command] + ([str(demo_npz)] if command == "fit" else []) + ["--out", str(out)]
    code, _, err = _cli(capsys, *args)
    assert code == 2 and f"seds-casadi {command}: error: --out" in err, err
    assert "Traceback" not in err and blocker.read_text() == "x"


def test_fit_on_one_dimensional_demonstrations(tmp_path, capsys):
    t = np.linspace(0, 1, 30)[:, None]
    p = tmp_path / "d1.npz"
    np.savez(p, pos_0=(1 - t) ** 2, pos_1=2 * (1 - t) ** 2, dt=0.03)
    code, out, err = _cli(capsys, "fit", str(p), "-K", "2", "-q", "--out", str(tmp_path / "o"))
    assert code == 0, err
    assert StableDS.load(tmp_path / "o" / "model.npz").n_dims == 1
    assert (tmp_path / "o" / "streamlines.png").stat().st_size > 1000


def test_field_errors_are_error_lines(tmp_path, capsys):
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    for field, msg in ((str(tmp_path), "is a folder"), (str(deep), "nested too deeply")):
        code, _, err = _cli(capsys, "validate", "--field", field, "--out", str(tmp_path / "v"))
        assert code == 2 and msg in err and "Traceback" not in err, err


def test_debug_shows_the_traceback(tmp_path, capsys):
    with pytest.raises(ValueError, match="no field"):
        main(["validate", "--field", "nofield", "--out", str(tmp_path / "v"), "--debug"])


# ------------------------------------------------------------------ 6. misread input
def test_npz_demonstrations_with_a_gap_or_unknown_entries_are_refused(tmp_path, spiral_demos):
    P, V = spiral_demos.positions, spiral_demos.velocities
    cases = {"gap": ({"pos_0": P[0], "pos_2": P[1], "dt": 0.05}, "pos_1 is missing"),
             "typo": ({"pos_0": P[0], "pos_1": P[1], "dt": 0.05, "trget": P[0][-1]},
                      "did you mean 'target'"),
             "complex": ({"pos_0": P[0] + 1j, "dt": 0.05}, "complex"),
             "partial_vel": ({"pos_0": P[0], "pos_1": P[1], "vel_0": V[0]}, "vel_1 is missing")}
    for name, (arrays, msg) in cases.items():
        p = tmp_path / f"{name}.npz"
        np.savez(p, **arrays)
        with pytest.raises(ValueError, match=msg) as e:
            load_demonstrations(p)
        assert str(p) in str(e.value)


def _csv(tmp_path, name, text, **kw):
    p = tmp_path / name
    p.write_bytes(text.encode("utf-8"))
    return p


def test_csv_demonstrations_are_read_unambiguously(tmp_path):
    rows = "".join(f"0,{0.1 * i:.1f},{1 - 0.1 * i:.2f},{0.5 - 0.05 * i:.3f}\n" for i in range(8))
    ok = load_demonstrations(_csv(tmp_path, "ok.csv", "demo,t,x0,x1\n" + rows))
    # a UTF-8 BOM and quoted headers are the same file
    for name, head in (("bom.csv", "\ufeffdemo,t,x0,x1\n"), ("q.csv", '"demo","t","x0","x1"\n')):
        d = load_demonstrations(_csv(tmp_path, name, head + rows))
        np.testing.assert_array_equal(d.positions[0], ok.positions[0])
    bad = {"gap.csv": ("demo,t,x0,x2\n", "x1 is missing"),
           "dup.csv": ("demo,t,x0,x0\n", "'x0' appears twice"),
           "typo.csv": ("demo,t,x0,y1\n", "unknown column 'y1'")}
    for name, (head, msg) in bad.items():
        with pytest.raises(ValueError, match=msg):
            load_demonstrations(_csv(tmp_path, name, head + rows))
    with pytest.raises(ValueError, match="rows of demo 0 are not contiguous"):
        load_demonstrations(_csv(tmp_path, "split.csv", _interleaved()))


def _interleaved() -> str:
    """Rows of demo 0, then demo 1, then demo 0 again."""
    lines = ["demo,t,x0,x1"]
    for demo in (0, 1, 0):
        lines += [f"{demo},{0.1 * i:.1f},{1 - 0.1 * i:.2f},{0.2 * i:.2f}" for i in range(5)]
    return "\n".join(lines) + "\n"


def test_field_files_refuse_misspelt_entries_with_did_you_mean():
    spec = _field_spec("flat")
    spec["wall_restituion"] = 0.9
    with pytest.raises(ValueError, match="did you mean 'wall_restitution'"):
        Field.from_dict(spec, "mine.json")
    spec = _field_spec("arctan")
    spec["surface"]["steepnes"] = 3.0
    with pytest.raises(ValueError, match="did you mean 'steepness'"):
        Field.from_dict(spec, "mine.json")
    spec = _field_spec("flat")
    spec["hole"]["radiu"] = 0.05
    with pytest.raises(ValueError, match="did you mean 'radius'"):
        Field.from_dict(spec, "mine.json")
    with pytest.raises(ValueError, match="did you mean 'arctan'"):
        load_field("arctn")


@pytest.mark.parametrize("change, msg", [
    ({"bounds": [0, 1000, -0.5, 0.5]}, "at most 100 m"),
    ({"surface": {"shape": "rough", "amplitude": 0.002, "width": 0.05, "bumps": 1e6}},
     "at most 5000"),
    ({"bounds": [0, 30, -15, 15], "ball_region": [0, 1, -0.5, 0.5],
      "surface": {"shape": "rough", "amplitude": 0.002, "width": 0.05, "bumps": 10}},
     "table of"),
    ({"surface": {"shape": "rough", "amplitude": 0.002, "width": 0.05, "bumps": 2.5}},
     "whole number"),
])
def test_field_size_limits_come_before_allocation(change, msg):
    spec = _field_spec("rough_flat")
    spec.update(change)
    t = time.perf_counter()
    with pytest.raises(ValueError, match=msg):
        Field.from_dict(spec, "big.json")
    assert time.perf_counter() - t < 1.0


# ------------------------------------------------------------------ 8. signals, concurrency
def test_a_second_run_on_the_same_out_is_refused(tmp_path, capsys, demo_npz):
    from seds_casadi.app.outdir import output_folder

    out = tmp_path / "o"
    with output_folder(out):
        code, _, err = _cli(capsys, "fit", str(demo_npz), "--out", str(out))
    assert code == 2 and "in use by another seds-casadi run" in err
    assert not (out / "model.npz").exists()


def test_temporary_files_of_a_killed_run_are_swept(tmp_path):
    from seds_casadi.app.outdir import LOCK_NAME, output_folder

    out = tmp_path / "o"
    (out / "models").mkdir(parents=True)
    stale = [out / ".tmp-abc.npz", out / "models" / ".tmp-x"]
    for p in stale:
        p.write_bytes(b"")
    (out / "keep.csv").write_text("a\n")
    with output_folder(out):
        assert not any(p.exists() for p in stale) and (out / "keep.csv").exists()
        assert (out / LOCK_NAME).read_text() == str(os.getpid())
    assert not (out / LOCK_NAME).exists() and (out / "keep.csv").exists()


def test_a_failed_command_leaves_no_folder(tmp_path, capsys):
    out = tmp_path / "new"
    code, _, err = _cli(capsys, "fit", str(tmp_path / "missing.npz"), "--out", str(out))
    assert code == 2 and "missing.npz" in err and not out.exists()


#: the first statement of the children below: Ctrl-C handled as under a terminal's shell
#: (Python's handler, not blocked). A test runner started in the background, by nohup or by a
#: CI service, can hand its children SIGINT ignored or blocked, and then no Ctrl-C reaches
#: them whatever the program does (seen: a fresh-clone run under nohup failed both tests below;
#: the same run in the foreground passed)
_AS_FROM_A_TERMINAL = ("import signal; signal.signal(signal.SIGINT, signal.default_int_handler); "
                       "signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})")

_SCRIPT = _AS_FROM_A_TERMINAL + """
import sys, time
from seds_casadi.app.executors import open_executor
if __name__ == "__main__":
    try:
        with open_executor(2) as ex:
            list(ex.map(time.sleep, [1.0, 1.0]))  # both workers started
            futures = [ex.submit(time.sleep, 60) for _ in range(4)]
            time.sleep(0.5)
            print(" ".join(map(str, ex._processes)), flush=True)
            for f in futures:
                f.result()
    except KeyboardInterrupt:
        print("interrupted", flush=True)
"""


def _alive(pid: str) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split()[2] != "Z"
    except OSError:
        return False


@pytest.mark.slow
@pytest.mark.parametrize("sig", ["SIGINT", "SIGKILL"])
def test_workers_stop_within_two_seconds(tmp_path, sig):
    import signal
    import subprocess
    import sys

    script = tmp_path / "run.py"
    script.write_text(_SCRIPT)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
         os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env, start_new_session=True)
    try:
        pids = proc.stdout.readline().split()
        assert len(pids) == 2
        t = time.perf_counter()
        if sig == "SIGINT":  # Ctrl-C reaches the whole process group
            os.killpg(proc.pid, signal.SIGINT)
        else:
            proc.kill()
        while any(map(_alive, pids)) and time.perf_counter() - t < 5:
            time.sleep(0.05)
        assert not any(map(_alive, pids)) and time.perf_counter() - t < 2.0
        out, err = proc.communicate(timeout=30)
        if sig == "SIGINT":
            assert "interrupted" in out and "Traceback" not in err, err
    finally:
        if proc.poll() is None:
            proc.kill()


# ------------------------------------------------------------------ 9. weaker checks
def test_huge_demonstrations_and_bad_fit_info_have_clear_errors(spiral_demos):
    P = [p * 1e306 for p in spiral_demos.positions]
    with pytest.raises(ValueError, match="rescale"):
        Demonstrations(P, dt=0.05)
    with pytest.raises(TypeError, match="fit_info must be a dict"):
        I2 = np.eye(2)
        StableDS(np.ones(1), np.zeros((1, 4)), np.block([[I2, -I2], [-I2, 2 * I2]])[None],
                 np.zeros(2), fit_info=[("a", 1)])


def _children(pid: int) -> list[str]:
    out = []
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                with open(f"/proc/{d}/stat") as fh:
                    f = fh.read().rsplit(")", 1)[1].split()
                if int(f[1]) == pid and f[0] != "Z":
                    out.append(d)
            except (OSError, IndexError, ValueError):
                pass
    return out


def _describe(pids) -> str:
    """The command lines of the processes still alive (for the failure message)."""
    out = []
    for p in pids:
        try:
            with open(f"/proc/{p}/cmdline", "rb") as fh:
                cmd = fh.read().replace(bytes(1), b" ").decode(errors="replace")
            out.append(f"{p}: {cmd[:200]}")
        except OSError:
            pass
    return "; ".join(out)


def _wait_for_children(pid: int, n: int, timeout: float) -> list:
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < timeout:
        kids = _children(pid)
        if len(kids) >= n:
            return kids
        time.sleep(0.2)
    return _children(pid)


@pytest.mark.slow
def test_ctrl_c_on_a_command_with_workers_ends_cleanly(tmp_path):
    """``seds-casadi lasa --workers 2`` interrupted while its workers fit: exit 130 within
    2 s, one line and no traceback, no worker left, no temporary file."""
    import signal
    import subprocess
    import sys

    out = tmp_path / "lasa"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
         os.environ.get("PYTHONPATH", "")]))
    main = (_AS_FROM_A_TERMINAL + "; import runpy; "
            "runpy.run_module('seds_casadi', run_name='__main__', alter_sys=True)")
    proc = subprocess.Popen([sys.executable, "-c", main, "lasa", "--workers", "2",
                             "--objectives", "direction", "--protocols", "all", "--no-figures",
                             "--out", str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env, start_new_session=True)
    try:
        _wait_for_children(proc.pid, 2, 60.0)
        time.sleep(3.0)  # the workers are importing or fitting
        # wait again: under load a first count can include a short-lived child (a compiler)
        workers = _wait_for_children(proc.pid, 2, 60.0)
        assert proc.poll() is None and len(workers) >= 2
        t = time.perf_counter()
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=30)
        assert time.perf_counter() - t < 3.0
        assert proc.returncode == 130 and "interrupted" in err and "Traceback" not in err, err
        # every child (workers; a compiler or the pool's resource tracker when one was
        # running) gone within 2 s of the interruption
        deadline = t + 2.0
        while any(map(_alive, workers)) and time.perf_counter() < deadline:
            time.sleep(0.05)
        assert not [w for w in workers if _alive(w)], _describe(workers)
        assert not [p for p in out.rglob(".tmp-*")]
    finally:
        if proc.poll() is None:
            proc.kill()


def test_a_urdf_without_a_flange_takes_its_chains_tip():
    pytest.importorskip("pinocchio")
    from seds_casadi.robots.models import load_robot
    from seds_casadi.robots.urdf import ROBOTS_FOLDER

    path = os.path.join(ROBOTS_FOLDER, "wam7.urdf")
    known, own = load_robot("wam"), load_robot(path)
    named = load_robot(path + "#wam_flange")
    for r in (own, named):
        f, g = r.model.frames[r.head_frame], known.model.frames[known.head_frame]
        assert f.parentJoint == g.parentJoint and f.placement.isApprox(g.placement)
    with pytest.raises(ValueError, match="no frame 'nolink'"):
        load_robot(path + "#nolink")


def test_guarded_metadata_takes_numpy_values_and_refuses_others(tmp_path):
    """One JSON encoder for every guarded file (core.model_files.numpy_json)."""
    from seds_casadi.core.model_files import read_guarded, write_guarded

    meta = {"k": np.int64(3), "x": np.float32(0.5), "v": np.arange(3)}
    write_guarded(tmp_path / "m.npz", "t", 1, {"a": np.ones(2)}, meta)
    _, back, _ = read_guarded(tmp_path / "m.npz", "t", (1,), {"a": 1})
    assert back == {"k": 3, "x": 0.5, "v": [0, 1, 2]}
    with pytest.raises(TypeError, match="set is not JSON serialisable"):
        write_guarded(tmp_path / "n.npz", "t", 1, {"a": np.ones(2)}, {"s": {1, 2}})
    assert not (tmp_path / "n.npz").exists()
