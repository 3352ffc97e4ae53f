"""How good a fitted model is on demonstrations: the fit report (issue 29).

:func:`fit_report` (also ``SEDS.report(demos)`` and ``seds-casadi fit``) reproduces each
demonstration from its start with the fitted model and says, per demonstration, in words a user
can act on:

* whether the reproduction **reaches the target** (within :data:`REACH_FRACTION` of the data's
  extent, within :data:`DURATION_FACTOR` times the demonstration's duration),
* its **duration** and **peak speed** against the demonstration's,
* the three metrics of the LASA evaluation (:mod:`seds_casadi.core.metrics`): velocity **RMSE**
  and **e_dot** on the demonstration's samples, and the **DTW** distance between the
  reproduction and the demonstration.

It warns about what a user would otherwise have to find out by hand: demonstrations whose end
points lie apart (each is shifted onto its own end point before the fit, SEDS's preprocessing:
:func:`end_offsets`), reproductions whose peak speed exceeds the demonstration's by more than
:data:`OVERSHOOT` - 1 or stays below :data:`UNDERSHOOT` of it, a reproduction that does not
reach the target, and a K chosen at the edge of the range searched
(``SEDS(n_components="auto")``).
"""

from __future__ import annotations

import json
import warnings
from dataclasses import asdict, dataclass, field

import numpy as np

from .demonstrations import Demonstrations
from .metrics import dtw_distance, pointwise_direction_error, velocity_rmse
from .search import reproduction_substeps

__all__ = ["DemoReport", "FitReport", "fit_report", "end_offsets", "warn_ends_apart",
           "REACH_FRACTION", "DURATION_FACTOR", "OVERSHOOT", "UNDERSHOOT", "ENDS_APART",
           "SPEED_BAND"]

#: a reproduction reaches the target when it comes within this fraction of the data's extent
REACH_FRACTION = 0.01
#: ... within this many times the demonstration's duration
DURATION_FACTOR = 3.0
#: a reproduction whose peak speed is above this times the demonstration's is warned about
OVERSHOOT = 1.5
#: ... and one whose peak speed is below this times the demonstration's (the mirror of
#: OVERSHOOT: 1 / 1.5); a motion that slow arrives late, and the hitting motion's strength
#: factor or a larger K may serve better
UNDERSHOOT = 1.0 / OVERSHOOT
#: the band of peak-speed ratios the report calls "as demonstrated"
SPEED_BAND = (0.8, 1.25)
#: demonstrations whose end points lie farther than this fraction of the extent from the target
#: are warned about (before the fit, and in the report)
ENDS_APART = 0.05


def end_offsets(demos: Demonstrations) -> tuple[np.ndarray, float]:
    """How far each demonstration's last recorded point lies from where the others end.

    Returns
    -------
    offsets : array, shape (n_demos,)
        ||x_T^n - m|| in the data's units (the positions as recorded, after trimming), m the
        target when it was given, else the component-wise median of the end points (the
        target, their mean, moves with an outlier; the median does not).
    extent : float
        The largest range of the recorded positions over the dimensions.
    """
    ends = np.stack([np.asarray(p)[-1] for p in demos.positions])
    allpos = np.concatenate(demos.positions)
    extent = max(float(np.max(np.ptp(allpos, axis=0))), 1e-300)
    # the demonstrations were shifted each onto its own end point when the target is the mean
    # of the end points (Demonstrations' default); a given target shows as zero shifts
    shifts = np.stack([np.asarray(p)[-1] - (q[-1] + demos.target)
                       for p, q in zip(demos.positions, demos.shifted_positions, strict=True)])
    ref = demos.target if np.allclose(shifts, 0) else np.median(ends, axis=0)
    return np.linalg.norm(ends - ref, axis=1), extent


def _ends_apart_messages(demos: Demonstrations, threshold: float = ENDS_APART) -> list[str]:
    off, extent = end_offsets(demos)
    return [f"demonstration {n + 1} ends {o:.3g} from where the others end "
            f"({100 * o / extent:.0f} % of the data's extent): each demonstration is shifted "
            "onto its own end point before the fit "
            "(SEDS's preprocessing), so this one is learned as if it ended at the target; check "
            "the recording, or give the target (Demonstrations(..., target=...))"
            for n, o in enumerate(off) if o > threshold * extent]


def warn_ends_apart(demos: Demonstrations, threshold: float = ENDS_APART,
                    stacklevel: int = 1) -> list[str]:
    """A ``UserWarning`` for each demonstration ending farther than ``threshold`` times the
    extent from the target (``SEDS.fit`` calls it before fitting); returns the messages."""
    msgs = _ends_apart_messages(demos, threshold)
    for m in msgs:
        warnings.warn(m, UserWarning, stacklevel=stacklevel + 1)
    return msgs


