"""One compile-and-cache helper for every piece of generated C in the package.

:func:`shared_library` turns C source into a loaded-ready shared library: the library's name is
the hash of everything that decides its bytes (source, compiler, flags, an extra key such as the
CPU's features), so a changed source never picks up a stale binary. The library is built in a
temporary folder, in its own process group (an interrupted or timed-out build kills the whole
group: no compiler is left running behind), and installed into the cache by an atomic rename
next to a ``.sha256`` record of its bytes. Before a cached library is handed out its bytes are
checked against that record; a truncated, empty or altered file is rebuilt instead of being
loaded (loading a truncated library can crash the interpreter).

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

import casadi as ca

_LOG = logging.getLogger(__name__)
_LOCK = threading.Lock()
#: compile timeout in seconds (a build that takes longer is killed and the caller falls back)
COMPILE_TIMEOUT = 600.0


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


def _digest(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _verified(lib: str) -> bool:
    """True if ``lib`` exists and its bytes match its ``.sha256`` record."""
    try:
        with open(lib + ".sha256") as fh:
            recorded = fh.read().strip()
        return bool(recorded) and _digest(lib) == recorded
    except OSError:
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


def _run_compiler(cmd: list[str], timeout: float) -> None:
    """Run the compiler in its own process group under a watchdog; kill the group on timeout,
    interruption, or the death of this process."""
    env = dict(os.environ, SEDS_CASADI_PARENT=str(os.getpid()))
    proc = subprocess.Popen(["sh", "-c", _WATCHDOG, "seds-casadi-cc", *cmd],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True, env=env)
    try:
        _, err = proc.communicate(timeout=timeout)
    except BaseException as exc:  # timeout, KeyboardInterrupt, SystemExit: leave nothing behind
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait()
        if isinstance(exc, subprocess.TimeoutExpired):
            raise CompileError(f"the C compiler took longer than {timeout:.0f} s") from None
        raise
    if proc.returncode != 0:
        raise CompileError("the C compiler failed: " + err.decode(errors="replace")[-2000:])


def shared_library(source: bytes, prefix: str, flags: tuple[str, ...] = ("-O1",),
                   libs: tuple[str, ...] = (), key_extra: str = "",
                   timeout: float | None = None) -> str:
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
        Seconds before the build is killed (default :data:`COMPILE_TIMEOUT`).

    Returns
    -------
    str
        Path of a library whose bytes were verified against the cache's record.

    Raises
    ------
    CompileError
        No compiler, or the build failed or timed out.
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
            _LOG.warning("cached library %s does not match its checksum; rebuilding it", lib)
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
                              COMPILE_TIMEOUT if timeout is None else timeout)
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


def _install(tmp_lib: str, lib: str, folder: str) -> None:
    """Copy a built library into the cache and record its digest, each by an atomic rename."""
    digest = _digest(tmp_lib)
    fd, staged = tempfile.mkstemp(prefix=".k-", suffix=".so", dir=folder)
    os.close(fd)
    shutil.copyfile(tmp_lib, staged)
    os.replace(staged, lib)
    fd, staged = tempfile.mkstemp(prefix=".k-", suffix=".sha256", dir=folder)
    with os.fdopen(fd, "w") as fh:
        fh.write(digest)
    os.replace(staged, lib + ".sha256")


#: staged files (``.k-*``) older than this many seconds are left-overs of a killed build
STALE_SECONDS = 3600.0


def _sweep_staged(folder: str) -> None:
    """Remove staged copies a killed build left in the cache folder."""
    import time

    now = time.time()
    for name in os.listdir(folder):
        if name.startswith(".k-"):
            p = os.path.join(folder, name)
            try:
                if now - os.path.getmtime(p) > STALE_SECONDS:
                    os.unlink(p)
            except OSError:
                pass
