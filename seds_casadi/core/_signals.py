"""Interrupts across C code that swallows Python exceptions.

CasADi calls our Python callbacks (the objective kernels, the progress line) from inside IPOPT
and catches whatever they raise: a ``KeyboardInterrupt`` raised there by Ctrl-C (or by a
SIGTERM handler that raises it) ends as IPOPT's ``NonIpopt_Exception_Thrown``, and the caller
would take the cut-short solve for a finished one. :class:`deferred_interrupts` holds the
signals' exceptions while such code runs: the handlers in force are still called at once, but
what they raise is kept (:attr:`pending`), the running code asks its solver to stop (IPOPT's
iteration callback returns 1), and the exception is raised when the block ends, in Python, where
it reaches the caller.

:func:`interrupt_on_termination` makes SIGTERM and SIGHUP end a command as Ctrl-C does. Its
handler never raises while Python code runs under a CasADi call (SWIG's conversions, such as
building a ``DM`` from a numpy array, try one overload after another and drop what the failed
ones raised) or during an import: there the signal is delivered again a few milliseconds later,
until the interrupt can be raised where it reaches the caller (:func:`_raise_interrupt`).
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time

#: signals that end a command the way Ctrl-C does (:func:`interrupt_on_termination`): a kill, and
#: the terminal or SSH session closing (SIGHUP, where the platform has it)
TERMINATING = (signal.SIGTERM, *((signal.SIGHUP,) if hasattr(signal, "SIGHUP") else ()))
#: the signals whose Python handlers are held
SIGNALS = (signal.SIGINT, *TERMINATING)


#: seconds after an interrupt during which :func:`interrupt_on_termination`'s handler ignores
#: further signals: the clean-up's time (a command ends within 2 s of an interrupt)
GRACE_SECONDS = 2.0
#: time.monotonic() of the last interrupt the handler raised (None: none yet)
_stopping: float | None = None
#: seconds after which a signal that arrived under a CasADi call is delivered again
REDELIVER_SECONDS = 0.005
#: whether a signal's second delivery is scheduled (one at a time)
_redelivering = False


def _raise_interrupt(signum, frame) -> None:
    """Raise ``KeyboardInterrupt``, unless one was raised less than :data:`GRACE_SECONDS`
    ago: a second Ctrl-C or a SIGTERM right after the first does not cut short the clean-up
    the first one started (it removes the run lock and temporary files). Later signals
    interrupt again (an interrupt that C code swallowed is not the last word).

    Under a CasADi call (a frame of CasADi's Python module on the stack: SWIG's conversions,
    our callbacks) or an import (a frame of the import machinery) outside
    :class:`deferred_interrupts`, the exception could be dropped or turned into another by C
    code (measured: a SIGTERM during ``ca.DM(numpy array)`` left ``lasa`` running to the end,
    exit 0; a SIGHUP while exudyn's compiled module initialised became exudyn's ImportError, a
    traceback): the signal is delivered again after :data:`REDELIVER_SECONDS` instead, until
    it arrives outside them. Inside :class:`deferred_interrupts` it is raised at once (the
    block keeps it and raises it at its end)."""
    global _stopping
    now = time.monotonic()
    if _stopping is not None and now - _stopping < GRACE_SECONDS:
        return
    if deferred_interrupts._depth == 0 and _in_fragile_code(frame):
        _redeliver(signum)
        return
    _stopping = now
    raise KeyboardInterrupt


def _casadi_dir() -> str | None:
    """The directory of CasADi's Python package, once it is imported (None before)."""
    module = sys.modules.get("casadi")
    path = getattr(module, "__file__", None)
    return os.path.dirname(os.path.abspath(path)) + os.sep if path else None


def _in_fragile_code(frame) -> bool:
    """Whether ``frame`` or one of its callers is code of CasADi's Python package or of the
    import machinery (a module being imported: extension modules' initialisation turns an
    exception raised in it into an ImportError)."""
    root = _casadi_dir()
    while frame is not None:
        name = frame.f_code.co_filename
        if name.startswith("<frozen importlib") or (
                root is not None and os.path.abspath(name).startswith(root)):
            return True
        frame = frame.f_back
    return False


def _redeliver(signum: int) -> None:
    """Send ``signum`` to the main thread again after :data:`REDELIVER_SECONDS` (once: a
    signal arriving while a second delivery is scheduled joins it)."""
    global _redelivering
    if _redelivering:
        return
    _redelivering = True
    main = threading.main_thread().ident

    def again() -> None:
        global _redelivering
        _redelivering = False
        try:
            signal.pthread_kill(main, signum)
        except (ProcessLookupError, OSError):  # the main thread has ended
            pass

    timer = threading.Timer(REDELIVER_SECONDS, again)
    timer.daemon = True
    timer.start()


def raise_pending_interrupt() -> None:
    """Raise now the interrupt of a signal that arrived under a CasADi call and waits for its
    second delivery (:func:`_redeliver`, a few milliseconds): called before a result file is
    put in place, so that nothing is written as complete after a signal. The second delivery
    then falls in the interrupt's grace (:data:`GRACE_SECONDS`)."""
    global _stopping
    if _redelivering and threading.current_thread() is threading.main_thread():
        _stopping = time.monotonic()
        raise KeyboardInterrupt


