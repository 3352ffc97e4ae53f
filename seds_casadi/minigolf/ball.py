"""A golf ball on a field: impact, skid, rolling on z = H(x, y), walls and the hole. Vectorised.

Model (per unit mass; horizontal position p = (x, y), horizontal velocity u; g = 9.81 m/s^2):

* **Rolling without slipping.** Static friction removes 2/7 of the tangential gravity, the normal
  force keeps the ball on the surface:

      u' = -[(5/7) g + u^T Hess(H) u] grad(H) / (1 + |grad(H)|^2)  - rolling resistance

  which conserves (7/10)|v|^2 + g H without resistance (|v|^2 = |u|^2 + (grad(H).u)^2) and gives
  (5/7) g sin(theta) along an inclined plane.
* **Rolling resistance.** A deceleration (5/7) rho g cos(theta) along the surface velocity
  (rho from the field's Stimpmeter reading, times the field's local friction factor), projected
  on the horizontal plane; the normal force per unit mass is g cos(theta) (cos(theta) =
  1 / sqrt(1 + |grad(H)|^2)), and sliding friction mu_k g cos(theta) scales with it too.
* **Skid after the impact.** A struck ball has no spin: its contact point slips at the ball's
  velocity. Kinetic friction mu_k g (mu_k = 0.2) acts against the slip, which therefore falls at
  (7/2) mu_k g (gravity's full tangential part acts on both); the ball rolls once the slip is
  gone (on flat ground at 5/7 of the launch speed, after v0 / (3.5 mu_k g) seconds). Tracking
  the slip's direction, not only its size, matters on slopes: friction then also resists the
  sideways slide that gravity starts (checked against exudyn's contact model).
* **Walls** reflect the ball's centre at one ball radius from the boundary with the field's
  restitution e. They turn the velocity but not the spin, so a rolling ball leaves a wall
  slipping at (1 + e) times its normal speed and friction then brings it back to rolling (head
  on, it comes back at (5e - 2)/7 of its speed, not e; found against exudyn's rigid ball,
  whose paths after a wall otherwise differed by centimetres). At **edges** the ball is lost.
* **Hole capture.** A ball whose centre crosses the hole at distance b from its centre drops in
  if it falls by its own radius before crossing the chord: speed < 2 sqrt(R^2 - b^2) /
  sqrt(2 r / g) (1.64 m/s through the centre of a 108 mm hole; less off-centre). A ball that
  comes to rest over the hole drops in.
* **Impact** (club head to ball, along the club's velocity): v_ball = (1 + e) m_c / (m_c + m_b)
  v_club, with an effective club-head mass m_c = 0.35 kg and restitution e = 0.8 (a putter face).

Integration: a fixed step (default 10 ms), drift-kick-drift: the surface read at the step's
mid-point, the velocity kicked by the acceleration there, the position advanced by the trapezoid
rule (exact for a constant deceleration). Second order and time-symmetric, so that the energy
(7/10)|v|^2 + g H stays put without resistance (1e-5 of a 10 cm bowl's depth energy over 10 s;
the explicit Euler step used before gained 16 %). Steps are split on strongly curved surfaces
(:func:`substeps`), and a field whose surface curves more tightly than the ball's radius is
refused at load time (:meth:`~seds_casadi.minigolf.surface.Surface.extremes`), so that the step
stays finite on every surface a field file can describe. The hole test runs on the step's
segment so that a fast ball cannot jump over it.

Two engines share exactly these equations: ``"numpy"``, the readable reference here (also
records paths), and ``"compiled"``, the same step written in CasADi and run in C over many shots
on two threads (:class:`~seds_casadi.minigolf.ball_kernel.BallKernel`; by default as a blocked C
loop generated from the CasADi step, :mod:`seds_casadi.codegen.simd`), 17-20x faster on analytic
fields. Surfaces whose exact evaluation is expensive ("rough": hundreds of bumps; "heightmap": a
spline) are read by the compiled engine from a table of derivatives on a 1 cm grid
(:meth:`~seds_casadi.minigolf.surface.Surface.table`), interpolated linearly.
"""

from __future__ import annotations

import numpy as np

from ..motion.golf import BALL_MASS, BALL_RADIUS, G
from .ball_kernel import ball_kernel
from .ball_physics import MU_SLIDE, STOP_SPEED, ShotResult
from .fields import Field

__all__ = ["impact", "capture_speed", "simulate_shots", "substeps", "CLUB_MASS", "RESTITUTION"]

#: the impact model's effective club-head mass [kg] and restitution (a putter face)
CLUB_MASS = 0.35
RESTITUTION = 0.8


