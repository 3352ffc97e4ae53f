"""Atomic file writes (a partial file never appears under the final name), the names that may
become file names, and guarded reads: every file the project reads is opened by
:func:`open_regular` (a regular file of bounded size, checked before it is opened) and every
``.npz`` by :func:`read_npz` (each entry's uncompressed size checked before decompressing)."""

from __future__ import annotations

import csv
import os
import re
import stat
import tempfile
from collections.abc import Iterable
from typing import IO

from ._signals import raise_pending_interrupt

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
        raise_pending_interrupt()  # a signal's interrupt first: nothing written after it
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
        raise_pending_interrupt()  # a signal's interrupt first: nothing written after it
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


class InputFileError(ValueError):
    """A file given to read is not a regular file, or is larger than its kind may be (checked
    before it is opened, parsed or decompressed)."""


def _megabytes(n: float) -> str:
    return f"{n / 1e6:.3g} MB"


def _check_stat(path: str, st: os.stat_result, max_bytes: int, what: str) -> None:
    if stat.S_ISDIR(st.st_mode):
        raise InputFileError(f"{path} is a folder, not a {what}")
    if not stat.S_ISREG(st.st_mode):
        kind = ("a named pipe" if stat.S_ISFIFO(st.st_mode) else
                "a device" if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode) else
                "a socket" if stat.S_ISSOCK(st.st_mode) else "not a plain file")
        raise InputFileError(f"{path} is not a regular file ({kind}); give a {what} saved on "
                             "disk")
    if st.st_size > max_bytes:
        raise InputFileError(f"{path} is {_megabytes(st.st_size)}, more than the "
                             f"{_megabytes(max_bytes)} a {what} may be")


def open_regular(path: str | os.PathLike, max_bytes: int, what: str, text: bool = False,
                 **kwargs) -> IO:
    """Open a file for reading once it is known to be a regular file of at most ``max_bytes``.

    A named pipe, a device (``/dev/zero``, ``/dev/urandom``) or a socket would block in
    ``open()`` or be read until memory runs out: the path is checked with ``os.stat`` before
    it is opened, and again (``fstat``) on what was opened (opened without blocking, so a file
    swapped for a pipe in between cannot hang either).

    Parameters
    ----------
    path : path-like
    max_bytes : int
        Largest size accepted.
    what : str
        What the file should be, for the messages (``"field file"``).
    text : bool
        Open in text mode (``kwargs``: ``encoding``, ``newline``), else binary.

    Raises
    ------
    FileNotFoundError
        No file at ``path``.
    InputFileError
        A folder, not a regular file, or larger than ``max_bytes`` (a ``ValueError`` naming
        the path).
    """
    path = os.fspath(path)
    _check_stat(path, os.stat(path), max_bytes, what)
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    try:
        _check_stat(path, os.fstat(fd), max_bytes, what)
        os.set_blocking(fd, True)
        return os.fdopen(fd, "r" if text else "rb", **kwargs)
    except BaseException:
        os.close(fd)
        raise


#: bytes an ``.npz`` file's members may hold beyond 8 per value (array headers, texts)
NPZ_OVERHEAD_BYTES = 64 * 1024 * 1024


def read_npz(path: str | os.PathLike, what: str, max_values: int,
             member_bytes: dict[str, int] | None = None,
             only: tuple[str, ...] | None = None) -> dict:
    """The arrays of an ``.npz`` file (no pickle), with every size checked before anything is
    decompressed or allocated.

    The file must be a regular file (:func:`open_regular`); each member's uncompressed size, as
    the archive declares it (``ZipInfo.file_size``: decompression stops there), is checked
    against ``member_bytes`` (by entry name) and their sum against ``8 * max_values`` plus
    :data:`NPZ_OVERHEAD_BYTES`; then the number of values the arrays' headers declare against
    ``max_values``. A small file that decompresses to gigabytes (a zip bomb) is refused
    without being decompressed.

    Parameters
    ----------
    path : path-like
    what : str
        What the file should be, for the messages.
    max_values : int
        Most values (array elements) the file may hold.
    member_bytes : dict of str -> int, optional
        Largest uncompressed size of named entries (e.g. a scalar ``version``).
    only : tuple of str, optional
        Load only these entries (those present).

    Raises
    ------
    FileNotFoundError
        No file at ``path``.
    InputFileError
        Not a regular file, or larger than allowed (before decompressing).
    ValueError, zipfile.BadZipFile, OSError
        Not an ``.npz`` file, or an entry numpy cannot read without pickle.
    """
    import zipfile

    import numpy as np

    path = os.fspath(path)
    max_bytes = 8 * int(max_values) + NPZ_OVERHEAD_BYTES
    limits = member_bytes or {}
    with open_regular(path, max_bytes, what) as fh:
        with zipfile.ZipFile(fh) as z:
            infos = z.infolist()
            total = 0
            for info in infos:
                name = info.filename[:-4] if info.filename.endswith(".npy") else info.filename
                limit = limits.get(name)
                if limit is not None and info.file_size > limit:
                    raise InputFileError(
                        f"{path}: entry {name!r} holds {_megabytes(info.file_size)} "
                        f"uncompressed, more than the {limit} bytes it may in a {what}")
                total += info.file_size
            if total > max_bytes:
                raise InputFileError(f"{path}: its entries hold {_megabytes(total)} "
                                     f"uncompressed, more than the {_megabytes(max_bytes)} a "
                                     f"{what} may")
            values = 0
            for info in infos:
                with z.open(info) as member:
                    version = np.lib.format.read_magic(member)
                    read = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                            else np.lib.format.read_array_header_2_0)
                    shape, _, dtype = read(member)
                    n = int(np.prod(shape, dtype=float))
                    values += n
                    # numpy allocates what the header declares before reading: it must be
                    # what the entry holds
                    if not dtype.hasobject and n * dtype.itemsize + member.tell() != \
                            info.file_size:
                        raise InputFileError(
                            f"{path}: entry {info.filename!r} declares {shape} values of "
                            f"{dtype} but holds {info.file_size - member.tell()} bytes of "
                            "data; the file is corrupt")
            if values > max_values:
                raise InputFileError(f"{path}: {values:.0f} values, more than the "
                                     f"{max_values} a {what} may hold")
        fh.seek(0)
        with np.load(fh, allow_pickle=False) as f:
            return {k: f[k] for k in f.files if only is None or k in only}
