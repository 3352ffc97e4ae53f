"""Issue 30 (reliability): what an independent fuzz campaign (``benchmarks/fuzz_reliability.py``)
found on the code after the fixes of ``tests/test_reliability_30.py`` and ``_30b.py``; each test
fails on the code before its fix.

* JSON with an integer longer than Python converts (4,300 digits) escaped ``json`` as a bare
  ``ValueError`` with Python's advice (a field file) or an unreadable-file error without the file
  (a model file's ``fit_info``);
* numbers of a model that overflow: a plain model's velocity at 1.7e308 was NaN (``inf - inf``
  in ``A_k (x - x*)``); a model whose means lie 1e300 away (a model file with a valid
  checksum) predicted NaN everywhere (every Gaussian's log-density ``-inf``);
* a model file declaring 200,000 components took minutes to load;
* values with no meaning accepted: ``rollout(tol=-1)`` (ran all its steps),
  ``Demonstrations(dt=True)``.
"""

import os
import time

import numpy as np
import pytest
from test_reliability_30 import _PRELUDE  # the children's first statement


def _plain_model(scale: float = 1.0):
    """A certified 2-D model of two components (A_k = -diag(1, 2), -diag(2, 1)) whose means
    are ``scale`` times (1, 0.5) and (-0.5, 1.5), from arrays."""
    from seds_casadi import StableDS

    target = np.array([0.5, -0.2])
    mus = scale * np.array([[1.0, 0.5], [-0.5, 1.5]])
    As = [-np.diag([1.0, 2.0]), -np.diag([2.0, 1.0])]
    means, covs = [], []
    for mu, A, sx in zip(mus, As, (0.3, 0.5)):
        Sx = sx ** 2 * np.eye(2)
        means.append(np.r_[mu, A @ (mu - target)])
        covs.append(np.block([[Sx, Sx @ A.T], [A @ Sx, A @ Sx @ A.T + 1e-3 * np.eye(2)]]))
    return StableDS([0.5, 0.5], np.array(means), np.array(covs), target)


# ------------------------------------------------------------------ JSON integers
def test_json_with_an_integer_python_will_not_convert_is_refused_naming_the_file(tmp_path):
    import sys

    from seds_casadi import ModelFileError, StableDS
    from seds_casadi.core.model_files import write_guarded
    from seds_casadi.minigolf.fields import load_field

    field = tmp_path / "green.json"
    field.write_text('{"name": "green", "stimp": ' + "9" * 5000 + "}")
    with pytest.raises(ValueError, match=r"green\.json: not valid JSON"):
        load_field(field)

    model = tmp_path / "model.npz"
    _plain_model().save(model)
    with np.load(model) as f:
        arrays = {k: f[k] for k in ("priors", "means", "covariances", "target")}
        version = int(f["version"])
    limit = sys.get_int_max_str_digits()
    sys.set_int_max_str_digits(0)  # json.dumps writes it; the reader must refuse it
    try:
        write_guarded(model, "seds_casadi.StableDS", version, arrays,
                      {"n": 10 ** 5000}, meta_key="fit_info")
    finally:
        sys.set_int_max_str_digits(limit)
    with pytest.raises(ModelFileError, match=r"model\.npz: entry 'fit_info' is not valid JSON"):
        StableDS.load(model)


# ------------------------------------------------------------------ overflow
def test_a_velocity_beyond_the_largest_float_is_inf_never_nan():
    """f(x) = sum h_k A_k (x - x*) at |x| ~ 1.7e308: +-inf where it overflows, never NaN
    (was NaN: +inf and -inf terms summed); unchanged near the data."""
    model = _plain_model()
    big = 1.7e308
    for x in ([big, big], [-big, big], [big, -1.0], [1e300, -1e300]):
        y = model.predict(np.array(x))
        assert not np.any(np.isnan(y)), (x, y)
    y = model.predict(np.array([big, -1.0]))
    assert y[0] == -np.inf  # the first gain is -1 or -2 along x: the velocity points back
    x = np.array([[0.3, 0.1], [2.0, -1.0], [-40.0, 7.0]])
    direct = model.predict(x)
    e = x - model.target
    # the oracle: Eq. 5 from the responsibilities (numpy, from the gmm module)
    from seds_casadi.core.gmm import responsibilities

    h = responsibilities(x, model.priors, model.means[:, :2], model.covariances[:, :2, :2])
    want = np.einsum("nk,kij,nj->ni", h, model.A, e)
    np.testing.assert_allclose(direct, want, rtol=1e-12, atol=1e-14)