def impact(club_velocity, club_mass: float = CLUB_MASS, restitution: float = RESTITUTION,
           ball_mass: float = BALL_MASS, face_normal=None) -> np.ndarray:
    """Ball launch velocity from the club-head velocity (horizontal part), shape (n, 2) or (2,).

    v_ball = (1 + e) m_c / (m_c + m_b) v_club: a central impact with a square face (its normal
    along the club's velocity). With ``face_normal`` (n, 3) or (3,), a frictionless flat face at
    any angle: only the velocity's component along the normal is passed on, and the ball leaves
    along the normal, v_ball = (1 + e) m_c / (m_c + m_b) (v_club . n) n.
    """
    v = np.asarray(club_velocity, dtype=float)
    if not (club_mass > 0 and ball_mass > 0 and 0 <= restitution <= 1):
        raise ValueError("masses must be positive and the restitution in [0, 1]")
    k = (1 + restitution) * club_mass / (club_mass + ball_mass)
    if face_normal is not None:
        n = np.asarray(face_normal, dtype=float)
        if v.shape[-1] != 3 or n.shape[-1] != 3:
            raise ValueError("with face_normal, give 3-D club velocities and normals")
        n = n / np.linalg.norm(n, axis=-1, keepdims=True)
        v = np.sum(v * n, axis=-1, keepdims=True) * n
    if v.shape[-1] == 3:
        v = v[..., :2]
    return k * v


def capture_speed(offset, hole_radius: float, ball_radius: float = BALL_RADIUS) -> np.ndarray:
    """Largest speed at which a ball crossing the hole at ``offset`` from its centre drops in."""
    b = np.abs(np.asarray(offset, dtype=float))
    chord = 2 * np.sqrt(np.maximum(hole_radius**2 - b**2, 0.0))
    return chord / np.sqrt(2 * ball_radius / G)


def simulate_shots(field: Field, ball_xy, launch_velocity, dt: float = 0.01,
                   max_time: float = 20.0, record_paths: bool = False,
                   engine: str = "auto", hole=None, stop_at_walls: bool = False) -> ShotResult:
    """Simulate many shots at once.

    Parameters
    ----------
    field : Field
    ball_xy : array, shape (n, 2) or (2,)
        Ball positions before the shot (inside the field's ball region).
    launch_velocity : array, shape (n, 2) or (2,)
        Ball velocities just after the impact (see :func:`impact`), horizontal [m/s].
    dt : float
        Step [s]; split into :func:`substeps` on strongly curved surfaces.
    max_time : float
        Time limit [s]; shots still moving then are neither sunk nor stopped.
    record_paths : bool
        Keep each ball's path (numpy engine).
    hole : array, shape (n, 2) or (2,), optional
        Hole position per shot (default: the field's hole); inside the field's bounds.
    engine : {"auto", "compiled", "numpy"}
        "auto" uses the compiled engine for batches of more than a few shots when a C compiler
        is available (and always when paths are not needed), else numpy.
    stop_at_walls : bool, default False
        End a shot at its first wall contact (for searches that count only direct shots: a
        shot that touched a wall is no success then, and the rest of its roll, the longest
        part of a fast shot's, need not be simulated). Such a shot ends at the next check (every
        step on the numpy engine, every 0.5 s on the compiled one): unless it sank, stopped or
        left before that check, it is reported as none of them, at the check's position and
        time, with its wall contacts. Shots without a wall contact are unchanged.

    Returns
    -------
    ShotResult
    """
    engine = _choose_engine(engine, record_paths, ball_xy)
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
    Hh = _holes(field, hole, len(P))
    dt = dt / substeps(field, U, dt)
    if engine == "compiled":
        return ball_kernel(field, dt).run(P, U, max_time, Hh, stop_at_walls)
    return _simulate_numpy(field, P, U, Hh, dt, max_time, record_paths, stop_at_walls)


#: largest turn of the velocity by the surface's curvature within one step [rad]
MAX_TURN = 0.25


def substeps(field: Field, launch_velocity, dt: float) -> int:
    """Steps per ``dt`` that keep the step stable on the field's surface (step control).

    A ball at speed v on a surface of curvature kappa turns by about kappa v dt per step; the
    step is split so that this stays below :data:`MAX_TURN` for the fastest ball the shots can
    give (launch speed along the surface, plus the field's whole drop). 1 on the shipped fields
    at play's speeds; the surface's curvature is bounded at load time (below 1 / ball radius).
    """
    ext = field.surface.extremes(field.bounds)
    u2 = float(np.max(np.sum(np.square(launch_velocity), axis=-1), initial=0.0))
    v = np.sqrt(u2 * (1 + ext["slope"] ** 2) + 2 * G * ext["height_range"])
    return max(1, int(np.ceil(dt * ext["curvature"] * v / MAX_TURN)))


