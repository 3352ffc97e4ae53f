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

Integration: a fixed step (default 10 ms): velocity by explicit Euler, position by the trapezoid
rule (exact for a constant deceleration), the hole test on the step's segment so that a fast
ball cannot jump over it.

Two engines share exactly these equations: ``"numpy"``, the readable reference (also records
paths), and ``"compiled"``, the same step written in CasADi and run in C over many shots on two
threads (:class:`BallKernel`; by default as a vectorised loop generated from the CasADi step,
:mod:`seds_casadi.simd`), 17-20x faster on analytic fields. Surfaces whose exact evaluation is expensive
("rough": hundreds of bumps; "heightmap": a spline) are read by the compiled engine from a table
of derivatives on a 1 cm grid (:meth:`Surface.table`), interpolated linearly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..motion.golf import BALL_MASS, BALL_RADIUS, G
from .fields import Field

__all__ = ["BALL_MASS", "BALL_RADIUS", "G", "impact", "capture_speed", "simulate_shots",
           "ShotResult", "BallKernel", "ball_kernel"]

MU_SLIDE = 0.2
CLUB_MASS = 0.35
RESTITUTION = 0.8
STOP_SPEED = 0.005


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
    wall_contacts : array of int, shape (n,)
        How often each ball hit a wall.
    """

    sunk: np.ndarray
    out: np.ndarray
    stopped: np.ndarray
    final_position: np.ndarray
    time: np.ndarray
    paths: list | None = None
    wall_contacts: np.ndarray | None = None

    @property
    def success_rate(self) -> float:
        """Fraction of shots sunk."""
        return float(np.mean(self.sunk))


def _rolling_acc(field: Field, P, U, slide):
    """Surface terms of one step: the gravity acceleration (blended between sliding and
    rolling by ``slide``), the full (sliding) one, the velocity's unit vector and the rolling
    resistance's magnitude."""
    s = field.surface
    grad = s.gradient(P)
    hess = s.hessian(P)
    curv = np.einsum("ni,nij,nj->n", U, hess, U)
    s2 = 1.0 + np.sum(grad * grad, axis=1)
    # slide: fraction of the step still sliding (0 rolling, 1 sliding; in between at the
    # transition, so that the speed at the end of that step is exact on flat ground)
    full = -((G + curv) / s2)[:, None] * grad
    acc = -(((5.0 / 7.0 + (2.0 / 7.0) * slide) * G + curv) / s2)[:, None] * grad
    vs = np.sqrt(np.sum(U * U, axis=1) + np.sum(grad * U, axis=1) ** 2)
    unit = U / np.maximum(vs, 1e-12)[:, None]
    resist = (1 - slide) * (5.0 / 7.0) * field.rolling_resistance \
        * field.surface.friction_factor(P) * G
    return acc, full, unit, resist


