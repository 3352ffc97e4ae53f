"""The sinking set around the teacher's shots, and noisy examples drawn from it (Eq. 15-16).

The paper treats its training examples as noisy observations of a function g(s) of the
situation, (alpha^m, kappa^m) = (g_alpha(s^m) + eps_alpha, g_kappa(s^m) + eps_kappa) (Eq. 15),
the noise standing for "the small redundancies caused by the hole being larger than the ball"
(its footnote 6): any hit inside the set of parameters that sink the ball is a good example.
The teacher of :mod:`seds_casadi.minigolf.teacher` gives the middle of that set; here the set
itself is measured around each of its shots and examples are drawn from it.

For each taught situation the **sinking set** is the successful angle interval (direct shots,
as the teacher's) at a few gains around the taught one, found on a fine angle scan of the
field's ball model:

* fixed speed (the paper's rough flat and double hill: "the speed was fixed"): the taught gain
  only, so eps_kappa = 0;
* otherwise (arctan, minimal speed): ``n_gains`` gains from kappa / (1 + margin) to
  kappa (1 + margin) with the teacher's own ``speed_margin`` (its hits are that fraction
  faster than the slowest that sinks over 1 deg; the lowest gain is that slowest one).

A draw (:meth:`SinkingSet.draw`) takes, per situation, a gain uniformly over the gains where
the set is not empty (the interval's edges interpolated linearly between the measured gains)
and an angle uniformly over the interval at that gain: the teacher's examples as any
successful hit, not the centre of the range.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .hitting_data import HittingDataset
from .teacher import Teacher, true_runs

__all__ = ["SinkingSet", "sinking_set"]


@dataclass(frozen=True)
class SinkingSet:
    """The successful angle intervals around a data set's shots (module docstring).

    Attributes
    ----------
    gains : array, shape (n, n_gains)
        Speed gains kappa at which the interval was measured, increasing per row.
    lower, upper : array, shape (n, n_gains)
        Edges of the successful angle interval [deg] at each gain (NaN: none sinks there).
    fixed_speed : bool
        The data set's speed is fixed (one gain; the learners predict the angle only).
    """

    gains: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    fixed_speed: bool

    def __post_init__(self) -> None:
        shapes = {np.shape(self.gains), np.shape(self.lower), np.shape(self.upper)}
        if len(shapes) != 1 or len(np.shape(self.gains)) != 2:
            raise ValueError(f"gains, lower and upper must have one shape (n, n_gains), got "
                             f"{sorted(shapes)}")
        ok = np.isfinite(self.lower) & np.isfinite(self.upper)
        if not ok.any(axis=1).all():
            raise ValueError("every situation needs a successful interval at one gain at "
                             "least")
        if np.any(self.upper[ok] < self.lower[ok]):
            raise ValueError("an interval's upper edge is below its lower edge")

    def __len__(self) -> int:
        return len(self.gains)

    @property
    def widths(self) -> np.ndarray:
        """Width [deg] of each interval, shape (n, n_gains) (NaN where none sinks)."""
        return self.upper - self.lower

    def draw(self, rng: np.random.Generator, spread: float = 1.0) -> np.ndarray:
        """One noisy example per situation (Eq. 15): (alpha [deg], kappa), shape (n, 2).

        The gain is uniform over the span of gains whose interval is not empty (the taught
        gain with a fixed speed), the angle uniform over the interval at that gain; with
        ``spread`` < 1 over the middle ``spread`` of each (0: the middles, no noise).
        """
        if not (np.isfinite(spread) and 0 <= spread <= 1):
            raise ValueError(f"spread must be in [0, 1], got {spread}")
        n, m = self.gains.shape
        out = np.empty((n, 2))
        u = 0.5 + spread * (rng.random((n, 2)) - 0.5)
        for i in range(n):
            ok = np.flatnonzero(np.isfinite(self.lower[i]) & np.isfinite(self.upper[i]))
            g, lo, hi = self.gains[i, ok], self.lower[i, ok], self.upper[i, ok]
            if len(ok) == 1 or self.fixed_speed:
                j = ok[len(ok) // 2] if self.fixed_speed else ok[0]
                kappa, a0, a1 = self.gains[i, j], self.lower[i, j], self.upper[i, j]
            else:
                kappa = g[0] + u[i, 1] * (g[-1] - g[0])
                a0, a1 = np.interp(kappa, g, lo), np.interp(kappa, g, hi)
            out[i] = a0 + u[i, 0] * (a1 - a0), kappa
        return out


def sinking_set(teacher: Teacher, dataset: HittingDataset, n_gains: int = 5,
                step_deg: float = 0.02, half_span_deg: float = 15.0) -> SinkingSet:
    """Measure the sinking set around each shot of a data set (module docstring).

    Parameters
    ----------
    teacher : Teacher
        The teacher that collected ``dataset`` (its field, stroke, ball model and banks).
    dataset : HittingDataset
    n_gains : int, default 5
        Gains measured per situation without a fixed speed (odd: the taught one among them).
    step_deg : float, default 0.02
        Angle step of the scan [deg]: the resolution of the intervals' edges.
    half_span_deg : float, default 15
        The scan covers the taught angle +- this [deg].

    Returns
    -------
    SinkingSet
    """
    if int(n_gains) < 1:
        raise ValueError(f"n_gains must be at least 1, got {n_gains}")
    if not (np.isfinite(step_deg) and 0 < step_deg < half_span_deg):
        raise ValueError(f"step_deg must be positive and below half_span_deg, got {step_deg}")
    fixed = dataset.strategy == "fixed_speed"
    margin = teacher.speed_margin
    levels = (np.zeros(1) if fixed or int(n_gains) == 1
              else np.linspace(-1.0, 1.0, int(n_gains)))
    offsets = np.deg2rad(np.arange(-half_span_deg, half_span_deg + 0.5 * step_deg, step_deg))
    n = len(dataset)
    gains = np.empty((n, len(levels)))
    lower = np.full_like(gains, np.nan)
    upper = np.full_like(gains, np.nan)
    for i in range(n):
        a, k = dataset.alpha[i], dataset.kappa[i]
        gains[i] = k * (1 + margin) ** levels
        scan = a + offsets
        rows = teacher.map(dataset.ball[i], dataset.hole[i], scan, gains[i])
        for j, row in enumerate(rows):
            runs = true_runs(row)
            if not runs:
                continue
            # the run holding the taught angle, else the nearest (the strategy's band)
            dist = [0.0 if scan[s] <= a <= scan[e - 1] else min(abs(scan[s] - a),
                                                                 abs(scan[e - 1] - a))
                    for s, e in runs]
            s, e = runs[int(np.argmin(dist))]
            lower[i, j], upper[i, j] = np.rad2deg(scan[s]), np.rad2deg(scan[e - 1])
    return SinkingSet(gains, lower, upper, fixed)