def _choose_engine(engine: str, record_paths: bool, ball_xy) -> str:
    if engine not in ("auto", "compiled", "numpy"):
        raise ValueError(f"engine must be 'auto', 'compiled' or 'numpy', got {engine!r}")
    if engine == "compiled" and record_paths:
        raise ValueError("record_paths needs engine='numpy' (the compiled engine keeps no paths)")
    if engine == "auto":
        from ..codegen import compiler_available

        engine = ("compiled" if (not record_paths and compiler_available()
                                 and np.size(ball_xy) > 16) else "numpy")
    return engine


def _holes(field: Field, hole, n: int) -> np.ndarray:
    if hole is None:
        return np.tile(field.hole, (n, 1))
    H = np.atleast_2d(np.asarray(hole, dtype=float))
    if H.shape == (1, 2):
        H = np.repeat(H, n, axis=0)
    if H.shape != (n, 2) or not np.all(np.isfinite(H)):
        raise ValueError(f"hole must be finite, shape (2,) or ({n}, 2); got {np.shape(hole)}")
    b, R = field.bounds, field.hole_radius
    bad = ~((b[0] + R <= H[:, 0]) & (H[:, 0] <= b[1] - R) & (b[2] + R <= H[:, 1])
            & (H[:, 1] <= b[3] - R))
    if bad.any():
        raise ValueError(f"hole at {list(H[np.argmax(bad)])} is outside the field "
                         f"{list(b)} (keep it one hole radius inside)")
    return H


# ------------------------------------------------------------------ numpy engine (the reference)
def _simulate_numpy(field: Field, P: np.ndarray, U: np.ndarray, Hh: np.ndarray, dt: float,
                    max_time: float, record_paths: bool,
                    stop_at_walls: bool = False) -> ShotResult:
    """The numpy engine: steps every moving shot until all are done or the time is up; P and U
    (n, 2) are advanced in place."""
    n = len(P)
    # slip velocity of the contact point: a struck ball has no spin, so it slips at its speed
    S = U.copy()
    active = np.ones(n, bool)
    sunk = np.zeros(n, bool)
    out = np.zeros(n, bool)
    stopped = np.zeros(n, bool)
    t_end = np.full(n, max_time)
    walls = np.zeros(n, int)
    paths = [[p.copy()] for p in P] if record_paths else None
    steps = int(np.ceil(max_time / dt))
    for k in range(steps):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        p, u, hole, s = P[idx], U[idx], Hh[idx], S[idx]
        new_p, new_u, new_s, rest = _step(field, p, u, s, dt)
        drop = _drops(p, new_p, new_u, hole, field.hole_radius)
        lost, hits = _boundary(field, new_p, new_u, new_s)
        walls[idx] += hits
        P[idx], U[idx], S[idx] = new_p, new_u, new_s
        t = (k + 1) * dt
        done_sunk = drop
        done_out = lost & ~drop
        done_stop = rest & ~drop & ~lost
        sunk[idx[done_sunk]] = True
        out[idx[done_out]] = True
        stopped[idx[done_stop]] = True
        fin = done_sunk | done_out | done_stop
        t_end[idx[fin]] = t
        if stop_at_walls:   # ended by its wall contact: neither sunk, out nor stopped
            fin = fin | (walls[idx] > 0)
            t_end[idx[(walls[idx] > 0) & ~(done_sunk | done_out | done_stop)]] = t
        active[idx[fin]] = False
        if record_paths:
            for i in idx:
                paths[i].append(P[i].copy())
    return ShotResult(sunk, out, stopped, P, t_end,
                      [np.array(q) for q in paths] if record_paths else None, walls)


