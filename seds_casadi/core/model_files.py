"""One guarded file format for saved artefacts (models, motions): ``.npz`` without pickle.

A guarded file holds plain arrays plus four entries: ``format`` (what the file is, e.g.
``"seds_casadi.StableDS"``), ``version``, ``meta`` (a JSON text) and ``checksum`` (SHA-256 over
the arrays of the schema, in its order, as little-endian float64 or their raw bytes, and the JSON
text). :func:`write_guarded` writes atomically (a partial file never appears under the final
name); :func:`read_guarded` refuses, with a :class:`~seds_casadi.ModelFileError` that names the
file and the entry, anything unreadable, of another format or version, incomplete, of the wrong
type or shape, or whose checksum does not match (corrupt or edited). The caller then re-validates
the meaning (e.g. the stability certificate).
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable

import numpy as np

from ._io import InputFileError, atomic_npz, read_npz
from .errors import ModelFileError

_RESERVED = ("format", "version", "meta", "checksum")
#: most values a guarded file may hold (checked from the headers before anything is loaded;
#: the file's size and its entries' uncompressed sizes are bounded by 8 bytes a value)
MAX_VALUES = 100_000_000
#: largest uncompressed size of the small entries (a zip bomb in ``version`` is refused
#: before it is decompressed)
RESERVED_BYTES = {"format": 4096, "version": 4096, "checksum": 4096}


def numpy_json(value):
    """``default`` of :func:`json.dumps` for metadata: numpy scalars and arrays as plain
    numbers and lists; anything else is refused."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def checksum(arrays: list[np.ndarray], meta_json: str) -> str:
    """SHA-256 of the arrays (float arrays as little-endian float64) and the meta JSON."""
    h = hashlib.sha256()
    for a in arrays:
        a = np.asarray(a)
        h.update(np.ascontiguousarray(a, dtype="<f8").tobytes() if a.dtype.kind in "fiub"
                 else np.ascontiguousarray(a).tobytes())
    h.update(meta_json.encode("utf-8"))
    return h.hexdigest()


def write_guarded(path: str | os.PathLike, kind: str, version: int,
                  arrays: dict[str, np.ndarray], meta: dict | None = None,
                  meta_key: str = "meta", json_default: Callable | None = None) -> None:
    """Write ``arrays`` (in the order given: that order is the checksum's) and ``meta``.

    Parameters
    ----------
    path : path-like
    kind : str
        The ``format`` entry.
    version : int
    arrays : dict of name -> array
        Plain numeric arrays (no objects).
    meta : dict, optional
        JSON-serialisable metadata.
    meta_key : str
        Entry name of the JSON text (``"fit_info"`` for a StableDS).
    json_default : callable, optional
        ``default`` of :func:`json.dumps` for values JSON does not know (default:
        :func:`numpy_json`, numpy scalars and arrays as plain numbers and lists).
    """
    bad = [k for k in arrays if k in _RESERVED or k == meta_key]
    if bad:
        raise ValueError(f"array names {bad} are reserved")
    meta_json = json.dumps(meta or {}, sort_keys=True, default=json_default or numpy_json)
    entries = {"format": np.array(kind), "version": np.array(int(version)),
               **{k: np.asarray(v) for k, v in arrays.items()},
               meta_key: np.array(meta_json),
               "checksum": np.array(checksum(list(arrays.values()), meta_json))}
    atomic_npz(path, **entries)


def read_guarded(path: str | os.PathLike, kind: str, versions: tuple[int, ...],
                 schema: dict[str, int | None | tuple[int | None, str]] | Callable,
                 meta_key: str = "meta"
                 ) -> tuple[dict[str, np.ndarray], dict, int]:
    """Read and verify a file written by :func:`write_guarded`.

    Parameters
    ----------
    path : path-like
    kind : str
        The expected ``format``.
    versions : tuple of int
        Versions this reader understands.
    schema : dict of name -> ndim or None, or (ndim or None, kinds)
        The arrays the file must hold, in checksum order, with their number of dimensions
        (None: any) and the dtype kinds allowed (default ``"f"``, float; ``"i"`` integer); or
        a function of the file's (checksummed) meta giving that dict, for files whose arrays
        depend on it.
    meta_key : str

    Returns
    -------
    arrays : dict of name -> array
    meta : dict
    version : int

    Raises
    ------
    FileNotFoundError
        No file at ``path``.
    ModelFileError
        Anything else that is wrong with the file (the message names the entry): also a path
        that is not a regular file (a named pipe, a device), a file larger than
        :data:`MAX_VALUES` values allow, or an entry whose uncompressed size is more than it
        may be (checked before anything is decompressed).
    """
    path = os.fspath(path)
    try:
        data = read_npz(path, f"{kind} file", MAX_VALUES, member_bytes=RESERVED_BYTES)
    except FileNotFoundError:
        raise
    except InputFileError as exc:  # not a regular file, too large: the message names it
        raise ModelFileError(str(exc)) from None
    except Exception as exc:  # noqa: BLE001 - any reader failure means a bad file
        raise ModelFileError(f"{path}: not a readable {kind} file ({exc})") from None
    missing = [k for k in ("format", "version", meta_key, "checksum") if k not in data]
    if missing:
        raise ModelFileError(f"{path}: missing entries {missing}; not a complete {kind} file "
                             "(written by an older version without a checksum? save it again)")
    if str(data["format"]) != kind:
        raise ModelFileError(f"{path}: format {str(data['format'])!r} is not {kind!r}")
    if data["version"].dtype.kind not in "iu" or data["version"].shape != ():
        raise ModelFileError(f"{path}: entry 'version' is not an integer")
    version = int(data["version"])
    if version not in versions:
        raise ModelFileError(f"{path}: version {version} is not supported (this library reads "
                             f"version {', '.join(map(str, versions))})")
    meta_json = str(data[meta_key])
    try:
        meta = json.loads(meta_json)
    except (ValueError, RecursionError) as exc:  # also an integer of more digits than
        # Python converts (sys.get_int_max_str_digits)
        raise ModelFileError(f"{path}: entry {meta_key!r} is not valid JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise ModelFileError(f"{path}: entry {meta_key!r} is not a JSON object")
    if callable(schema):
        try:
            schema = schema(meta)
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelFileError(f"{path}: entry {meta_key!r} does not describe the file's "
                                 f"arrays ({type(exc).__name__}: {exc})") from None
    missing = [k for k in schema if k not in data]
    if missing:
        raise ModelFileError(f"{path}: missing entries {missing}; not a complete {kind} file")
    for name, spec in schema.items():
        ndim, kinds = spec if isinstance(spec, tuple) else (spec, "f")
        a = data[name]
        if a.dtype.kind not in kinds:
            what = {"f": "a float", "i": "an integer"}.get(kinds, f"a {kinds!r}")
            raise ModelFileError(f"{path}: entry {name!r} is not {what} array ({a.dtype})")
        if ndim is not None and a.ndim != ndim:
            raise ModelFileError(f"{path}: entry {name!r} has {a.ndim} dimensions, not {ndim}")
        if not np.all(np.isfinite(a)):
            raise ModelFileError(f"{path}: entry {name!r} holds NaN or infinite values")
    if checksum([data[k] for k in schema], meta_json) != str(data["checksum"]):
        raise ModelFileError(f"{path}: checksum mismatch; the file is corrupt or was edited")
    return {k: data[k] for k in schema}, meta, version