def test_responsibilities_stay_finite_beyond_every_component():
    """Points ~1e154 standard deviations from every component: the weights are finite and
    sum to one (every log-density was -inf and log-sum-exp NaN)."""
    from seds_casadi.core.gmm import responsibilities

    means = np.array([[0.0, 0.0], [1.0, 1.0]])
    covs = np.array([1e-200 * np.eye(2), 1e-200 * np.eye(2)])
    h = responsibilities(np.array([[1e60, -1e60], [3.0, 4.0], [1.0, 1.0]]), [0.3, 0.7],
                         means, covs)
    assert np.all(np.isfinite(h)) and np.allclose(h.sum(axis=1), 1.0)
    np.testing.assert_allclose(h[2], [0.0, 1.0], atol=1e-12)  # unchanged where it is finite


@pytest.mark.parametrize("what", ["means", "target", "covariances"])
def test_model_parameters_beyond_any_demonstration_are_refused(what):
    """Means or a target beyond the demonstrations' bound (1e100; covariances beyond its
    square) cannot be evaluated (NaN everywhere): the model is refused when built, so also
    when its file is loaded."""
    from seds_casadi import StabilityError, StableDS

    m = _plain_model()
    arrays = {"priors": m.priors, "means": m.means.copy(), "covariances": m.covariances.copy(),
              "target": m.target.copy()}
    if what == "means":
        arrays["means"] = arrays["means"] * 1e300
    elif what == "target":
        arrays["target"] = arrays["target"] + 1e308
    else:
        arrays["covariances"] = arrays["covariances"] * 1e300
    with pytest.raises(StabilityError, match="beyond the 1e\\+100"):
        StableDS(**arrays)


def test_a_model_file_declaring_too_many_components_is_refused_at_once(tmp_path):
    """200,000 components took minutes to load (the certificate and the CasADi function of
    every component); a file may hold 1000, checked before the model is built."""
    from seds_casadi import ModelFileError, StableDS
    from seds_casadi.core.stable_ds import MAX_FILE_COMPONENTS

    m = _plain_model()
    n = 50 * MAX_FILE_COMPONENTS
    big = StableDS.__new__(StableDS)
    big.__dict__.update(m.__dict__)
    big.priors = np.full(n, 1.0 / n)
    big.means = np.repeat(m.means[:1], n, axis=0)
    big.covariances = np.repeat(m.covariances[:1], n, axis=0)
    path = tmp_path / "big.npz"
    big.save(path)
    t = time.perf_counter()
    with pytest.raises(ModelFileError, match=r"declares 50000 components, more than the 1000"):
        StableDS.load(path)
    assert time.perf_counter() - t < 5.0


# ------------------------------------------------------------------ meaningless numbers
@pytest.mark.parametrize("kwargs, error", [
    ({"tol": -1.0}, ValueError), ({"tol": float("nan")}, ValueError),
    ({"tol": "small"}, TypeError), ({"dt": True}, TypeError), ({"dt": "0.01"}, TypeError),
    ({"max_steps": -5}, ValueError), ({"max_steps": 2.5}, ValueError)])
def test_rollout_refuses_numbers_with_no_meaning(kwargs, error):
    """tol=-1 ran all 20,000 steps (no distance is below it) and was accepted; a boolean dt was
    taken as 1 s."""
    model = _plain_model()
    kw = {"dt": 0.01, **kwargs}
    t = time.perf_counter()
    with pytest.raises(error, match=next(iter(kwargs))):
        model.rollout(np.array([1.0, 1.0]), **kw)
    assert time.perf_counter() - t < 1.0
    path = model.rollout(np.array([1.0, 1.0]), dt=0.01, max_steps=0, warn=False)
    assert path.shape == (1, 2)  # zero steps: the start, a request with a meaning


@pytest.mark.parametrize("dt", [True, "0.1", [0.1, 0.2]])
def test_demonstrations_refuse_a_time_step_that_is_not_a_number(dt):
    from seds_casadi import Demonstrations

    pos = [np.linspace([1.0, 2.0], [0.0, 0.0], 20)]
    with pytest.raises(TypeError, match="dt must be a number"):
        Demonstrations(pos, dt=dt)
    assert Demonstrations(pos, dt=np.float32(0.1)).dt == pytest.approx(0.1)



def test_lasa_refuses_a_largest_k_below_one(tmp_path, capsys):
    """``lasa --k-max 0`` (or -3) ran and exited 0: the bound of ``-K bic`` is a count."""
    from seds_casadi.app.cli import main

    for value in ("0", "-3"):
        with pytest.raises(SystemExit) as exc:
            main(["lasa", "--k-max", value, "--out", str(tmp_path / "out")])
        assert exc.value.code == 2
        assert f"argument --k-max: must be at least 1, got {value}" in capsys.readouterr().err
        assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------ signals


