"""Atomic file writes (a partial file never appears under the final name) and the names that
may become file names."""

from __future__ import annotations

import csv
import os
import re
import tempfile
from collections.abc import Iterable

#: a name that may become a file name under an output folder: letters, digits, '.', '_', '-',
#: not starting with '.' or '-' (no hidden file, no option, no '..'), at most 64 characters
PLAIN_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9._-]{0,63}")


def is_plain_name(name) -> bool:
    """Whether ``name`` is a :data:`PLAIN_NAME` (so it cannot lead out of a folder)."""
    return isinstance(name, str) and PLAIN_NAME.fullmatch(name) is not None


def umask() -> int:
    """The process's umask (read by setting and restoring it)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


# the old private name, still imported by app/replay.py: removed by the game-layer change
# (it imports umask)


def _public(fd: int) -> None:
    """Give a temporary file (``mkstemp`` makes it 0600) the mode a plain ``open`` would:
    0666 minus the umask (0644 under the usual umask 022)."""
    try:
        os.fchmod(fd, 0o666 & ~umask())
    except (AttributeError, OSError):  # no fchmod (Windows) or a file system without modes
        pass


def atomic_text(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file in the same folder."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", dir=folder)
    _public(fd)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_npz(path: str | os.PathLike, **arrays) -> None:
    """Write arrays to an ``.npz`` file atomically (no pickle: plain arrays only)."""
    import numpy as np

    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=".npz", dir=folder)
    _public(fd)
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, **arrays)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_csv(path: str | os.PathLike, header: Iterable[str], rows: Iterable[Iterable]) -> None:
    """Write a CSV file (header, then rows; floats with 6 significant digits) atomically."""
    import io

    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(list(header))
    for row in rows:
        w.writerow([f"{v:.6g}" if isinstance(v, float) else v for v in row])
    atomic_text(path, buf.getvalue())


def data_folder(package: str) -> str:
    """File-system folder of a data package shipped with seds_casadi (through ``importlib``).

    Parameters
    ----------
    package : {"seds_casadi._fields", "seds_casadi._robots", "seds_casadi.data"}
        The repository's ``fields/`` and ``robots/`` are installed as the data packages
        ``seds_casadi._fields`` and ``seds_casadi._robots`` (plain and editable installs alike).
    """
    from importlib.resources import files

    return os.fspath(files(package))


def npz_value_count(path: str | os.PathLike) -> int:
    """Number of values in an ``.npz`` file, read from its arrays' headers (nothing is loaded,
    so a size limit can be checked before allocating)."""
    import zipfile

    import numpy as np

    total = 0
    with zipfile.ZipFile(path) as z:
        for name in z.namelist():
            with z.open(name) as fh:
                version = np.lib.format.read_magic(fh)
                read = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                        else np.lib.format.read_array_header_2_0)
                shape, _, _ = read(fh)
                total += int(np.prod(shape, dtype=float))
    return total
