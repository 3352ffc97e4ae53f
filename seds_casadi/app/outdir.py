"""The output folder of a command (``--out``): checked, locked and swept before any work.

:func:`output_folder` makes sure the folder can be written before a command spends minutes on
work it could not save (a path that is a file, lies under a file or is not writable is a
``ValueError`` naming it), holds an exclusive lock on it for the command's duration (a second run
on the same folder is refused at once instead of mixing its outputs with the first's; the
lock file is removed at the end, and so is the folder if the command made it and left it
empty) and removes the temporary files (``.tmp-*``, written before an atomic rename by
:mod:`seds_casadi.core._io`, :func:`seds_casadi.app.plotting.save_figure` and the replay's GIF
writer) that a killed run left behind: while the lock is held no other run
can be writing them. :func:`path_under` builds the path of every file a command names after
its input (a field's name): plain names only, inside the folder.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import re
from collections.abc import Iterator

from ..core._io import is_plain_name

#: name of the lock file inside an output folder
LOCK_NAME = ".seds-casadi.lock"


def _check_writable(path: str) -> None:
    """A ``ValueError`` naming ``path`` when it cannot be (made into) a writable folder."""
    if os.path.exists(path) and not os.path.isdir(path):
        raise ValueError(f"--out {path!r} is a file, not a folder; give a folder path "
                         f"(it is created if missing)")
    parent = path
    while parent and not os.path.exists(parent):
        parent = os.path.dirname(parent.rstrip(os.sep)) or "."
    if parent and not os.path.isdir(parent):
        raise ValueError(f"--out {path!r} lies under {parent!r}, which is a file; give a "
                         f"folder path")
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"--out {path!r}: cannot create the folder ({exc.strerror}); choose "
                         f"another place") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise ValueError(f"--out {path!r} is not writable; choose another folder or change "
                         f"its permissions")


def path_under(out: str | os.PathLike, *parts: str) -> str:
    """The path ``out/part/...`` of a file a command writes, every part a plain name
    (:func:`~seds_casadi.core._io.is_plain_name`; e.g. ``"datasets", f"{field.name}.npz"``).

    Raises
    ------
    ValueError
        A part is not a plain name (``..``, a path separator, a leading dot, ...), or the path
        would lie outside ``out`` (a folder in it that is a link to elsewhere): nothing is
        written outside ``--out``.
    """
    for part in parts:
        if not is_plain_name(part):
            raise ValueError(f"{part!r} cannot be a file name under --out {os.fspath(out)!r}: "
                             "only letters, digits, '.', '_' and '-' (at most 64, not "
                             "starting with '.' or '-'); rename what it was made from (a "
                             "field's 'name', say)")
    path = os.path.join(os.fspath(out), *parts)
    root = os.path.realpath(out)
    if os.path.commonpath([root, os.path.realpath(path)]) != root:
        raise ValueError(f"{path} would be written outside --out {os.fspath(out)!r} (through "
                         "a link); nothing is written outside it")
    return path


#: the temporary name a figure was written under before issue 30 (``NAME.tmp-PID.EXT``, now
#: ``.tmp-PID-NAME``): a run of an older version killed while saving left it; swept too
_OLD_FIGURE_TEMP = re.compile(r".+\.tmp-\d+\.(png|pdf|svg|gif|jpg)")


def sweep_temporary_files(path: str) -> list[str]:
    """Remove ``.tmp-*`` files under ``path`` (left by a killed run), and figures' temporary
    files of the older naming ``NAME.tmp-PID.EXT``; returns their paths."""
    removed = []
    for root, _, files in os.walk(path):
        for name in files:
            if name.startswith(".tmp-") or _OLD_FIGURE_TEMP.fullmatch(name):
                p = os.path.join(root, name)
                with contextlib.suppress(OSError):
                    os.unlink(p)
                    removed.append(p)
    return removed


@contextlib.contextmanager
def output_folder(path: str | os.PathLike) -> Iterator[str]:
    """Check, create and lock the output folder ``path`` for a ``with`` block.

    Raises
    ------
    ValueError
        ``path`` is a file, under a file or not writable, or another run holds its lock.
    """
    path = os.fspath(path)
    created = not os.path.exists(path)
    _check_writable(path)
    lock_path = os.path.join(path, LOCK_NAME)
    try:
        fd = os.open(lock_path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as exc:
        raise ValueError(f"--out {path!r}: cannot create its lock file ({exc.strerror})") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            if exc.errno not in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                raise
            other = os.pread(fd, 64, 0).decode(errors="replace").strip() or "?"
            raise ValueError(f"--out {path!r} is in use by another seds-casadi run (pid "
                             f"{other}); wait for it to finish or choose another folder") \
                from None
        try:  # the lock file may have been removed by the run that held it just now
            same = os.stat(lock_path).st_ino == os.fstat(fd).st_ino
        except OSError:
            same = False
        if not same:
            raise ValueError(f"--out {path!r} was in use by another seds-casadi run a moment "
                             "ago; run again")
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
        sweep_temporary_files(path)
        try:
            yield path
        finally:  # no leftovers: the lock file goes, and a folder made for nothing too
            with contextlib.suppress(OSError):
                os.unlink(lock_path)
            if created:
                with contextlib.suppress(OSError):
                    os.rmdir(path)  # only if empty
    finally:
        os.close(fd)  # releases the lock
