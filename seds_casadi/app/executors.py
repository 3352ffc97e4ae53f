"""Where repeated work runs: this process, local worker processes, or a Dask cluster.

Every long command (``lasa``, ``table1``) submits plain picklable tasks to a
``concurrent.futures.Executor``; :func:`open_executor` picks one from the command-line options.
"""

from __future__ import annotations

import contextlib
import multiprocessing
from collections.abc import Iterator
from concurrent.futures import Executor, Future, ProcessPoolExecutor

__all__ = ["open_executor", "InlineExecutor"]


class InlineExecutor(Executor):
    """Runs each task at once in this process (``workers=1``); errors surface in ``result()``."""

    def submit(self, fn, /, *args, **kwargs) -> Future:
        fut: Future = Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001 - handed to the caller through the future
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
        try:
            client = Client(dask, timeout=timeout)
        except (OSError, TimeoutError) as exc:
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
    ex = ProcessPoolExecutor(max_workers=int(workers),
                             mp_context=multiprocessing.get_context("spawn"))
    try:
        yield ex
    finally:
        ex.shutdown(wait=True, cancel_futures=True)
