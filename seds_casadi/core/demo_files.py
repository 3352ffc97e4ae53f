"""Demonstration files: ``.npz`` and ``.csv`` readers and the ``.npz`` writer.

``.npz`` (read with ``allow_pickle=False``): arrays ``pos_0``, ``pos_1``, ... of shape (T_n, d);
optional ``vel_n`` of the same shapes, ``t_n`` of shape (T_n,), a scalar ``dt`` and ``target`` of
shape (d,).

``.csv``: a header row, then one row per sample. Columns ``demo`` (an integer id; rows of one
demonstration are contiguous and in time order), ``t`` (time stamp, seconds; strictly increasing
within a demonstration, checked also when velocities are given), ``x0 .. x{d-1}``
(positions) and optionally ``v0 .. v{d-1}`` (velocities). Lines starting with ``#`` are comments.
"""

from __future__ import annotations

import csv
import difflib
import os
import re

import numpy as np

from ._io import InputFileError, atomic_npz, open_regular, read_npz
from .demonstrations import Demonstrations


def load_demonstrations(path: str | os.PathLike, **kwargs) -> Demonstrations:
    """Read demonstrations from a ``.npz`` or ``.csv`` file (formats in the module docstring).

    Parameters
    ----------
    path : str or path-like
    **kwargs
        Passed to :class:`Demonstrations` (``smoothing``, ``trim_speed``, ``target``, ...).

    Raises
    ------
    FileNotFoundError
        No file at ``path``.
    ValueError
        Anything wrong with the file, naming it: also a path that is not a regular file (a
        named pipe, ``/dev/zero``: refused before it is opened) or a file larger than
        :data:`MAX_VALUES` values allow (refused from its size, and for ``.npz`` from each
        entry's declared uncompressed size, before anything is read or decompressed).
    """
    path = os.fspath(path)
    if not os.path.exists(path):
        raise FileNotFoundError(f"no demonstrations file at {path!r}")
    ext = os.path.splitext(path)[1].lower()
    if ext == ".npz":
        return _load_npz(path, kwargs)
    if ext == ".csv":
        return _load_csv(path, kwargs)
    raise ValueError(f"{path}: unknown demonstrations format {ext!r}; use .npz or .csv")


#: largest number of values a demonstrations file may hold (positions, velocities, times)
MAX_VALUES = 50_000_000
_NPZ_KEY = re.compile(r"^(pos|vel|t)_(\d+)$")
_CSV_KEY = re.compile(r"^([xv])(\d+)$")


