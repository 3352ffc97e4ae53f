"""Demonstrations: validation and preprocessing as SEDS does it.

Preprocessing (as in the original SEDS package, ``preprocess_demos``):

1. optional smoothing of the positions (centred moving average),
2. velocities by finite differences (second order, from a time step or time stamps) unless given,
3. trimming of leading and trailing standstill samples (speed below a threshold),
4. the target x* as the mean of the end points (or given), and the data shifted so the target is
   the origin. When the target is not given, each demonstration is shifted by its own end point
   (SEDS's choice), so every demonstration ends exactly at the attractor.

File formats (``.npz``, ``.csv``): :mod:`seds_casadi.core.demo_files`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.ndimage import uniform_filter1d

#: largest magnitude of a position or velocity accepted (squares must stay finite in the solve)
MAX_MAGNITUDE = 1e100


def _refuse_kind(kind: str, what: str) -> None:
    """A TypeError for arrays that are not real numbers: complex, boolean (True/False are no
    positions: a mask or a flag column passed by mistake), strings, dates."""
    if kind == "c":
        raise TypeError(f"{what}: complex values; demonstrations are real (give the real part "
                        "explicitly if that is what you mean)")
    if kind == "b":
        raise TypeError(f"{what}: boolean values (True/False) are not positions or velocities; "
                        "give numbers (convert with .astype(float) if that is what you mean)")
    if kind in "USMm":
        raise TypeError(f"{what}: not a numeric array (dtype kind {kind!r}); give numbers")


def _as_demo_list(arrays, what: str) -> list[np.ndarray]:
    if isinstance(arrays, np.ndarray):
        if arrays.ndim == 2:
            arrays = [arrays]
        elif arrays.ndim == 3:
            arrays = list(arrays)
        else:
            raise ValueError(
                f"{what}: expected a list of arrays of shape (T_n, d), a (T, d) array or an "
                f"(N, T, d) array; got an array of shape {arrays.shape}"
            )
    if not isinstance(arrays, Sequence) or isinstance(arrays, (str, bytes)):
        raise TypeError(f"{what}: expected a list of arrays of shape (T_n, d), got {type(arrays)}")
    if len(arrays) == 0:
        raise ValueError(f"{what}: the set of demonstrations is empty; give at least one")
    out = []
    for n, a in enumerate(arrays):
        try:
            kind = np.asarray(a).dtype.kind
        except (TypeError, ValueError):  # ragged: the conversion below says so
            kind = "O"
        _refuse_kind(kind, f"{what}[{n}]")
        try:
            a = np.asarray(a, dtype=float)
        except (TypeError, ValueError) as exc:
            raise TypeError(f"{what}[{n}]: not a numeric array ({exc})") from None
        if a.ndim == 1:
            a = a[:, None]
        if a.ndim != 2 or a.shape[1] == 0:
            raise ValueError(f"{what}[{n}]: expected shape (T_n, d) with d >= 1, got {a.shape}")
        if not np.all(np.isfinite(a)):
            bad = int(np.argwhere(~np.isfinite(a))[0, 0])
            raise ValueError(
                f"{what}[{n}]: contains NaN or infinite values (first at sample {bad}); "
                "remove or interpolate those samples"
            )
        big = float(np.abs(a).max()) if a.size else 0.0
        if big > MAX_MAGNITUDE:
            raise ValueError(
                f"{what}[{n}]: values up to {big:.3g} are too large to learn from (their squares "
                f"overflow); rescale the data, e.g. to metres, below {MAX_MAGNITUDE:.0e}"
            )
        out.append(a)
    return out


def _check_positions(pos: list[np.ndarray]) -> list[np.ndarray]:
    d = pos[0].shape[1]
    for n, p in enumerate(pos):
        if p.shape[1] != d:
            raise ValueError(
                f"positions[{n}] has {p.shape[1]} dimensions but positions[0] has {d}; "
                "all demonstrations must have the same dimension"
            )
        if p.shape[0] < 2:
            raise ValueError(
                f"positions[{n}] has {p.shape[0]} sample(s); a demonstration needs at least 2"
            )
    return pos


def _check_velocities(vel: list[np.ndarray], pos: list[np.ndarray]) -> list[np.ndarray]:
    if len(vel) != len(pos):
        raise ValueError(
            f"{len(vel)} velocity arrays for {len(pos)} demonstrations; give one per demo"
        )
    for n, (p, v) in enumerate(zip(pos, vel)):
        if v.shape != p.shape:
            raise ValueError(f"velocities[{n}] has shape {v.shape} but positions[{n}] has {p.shape}")
    return vel


def _finite_differences(pos: list[np.ndarray], dt: float | None, times) -> list[np.ndarray]:
    """Velocities by second-order finite differences from time stamps or a time step."""
    if times is not None:
        tl = _as_demo_list(times, "times")
        vel = []
        for n, (p, t) in enumerate(zip(pos, tl)):
            t = t.ravel()
            if t.shape[0] != p.shape[0]:
                raise ValueError(f"times[{n}] has {t.shape[0]} stamps for {p.shape[0]} positions")
            if np.any(np.diff(t) <= 0):
                raise ValueError(f"times[{n}] must be strictly increasing")
            vel.append(np.gradient(p, t, axis=0))
        if len(tl) != len(pos):
            raise ValueError(f"{len(tl)} time arrays for {len(pos)} demonstrations")
        return vel
    if dt is not None:
        return [np.gradient(p, dt, axis=0) for p in pos]
    raise ValueError(
        "velocities are not given: pass velocities=, dt= (time step) or times= "
        "(time stamps) so they can be derived by finite differences"
    )


def _trim_standstill(pos, vel, trim_speed) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Drop leading and trailing samples slower than the threshold (SEDS's ``tol_cutting``)."""
    for n, v in enumerate(vel):
        if not np.all(np.isfinite(v)) or float(np.abs(v).max()) > MAX_MAGNITUDE:
            raise ValueError(
                f"velocities[{n}]: NaN, infinite or above {MAX_MAGNITUDE:.0e} (from finite "
                "differences of positions too large or a time step too small); rescale the data"
            )
    speeds = [np.linalg.norm(v, axis=1) for v in vel]
    vmax = max(float(s.max()) for s in speeds)
    if not vmax > 0.0:
        raise ValueError(
            "the demonstrations never move (all velocities are zero); there is no motion to learn"
        )
    thr = 1e-3 * vmax if trim_speed is None else float(trim_speed)
    if not np.isfinite(thr) or thr < 0:
        raise ValueError(f"trim_speed must be a finite number >= 0, got {trim_speed}")
    tp, tv = [], []
    for n, (p, v, s) in enumerate(zip(pos, vel, speeds)):
        moving = np.flatnonzero(s > thr)
        if moving.size == 0:
            raise ValueError(
                f"demonstration {n} never moves faster than {thr:.3g} (trim_speed); "
                "remove it or lower trim_speed"
            )
        lo, hi = moving[0], min(moving[-1] + 1, len(p) - 1)
        if hi - lo + 1 < 2:
            raise ValueError(
                f"demonstration {n} keeps fewer than 2 samples after trimming standstill"
            )
        tp.append(p[lo : hi + 1].copy())
        tv.append(v[lo : hi + 1].copy())
    return tp, tv


