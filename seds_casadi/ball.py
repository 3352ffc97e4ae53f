"""A golf ball on a field: impact, skid, rolling on z = H(x, y), walls and the hole. Vectorised.

Model (per unit mass; horizontal position p = (x, y), horizontal velocity u; g = 9.81 m/s^2):

* **Rolling without slipping.** Static friction removes 2/7 of the tangential gravity, the normal
  force keeps the ball on the surface:

      u' = -[(5/7) g + u^T Hess(H) u] grad(H) / (1 + |grad(H)|^2)  - rolling resistance

  which conserves (7/10)|v|^2 + g H without resistance (|v|^2 = |u|^2 + (grad(H).u)^2) and gives
  (5/7) g sin(theta) along an inclined plane.
* **Rolling resistance.** A deceleration (5/7) rho g along the surface velocity (rho from the
  field's Stimpmeter reading, times the field's local friction factor), projected on the
  horizontal plane.
* **Skid after the impact.** A struck ball has no spin: it slides with kinetic friction mu_k
  (0.2) until it rolls, which happens when its speed has fallen to 5/7 of the launch speed on
  flat ground (after v0 / (3.5 mu_k g) seconds); full tangential gravity acts while sliding.
* **Walls** reflect the ball's centre at one ball radius from the boundary with the field's
  restitution; at **edges** the ball is lost.
* **Hole capture.** A ball whose centre crosses the hole at distance b from its centre drops in
  if it falls by its own radius before crossing the chord: speed < 2 sqrt(R^2 - b^2) /
  sqrt(2 r / g) (1.64 m/s through the centre of a 108 mm hole; less off-centre). A ball that
  comes to rest over the hole drops in.
* **Impact** (club head to ball, along the club's velocity): v_ball = (1 + e) m_c / (m_c + m_b)
  v_club, with an effective club-head mass m_c = 0.35 kg and restitution e = 0.8 (a putter face).

Integration: semi-implicit Euler with a fixed step (default 2 ms).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .fields import Field

__all__ = ["BALL_MASS", "BALL_RADIUS", "G", "impact", "capture_speed", "simulate_shots",
           "ShotResult"]

G = 9.81
BALL_MASS = 0.0459
BALL_RADIUS = 0.02135
MU_SLIDE = 0.2
CLUB_MASS = 0.35
RESTITUTION = 0.8
STOP_SPEED = 0.005


def impact(club_velocity, club_mass: float = CLUB_MASS, restitution: float = RESTITUTION,
           ball_mass: float = BALL_MASS) -> np.ndarray:
    """Ball launch velocity from the club-head velocity (horizontal part), shape (n, 2) or (2,).

    v_ball = (1 + e) m_c / (m_c + m_b) v_club (a central impact along the club's velocity).
    """
    v = np.asarray(club_velocity, dtype=float)
    if v.shape[-1] == 3:
        v = v[..., :2]
    if not (club_mass > 0 and ball_mass > 0 and 0 <= restitution <= 1):
        raise ValueError("masses must be positive and the restitution in [0, 1]")
    return (1 + restitution) * club_mass / (club_mass + ball_mass) * v


def capture_speed(offset, hole_radius: float, ball_radius: float = BALL_RADIUS) -> np.ndarray:
    """Largest speed at which a ball crossing the hole at ``offset`` from its centre drops in."""
    b = np.abs(np.asarray(offset, dtype=float))
    chord = 2 * np.sqrt(np.maximum(hole_radius**2 - b**2, 0.0))
    return chord / np.sqrt(2 * ball_radius / G)


@dataclass
class ShotResult:
    """Outcome of simulated shots (arrays over shots).

    Attributes
    ----------
    sunk, out, stopped : array of bool, shape (n,)
    final_position : array, shape (n, 2)
    time : array, shape (n,)
        When the shot ended (sunk, out or stopped), or the time limit.
    paths : list of array (T, 2) or None
        Ball paths when requested.
    """

    sunk: np.ndarray
    out: np.ndarray
    stopped: np.ndarray
    final_position: np.ndarray
    time: np.ndarray
    paths: list | None = None

    @property
    def success_rate(self) -> float:
        """Fraction of shots sunk."""
        return float(np.mean(self.sunk))


def _rolling_acc(field: Field, P, U, rolling):
    s = field.surface
    grad = s.gradient(P)
    hess = s.hessian(P)
    curv = np.einsum("ni,nij,nj->n", U, hess, U)
    s2 = 1.0 + np.sum(grad * grad, axis=1)
    gfac = np.where(rolling, 5.0 / 7.0, 1.0) * G
    acc = -((gfac + curv) / s2)[:, None] * grad
    vs = np.sqrt(np.sum(U * U, axis=1) + np.sum(grad * U, axis=1) ** 2)
    unit = U / np.maximum(vs, 1e-12)[:, None]
    resist = np.where(rolling, (5.0 / 7.0) * field.rolling_resistance
                      * field.surface.friction_factor(P), MU_SLIDE) * G
    return acc, unit, resist, grad, s2


def simulate_shots(field: Field, ball_xy, launch_velocity, dt: float = 0.002,
                   max_time: float = 20.0, record_paths: bool = False) -> ShotResult:
    """Simulate many shots at once.

    Parameters
    ----------
    field : Field
    ball_xy : array, shape (n, 2) or (2,)
        Ball positions before the shot (inside the field's ball region).
    launch_velocity : array, shape (n, 2) or (2,)
        Ball velocities just after the impact (see :func:`impact`), horizontal [m/s].
    dt : float
        Step [s].
    max_time : float
        Time limit [s]; shots still moving then are neither sunk nor stopped.
    record_paths : bool
        Keep each ball's path.
    """
    P = field.check_situation(ball_xy).copy()
    U = np.atleast_2d(np.asarray(launch_velocity, dtype=float)).copy()
    if U.shape != P.shape:
        if U.shape == (1, 2):
            U = np.repeat(U, len(P), axis=0)
        else:
            raise ValueError(f"launch_velocity has shape {U.shape} for {len(P)} ball positions")
    if not np.all(np.isfinite(U)):
        raise ValueError("launch_velocity contains NaN or infinite values")
    if not (np.isfinite(dt) and dt > 0 and np.isfinite(max_time) and max_time > 0):
        raise ValueError("dt and max_time must be positive")
    n = len(P)
    skid_left = np.linalg.norm(U, axis=1) / (3.5 * MU_SLIDE * G)
    active = np.ones(n, bool)
    sunk = np.zeros(n, bool)
    out = np.zeros(n, bool)
    stopped = np.zeros(n, bool)
    t_end = np.full(n, max_time)
    paths = [[p.copy()] for p in P] if record_paths else None
    b = field.bounds
    r = BALL_RADIUS
    hole, R = field.hole, field.hole_radius
    steps = int(np.ceil(max_time / dt))
    for k in range(steps):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        p, u = P[idx], U[idx]
        rolling = skid_left[idx] <= 0
        acc, unit, resist, grad, s2 = _rolling_acc(field, p, u, rolling)
        speed = np.linalg.norm(u, axis=1)
        # a ball at (nearly) rest stays there when resistance can hold it on the slope
        slope_acc = np.linalg.norm(acc, axis=1)
        rest = (speed < STOP_SPEED) & rolling & (slope_acc <= resist)
        dv = dt * (acc - resist[:, None] * unit)
        # resistance cannot reverse the motion within a step
        new_u = u + dv
        reverse = (np.sum(new_u * u, axis=1) < 0) & (slope_acc <= resist)
        new_u[reverse] = 0.0
        new_u[rest] = 0.0
        new_p = p + dt * new_u
        skid_left[idx] -= dt
        # hole: closest approach of the step's segment to the hole centre
        seg = new_p - p
        L2 = np.maximum(np.sum(seg * seg, axis=1), 1e-300)
        lam = np.clip(np.sum((hole - p) * seg, axis=1) / L2, 0.0, 1.0)
        closest = p + lam[:, None] * seg
        off = np.linalg.norm(closest - hole, axis=1)
        drop = (off < R) & (np.linalg.norm(new_u, axis=1) < capture_speed(off, R))
        # boundary
        if field.boundary == "walls":
            for j, (lo, hi) in enumerate(((b[0], b[1]), (b[2], b[3]))):
                low = new_p[:, j] < lo + r
                high = new_p[:, j] > hi - r
                new_p[low, j] = 2 * (lo + r) - new_p[low, j]
                new_p[high, j] = 2 * (hi - r) - new_p[high, j]
                new_u[low | high, j] *= -field.wall_restitution
            lost = np.zeros(len(idx), bool)
        else:
            lost = ((new_p[:, 0] < b[0]) | (new_p[:, 0] > b[1]) | (new_p[:, 1] < b[2])
                    | (new_p[:, 1] > b[3]))
        P[idx], U[idx] = new_p, new_u
        t = (k + 1) * dt
        done_sunk = drop
        done_out = lost & ~drop
        done_stop = rest & ~drop & ~lost
        sunk[idx[done_sunk]] = True
        out[idx[done_out]] = True
        stopped[idx[done_stop]] = True
        fin = done_sunk | done_out | done_stop
        t_end[idx[fin]] = t
        active[idx[fin]] = False
        if record_paths:
            for i in idx:
                paths[i].append(P[i].copy())
    return ShotResult(sunk, out, stopped, P, t_end,
                      [np.array(q) for q in paths] if record_paths else None)
