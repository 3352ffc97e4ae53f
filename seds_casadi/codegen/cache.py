"""One compile-and-cache helper for every piece of generated C in the package.

:func:`shared_library` turns C source into a loaded-ready shared library: the library's name is
the hash of everything that decides its bytes (source, compiler, flags, an extra key such as the
CPU's features), so a changed source never picks up a stale binary. The library is built in a
temporary folder, in its own process group (an interrupted or timed-out build kills the whole
group: no compiler is left running behind), and installed into the cache by an atomic rename
next to a ``.sha256`` record of its bytes and its own file name. Before a cached library is handed
out its bytes and name are checked against that record; a truncated, empty or altered file, or a
library swapped with another together with their records (each record then names the other
file), is rebuilt instead of being loaded (loading a truncated library can crash the interpreter;
a swapped one lacks the symbols its callers look up).

A build is killed, and the caller falls back to uncompiled code (CasADi's), when
the compiler makes no progress (its processes used under :data:`STALL_CPU_FRACTION` of a core
over :data:`STALL_SECONDS`: a compiler blocked on a lock, a network file system or a terminal) or
when it runs longer than :func:`compile_timeout` (60 s plus 120 s per MB of C, at most 600 s;
``$SEDS_CASADI_COMPILE_TIMEOUT`` seconds if set).

The cache folder is ``$SEDS_CASADI_CACHE`` (default ``~/.cache/seds_casadi``). ``SEDS_CASADI_JIT=0``
turns compilation off everywhere; callers then use CasADi's virtual machine.
"""

from __future__ import annotations

import hashlib
import logging
import os
import shutil
import signal
import subprocess
import tempfile
import threading
import time

import casadi as ca

_LOG = logging.getLogger(__name__)
_LOCK = threading.Lock()
#: the longest compile timeout in seconds (a build that takes longer is killed and the caller
#: falls back); smaller sources get less, see :func:`compile_timeout`
COMPILE_TIMEOUT = 600.0
#: a build whose processes use less than STALL_CPU_FRACTION of a core over STALL_SECONDS is
#: taken to hang and killed (a working compiler uses a core, or a share of one on a loaded machine)
STALL_SECONDS = 30.0
STALL_CPU_FRACTION = 0.02


class CompileError(RuntimeError):
    """The C compiler is missing, failed, timed out or was interrupted."""


def compiler_available() -> str | None:
    """Path of a C compiler generated code can be compiled with, or None.

    None when ``SEDS_CASADI_JIT`` is ``0``/``false``/``no``/``off`` or no compiler is found
    (``$CC``, else ``cc``, else ``gcc``).
    """
    if os.environ.get("SEDS_CASADI_JIT", "1").strip().lower() in ("0", "false", "no", "off"):
        return None
    return shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")


def cache_folder() -> str:
    """Folder of the compiled-code cache (``$SEDS_CASADI_CACHE`` or ``~/.cache/seds_casadi``)."""
    return os.environ.get("SEDS_CASADI_CACHE") or os.path.join(
        os.path.expanduser("~"), ".cache", "seds_casadi")


def compile_timeout(source_bytes: int) -> float:
    """Seconds a build of ``source_bytes`` of C may take before it is killed.

    ``$SEDS_CASADI_COMPILE_TIMEOUT`` if set (a positive number), else 60 s plus 120 s per MB of
    source, at most :data:`COMPILE_TIMEOUT` (the largest SEDS kernels, about 10 MB of C, keep the
    full 600 s; a hanging compiler is stopped sooner by the stall check of
    :func:`shared_library`).

    Raises
    ------
    ValueError
        ``$SEDS_CASADI_COMPILE_TIMEOUT`` is not a positive number.
    """
    env = os.environ.get("SEDS_CASADI_COMPILE_TIMEOUT", "").strip()
    if env:
        try:
            value = float(env)
        except ValueError:
            value = float("nan")
        if not (value > 0 and value < float("inf")):
            raise ValueError(f"SEDS_CASADI_COMPILE_TIMEOUT must be a positive number of "
                             f"seconds, got {env!r}")
        return value
    return min(COMPILE_TIMEOUT, 60.0 + 120.0 * source_bytes / 1e6)