def _target_and_shifts(tp: list[np.ndarray], target, shift_each: bool):
    """The attractor (given, or the mean end point) and the shift of each demonstration."""
    d = tp[0].shape[1]
    if target is not None:
        tgt = np.asarray(target, dtype=float).ravel()
        if tgt.shape != (d,) or not np.all(np.isfinite(tgt)):
            raise ValueError(f"target must be a finite array of shape ({d},), got {target!r}")
        return tgt, [tgt for _ in tp]
    tgt = np.mean([p[-1] for p in tp], axis=0)
    return tgt, [p[-1] if shift_each else tgt for p in tp]


class Demonstrations:
    """A set of N demonstrations of a d-dimensional motion, preprocessed as SEDS does.

    Parameters
    ----------
    positions : list of array, each shape (T_n, d)
        Positions of each demonstration, in time order (T_n may differ between demonstrations).
        An (N, T, d) array is accepted too.
    velocities : list of array, each shape (T_n, d), optional
        Velocities; derived by finite differences from ``dt`` or ``times`` when not given.
    dt : float, optional
        Constant time step [s] between samples.
    times : list of array, each shape (T_n,), optional
        Time stamps [s] of each sample (strictly increasing).
    target : array, shape (d,), optional
        The attractor x*. Default: the mean of the demonstrations' end points.
    smoothing : int, default 0
        Width (samples) of a centred moving average applied to the positions before
        differentiation; 0 or 1 for none. Ignored when velocities are given.
    trim_speed : float, optional
        Leading and trailing samples slower than this are trimmed (SEDS's ``tol_cutting``).
        Default: 1e-3 times the fastest speed in the set. Use 0 to keep every sample.
    shift_each : bool, default True
        When ``target`` is not given, shift each demonstration by its own end point so that all
        end exactly at the attractor (as SEDS does). With False, all are shifted by x* only.

    Attributes
    ----------
    positions : list of array, shape (T_n, d)
        Trimmed positions in the caller's coordinates.
    velocities : list of array, shape (T_n, d)
    target : array, shape (d,)
    shifted_positions : list of array, shape (T_n, d)
        Positions in the attractor frame (x* at the origin) used for learning.
    """

    def __init__(
        self,
        positions,
        velocities=None,
        dt: float | None = None,
        times=None,
        target=None,
        smoothing: int = 0,
        trim_speed: float | None = None,
        shift_each: bool = True,
    ) -> None:
        pos = _check_positions(_as_demo_list(positions, "positions"))
        shortest = min(len(p) for p in pos)
        if (isinstance(smoothing, bool) or not isinstance(smoothing, int | np.integer)
                or not 0 <= int(smoothing) <= shortest):
            raise ValueError(f"smoothing must be a whole number of samples in 0..{shortest} (the "
                             f"shortest demonstration's length; 0 or 1: none), got {smoothing!r}")
        self.dt: float | None = None
        if dt is not None and (velocities is not None or times is None):
            self.dt = self._check_dt(dt)
        if velocities is not None:
            vel = _check_velocities(_as_demo_list(velocities, "velocities"), pos)
        else:
            if smoothing and int(smoothing) > 1:
                pos = [uniform_filter1d(p, size=int(smoothing), axis=0, mode="nearest") for p in pos]
            vel = _finite_differences(pos, self.dt, times)
        tp, tv = _trim_standstill(pos, vel, trim_speed)
        tgt, shifts = _target_and_shifts(tp, target, shift_each)
        self._set(tp, tv, tgt, shifts)

    @staticmethod
    def _check_dt(dt) -> float:
        a = np.asarray(dt)
        if a.shape != () or a.dtype.kind not in "iuf":  # not True (a flag), not "0.1"
            raise TypeError(f"dt must be a number: a positive finite time step [s], got {dt!r}")
        dt = float(a)
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive finite time step, got {dt}")
        return dt

    def _set(self, positions, velocities, target, shifts) -> None:
        self.positions = positions
        self.velocities = velocities
        self.target = np.asarray(target, dtype=float)
        self._shifts = [np.asarray(s, dtype=float) for s in shifts]
        self.shifted_positions = [p - s for p, s in zip(positions, self._shifts)]

    @classmethod
    def _from_processed(cls, positions, velocities, target, shifts, dt) -> Demonstrations:
        obj = cls.__new__(cls)
        obj.dt = dt
        obj._set(positions, velocities, target, shifts)
        return obj

    @classmethod
    def from_samples(cls, X, Xdot, target=None) -> Demonstrations:
        """Samples without time order (e.g. a cross-validation fold) as one set, unprocessed.

        Parameters
        ----------
        X : array, shape (n_samples, d)
            Positions.
        Xdot : array, shape (n_samples, d)
            Velocities at those positions.
        target : array, shape (d,), optional
            The attractor (default: the origin).

        Returns
        -------
        Demonstrations
            One "demonstration" holding the samples as given (no smoothing, trimming or
            shifting). Its samples carry no phase, so the direction objective weights them
            uniformly (Eq. 11 needs the time order within each demonstration).
        """
        for name, a in (("X", X), ("Xdot", Xdot)):
            try:
                kind = np.asarray(a).dtype.kind
            except (TypeError, ValueError):  # ragged: the conversion below says so
                kind = "O"
            _refuse_kind(kind, name)
        X = np.asarray(X, dtype=float)
        V = np.asarray(Xdot, dtype=float)
        if X.ndim != 2 or X.shape[0] < 2 or X.shape[1] < 1:
            raise ValueError(f"X must have shape (n_samples >= 2, d), got {X.shape}")
        if V.shape != X.shape:
            raise ValueError(f"the velocities have shape {V.shape}, the positions {X.shape}; "
                             "give one velocity per position")
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(V))):
            raise ValueError("the samples contain NaN or infinite values")
        d = X.shape[1]
        tgt = np.zeros(d) if target is None else np.asarray(target, dtype=float).ravel()
        if tgt.shape != (d,) or not np.all(np.isfinite(tgt)):
            raise ValueError(f"target must be a finite array of shape ({d},), got {target!r}")
        obj = cls._from_processed([X.copy()], [V.copy()], tgt, [tgt], None)
        obj._phase = np.zeros(len(X))
        return obj

    # ------------------------------------------------------------------ views
    @property
    def time_ordered(self) -> bool:
        """Whether the samples are trajectories in time order (False for
        :meth:`from_samples`, whose samples carry no phase and no time step)."""
        return getattr(self, "_phase", None) is None

    @property
    def n_demos(self) -> int:
        """Number of demonstrations N."""
        return len(self.positions)

    @property
    def n_dims(self) -> int:
        """Dimension d of the state."""
        return int(self.positions[0].shape[1])

    @property
    def n_samples(self) -> int:
        """Total number of samples over all demonstrations."""
        return int(sum(len(p) for p in self.positions))

    def stacked(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """All samples stacked, in the attractor frame.

        Returns
        -------
        X : array, shape (n_samples, d)
            Positions relative to the target (x - x*).
        Xdot : array, shape (n_samples, d)
        phase : array, shape (n_samples,)
            t / T^n in [0, 1] within each demonstration (the weights of Eq. 11 use it).
        demo : array of int, shape (n_samples,)
        """
        X = np.concatenate(self.shifted_positions)
        Xd = np.concatenate(self.velocities)
        phase = getattr(self, "_phase", None)
        if phase is None or len(phase) != len(X):
            phase = np.concatenate([np.linspace(0.0, 1.0, len(p)) for p in self.positions])
        demo = np.concatenate([np.full(len(p), n) for n, p in enumerate(self.positions)])
        return X, Xd, phase, demo

    def estimated_dt(self) -> float:
        """The time step between samples: ``dt`` if known, else the median of segment length
        over mean speed (works after :meth:`subsample`, which forgets ``dt``)."""
        if self.dt:
            return float(self.dt)
        dts = []
        for p, v in zip(self.positions, self.velocities):
            seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
            spd = 0.5 * (np.linalg.norm(v[1:], axis=1) + np.linalg.norm(v[:-1], axis=1))
            ok = spd > 1e-12
            if ok.any():
                dts.append(np.median(seg[ok] / spd[ok]))
        if not dts:
            raise ValueError("cannot estimate a time step: the demonstrations do not move")
        return float(np.median(dts))

    def subsample(self, n_per_demo: int) -> Demonstrations:
        """A new set with about ``n_per_demo`` evenly spaced samples per demonstration.

        The first and last samples are always kept. Demonstrations shorter than that are kept whole.
        """
        n_per_demo = int(n_per_demo)
        if n_per_demo < 2:
            raise ValueError(f"n_per_demo must be at least 2, got {n_per_demo}")
        pos, vel = [], []
        for p, v in zip(self.positions, self.velocities):
            idx = np.unique(np.round(np.linspace(0, len(p) - 1, n_per_demo)).astype(int))
            pos.append(p[idx])
            vel.append(v[idx])
        dt = None
        return Demonstrations._from_processed(pos, vel, self.target, self._shifts, dt)

    def select(self, indices) -> Demonstrations:
        """A new set holding only the demonstrations at ``indices`` (same target)."""
        idx = [int(i) for i in np.atleast_1d(indices)]
        if not idx:
            raise ValueError("select: no demonstration indices given")
        for i in idx:
            if not 0 <= i < self.n_demos:
                raise ValueError(f"select: index {i} out of range for {self.n_demos} demonstrations")
        return Demonstrations._from_processed(
            [self.positions[i] for i in idx],
            [self.velocities[i] for i in idx],
            self.target,
            [self._shifts[i] for i in idx],
            self.dt,
        )

    def __repr__(self) -> str:
        lens = [len(p) for p in self.positions]
        return f"Demonstrations(n_demos={self.n_demos}, n_dims={self.n_dims}, samples={lens})"