@dataclass(frozen=True)
class DemoReport:
    """One demonstration's line of a :class:`FitReport` (durations in seconds, speeds and RMSE
    in the data's units per second, DTW in the data's units)."""

    demo: int
    reached: bool
    final_distance: float
    duration_demo: float
    duration_reproduction: float
    peak_speed_demo: float
    peak_speed_reproduction: float
    rmse: float
    e_dot: float
    dtw: float
    end_offset: float

    @property
    def speed_ratio(self) -> float:
        """Peak speed of the reproduction over the demonstration's."""
        return self.peak_speed_reproduction / max(self.peak_speed_demo, 1e-300)

    @property
    def speed_as_demonstrated(self) -> bool:
        """The peak-speed ratio is within :data:`SPEED_BAND`."""
        return SPEED_BAND[0] <= self.speed_ratio <= SPEED_BAND[1]


@dataclass(frozen=True)
class FitReport:
    """The fit report: one :class:`DemoReport` per demonstration, the warnings, the choice the
    learner made (``fit_info["choice"]``) and the reproductions.

    ``str(report)`` is the table printed by ``seds-casadi fit``; :meth:`to_dict` and
    :meth:`save` give it as JSON.
    """

    rows: tuple[DemoReport, ...]
    warnings: tuple[str, ...]
    choice: dict = field(default_factory=dict)
    reach_tolerance: float = 0.0
    #: the reproductions, each shape (T_n, d), sampled at the data's step
    paths: tuple = field(default=(), repr=False)
    #: the reproductions' speeds at every step of their rollouts (``speed_dt`` apart: the
    #: peaks the table reports are among them; ``paths`` keep the data's step)
    speeds: tuple = field(default=(), repr=False)
    dt: float = 0.0
    speed_dt: float = 0.0

    @property
    def all_reached(self) -> bool:
        """Every reproduction reached the target."""
        return all(r.reached for r in self.rows)

    def to_dict(self) -> dict:
        """The report as plain JSON types (no paths)."""
        return {"rows": [dict(asdict(r), speed_ratio=r.speed_ratio) for r in self.rows],
                "warnings": list(self.warnings), "choice": _plain(self.choice),
                "reach_tolerance": self.reach_tolerance, "all_reached": self.all_reached}

    def save(self, path: str) -> None:
        """Write :meth:`to_dict` as JSON."""
        with open(path, "w", encoding="utf-8") as f:
            json.dump(self.to_dict(), f, indent=1)

    def __str__(self) -> str:
        head = (f"{'demo':>4} {'reaches':>8} {'duration s':>16} {'peak speed':>22} "
                f"{'RMSE':>9} {'e_dot':>6} {'DTW':>9}")
        sub = f"{'':>4} {'target':>8} {'repro / demo':>16} {'repro / demo (ratio)':>22}"
        lines = [head, sub]
        for r in self.rows:
            mark = "" if r.speed_as_demonstrated else " !"
            lines.append(
                f"{r.demo:>4} {'yes' if r.reached else 'NO':>8} "
                f"{r.duration_reproduction:>7.3g} / {r.duration_demo:<6.3g} "
                f"{r.peak_speed_reproduction:>7.3g} / {r.peak_speed_demo:<6.3g}"
                f"({r.speed_ratio:.2f}){mark:2}"
                f"{r.rmse:>9.3g} {r.e_dot:>6.3f} {r.dtw:>9.4g}")
        n = len(self.rows)
        ok_speed = sum(r.speed_as_demonstrated for r in self.rows)
        lines.append(f"{sum(r.reached for r in self.rows)}/{n} reproductions reach the target "
                     f"(within {self.reach_tolerance:.3g}); {ok_speed}/{n} peak speeds within "
                     f"{SPEED_BAND[0]:g}-{SPEED_BAND[1]:g} x the demonstration's")
        ch = self.choice or {}
        if "n_components" in ch and "candidates" in ch:
            lines.append(f"K = {ch['n_components']} chosen among {sorted(ch['candidates'])}: "
                         f"{ch.get('rule', '')}")
            c = (ch["candidates"].get(ch["n_components"]) or {}).get("time_scale")
            if c:
                lines.append(f"its velocities are scaled by {c:.3g}: its reproductions peaked "
                             f"{1 / c:.3g}x too fast, each by about as much (same paths, same "
                             "certificate)")
        for name, why in (ch.get("settings") or {}).items():
            if why != "given":
                lines.append(f"{name}: {why}")
        lines += [f"warning: {w}" for w in self.warnings]
        return "\n".join(lines)