def _start(tmp_path, code: str, *args):
    import subprocess
    import sys

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONUNBUFFERED="1",
               PYTHONPATH=os.pathsep.join([root, os.environ.get("PYTHONPATH", "")]))
    return subprocess.Popen([sys.executable, "-c", _PRELUDE + code, *args], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env=env, start_new_session=True)


def _run_python(code: str, **kwargs):
    """Run ``code`` in a new Python with this checkout importable; its completed process,
    asserted to have exited 0 (its stderr in the message otherwise)."""
    import subprocess
    import sys

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       env=dict(os.environ, PYTHONPATH=root), **kwargs)
    assert r.returncode == 0, r.stderr[-2000:]
    return r


def _read_until(proc, marker: str, timeout: float = 120.0) -> str:
    seen = []
    deadline = time.perf_counter() + timeout
    for line in proc.stdout:
        seen.append(line)
        if marker in line or time.perf_counter() > deadline:
            break
    assert any(marker in line for line in seen), "".join(seen)
    return "".join(seen)


@pytest.mark.slow
def test_a_second_signal_does_not_cut_the_clean_up_short(tmp_path):
    """Ctrl-C, then SIGTERM every 50 ms until the command ends (a user pressing Ctrl-C again,
    a supervisor's kill): exit 130, one ``interrupted`` line, no run lock, no temporary file.
    Before: the second signal arrived during the clean-up and the command died of it (signal
    2 or 15) after or instead of its message."""
    import signal

    from seds_casadi import save_demonstrations
    from seds_casadi.core import load_lasa

    save_demonstrations(tmp_path / "demos.npz", load_lasa("Sshape"))
    out = tmp_path / "out"
    proc = _start(tmp_path, "from seds_casadi.app.cli import main; sys.exit(main())", "fit",
                  str(tmp_path / "demos.npz"), "-K", "15", "--formulation", "constrained",
                  "--max-iter", "5000", "--out", str(out))
    try:
        text = _read_until(proc, ": iteration ")
        os.killpg(proc.pid, signal.SIGINT)
        t = time.perf_counter()
        while proc.poll() is None and time.perf_counter() - t < 5.0:
            time.sleep(0.05)
            try:
                os.killpg(proc.pid, signal.SIGTERM)
            except ProcessLookupError:
                break
        proc.wait(10)
        text += proc.stdout.read()
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 130, (proc.returncode, text[-2000:])
    assert text.count("interrupted") == 1 and "Traceback" not in text, text[-2000:]
    assert not (out / "model.npz").exists()
    assert not list(tmp_path.rglob(".tmp-*")) and not list(tmp_path.rglob(".seds-casadi.lock"))


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_an_interrupt_while_the_command_line_is_built_exits_130(tmp_path, sig):
    """The parser lists the robots, which imports Pinocchio (about a second on one core): a
    signal then ended the command by the signal itself (SIGTERM) or with a traceback (Ctrl-C)
    instead of exit 130 and one line."""
    import signal

    # the parser takes 0.1-1 s (it lists the robots): here it is held 2 s once it starts,
    # so that the signal arrives while it is built, whatever the machine's speed
    code = ("import time; import seds_casadi.app.cli as cli; build = cli.build_parser\n"
            "def slow():\n"
            "    print('parser', flush=True); time.sleep(2.0); return build()\n"
            "cli.build_parser = slow\n"
            "sys.exit(cli.main())")
    proc = _start(tmp_path, code, "fit", "none.npz", "--out", str(tmp_path / "out"))
    try:
        _read_until(proc, "parser")
        time.sleep(0.1)
    finally:
        text, _ = _signal_and_read(proc, getattr(signal, sig))
    assert proc.returncode == 130, (proc.returncode, text[-2000:])
    assert text.strip() == _FIT_INTERRUPTED, text
    assert not (tmp_path / "out").exists()


#: what ``seds-casadi fit`` prints when it is interrupted
_FIT_INTERRUPTED = ("seds-casadi fit: interrupted; the files written so far are complete, the "
                    "rest was not written")


def _signal_and_read(proc, sig) -> tuple[str, float]:
    """Send ``sig`` to the process group of ``proc`` (if it still runs), read its output until
    it ends (killed after 10 s): (the output, seconds from the signal to the end)."""
    import signal

    t = time.perf_counter()
    try:
        if proc.poll() is None:
            os.killpg(proc.pid, sig)
        text = proc.stdout.read()
        proc.wait(10)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return text, time.perf_counter() - t


