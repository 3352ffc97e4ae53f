"""Progress of long loops: a tqdm bar on a terminal, and elsewhere (a log file, CI, a pipe) a
plain line through ``logging`` every few seconds, which never garbles a log.

The lines go to the logger ``seds_casadi.progress`` at INFO (the command line shows them;
``--quiet`` hides them, as it hides the bars); ``enabled=False`` gives neither.
"""

from __future__ import annotations

import logging
import sys
import time
from collections.abc import Iterable

_LOG = logging.getLogger("seds_casadi.progress")

#: seconds between two progress lines when there is no terminal
LOG_EVERY = 10.0


def _terminal(stream=None) -> bool:
    try:
        return bool((sys.stderr if stream is None else stream).isatty())
    except (AttributeError, ValueError):
        return False


class _LogLines:
    """``tqdm``'s interface used here (iteration, ``update``, ``close``) as logged lines."""

    def __init__(self, iterable, total=None, desc: str = "progress", unit: str = "it",
                 every: float = LOG_EVERY):
        self.iterable, self.desc, self.unit, self.every = iterable, desc, unit, every
        if total is None and iterable is not None and hasattr(iterable, "__len__"):
            total = len(iterable)
        self.total, self.n = total, 0
        self.start = self.last = time.perf_counter()
        self.closed = False

    def __iter__(self):
        try:
            for item in self.iterable:
                yield item
                self.update(1)
        finally:
            self.close()

    def _line(self) -> None:
        of = f"/{self.total}" if self.total else ""
        _LOG.info("%s: %d%s %s%s (%.0f s)", self.desc, self.n, of, self.unit,
                  "s" if self.n != 1 else "", time.perf_counter() - self.start)

    def update(self, n: int = 1) -> None:
        self.n += n
        now = time.perf_counter()
        if now - self.last >= self.every and not (self.total and self.n >= self.total):
            self.last = now
            self._line()

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            if time.perf_counter() - self.start >= self.every:  # a long loop: say it ended
                self._line()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def progress_bar(iterable: Iterable | None = None, enabled: bool = True, **kwargs):
    """``iterable`` with its progress shown: a tqdm bar on stderr when it is a terminal, else
    a log line (``seds_casadi.progress``, INFO) every :data:`LOG_EVERY` seconds and one at the
    end of a loop that took longer; ``enabled=False``: nothing. ``iterable=None`` with
    ``total=`` gives an object to ``update(n)`` and ``close()``, as tqdm's."""
    from tqdm.auto import tqdm

    if not enabled:
        return tqdm(iterable, disable=True, **kwargs)
    if _terminal(kwargs.get("file")):   # tqdm writes to file= (default stderr)
        return tqdm(iterable, **kwargs)
    return _LogLines(iterable, kwargs.get("total"), kwargs.get("desc", "progress"),
                     kwargs.get("unit", "it"))
