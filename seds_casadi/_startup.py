"""Ctrl-C and SIGTERM while the ``seds-casadi`` console script imports the package.

Importing ``seds_casadi`` (CasADi, numpy, scikit-learn) takes one to two seconds before the
command line's own handlers (:func:`~seds_casadi.core._signals.interrupt_on_termination`) are
in place. A signal then ended the command with Python's defaults: a ``KeyboardInterrupt``
traceback for Ctrl-C, death by the signal for SIGTERM. In the console script (and only there,
and only where Python's default handlers are in force), :func:`exit_on_early_signals` makes
such a signal print the command's ``interrupted`` line and exit 130 at once: nothing has been
written or started yet. The command line replaces these handlers as soon as it starts, and
puts Python's own back when it ends. Importing this module installs them
(:data:`STARTUP_HANDLERS`): ``seds_casadi/__init__.py`` imports it first.

Standard library only: this module runs before the package's heavy imports.
"""

from __future__ import annotations

import os
import signal
import sys

#: the console script's name (``[project.scripts]`` in pyproject.toml)
SCRIPT = "seds-casadi"


def _exit_at_once(signum, frame) -> None:
    """Print the interrupted line of the command named on the command line and exit 130."""
    words = [a for a in sys.argv[1:] if not a.startswith("-")]
    command = f" {words[0]}" if words else ""
    try:
        sys.stderr.write(f"{SCRIPT}{command}: interrupted; the files written so far are "
                         "complete, the rest was not written\n")
        sys.stderr.flush()
    finally:
        os._exit(130)


#: recognised by the command line as a handler it may replace (like Python's own)
_exit_at_once.seds_casadi_startup = True  # type: ignore[attr-defined]


def exit_on_early_signals() -> bool:
    """In the ``seds-casadi`` console script, make SIGINT, SIGTERM and SIGHUP exit 130 at once
    while the package is imported (each where Python's default handler is in force: an
    ignored signal stays ignored). Returns whether anything was installed."""
    if not sys.argv or os.path.basename(sys.argv[0]) != SCRIPT:
        return False
    installed = False
    defaults = {signal.SIGINT: signal.default_int_handler, signal.SIGTERM: signal.SIG_DFL}
    if hasattr(signal, "SIGHUP"):
        defaults[signal.SIGHUP] = signal.SIG_DFL
    for sig, default in defaults.items():
        try:
            if signal.getsignal(sig) is default:
                signal.signal(sig, _exit_at_once)
                installed = True
        except ValueError:  # not the main thread
            return installed
    return installed


#: whether this import installed the start-up handlers (in the console script)
STARTUP_HANDLERS = exit_on_early_signals()