def interrupt_on_termination() -> dict:
    """Make each of :data:`TERMINATING` raise ``KeyboardInterrupt`` (so the clean-up of Ctrl-C
    runs: workers stopped, temporary files and the run lock removed, exit 130), and Ctrl-C
    too where Python's own handler is in force (an ignored SIGINT stays ignored): a signal
    within :data:`GRACE_SECONDS` of an interrupt does not cut its clean-up short. Returns the
    previous handlers for :func:`restore_handlers`. Outside the main thread nothing changes
    (and an empty dict is returned)."""
    global _stopping
    previous = {}
    _stopping = None
    for sig in SIGNALS:
        current = signal.getsignal(sig)
        if sig == signal.SIGINT and not (current is signal.default_int_handler
                                         or getattr(current, "seds_casadi_startup", False)):
            continue
        try:
            previous[sig] = signal.signal(sig, _raise_interrupt)
        except ValueError:  # not the main thread: leave signals alone
            break
    return previous


def restore_handlers(previous: dict) -> None:
    """Put back the handlers :func:`interrupt_on_termination` replaced."""
    global _stopping
    for sig, handler in previous.items():
        if getattr(handler, "seds_casadi_startup", False):  # the import's: Python's own now
            handler = signal.default_int_handler if sig == signal.SIGINT else signal.SIG_DFL
        try:
            signal.signal(sig, handler)
        except (ValueError, TypeError):  # not the main thread, or a handler set from C
            pass
    _stopping = None


def ignore_until_exit() -> None:
    """For a process that ends after an interrupt: ignore :data:`SIGNALS` from now on, so that
    a second Ctrl-C or a SIGTERM neither cuts its clean-up short nor kills it while the
    interpreter shuts down (Python's finalisation puts the default handlers back in place of
    its own, but leaves an ignored signal ignored)."""
    for sig in SIGNALS:
        try:
            signal.signal(sig, signal.SIG_IGN)
        except ValueError:  # not the main thread
            break


class deferred_interrupts:
    """Context manager: what the SIGINT / SIGTERM handlers raise inside the block is raised at
    its end instead (the first such exception; it wins over an exception the block raises).

    Only the main thread can install signal handlers: in another thread (where signals are never
    handled) the block changes nothing and :attr:`pending` stays ``False``. Blocks may nest; the
    handlers are restored when the outermost one ends.
    """

    _lock = threading.Lock()
    _depth = 0
    _previous: dict = {}
    _exception: BaseException | None = None

    def __enter__(self) -> deferred_interrupts:
        self._installed = False
        if threading.current_thread() is not threading.main_thread():
            return self
        cls = type(self)
        with cls._lock:
            if cls._depth == 0:
                # known to _hold before it is installed: a signal in between is not lost
                cls._exception = None
                cls._previous = {s: h for s in SIGNALS
                                 if callable(h := signal.getsignal(s))}  # not SIG_DFL/IGN
                try:
                    _set_handlers(dict.fromkeys(cls._previous, _hold))
                except BaseException:  # a signal before _hold was in place: back to before
                    _set_handlers(cls._previous)
                    cls._previous = {}
                    raise
            cls._depth += 1
            self._installed = True
        return self

    @property
    def pending(self) -> bool:
        """Whether a signal's handler raised inside the block (the code should stop now)."""
        return self._installed and type(self)._exception is not None

    def __exit__(self, exc_type, exc, tb) -> bool:
        if not self._installed:
            return False
        cls = type(self)
        with cls._lock:
            cls._depth -= 1
            if cls._depth == 0:
                try:
                    _set_handlers(cls._previous)
                finally:
                    # read after the handlers are back: a signal in between is not lost
                    held, cls._exception, cls._previous = cls._exception, None, {}
            else:
                held = cls._exception
        if held is not None and held is not exc:
            raise held
        return False


def _hold(signum, frame) -> None:
    """The handler in force inside :class:`deferred_interrupts`: calls the previous one and
    keeps what it raises."""
    handler = deferred_interrupts._previous.get(signum)
    if handler is None:
        return
    try:
        handler(signum, frame)
    except BaseException as exc:  # kept, raised at the block's end
        if deferred_interrupts._exception is None:
            deferred_interrupts._exception = exc


def _set_handlers(handlers: dict) -> None:
    """Install every handler of ``handlers`` (signal -> handler), even when a signal's handler
    raises in between (then the first such exception is raised once all are in place): no
    handler of ours is left behind, none of the caller's is lost."""
    first = None
    todo = list(handlers.items())
    while todo:
        try:
            signal.signal(*todo[0])
            todo.pop(0)
        except (ValueError, OSError, TypeError):  # signal.signal's own errors
            raise
        except BaseException as exc:  # a signal's handler raised: finish, then raise it
            first = first or exc
    if first is not None:
        raise first
