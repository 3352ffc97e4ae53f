"""Where repeated work runs: this process, local worker processes, or a Dask cluster.

Every long command (``lasa``, ``table1``) submits plain picklable tasks to a
``concurrent.futures.Executor``; :func:`open_executor` picks one from the command-line options.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import threading
import time
from collections.abc import Iterator
from concurrent.futures import Executor, Future, ProcessPoolExecutor, ThreadPoolExecutor

__all__ = ["open_executor", "InlineExecutor", "stop_workers", "check_scheduler"]


class InlineExecutor(Executor):
    """Runs each task at once in this process (``workers=1``); errors surface in ``result()``.

    An interruption (``KeyboardInterrupt`` from Ctrl-C or SIGTERM, ``SystemExit``) is raised by
    ``submit`` itself: ``Executor.map`` submits every task before it returns, so an interruption
    kept in the first task's future would let all the others run.
    """

    def submit(self, fn, /, *args, **kwargs) -> Future:
        fut: Future = Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except Exception as exc:  # noqa: BLE001 - handed to the caller through the future
            fut.set_exception(exc)
        return fut


@contextlib.contextmanager
def open_executor(workers: int = 1, dask: str | None = None,
                  timeout: float = 10.0) -> Iterator[Executor]:
    """An executor for the duration of a ``with`` block.

    Parameters
    ----------
    workers : int
        Local worker processes (1: run in this process). Processes are spawned, not forked: a
        forked child of a process that has loaded CasADi can deadlock.
    dask : str, optional
        Address of a Dask distributed scheduler (``tcp://host:8786``); overrides ``workers``.
        The workers need ``seds_casadi`` installed.
    timeout : float
        Seconds to wait for the scheduler before giving up with a clear error.
    """
    if dask:
        try:
            from distributed import Client
        except ImportError:  # pragma: no cover - dask is a dependency
            raise ValueError("--dask needs the 'distributed' package: pip install 'seds_casadi[dask]'") \
                from None
        check_scheduler(dask, timeout)
        try:
            client = Client(dask, timeout=timeout)
        except Exception as exc:  # noqa: BLE001 - whatever the address answered
            raise ValueError(f"cannot reach the Dask scheduler at {dask!r} within {timeout:g} s "
                             f"({type(exc).__name__}: {exc}); check the address and that "
                             f"the scheduler is running") from None
        try:
            yield client.get_executor()
        finally:
            client.close()
        return
    if int(workers) < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    if int(workers) == 1:
        yield InlineExecutor()
        return
    ex = _Pool(max_workers=int(workers), mp_context=multiprocessing.get_context("spawn"),
               initializer=_worker_start, initargs=(os.getpid(),))
    try:
        yield ex
    except BaseException:
        stop_workers(ex)
        raise
    finally:
        ex.shutdown(wait=True, cancel_futures=True)


class _Pool(ProcessPoolExecutor):
    """A process pool whose workers start with Ctrl-C blocked: a SIGINT sent to the whole
    process group (a terminal's Ctrl-C) while a worker is still starting up is left to the
    parent, which stops the workers (:func:`stop_workers`), instead of printing a traceback."""

    def _spawn_process(self) -> None:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            super()._spawn_process()
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _worker_start(parent: int) -> None:
    """In each worker process: leave Ctrl-C to the parent (which stops the workers), exit
    when the parent is gone (killed by SIGKILL, say) instead of living on as an orphan, and sum
    SEDS's objective on one thread (the workers already share the cores) unless the user set
    ``SEDS_CASADI_THREADS``."""
    os.environ.setdefault("SEDS_CASADI_THREADS", "1")
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, name="seds-casadi-parent-watch", daemon=True).start()


def stop_workers(ex: ProcessPoolExecutor, grace: float = 1.0) -> None:
    """Terminate the worker processes of ``ex`` now (running tasks are abandoned): SIGTERM,
    then SIGKILL for any still alive after ``grace`` seconds."""
    # tasks already cancelled (``Executor.map`` cancels the rest when interrupted) are dropped
    # first: the pool's manager thread would fail them again on finding its workers gone and
    # die with InvalidStateError (CPython 3.11's terminate_broken does not skip done futures)
    pending = getattr(ex, "_pending_work_items", None)
    if isinstance(pending, dict):
        for key, item in list(pending.items()):
            if item.future.done():
                pending.pop(key, None)
    procs = list((getattr(ex, "_processes", None) or {}).values())
    for p in procs:
        with contextlib.suppress(Exception):
            p.terminate()
    deadline = time.monotonic() + grace
    for p in procs:
        with contextlib.suppress(Exception):
            p.join(max(0.0, deadline - time.monotonic()))
            if p.is_alive():
                p.kill()
                p.join(1.0)
    # let the pool's manager thread mark the abandoned tasks as failed before anything cancels
    # them (a cancelled task it then fails raises InvalidStateError in that thread, 3.11)
    manager = getattr(ex, "_executor_manager_thread", None)
    if manager is not None:
        manager.join(grace)


def check_scheduler(address: str, timeout: float = 10.0) -> dict:
    """Ask ``address`` who it is within ``timeout`` seconds (one deadline for connecting, the
    handshake and the answer); returns the scheduler's identity.

    Raises
    ------
    ValueError
        Nothing answers, something that is not a Dask scheduler answers (a web server, a
        worker, any other service), or no answer within ``timeout``; the message names the
        address and what to check.
    """
    import asyncio

    from distributed.core import rpc

    async def ask() -> dict:
        r = rpc(address, timeout=timeout)
        try:
            return await asyncio.wait_for(r.identity(), timeout)
        finally:
            await r.close_rpc()

    hint = "check the address (tcp://HOST:8786) and that `dask scheduler` runs there"
    _check_port(address, timeout, hint)
    try:
        # in a thread of its own: the caller may be inside an event loop (a notebook)
        with ThreadPoolExecutor(1) as pool:
            who = pool.submit(asyncio.run, asyncio.wait_for(ask(), timeout)).result()
    except TimeoutError:
        raise ValueError(f"--dask {address!r}: no answer from a Dask scheduler within "
                         f"{timeout:g} s; {hint}") from None
    except Exception as exc:  # noqa: BLE001 - whatever the address answered is not a scheduler
        raise ValueError(f"--dask {address!r}: not a reachable Dask scheduler "
                         f"({type(exc).__name__}: {str(exc)[:200]}); {hint}") from None
    if not isinstance(who, dict) or who.get("type") != "Scheduler":
        kind = who.get("type") if isinstance(who, dict) else type(who).__name__
        raise ValueError(f"--dask {address!r} answers as {kind!r}, not a Dask scheduler; {hint}")
    return who


def _check_port(address: str, timeout: float, hint: str) -> None:
    """For a ``tcp://host:port`` address: a refused or unroutable connection fails at once."""
    import socket
    from urllib.parse import urlsplit

    u = urlsplit(address if "://" in address else "tcp://" + address)
    if u.scheme != "tcp" or not u.hostname or not u.port:
        return  # other schemes: left to distributed
    try:
        socket.create_connection((u.hostname, u.port), timeout=timeout).close()
    except OSError as exc:
        raise ValueError(f"--dask {address!r}: cannot connect ({exc.strerror or exc}); "
                         f"{hint}") from None