def _group_cpu_seconds(pgid: int) -> float | None:
    """CPU time (user + system, including reaped children) of the processes in group ``pgid``;
    None where ``/proc`` cannot be read. The group's leader, the watchdog shell, adds about 1 ms
    per half second (its ``sleep``), well under :data:`STALL_CPU_FRACTION`."""
    try:
        pids = [p for p in os.listdir("/proc") if p.isdigit()]
        tick = os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError):
        return None
    total = 0
    for pid in pids:
        try:
            with open(f"/proc/{pid}/stat", "rb") as fh:
                stat = fh.read()
        except OSError:
            continue  # the process ended meanwhile
        fields = stat[stat.rfind(b")") + 2:].split()  # after "pid (comm) "
        if len(fields) > 14 and int(fields[2]) == pgid:  # fields[2]: pgrp
            total += sum(int(v) for v in fields[11:15])  # utime stime cutime cstime
    return total / tick


def _record(lib: str, digest: str) -> str:
    """The ``.sha256`` record of ``lib``: its digest and its file name (``sha256sum``'s layout)."""
    return f"{digest}  {os.path.basename(lib)}\n"


def _digest(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _verified(lib: str) -> bool:
    """True if ``lib`` exists, its bytes match its ``.sha256`` record and the record names
    ``lib`` (a library and its record moved or swapped under another library's name fail)."""
    try:
        with open(lib + ".sha256") as fh:
            recorded = fh.read(4096)
        return recorded == _record(lib, _digest(lib))
    except (OSError, UnicodeDecodeError):
        return False


#: a POSIX shell wrapper, leader of the compiler's process group: it runs the compiler and, if the
#: Python process that started it goes away (killed by any signal, even SIGKILL), kills the whole
#: group (compiler driver, cc1, as) within half a second
_WATCHDOG = """
"$@" &
child=$!
while kill -0 "$child" 2>/dev/null; do
  if ! kill -0 "$SEDS_CASADI_PARENT" 2>/dev/null; then kill -KILL -$$; fi
  sleep 0.5
done
wait "$child"
"""


class _Stalled(Exception):
    """The compiler's processes made no progress."""


def _wait(proc: subprocess.Popen, timeout: float, stall: float | None) -> bytes:
    """Wait for ``proc`` and return its standard error; raise ``subprocess.TimeoutExpired``
    after ``timeout`` s, :class:`_Stalled` when its group uses less than
    :data:`STALL_CPU_FRACTION` of a core over a window of ``stall`` s."""
    start = time.monotonic()
    window_start, window_cpu = start, _group_cpu_seconds(proc.pid)
    while True:
        left = timeout - (time.monotonic() - start)
        step = min(left, 0.25 if stall is None else max(0.05, stall / 8))
        try:
            return proc.communicate(timeout=max(step, 0.0))[1]
        except subprocess.TimeoutExpired:
            now = time.monotonic()
            if now - start >= timeout:
                raise
            if stall is None or window_cpu is None or now - window_start < stall:
                continue
            cpu = _group_cpu_seconds(proc.pid)
            if cpu is None:
                continue
            if cpu - window_cpu < STALL_CPU_FRACTION * (now - window_start):
                raise _Stalled(now - window_start) from None
            window_start, window_cpu = now, cpu


def _run_compiler(cmd: list[str], timeout: float, stall: float | None = None) -> None:
    """Run the compiler in its own process group under a watchdog; kill the group on timeout,
    when it stalls (``stall``: see :func:`_wait`), on interruption, or on the death of this
    process."""
    env = dict(os.environ, SEDS_CASADI_PARENT=str(os.getpid()))
    proc = subprocess.Popen(["sh", "-c", _WATCHDOG, "seds-casadi-cc", *cmd],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True, env=env)
    try:
        err = _wait(proc, timeout, stall)
    except BaseException as exc:  # timeout, KeyboardInterrupt, SystemExit: leave nothing behind
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait()
        if isinstance(exc, subprocess.TimeoutExpired):
            raise CompileError(f"the C compiler took longer than {timeout:.0f} s") from None
        if isinstance(exc, _Stalled):
            raise CompileError(f"the C compiler made no progress for {exc.args[0]:.0f} s "
                               f"(it used no CPU time: it hangs)") from None
        raise
    if proc.returncode != 0:
        raise CompileError("the C compiler failed: " + err.decode(errors="replace")[-2000:])


def shared_library(source: bytes, prefix: str, flags: tuple[str, ...] = ("-O1",),
                   libs: tuple[str, ...] = (), key_extra: str = "",
                   timeout: float | None = None, stall: float | None = None) -> str:
    """Compile C ``source`` into a cached shared library and return its path.

    Parameters
    ----------
    source : bytes
        The C source.
    prefix : str
        File-name prefix in the cache (``{prefix}_{hash}.so``).
    flags : tuple of str
        Compiler flags (``-shared -fPIC`` are added).
    libs : tuple of str
        Libraries to link (``-lm``, ...).
    key_extra : str
        Anything else the binary depends on (e.g. the CPU's feature flags with ``-march=native``).
    timeout : float, optional
        Seconds before the build is killed (default :func:`compile_timeout` of the source).
    stall : float, optional
        Seconds without progress (under :data:`STALL_CPU_FRACTION` of a core used) before the
        build is killed (default :data:`STALL_SECONDS`).

    Returns
    -------
    str
        Path of a library whose bytes were verified against the cache's record.

    Raises
    ------
    CompileError
        No compiler, or the build failed, timed out or hung.
    """
    cc = compiler_available()
    if cc is None:
        raise CompileError("no C compiler available (or SEDS_CASADI_JIT=0)")
    all_flags = ("-shared", "-fPIC", *flags)
    key = hashlib.sha256(source + ca.__version__.encode() + cc.encode()
                         + " ".join(all_flags + tuple(libs)).encode()
                         + key_extra.encode()).hexdigest()[:24]
    folder = cache_folder()
    lib = os.path.join(folder, f"{prefix}_{key}.so")
    with _LOCK:
        if _verified(lib):
            return lib
        if os.path.exists(lib):
            if _old_record(lib):  # a digest without the name (an older cache): rebuilt quietly
                _LOG.info("cached library %s has a record without its name; rebuilding it", lib)
            else:
                _LOG.warning("cached library %s does not match its checksum record; rebuilding "
                             "it", lib)
        try:
            os.makedirs(folder, exist_ok=True)
            _sweep_staged(folder)
            tmpdir = tempfile.mkdtemp(prefix=f"seds_{prefix}_")
        except OSError as exc:
            raise CompileError(f"the compile cache {folder!r} cannot be written ({exc}); set "
                               "SEDS_CASADI_CACHE to a writable folder") from None
        try:
            c_path = os.path.join(tmpdir, "k.c")
            with open(c_path, "wb") as fh:
                fh.write(source)
            tmp_lib = os.path.join(tmpdir, "k.so")
            _LOG.info("compiling %s (%d kB of C)", prefix, len(source) // 1024)
            try:
                _run_compiler([cc, *all_flags, c_path, "-o", tmp_lib, *libs],
                              compile_timeout(len(source)) if timeout is None else timeout,
                              STALL_SECONDS if stall is None else stall)
            except OSError as exc:
                raise CompileError(f"the C compiler could not run: {exc}") from None
            try:
                _install(tmp_lib, lib, folder)
            except OSError as exc:
                raise CompileError(f"cannot store the library in the compile cache {folder!r} "
                                   f"({exc})") from None
        finally:
            shutil.rmtree(tmpdir, ignore_errors=True)
        return lib


def _old_record(lib: str) -> bool:
    """True if ``lib``'s record is a bare digest, the layout before records named their file."""
    try:
        with open(lib + ".sha256") as fh:
            text = fh.read(100).strip()
    except (OSError, UnicodeDecodeError):
        return False
    return len(text) == 64 and all(c in "0123456789abcdef" for c in text)


def _install(tmp_lib: str, lib: str, folder: str) -> None:
    """Copy a built library into the cache and record its digest, each by an atomic rename."""
    digest = _digest(tmp_lib)
    fd, staged = tempfile.mkstemp(prefix=".k-", suffix=".so", dir=folder)
    os.close(fd)
    shutil.copyfile(tmp_lib, staged)
    os.replace(staged, lib)
    fd, staged = tempfile.mkstemp(prefix=".k-", suffix=".sha256", dir=folder)
    with os.fdopen(fd, "w") as fh:
        fh.write(_record(lib, digest))
    os.replace(staged, lib + ".sha256")


#: staged files (``.k-*``) older than this many seconds are left-overs of a killed build
STALE_SECONDS = 3600.0


def _sweep_staged(folder: str) -> None:
    """Remove staged copies a killed build left in the cache folder."""
    now = time.time()
    for name in os.listdir(folder):
        if name.startswith(".k-"):
            p = os.path.join(folder, name)
            try:
                if now - os.path.getmtime(p) > STALE_SECONDS:
                    os.unlink(p)
            except OSError:
                pass
