"""Swings of the hitting motion integrated in time: hit detection, the hitting velocity a
tracker measures, perturbations during a swing, rollouts and vectorised probes.

* **Hit detection** (:func:`plane_crossing`, also used by the robot controller): the club hits
  the ball when a step crosses the plane through the ball perpendicular to the commanded hitting
  direction R_alpha psi*, within ``hit_radius`` of the ball's centre.
* **The hitting velocity of a rollout** (:func:`period_mean_velocity`). Eq. 8 is singular at x*:
  a step that starts a fraction of a millimetre before the ball with a micrometre of sideways
  offset is commanded far off psi*, which no club (with inertia) would follow. A rollout
  therefore reports the club's mean velocity over the last control period before it reaches the
  ball (what a tracker at the controller's rate measures); the commanded velocities stay in
  ``velocities``.
* **Perturbations** (:class:`Perturbations`, also used by the robot simulation): changes applied
  on the fly at given times, without re-planning (the paper's Fig. 8).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..codegen import FastEvaluator, batch_evaluate
from ..core.strength import as_points
from ._validation import check_alpha_kappa
from .resting import check_rest_mode, resting_system

if TYPE_CHECKING:  # pragma: no cover
    from .hitting import HittingMotion

__all__ = ["RolloutResult", "Perturbations", "plane_crossing", "period_mean_velocity", "rollout",
           "probe"]


def plane_crossing(before, after, target, direction, hit_radius: float):
    """Whether steps ``before -> after`` cross the plane through ``target`` perpendicular to
    ``direction`` (from behind), within ``hit_radius`` of ``target``: the hit of a swing.

    Parameters
    ----------
    before, after : array, shape (3,) or (n, 3)
        Club positions at the start and end of each step.
    target : array, shape (3,)
        The ball's centre (or the club face's contact point).
    direction : array, shape (3,)
        The commanded hitting direction R_alpha psi*.
    hit_radius : float

    Returns
    -------
    hit : bool or bool array, shape (n,)
    fraction : float or array, shape (n,)
        lambda in [0, 1]: the crossing is at ``before + lambda (after - before)`` (0 without one).
    point : array, shape (3,) or (n, 3)
        That crossing point (``before`` without a crossing).
    """
    s0 = (before - target) @ direction
    s1 = (after - target) @ direction
    crossed = (s0 < 0) & (s1 >= 0)
    if not crossed.any():  # the common case, kept cheap (about 1 us) for the 500 Hz controller
        return crossed, 0.0 * s0, before
    lam = np.where(crossed, -s0 / np.where(crossed, s1 - s0, 1.0), 0.0)
    point = before + lam[..., None] * (after - before)
    hit = crossed & (np.linalg.norm(point - target, axis=-1) <= hit_radius)
    return hit, lam, point


def period_mean_velocity(previous, before, point, fraction, dt: float) -> np.ndarray:
    """The club's mean velocity over the control period ``dt`` that ends at the crossing
    ``point`` = before + fraction (after - before), ``previous`` the position one period before
    ``before`` (the hitting velocity a tracker at the controller's rate measures)."""
    fraction = np.asarray(fraction)[..., None]
    return (point - (previous + fraction * (before - previous))) / dt


class Perturbations:
    """Changes applied during a swing at given times, without re-planning (Fig. 8).

    Parameters
    ----------
    events : sequence of dict, or None
        Each has a finite time ``t`` [s] and any of ``keys`` (e.g. ``ball``, a new position).
    keys : tuple of str
        What an event may change.

    Attributes
    ----------
    applied : list of dict
        Copies of the events handed out by :meth:`due` so far, in time order.
    """

    def __init__(self, events: Sequence[Mapping] | None, keys: tuple[str, ...]) -> None:
        events = list(events or [])
        for e in events:
            if not isinstance(e, Mapping) or "t" not in e:
                raise ValueError(f"each perturbation needs a finite time 't': {e!r}")
            try:
                t = float(e["t"])
            except (TypeError, ValueError):
                t = np.nan
            if not np.isfinite(t):
                raise ValueError(f"each perturbation needs a finite time 't': {e!r}")
            unknown = sorted(set(e) - {"t", *keys})
            if unknown:
                raise ValueError(f"unknown perturbation key(s) {unknown} in {dict(e)!r}; "
                                 f"valid: t, {', '.join(keys)}")
        self._events = sorted(events, key=lambda e: float(e["t"]))
        self._next = 0
        self.applied: list[dict] = []

    def due(self, t: float) -> list[dict]:
        """The events not handed out yet whose time is at most ``t`` (copies, in time order)."""
        ev, out = self._events, []
        while self._next < len(ev) and float(ev[self._next]["t"]) <= t + 1e-12:
            out.append(dict(ev[self._next]))
            self._next += 1
        self.applied.extend(out)
        return out


@dataclass
class RolloutResult:
    """A swing integrated by :meth:`HittingMotion.rollout`.

    Attributes
    ----------
    times : array, shape (T,)
    positions : array, shape (T, 3)
        Club-head positions in the field frame.
    velocities : array, shape (T, 3)
        Commanded velocities.
    balls : array, shape (T, 3)
        Ball position at each step.
    hit : bool
        Whether the club reached the ball (crossed the plane through it, perpendicular to the
        commanded direction, within ``hit_radius``).
    hit_time, hit_position, hit_velocity :
        At the moment of the hit (interpolated to the crossing of the plane through the ball
        perpendicular to the commanded hitting direction); the hitting velocity is the club's
        mean velocity over the last control period ``dt``. None without a hit.
    commanded_direction : array, shape (3,)
        R_alpha psi* for the alpha in force at the hit.
    commanded_speed : float
        kappa v* at the hit.
    """

    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    balls: np.ndarray
    hit: bool
    hit_time: float | None = None
    hit_position: np.ndarray | None = None
    hit_velocity: np.ndarray | None = None
    commanded_direction: np.ndarray | None = None
    commanded_speed: float | None = None
    events: list = field(default_factory=list)

    @property
    def direction_error_deg(self) -> float:
        """Angle [deg] between the hitting velocity and the commanded direction."""
        if not self.hit:
            return float("nan")
        u = self.hit_velocity / np.linalg.norm(self.hit_velocity)
        return float(np.degrees(np.arccos(np.clip(u @ self.commanded_direction, -1, 1))))

    @property
    def speed_error(self) -> float:
        """Relative error of the hitting speed against kappa v*."""
        if not self.hit:
            return float("nan")
        return float(np.linalg.norm(self.hit_velocity) / self.commanded_speed - 1.0)


@dataclass
class _Track:
    """The samples of a rollout as it is integrated."""

    T: list = field(default_factory=list)
    P: list = field(default_factory=list)
    V: list = field(default_factory=list)
    B: list = field(default_factory=list)

    def add(self, t, x, v, b) -> None:
        self.T.append(t)
        self.P.append(x.copy())
        self.V.append(v)
        self.B.append(b.copy())

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        return np.array(self.T), np.array(self.P), np.array(self.V), np.array(self.B)


def rollout(motion: HittingMotion, start, alpha: float = 0.0, kappa: float = 1.0,
            dt: float = 0.002, ball=None, perturb: Sequence[dict] | None = None,
            max_time: float = 5.0, rest_mode: str = "flat", rest_time: float = 0.5,
            params: Callable | None = None, hit_radius: float = 0.02,
            hole=None) -> RolloutResult:
    """Integrate a swing of ``motion`` from ``start`` until the club hits the ball, then rest
    (explicit Euler at ``dt``); the parameters are those of :meth:`HittingMotion.rollout`."""
    x = as_points(start, 3, "start")[0][0].copy()
    alpha, kappa = check_alpha_kappa(alpha, kappa)
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be positive, got {dt}")
    b = np.zeros(3) if ball is None else as_points(ball, 3, "ball")[0][0].copy()
    events = Perturbations(perturb, ("ball", "hole", "alpha", "kappa"))
    hole = None if hole is None else np.asarray(hole, float).copy()
    check_rest_mode(rest_mode)
    if not (np.isfinite(hit_radius) and hit_radius > 0):
        raise ValueError(f"hit_radius must be positive, got {hit_radius}")
    ds = FastEvaluator(motion._function())  # Eq. 14 at one point, without per-call overhead
    track = _Track()
    t, hit = 0.0, None
    for _ in range(int(np.ceil(max_time / dt))):
        for e in events.due(t):
            if "ball" in e:
                b = as_points(e["ball"], 3, "perturbation ball")[0][0].copy()
            if "hole" in e:
                hole = np.asarray(e["hole"], float).copy()
            if "alpha" in e or "kappa" in e:
                alpha, kappa = check_alpha_kappa(e.get("alpha", alpha), e.get("kappa", kappa))
        if params is not None:
            alpha, kappa = check_alpha_kappa(*params(t, b.copy(), hole))
        v = ds(x - b, alpha, kappa)
        track.add(t, x, v, b)
        psi = motion.commanded_direction(alpha)
        x_new = x + dt * v
        hit_now, lam, p_hit = plane_crossing(x, x_new, b, psi, hit_radius)
        if hit_now:
            lam = float(lam)
            v_hit = (period_mean_velocity(track.P[-2], x, p_hit, lam, dt) if len(track.P) >= 2
                     else v.copy())
            hit = (t + lam * dt, p_hit, v_hit, psi, kappa * motion.hitting_speed)
            x, t = p_hit, t + lam * dt
            break
        x, t = x_new, t + dt
    if hit is None:
        return RolloutResult(*track.arrays(), False, events=events.applied)
    t_hit, p_hit, v_hit, psi, spd = hit
    A, rest = resting_system(p_hit, v_hit, motion.rest_length, rest_mode)
    for _ in range(int(np.ceil(rest_time / dt)) + 1):
        v = (x - rest) @ A.T
        track.add(t, x, v, b)
        x, t = x + dt * v, t + dt
    return RolloutResult(*track.arrays(), True, t_hit, p_hit, v_hit, psi, spd,
                         events=events.applied)


def probe(motion: HittingMotion, starts, alpha: float = 0.0, kappa: float = 1.0,
          dt: float = 0.002, max_time: float = 5.0, hit_radius: float = 0.02
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Swings of ``motion`` from many starts at once, the ball fixed at the origin; the
    parameters and results are those of :meth:`HittingMotion.probe`."""
    alpha, kappa = check_alpha_kappa(alpha, kappa)
    X, _ = as_points(starts, 3, "starts")
    n = len(X)
    psi = motion.commanded_direction(alpha)
    f, ball = motion._function(), np.zeros(3)
    x, prev = X.copy(), X.copy()
    hit = np.zeros(n, bool)
    vel = np.full((n, 3), np.nan)
    active = np.ones(n, bool)
    for step in range(int(np.ceil(max_time / dt))):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        xa = x[idx]
        v = batch_evaluate(f, xa.T, alpha, kappa)[0]
        xn = xa + dt * v
        done, lam, ph = plane_crossing(xa, xn, ball, psi, hit_radius)
        if np.any(done):
            j = idx[done]
            vel[j] = (period_mean_velocity(prev[j], xa[done], ph[done], lam[done], dt) if step
                      else v[done])
            hit[j] = True
            active[j] = False
        prev[idx] = xa
        x[idx] = xn
    spd = np.linalg.norm(vel, axis=1)
    cosang = np.clip((vel @ psi) / np.where(hit, spd, 1.0), -1.0, 1.0)
    err = np.where(hit, np.degrees(np.arccos(cosang)), np.nan)
    serr = np.where(hit, spd / (kappa * motion.hitting_speed) - 1.0, np.nan)
    return hit, err, serr