def simulate_shots(field: Field, ball_xy, launch_velocity, dt: float = 0.01,
                   max_time: float = 20.0, record_paths: bool = False,
                   engine: str = "auto", hole=None) -> ShotResult:
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
        Keep each ball's path (numpy engine).
    hole : array, shape (n, 2) or (2,), optional
        Hole position per shot (default: the field's hole); inside the field's bounds.
    engine : {"auto", "compiled", "numpy"}
        "auto" uses the compiled engine for batches of more than a few shots when a C compiler
        is available (and always when paths are not needed), else numpy.

    Returns
    -------
    ShotResult
    """
    if engine not in ("auto", "compiled", "numpy"):
        raise ValueError(f"engine must be 'auto', 'compiled' or 'numpy', got {engine!r}")
    if engine == "compiled" and record_paths:
        raise ValueError("record_paths needs engine='numpy' (the compiled engine keeps no paths)")
    if engine == "auto":
        from ..codegen import compiler_available

        engine = ("compiled" if (not record_paths and compiler_available()
                                 and np.size(ball_xy) > 16) else "numpy")
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
    if engine == "compiled":
        return ball_kernel(field, dt).run(P, U, max_time, Hh)
    n = len(P)
    # slip velocity of the contact point: a struck ball has no spin, so it slips at its speed
    S = U.copy()
    mg = MU_SLIDE * G
    active = np.ones(n, bool)
    sunk = np.zeros(n, bool)
    out = np.zeros(n, bool)
    stopped = np.zeros(n, bool)
    t_end = np.full(n, max_time)
    walls = np.zeros(n, int)
    paths = [[p.copy()] for p in P] if record_paths else None
    b = field.bounds
    r = BALL_RADIUS
    R = field.hole_radius
    steps = int(np.ceil(max_time / dt))
    for k in range(steps):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        p, u, hole, s = P[idx], U[idx], Hh[idx], S[idx]
        s_mag = np.linalg.norm(s, axis=1)
        # sliding friction acts against the slip, which falls at (7/2) mu g (plus gravity)
        slide = np.clip(s_mag / (3.5 * mg * dt), 0.0, 1.0)
        rolling = slide <= 0
        s_hat = s / np.maximum(s_mag, 1e-12)[:, None]
        acc, full, unit, resist = _rolling_acc(field, p, u, slide)
        speed = np.linalg.norm(u, axis=1)
        # a ball at (nearly) rest stays there when resistance can hold it on the slope
        slope_acc = np.linalg.norm(acc, axis=1)
        rest = (speed < STOP_SPEED) & rolling & (slope_acc <= resist)
        dv = dt * (acc - resist[:, None] * unit - (slide * mg)[:, None] * s_hat)
        new_s = s + dt * (full - 3.5 * mg * s_hat)
        new_s[(slide < 1) | (np.sum(new_s * s, axis=1) < 0)] = 0.0
        resist = resist + slide * mg
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
                hit = low | high
                walls[idx[hit]] += 1
                # the wall turns the velocity, not the spin: the contact point with the ground
                # then slips at (1 + e) times the normal speed, and friction brings the ball
                # back to rolling (a rolling ball comes off a wall slower than e v_n)
                new_s[hit, j] -= (1.0 + field.wall_restitution) * new_u[hit, j]
                new_u[hit, j] *= -field.wall_restitution
            lost = np.zeros(len(idx), bool)
        else:
            lost = ((new_p[:, 0] < b[0]) | (new_p[:, 0] > b[1]) | (new_p[:, 1] < b[2])
                    | (new_p[:, 1] > b[3]))
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
        active[idx[fin]] = False
        if record_paths:
            for i in idx:
                paths[i].append(P[i].copy())
    return ShotResult(sunk, out, stopped, P, t_end,
                      [np.array(q) for q in paths] if record_paths else None, walls)


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


# ------------------------------------------------------------------ compiled engine
_KERNELS: dict = {}


def ball_kernel(field: Field, dt: float = 0.01) -> BallKernel:
    """The compiled ball model of ``field`` (built once per field specification and step)."""
    import json

    key = (json.dumps(field.spec, sort_keys=True, default=str), field.name, float(dt),
           tuple(field.bounds), field.hole_radius, field.rolling_resistance)
    k = _KERNELS.get(key)
    if k is None:
        k = _KERNELS[key] = BallKernel(field, dt)
    return k


class BallKernel:
    """The ball model's step in CasADi, run in compiled C over many shots on two threads. Same
    equations as the numpy engine (module docstring).

    Two backends run the same CasADi SX step: ``"simd"`` translates it into a C loop over
    blocks of 64 shots that the compiler vectorises (AVX2: four shots per instruction) and that
    stops a block once all its shots are finished (:mod:`seds_casadi.simd`); ``"casadi"`` loops
    it ``steps_per_call`` times in CasADi's generated C and maps that over batches of shots
    (used when the step cannot be translated, e.g. a tabulated surface's interpolant call, or
    no compiler works). ``"auto"`` picks simd when it can.

    The state of a shot is (x, y, u_x, u_y, slip_x, slip_y, status, time, hole x, hole y, wall
    contacts) with status 0 while moving, 1 sunk, 2 out, 3 stopped; finished shots are frozen.
    Between calls the finished shots are dropped, so a batch costs what its longest shot needs.

    Parameters
    ----------
    field : Field
    dt : float
        Step [s].
    steps_per_call : int
        Steps per compiled call (1 s of play at the default step).
    batches : (int, int)
        Shots per compiled call: large batches for the bulk of the shots, small ones for the
        rest (so that 30 shots do not cost a large batch). CasADi backend.
    backend : {"auto", "simd", "casadi"}
    """

    def __init__(self, field: Field, dt: float = 0.01, steps_per_call: int = 100,
                 batches: tuple[int, int] = (1024, 32), backend: str = "auto") -> None:
        import casadi as ca

        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be positive, got {dt}")
        if backend not in ("auto", "simd", "casadi"):
            raise ValueError(f"backend must be 'auto', 'simd' or 'casadi', got {backend!r}")
        self.field, self.dt = field, float(dt)
        self.steps_per_call = int(steps_per_call)
        self.batches = (int(batches[0]), int(batches[1]))
        self._simd = None
        self.simd_error = None
        if backend in ("auto", "simd"):
            from ..codegen.simd import SimdLoop, UnsupportedOperation

            try:
                if field.surface.tabulated:
                    step, lookup, table = self._step(ca, tabulated_input=True)
                else:
                    step, lookup, table = self._step(ca), None, None
                self._simd = SimdLoop(step, "ball_steps", done_index=6, lookup=lookup,
                                      table=table)
            except (UnsupportedOperation, RuntimeError) as exc:
                if backend == "simd":
                    raise
                self.simd_error = str(exc)
        self.backend = "simd" if self._simd is not None else "casadi"
        self._big = self._small = None
        self.compiled = True
        if self._simd is None:
            self._build_casadi()

    def _build_casadi(self) -> None:
        import casadi as ca

        from ..codegen import compile_functions

        step = self._step(ca)
        s = ca.MX.sym("s", 11)
        x = s
        for _ in range(self.steps_per_call):
            x = step(x)
        chunk = ca.Function("ball_chunk", [s], [x])
        big = chunk.map(self.batches[0], "thread", 2)
        small = chunk.map(self.batches[1])
        self._big, self._small = compile_functions([big, small], ("-O2",))
        self.compiled = self._big.class_name() == "External"

    def _step(self, ca, tabulated_input: bool = False):
        """The step as an SX Function of the state. With ``tabulated_input`` (tabulated
        surfaces), the surface's table values are a second input instead of an interpolant
        call; returns (step, lookup, table) for :class:`seds_casadi.simd.SimdLoop`."""
        f, dt, r = self.field, self.dt, BALL_RADIUS
        mg = MU_SLIDE * G
        s = ca.SX.sym("s", 11)
        p, u, sl, status, t = s[0:2], s[2:4], s[4:6], s[6], s[7]
        if tabulated_input:
            (xs, ys), values = f.surface.table(f.bounds)
            aux = ca.SX.sym("aux", 6)
            grad, fr = aux[0:2], aux[5]
            hess = ca.vertcat(ca.horzcat(aux[2], aux[3]), ca.horzcat(aux[3], aux[4]))
            lookup = dict(ix=0, iy=1, x0=xs[0], dx=xs[1] - xs[0], nx=len(xs), y0=ys[0],
                          dy=ys[1] - ys[0], ny=len(ys), channels=6)
        else:
            grad, hess, fr = f.surface.casadi_terms(p, f.bounds)
        curv = ca.mtimes([u.T, hess, u])
        s2 = 1 + ca.dot(grad, grad)
        s_mag = ca.norm_2(sl)
        slide = ca.fmin(ca.fmax(s_mag / (3.5 * mg * dt), 0.0), 1.0)
        rolling = slide <= 0
        s_hat = sl / ca.fmax(s_mag, 1e-12)
        full = -((G + curv) / s2) * grad
        acc = -(((5.0 / 7.0 + (2.0 / 7.0) * slide) * G + curv) / s2) * grad
        vs = ca.sqrt(ca.dot(u, u) + ca.dot(grad, u) ** 2)
        unit = u / ca.fmax(vs, 1e-12)
        resist_roll = (1 - slide) * (5.0 / 7.0) * f.rolling_resistance * fr * G
        slope = ca.norm_2(acc)
        rest = ca.logic_and(ca.logic_and(ca.norm_2(u) < STOP_SPEED, rolling),
                            slope <= resist_roll)
        dv = dt * (acc - resist_roll * unit - slide * mg * s_hat)
        new_s = sl + dt * (full - 3.5 * mg * s_hat)
        new_s = ca.if_else(ca.logic_or(slide < 1, ca.dot(new_s, sl) < 0), ca.DM.zeros(2), new_s)
        holds = slope <= resist_roll + slide * mg
        nu = u + dv
        reverse = ca.logic_and(ca.dot(nu, u) < 0, holds)
        nu = ca.if_else(ca.logic_or(reverse, rest), ca.DM.zeros(2), nu)
        speed = ca.norm_2(u)
        decel = ca.fmax(-ca.dot(dv, u) / ca.fmax(speed, 1e-12), 1e-12) / dt
        tau = ca.fmin(speed / decel, dt)
        npos = p + ca.if_else(reverse, 0.5 * tau, 0.5 * dt) * (u + nu)
        seg = npos - p
        L2 = ca.fmax(ca.dot(seg, seg), 1e-300)
        hole = s[8:10]
        lam = ca.fmin(ca.fmax(ca.dot(hole - p, seg) / L2, 0.0), 1.0)
        off = ca.norm_2(p + lam * seg - hole)
        R = f.hole_radius
        cap = 2 * ca.sqrt(ca.fmax(R**2 - off**2, 0.0)) / np.sqrt(2 * r / G)
        drop = ca.logic_and(off < R, ca.norm_2(nu) < cap)
        b = f.bounds
        pos, vel, slip, lost, n_hit = [], [], [], 0, s[10]
        for j, (lo, hi) in enumerate(((b[0], b[1]), (b[2], b[3]))):
            low, high = npos[j] < lo + r, npos[j] > hi - r
            if f.boundary == "walls":
                hit = ca.logic_or(low, high)
                n_hit = n_hit + hit
                pos.append(ca.if_else(low, 2 * (lo + r) - npos[j],
                                      ca.if_else(high, 2 * (hi - r) - npos[j], npos[j])))
                vel.append(ca.if_else(hit, -f.wall_restitution * nu[j], nu[j]))
                slip.append(ca.if_else(hit, new_s[j] - (1 + f.wall_restitution) * nu[j],
                                       new_s[j]))
            else:
                pos.append(npos[j])
                vel.append(nu[j])
                slip.append(new_s[j])
                lost = ca.logic_or(lost, ca.logic_or(npos[j] < lo, npos[j] > hi))
        new_status = ca.if_else(drop, 1, ca.if_else(lost, 2, ca.if_else(rest, 3, 0)))
        new = ca.vertcat(pos[0], pos[1], vel[0], vel[1], slip[0], slip[1], new_status, t + dt,
                         hole, n_hit)
        out = ca.if_else(status == 0, new, s)
        if tabulated_input:
            return ca.Function("ball_step", [s, aux], [out]), lookup, values
        return ca.Function("ball_step", [s], [out])

    def run(self, P: np.ndarray, U: np.ndarray, max_time: float = 20.0,
            hole: np.ndarray | None = None) -> ShotResult:
        """Simulate shots from positions P (n, 2) with launch velocities U (n, 2) and holes
        ``hole`` (n, 2; default the field's). Inputs are not validated here: use
        :func:`simulate_shots`."""
        n = len(P)
        S = np.zeros((11, n))
        S[8:10] = (np.tile(self.field.hole, (n, 1)) if hole is None else hole).T
        S[0:2] = P.T
        S[2:4] = U.T
        S[4:6] = U.T  # no spin at the impact: the contact point slips at the ball's speed
        if self._simd is not None:
            # blocks stop once all their shots are done; between calls the finished shots are
            # dropped so that the blocks stay full of moving ones
            left = int(np.ceil(max_time / self.dt - 1e-9))
            active = np.arange(n)
            while active.size and left > 0:
                k = min(left, self.steps_per_call)
                X = np.ascontiguousarray(S[:, active])
                self._simd.run(X, k)
                S[:, active] = X
                left -= k
                active = active[X[6] == 0]
            return self._result(S, max_time)
        active = np.arange(n)
        nb, ns = self.batches
        t_call = self.steps_per_call * self.dt
        elapsed = 0.0
        while active.size and elapsed < max_time - 1e-12:
            n_big = (active.size // nb) * nb
            m = n_big + int(np.ceil((active.size - n_big) / ns)) * ns
            X = np.zeros((11, m))
            X[6] = 1.0  # padding: frozen
            X[:, :active.size] = S[:, active]
            out = np.empty_like(X)
            for c in range(0, n_big, nb):
                out[:, c:c + nb] = np.asarray(self._big(X[:, c:c + nb]))
            for c in range(n_big, m, ns):
                out[:, c:c + ns] = np.asarray(self._small(X[:, c:c + ns]))
            S[:, active] = out[:, :active.size]
            elapsed += t_call
            active = active[S[6, active] == 0]
        return self._result(S, max_time)

    @staticmethod
    def _result(S: np.ndarray, max_time: float) -> ShotResult:
        # a shot still rolling at the limit, or past it within the last call
        over = (S[7] > max_time + 1e-9) | (S[6] == 0)
        status = np.where(over, 0, S[6]).astype(int)
        return ShotResult(status == 1, status == 2, status == 3, S[0:2].T.copy(),
                          np.where(over, max_time, S[7]), None, S[10].astype(int))