def _did_you_mean(name: str, valid: list[str]) -> str:
    close = difflib.get_close_matches(name, valid, n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _indexed(path: str, found: dict[int, str], what: str) -> int:
    """The count n of entries indexed 0..n-1; an error naming the first missing index."""
    n = len(found)
    missing = [i for i in range(n) if i not in found]
    if missing:
        raise ValueError(f"{path}: {what}_{missing[0]} is missing but "
                         f"{what}_{max(found)} is given; number them 0, 1, 2, ... without gaps")
    return n


def _npz_entries(path: str) -> dict[str, np.ndarray]:
    try:
        return read_npz(path, "demonstrations file", MAX_VALUES)
    except InputFileError:  # not a regular file, or too large (before decompressing)
        raise
    except Exception as exc:  # noqa: BLE001 - any reader failure is a bad file
        raise ValueError(f"{path}: not a readable .npz file without pickled objects "
                         f"({type(exc).__name__}: {exc})") from None


def _load_npz(path: str, kwargs: dict) -> Demonstrations:
    data = _npz_entries(path)
    groups: dict[str, dict[int, str]] = {"pos": {}, "vel": {}, "t": {}}
    for key in data:
        m = _NPZ_KEY.match(key)
        if m:
            groups[m.group(1)][int(m.group(2))] = key
        elif key not in ("dt", "target"):
            valid = ["pos_0", "vel_0", "t_0", "dt", "target"]
            raise ValueError(f"{path}: unknown entry {key!r}{_did_you_mean(key, valid)}; a "
                             "demonstrations file holds pos_n, optionally vel_n or t_n, dt and "
                             "target")
    for key, a in data.items():
        if a.dtype.kind not in "fiu":
            raise ValueError(f"{path}: entry {key!r} holds {a.dtype} values; real numbers needed"
                             + (" (complex values are not demonstrations)"
                                if a.dtype.kind == "c" else ""))
    if not groups["pos"]:
        raise ValueError(f"{path}: no arrays named pos_0, pos_1, ... (see the documented format)")
    n = _indexed(path, groups["pos"], "pos")
    for what in ("vel", "t"):
        extra = sorted(set(groups[what]) - set(groups["pos"]))
        if extra:
            raise ValueError(f"{path}: {what}_{extra[0]} has no pos_{extra[0]}")
        if groups[what] and len(groups[what]) != n:
            lack = min(set(range(n)) - set(groups[what]))
            raise ValueError(f"{path}: {what}_n given for some demonstrations only "
                             f"({what}_{lack} is missing)")
    if groups["vel"] and groups["t"]:
        raise ValueError(f"{path}: both vel_n and t_n given; keep one (velocities are derived "
                         "from the time stamps otherwise)")
    pos = [data[f"pos_{i}"] for i in range(n)]
    kw = dict(kwargs)
    if groups["vel"]:
        kw.setdefault("velocities", [data[f"vel_{i}"] for i in range(n)])
    elif groups["t"]:
        kw.setdefault("times", [data[f"t_{i}"] for i in range(n)])
    if "dt" in data:
        if data["dt"].size != 1:
            raise ValueError(f"{path}: entry 'dt' must be one number, got shape "
                             f"{data['dt'].shape}")
        kw.setdefault("dt", float(data["dt"].ravel()[0]))
    if "target" in data:
        kw.setdefault("target", data["target"])
    return _demonstrations(path, pos, kw)


def _demonstrations(path: str, pos, kw) -> Demonstrations:
    """Demonstrations built from a file's arrays; their errors name the file."""
    try:
        return Demonstrations(pos, **kw)
    except (TypeError, ValueError) as exc:
        raise type(exc)(f"{path}: {exc}") from None


def _csv_rows(path: str) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """Header and data rows (with their line numbers) of a CSV file; a UTF-8 BOM, quotes and
    ``#`` comment lines are understood."""
    try:
        with open_regular(path, 40 * MAX_VALUES, "demonstrations file", text=True,
                          encoding="utf-8-sig", newline="") as fh:
            rows = [(i + 1, r) for i, r in enumerate(csv.reader(fh))
                    if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not a UTF-8 text file ({exc})") from None
    except csv.Error as exc:
        raise ValueError(f"{path}: not a readable CSV file ({exc})") from None
    if not rows:
        raise ValueError(f"{path}: empty CSV file")
    return [h.strip() for h in rows[0][1]], rows[1:]


def _csv_columns(path: str, header: list[str]) -> tuple[list[int], list[int]]:
    """Column indices of x0..x{d-1} and v0..v{d-1}; errors for unknown, duplicated, missing
    or gapped columns."""
    expect = ("; expected columns demo, t, x0..x{d-1} and optionally v0..v{d-1}")
    seen: set[str] = set()
    idx: dict[str, dict[int, int]] = {"x": {}, "v": {}}
    unknown = []
    for j, h in enumerate(header):
        if h in seen:
            raise ValueError(f"{path}: column {h!r} appears twice; keep one")
        seen.add(h)
        m = _CSV_KEY.match(h)
        if m:
            idx[m.group(1)][int(m.group(2))] = j
        elif h not in ("demo", "t"):
            unknown.append(h)
    others = f" (the file has unknown columns {unknown})" if unknown else ""
    for col in ("demo", "t", "x0"):
        if col not in header:
            raise ValueError(f"{path}: missing column {col!r}{others}{expect}")
    if unknown:
        h = unknown[0]
        raise ValueError(f"{path}: unknown column {h!r}"
                         f"{_did_you_mean(h, ['demo', 't', 'x0', 'x1', 'v0', 'v1'])}{expect}")
    for c in ("x", "v"):
        gap = [i for i in range(len(idx[c])) if i not in idx[c]]
        if gap:
            raise ValueError(f"{path}: column {c}{gap[0]} is missing but {c}{max(idx[c])} is "
                             f"given; number the columns {c}0, {c}1, ... without gaps")
    if idx["v"] and len(idx["v"]) != len(idx["x"]):
        raise ValueError(f"{path}: {len(idx['v'])} velocity columns for {len(idx['x'])} "
                         "positions")
    return ([idx["x"][i] for i in range(len(idx["x"]))],
            [idx["v"][i] for i in range(len(idx["v"]))])


def _load_csv(path: str, kwargs: dict) -> Demonstrations:
    header, rows = _csv_rows(path)
    xcols, vcols = _csv_columns(path, header)
    if not rows:
        raise ValueError(f"{path}: no data rows; the set of demonstrations is empty")
    table = np.empty((len(rows), len(header)))
    for r, (line, cells) in enumerate(rows):
        if len(cells) != len(header):
            raise ValueError(f"{path}: line {line} has {len(cells)} values for "
                             f"{len(header)} columns")
        try:
            table[r] = [float(c) for c in cells]
        except ValueError as exc:
            raise ValueError(f"{path}: line {line} is not numeric ({exc})") from None
    demo_ids = table[:, header.index("demo")]
    if not np.all(np.isfinite(demo_ids)) or np.any(demo_ids != np.round(demo_ids)):
        raise ValueError(f"{path}: column 'demo' must hold integer ids")
    starts = np.flatnonzero(np.r_[True, np.diff(demo_ids) != 0])
    ids = demo_ids[starts]
    if len(np.unique(ids)) != len(ids):
        again = next(i for k, i in enumerate(ids) if i in ids[:k])
        raise ValueError(f"{path}: the rows of demo {int(again)} are not contiguous; sort the "
                         "rows by demo, then by time")
    ends = np.r_[starts[1:], len(table)]
    _check_times(path, table[:, header.index("t")], [line for line, _ in rows], starts, ends)
    pos = [table[s:e][:, xcols] for s, e in zip(starts, ends)]
    kw = dict(kwargs)
    if vcols:
        kw.setdefault("velocities", [table[s:e][:, vcols] for s, e in zip(starts, ends)])
    else:
        kw.setdefault("times", [table[s:e, header.index("t")] for s, e in zip(starts, ends)])
    return _demonstrations(path, pos, kw)


def _check_times(path: str, t: np.ndarray, lines: list[int], starts, ends) -> None:
    """Each demonstration's ``t`` finite and strictly increasing, with or without velocity
    columns (the rows are the samples in time order: shuffled rows would be fitted as given)."""
    for s, e in zip(starts, ends):
        bad = np.flatnonzero(~np.isfinite(t[s:e]))
        if bad.size:
            raise ValueError(f"{path}: line {lines[s + bad[0]]}: t is not a finite number")
        back = np.flatnonzero(np.diff(t[s:e]) <= 0)
        if back.size:
            k = s + back[0] + 1
            raise ValueError(f"{path}: line {lines[k]}: t = {t[k]:g} does not come after "
                             f"t = {t[k - 1]:g} of the row before; the rows of a demonstration "
                             "must be in time order (sort them by demo, then by t)")


def save_demonstrations(path: str | os.PathLike, demos: Demonstrations) -> None:
    """Write demonstrations (positions and velocities, caller's coordinates) as ``.npz``."""
    arrays = {}
    for n, (p, v) in enumerate(zip(demos.positions, demos.velocities)):
        arrays[f"pos_{n}"] = p
        arrays[f"vel_{n}"] = v
    arrays["target"] = demos.target
    atomic_npz(path, **arrays)