def test_figures_temporary_files_of_the_older_naming_are_swept(tmp_path):
    """``NAME.tmp-PID.png``, what a run killed while saving a figure left before issue 30's
    fix, was never removed (the sweep took only ``.tmp-*``); other files are kept."""
    from seds_casadi.app.outdir import output_folder

    out = tmp_path / "out"
    out.mkdir()
    names = {"streamlines.tmp-999.png": False, ".tmp-abc": False, "notes.tmp-5.csv": True,
             "fig.tmp-x.png": True, "model.npz": True}
    for name in names:
        (out / name).write_text("x")
    with output_folder(out):
        pass
    assert {p.name for p in out.iterdir()} == {n for n, keep in names.items() if keep}


def test_an_interrupt_inside_casadis_conversions_is_an_interrupt():
    """Ctrl-C while CasADi's SWIG code turns a DM into an array came out as ``SystemError:
    <function DM.__array__ ...> returned a result with an exception set`` (a traceback of
    ``table1`` interrupted while the hitting motion was probed): batch_evaluate raises the
    KeyboardInterrupt itself. The interrupt is raised where a signal's handler would raise it,
    at the first line of CasADi's conversion (a trace function: deterministic), in a
    subprocess."""

    code = """
import sys
import casadi as ca, numpy as np
from seds_casadi.codegen import batch_evaluate
x = ca.SX.sym("x", 3)
f = ca.Function("f", [x], [ca.sin(x) * 2])
def trace(frame, event, arg):
    if event == "call" and frame.f_code.co_name == "toarray":
        raise KeyboardInterrupt
sys.settrace(trace)
try:
    batch_evaluate(f, np.ones((3, 4)))
    print("no exception")
except BaseException as exc:
    print(type(exc).__name__)
finally:
    sys.settrace(None)
"""
    r = _run_python(code)
    assert r.stdout.strip() == "KeyboardInterrupt", r.stdout


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_a_signal_under_a_casadi_call_interrupts_once_the_call_returns(sig):
    """The command line's handler (``interrupt_on_termination``) given a signal while CasADi's
    SWIG code builds a DM from a numpy array (``DM_from_array``, where SWIG drops what a failed
    overload raised: ``lasa`` SIGTERM'd at that moment ran to its end and exited 0, CI of
    2026-12-03): the DM is built, and the KeyboardInterrupt is raised in our code right after.
    The signal is sent at the conversion's first line by a trace function (deterministic), in
    a subprocess."""

    code = f"""
import signal, sys, time
import casadi as ca, numpy as np
from seds_casadi.core._signals import interrupt_on_termination, restore_handlers
signal.signal(signal.SIGINT, signal.default_int_handler)
previous = interrupt_on_termination()
sent = []
def trace(frame, event, arg):
    if event == "call" and frame.f_code.co_name == "DM_from_array" and not sent:
        sent.append(1)
        signal.raise_signal(signal.{sig})
sys.settrace(trace)
built = None
try:
    try:
        built = ca.DM(np.arange(4.0).reshape(2, 2))
    finally:
        sys.settrace(None)
    time.sleep(2.0)
    print("no interrupt", flush=True)
except KeyboardInterrupt:
    print("KeyboardInterrupt", "built" if built is not None and float(built[1, 1]) == 3.0
          else "not built", "sent" if sent else "not sent", flush=True)
except BaseException as exc:
    print(type(exc).__name__, exc, flush=True)
restore_handlers(previous)
"""
    r = _run_python(code)
    assert r.stdout.strip() == "KeyboardInterrupt built sent", (r.stdout, r.stderr[-2000:])


