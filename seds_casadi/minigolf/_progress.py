"""Progress bars (tqdm): shown on a terminal, quiet when stderr is not one or when not wanted."""

from __future__ import annotations

from collections.abc import Iterable


def progress_bar(iterable: Iterable, enabled: bool = True, **kwargs):
    """``iterable`` wrapped in a tqdm bar on stderr; ``enabled=False`` or a stderr that is not
    a terminal (a log file, CI, a pipe) gives no bar at all (tqdm's ``disable=None``)."""
    from tqdm.auto import tqdm

    return tqdm(iterable, disable=None if enabled else True, **kwargs)