def _step(field: Field, p, u, s, dt: float):
    """One step of the shots at p with velocities u and slips s, each (m, 2): the new
    position, velocity and slip (before the boundary), and which balls are at rest.

    Drift-kick-drift (position Verlet): the surface is read half-way, at p + u dt/2, the
    velocity-dependent curvature term u^T Hess(H) u at a predicted mid-step velocity, and the
    position advances by the trapezoid rule (exact for a constant deceleration). Second order,
    time-symmetric: energy stays within 1e-5 of the depth energy over 10 s in a frictionless
    bowl at 10 ms (explicit Euler gained 16 %)."""
    mid = p + 0.5 * dt * u
    surf = field.surface
    grad, hess, fr = surf.gradient(mid), surf.hessian(mid), surf.friction_factor(mid)
    s2 = 1.0 + np.sum(grad * grad, axis=1)
    cos = 1.0 / np.sqrt(s2)  # cos(theta): normal force, friction, resistance scale with it
    fric = MU_SLIDE * G * cos
    s_mag = np.sqrt(np.sum(s * s, axis=1) + np.sum(grad * s, axis=1) ** 2)  # along the surface
    # sliding friction acts against the slip, which falls at (7/2) mu g cos(theta) (plus
    # gravity); slide: fraction of the step still sliding (0 rolling, 1 sliding; in between at
    # the transition, so that the speed at the end of that step is exact on flat ground)
    slide = np.clip(s_mag / (3.5 * fric * dt), 0.0, 1.0)
    rolling = slide <= 0
    s_hat = s / np.maximum(s_mag, 1e-12)[:, None]
    k = (5.0 / 7.0 + (2.0 / 7.0) * slide) * G
    a0 = -((k + np.einsum("ni,nij,nj->n", u, hess, u)) / s2)[:, None] * grad
    um = u + 0.5 * dt * a0
    curv = np.einsum("ni,nij,nj->n", um, hess, um)
    acc = -((k + curv) / s2)[:, None] * grad
    full = -((G + curv) / s2)[:, None] * grad
    vs = np.sqrt(np.sum(um * um, axis=1) + np.sum(grad * um, axis=1) ** 2)
    unit = um / np.maximum(vs, 1e-12)[:, None]
    resist = (1 - slide) * (5.0 / 7.0) * field.rolling_resistance * fr * G * cos
    speed = np.linalg.norm(u, axis=1)
    # a ball at (nearly) rest stays there when resistance can hold it on the slope
    slope_acc = np.linalg.norm(acc, axis=1)
    rest = (speed < STOP_SPEED) & rolling & (slope_acc <= resist)
    dv = dt * (acc - resist[:, None] * unit - (slide * fric)[:, None] * s_hat)
    new_s = s + dt * (full - 3.5 * fric[:, None] * s_hat)
    new_s[(slide < 1) | (np.sum(new_s * s, axis=1) < 0)] = 0.0
    resist = resist + slide * fric
    # resistance cannot reverse the motion within a step
    new_u = u + dv
    reverse = (np.sum(new_u * u, axis=1) < 0) & (slope_acc <= resist)
    new_u[reverse] = 0.0
    new_u[rest] = 0.0
    # trapezoid: exact for a constant deceleration; a ball that stops within the step
    # travels u tau / 2 where tau is its stopping time
    decel = np.maximum(-np.sum(dv * u, axis=1) / np.maximum(speed, 1e-12), 1e-12) / dt
    tau = np.minimum(speed / decel, dt)
    new_p = p + np.where(reverse, 0.5 * tau, 0.5 * dt)[:, None] * (u + new_u)
    return new_p, new_u, new_s, rest


def _drops(p, new_p, new_u, hole, R: float) -> np.ndarray:
    """Whether each ball drops into its hole during the step from p to new_p: the closest
    approach of the step's segment to the hole's centre, and the capture speed there."""
    seg = new_p - p
    L2 = np.maximum(np.sum(seg * seg, axis=1), 1e-300)
    lam = np.clip(np.sum((hole - p) * seg, axis=1) / L2, 0.0, 1.0)
    closest = p + lam[:, None] * seg
    off = np.linalg.norm(closest - hole, axis=1)
    return (off < R) & (np.linalg.norm(new_u, axis=1) < capture_speed(off, R))


def _boundary(field: Field, new_p, new_u, new_s) -> tuple[np.ndarray, np.ndarray]:
    """Walls reflect the balls (new_p, new_u, new_s changed in place), edges lose them:
    returns (lost, number of wall contacts in this step) per ball."""
    b, r = field.bounds, BALL_RADIUS
    hits = np.zeros(len(new_p), int)
    if field.boundary != "walls":
        lost = ((new_p[:, 0] < b[0]) | (new_p[:, 0] > b[1]) | (new_p[:, 1] < b[2])
                | (new_p[:, 1] > b[3]))
        return lost, hits
    for j, (lo, hi) in enumerate(((b[0], b[1]), (b[2], b[3]))):
        low = new_p[:, j] < lo + r
        high = new_p[:, j] > hi - r
        new_p[low, j] = 2 * (lo + r) - new_p[low, j]
        new_p[high, j] = 2 * (hi - r) - new_p[high, j]
        hit = low | high
        hits += hit
        # the wall turns the velocity, not the spin: the contact point with the ground then
        # slips at (1 + e) times the normal speed, and friction brings the ball back to
        # rolling (a rolling ball comes off a wall slower than e v_n)
        new_s[hit, j] -= (1.0 + field.wall_restitution) * new_u[hit, j]
        new_u[hit, j] *= -field.wall_restitution
    return np.zeros(len(new_p), bool), hits