def _sigint_as_under_a_shell() -> None:
    """A child's first act (preexec_fn): Ctrl-C neither ignored nor blocked, as under a
    terminal's shell (a runner in the background can hand its children SIGINT ignored)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_an_interrupt_while_the_console_script_imports_the_package_exits_130(tmp_path, sig):
    """``seds-casadi`` signalled 0.2 s after it starts, while it imports the package (1-2 s,
    before the command line's own handlers): exit 130 with the command's ``interrupted`` line,
    no traceback, nothing written. Before: death by SIGTERM (exit -15), a KeyboardInterrupt
    traceback for Ctrl-C."""
    import signal
    import subprocess
    import sys

    exe = os.path.join(os.path.dirname(sys.executable), "seds-casadi")
    if not os.path.exists(exe):
        pytest.skip("the seds-casadi console script is not installed next to this Python")
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = tmp_path / "out"
    proc = subprocess.Popen([exe, "fit", "none.npz", "--out", str(out)], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True, preexec_fn=_sigint_as_under_a_shell,
                            env=dict(os.environ, PYTHONPATH=root))
    time.sleep(0.2)
    running = proc.poll() is None
    text, elapsed = _signal_and_read(proc, getattr(signal, sig))
    assert running, text
    assert proc.returncode == 130, (proc.returncode, text[-2000:])
    assert text.strip() == _FIT_INTERRUPTED, text
    assert elapsed < 2.0 and not out.exists()


def test_the_start_up_handlers_are_the_console_scripts_alone():
    """Imported as a library (``python -c``), the package leaves every signal's handler as
    it was; in the console script the command line takes them over and puts Python's own
    back when it ends (never the start-up handler, which would exit 130 after a complete
    run)."""

    code = ("import signal, sys; before = {s: signal.getsignal(s) for s in "
            "(signal.SIGINT, signal.SIGTERM)}; import seds_casadi; "
            "print(seds_casadi._startup.STARTUP_HANDLERS, all(signal.getsignal(s) is h "
            "for s, h in before.items()))\n"
            "sys.argv = ['/x/seds-casadi', 'fit']\n"
            "from seds_casadi._startup import exit_on_early_signals, _exit_at_once\n"
            "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
            "print(exit_on_early_signals(), signal.getsignal(signal.SIGTERM) is _exit_at_once)\n"
            "from seds_casadi.app.cli import main\n"
            "main(['fit', 'none.npz'])\n"
            "print(signal.getsignal(signal.SIGINT) is signal.default_int_handler, "
            "signal.getsignal(signal.SIGTERM) is signal.SIG_DFL)\n")
    r = _run_python(code, preexec_fn=_sigint_as_under_a_shell)
    lines = r.stdout.strip().splitlines()
    assert lines[0] == "False True" and lines[1] == "True True", r.stdout
    assert lines[-1] == "True True", r.stdout


def test_a_result_is_not_put_in_place_while_a_signal_waits_for_its_second_delivery(tmp_path):
    """A signal under a CasADi call waits a few milliseconds for its second delivery; a result
    file written in that time (the fuzz campaign: lasa's lasa.csv and summary.txt written
    just after a Ctrl-C, then exit 130) is not put in place: the interrupt is raised first.
    The second delivery is held 1 s here, so that the write surely falls in between."""

    target = tmp_path / "result.txt"
    code = f"""
import signal, sys, time
import casadi as ca, numpy as np
import seds_casadi.core._signals as S
from seds_casadi.core._io import atomic_text
S.REDELIVER_SECONDS = 1.0
signal.signal(signal.SIGINT, signal.default_int_handler)
previous = S.interrupt_on_termination()
def trace(frame, event, arg):
    if event == "call" and frame.f_code.co_name == "DM_from_array":
        sys.settrace(None)
        signal.raise_signal(signal.SIGTERM)
sys.settrace(trace)
try:
    ca.DM(np.eye(2))
    sys.settrace(None)
    atomic_text({str(target)!r}, "complete")
    print("written", flush=True)
except KeyboardInterrupt:
    print("KeyboardInterrupt", flush=True)
time.sleep(1.5)  # the second delivery falls in the interrupt's grace: no second interrupt
print("after", flush=True)
S.restore_handlers(previous)
"""
    r = _run_python(code)
    assert r.stdout.split() == ["KeyboardInterrupt", "after"], (r.stdout, r.stderr[-2000:])
    assert not target.exists() and not list(tmp_path.iterdir())


def test_a_signal_during_an_import_interrupts_once_the_import_is_done(tmp_path):
    """A signal while a module is being imported (``play`` SIGHUP'd while exudyn's compiled
    module initialised ended in exudyn's ImportError, a traceback: its initialisation took the
    KeyboardInterrupt for a failure): the import completes and the interrupt is raised in our
    code right after. The module sends the signal itself, from its first line."""

    (tmp_path / "slowmod.py").write_text(
        "import signal, time\nsignal.raise_signal(signal.SIGTERM)\ntime.sleep(0.05)\nDONE = 1\n")
    code = f"""
import sys, time
sys.path.insert(0, {str(tmp_path)!r})
from seds_casadi.core._signals import interrupt_on_termination, restore_handlers
previous = interrupt_on_termination()
try:
    import slowmod
    time.sleep(2.0)
    print("no interrupt", flush=True)
except KeyboardInterrupt:
    print("KeyboardInterrupt", getattr(sys.modules.get("slowmod"), "DONE", None), flush=True)
except BaseException as exc:
    print(type(exc).__name__, exc, flush=True)
restore_handlers(previous)
"""
    r = _run_python(code)
    assert r.stdout.split() == ["KeyboardInterrupt", "1"], (r.stdout, r.stderr[-2000:])
