"""Demonstration files: ``.npz`` and ``.csv`` readers and the ``.npz`` writer.

``.npz`` (read with ``allow_pickle=False``): arrays ``pos_0``, ``pos_1``, ... of shape (T_n, d);
optional ``vel_n`` of the same shapes, ``t_n`` of shape (T_n,), a scalar ``dt`` and ``target`` of
shape (d,).

``.csv``: a header row, then one row per sample. Columns ``demo`` (an integer id; rows of one
demonstration are contiguous and in time order), ``t`` (time stamp, seconds), ``x0 .. x{d-1}``
(positions) and optionally ``v0 .. v{d-1}`` (velocities). Lines starting with ``#`` are comments.
"""

from __future__ import annotations

import os

import numpy as np

from .demonstrations import Demonstrations

__all__ = ["load_demonstrations", "save_demonstrations"]


def load_demonstrations(path: str | os.PathLike, **kwargs) -> Demonstrations:
    """Read demonstrations from a ``.npz`` or ``.csv`` file (formats in the module docstring).

    Parameters
    ----------
    path : str or path-like
    **kwargs
        Passed to :class:`Demonstrations` (``smoothing``, ``trim_speed``, ``target``, ...).
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


def _load_npz(path: str, kwargs: dict) -> Demonstrations:
    try:
        with np.load(path, allow_pickle=False) as f:
            data = {k: f[k] for k in f.files}
    except Exception as exc:  # noqa: BLE001 - any reader failure is a bad file
        raise ValueError(f"{path}: not a readable .npz file ({exc})") from None
    n = 0
    pos, vel, tim = [], [], []
    while f"pos_{n}" in data:
        pos.append(data[f"pos_{n}"])
        if f"vel_{n}" in data:
            vel.append(data[f"vel_{n}"])
        if f"t_{n}" in data:
            tim.append(data[f"t_{n}"])
        n += 1
    if n == 0:
        raise ValueError(f"{path}: no arrays named pos_0, pos_1, ... (see the documented format)")
    kw = dict(kwargs)
    if vel:
        if len(vel) != n:
            raise ValueError(f"{path}: vel_n given for some demonstrations only")
        kw.setdefault("velocities", vel)
    elif tim:
        if len(tim) != n:
            raise ValueError(f"{path}: t_n given for some demonstrations only")
        kw.setdefault("times", tim)
    if "dt" in data:
        kw.setdefault("dt", float(data["dt"]))
    if "target" in data:
        kw.setdefault("target", data["target"])
    return Demonstrations(pos, **kw)


def _load_csv(path: str, kwargs: dict) -> Demonstrations:
    with open(path, encoding="utf-8") as fh:
        lines = [ln for ln in fh if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise ValueError(f"{path}: empty CSV file")
    header = [h.strip() for h in lines[0].split(",")]
    for col in ("demo", "t", "x0"):
        if col not in header:
            raise ValueError(
                f"{path}: missing column {col!r}; expected columns demo, t, x0..x{{d-1}} "
                "and optionally v0..v{d-1}"
            )
    try:
        table = np.array([[float(c) for c in ln.split(",")] for ln in lines[1:]], ndmin=2)
    except ValueError as exc:
        raise ValueError(f"{path}: a row is not numeric ({exc})") from None
    if table.size == 0:
        raise ValueError(f"{path}: no data rows; the set of demonstrations is empty")
    if table.shape[1] != len(header):
        raise ValueError(f"{path}: rows have {table.shape[1]} values for {len(header)} columns")
    xcols = [header.index(f"x{j}") for j in range(len(header)) if f"x{j}" in header]
    vcols = [header.index(f"v{j}") for j in range(len(header)) if f"v{j}" in header]
    if vcols and len(vcols) != len(xcols):
        raise ValueError(f"{path}: {len(vcols)} velocity columns for {len(xcols)} positions")
    demo_ids = table[:, header.index("demo")]
    starts = np.flatnonzero(np.r_[True, np.diff(demo_ids) != 0])
    ends = np.r_[starts[1:], len(table)]
    pos = [table[s:e][:, xcols] for s, e in zip(starts, ends)]
    tim = [table[s:e, header.index("t")] for s, e in zip(starts, ends)]
    kw = dict(kwargs)
    if vcols:
        kw.setdefault("velocities", [table[s:e][:, vcols] for s, e in zip(starts, ends)])
    else:
        kw.setdefault("times", tim)
    return Demonstrations(pos, **kw)


def save_demonstrations(path: str | os.PathLike, demos: Demonstrations) -> None:
    """Write demonstrations (positions and velocities, caller's coordinates) as ``.npz``."""
    arrays = {}
    for n, (p, v) in enumerate(zip(demos.positions, demos.velocities)):
        arrays[f"pos_{n}"] = p
        arrays[f"vel_{n}"] = v
    arrays["target"] = demos.target
    np.savez(path, **arrays)