def fit_report(model, demos: Demonstrations, reach_fraction: float = REACH_FRACTION,
               duration_factor: float = DURATION_FACTOR, overshoot: float = OVERSHOOT,
               undershoot: float = UNDERSHOOT) -> FitReport:
    """Reproduce every demonstration from its start and compare (see the module docstring).

    Parameters
    ----------
    model : StableDS or fitted SEDS
        With ``predict``, ``rollout``, ``target`` and ``stiffness``.
    demos : Demonstrations
        In time order (the demonstrations the model was fitted to, or others with its target).
    reach_fraction : float, default 0.01
        "Reaches the target": within this fraction of the data's extent.
    duration_factor : float, default 3
        A reproduction is given this many times the longest demonstration's duration.
    overshoot : float, default 1.5
        Warn when a reproduction's peak speed exceeds this times its demonstration's.
    undershoot : float, default 1 / 1.5
        Warn when a reproduction's peak speed is below this times its demonstration's.

    Returns
    -------
    FitReport
    """
    if not (np.isfinite(overshoot) and overshoot > 1.0 and 0.0 < undershoot < 1.0):
        raise ValueError(f"overshoot must be above 1 and undershoot within (0, 1), got "
                         f"{overshoot!r} and {undershoot!r}")
    model = getattr(model, "model_", model)
    if not isinstance(demos, Demonstrations):
        raise TypeError(f"fit_report takes Demonstrations, got {type(demos).__name__}")
    if not demos.time_ordered:
        raise ValueError("the report reproduces each demonstration from its start; these "
                         "samples have no time order")
    if np.asarray(model.target).shape != demos.target.shape:
        raise ValueError(f"the model is {np.asarray(model.target).size}-D and the "
                         f"demonstrations {demos.n_dims}-D")
    dt = float(demos.estimated_dt())
    pos = [np.asarray(p) + demos.target for p in demos.shifted_positions]
    off, extent = end_offsets(demos)
    tol = reach_fraction * extent
    sub = reproduction_substeps(model, dt)  # RK4 at h * stiffness <= 0.25, as the choice of K
    h = dt / sub
    longest = max(len(p) for p in pos) * dt
    steps = int(np.ceil(duration_factor * longest / h)) + 1
    starts = np.stack([p[0] for p in pos])
    paths, info = model.rollout(starts, dt=h, max_steps=steps, tol=tol, method="rk4",
                                return_info=True, warn=False)
    paths = [np.atleast_2d(p) for p in (paths if isinstance(paths, list) else [paths])]
    rows, msgs, out_paths, out_speeds = [], [], [], []
    for n, (p, v) in enumerate(zip(pos, demos.velocities, strict=True)):
        path = paths[n][::sub]
        if len(paths[n]) and (len(paths[n]) - 1) % sub:
            path = np.vstack([path, paths[n][-1]])
        speed_r = np.linalg.norm(model.predict(paths[n]), axis=1)
        speed_d = np.linalg.norm(v, axis=1)
        F = np.asarray(model.predict(p), dtype=float)
        reached = bool(info["converged"][n])
        row = DemoReport(
            demo=n + 1, reached=reached, final_distance=float(info["final_distance"][n]),
            duration_demo=(len(p) - 1) * dt,
            duration_reproduction=(len(paths[n]) - 1) * h,
            peak_speed_demo=float(speed_d.max()), peak_speed_reproduction=float(speed_r.max()),
            rmse=velocity_rmse(F, v),
            e_dot=float(np.mean(pointwise_direction_error(F, v, min_norm_product=0.0))),
            dtw=dtw_distance(path, p), end_offset=float(off[n]))
        rows.append(row)
        out_paths.append(path)
        out_speeds.append(speed_r)
        if not reached:
            msgs.append(f"the reproduction of demonstration {n + 1} does not reach the target "
                        f"within {duration_factor:g} x the longest demonstration's duration "
                        f"(it ends {row.final_distance:.3g} away, tolerance {tol:.3g})")
        if row.speed_ratio > overshoot:
            msgs.append(f"the reproduction of demonstration {n + 1} peaks at {row.speed_ratio:.2f} "
                        f"x the demonstration's speed (more than {overshoot:g} x)")
        elif row.speed_ratio < undershoot:
            msgs.append(f"the reproduction of demonstration {n + 1} peaks at only "
                        f"{row.speed_ratio:.2f} x the demonstration's speed (less than "
                        f"{undershoot:.2g} x): it moves slower than demonstrated")
    msgs = _ends_apart_messages(demos) + msgs
    choice = dict(getattr(model, "fit_info", {}).get("choice", {}) or {})
    if choice.get("at_edge"):
        lo, hi = choice["range"]
        tried = sorted(int(k) for k in choice.get("candidates", {})) or [lo, hi]
        msgs.append(f"K = {choice['n_components']} is at the edge of the range searched "
                    f"({lo}-{hi}; tried {', '.join(map(str, tried))}): a K outside it may be "
                    f"better; pass n_components=range({max(1, lo - 2)}, {hi + 3}) to search "
                    "every K of a wider one")
    return FitReport(tuple(rows), tuple(msgs), choice, tol, tuple(out_paths), tuple(out_speeds),
                     dt, h)


def _plain(v):
    if isinstance(v, dict):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_plain(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, float) and not np.isfinite(v):
        return None
    return v
