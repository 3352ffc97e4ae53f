"""The compiled ball engine: the ball model's step (:mod:`seds_casadi.minigolf.ball`) written
in CasADi and run in C over many shots on two threads.

:func:`ball_step` builds the step as an SX Function of a shot's state from pure pieces (surface
terms, the roll and skid, the hole, the walls or edges), the same equations as the numpy
reference; :class:`BallKernel` compiles it, as the vectorised loop of
:mod:`seds_casadi.codegen.simd` or as CasADi's own generated C, and runs batches of shots;
:func:`ball_kernel` keeps one per field and step.
"""

from __future__ import annotations

import json

import casadi as ca
import numpy as np

from ..motion.golf import BALL_RADIUS, G
from .ball_physics import MU_SLIDE, STOP_SPEED, ShotResult
from .fields import Field

__all__ = ["BallKernel", "ball_kernel", "ball_step", "STATE_SIZE"]

#: state of a shot: x, y, u_x, u_y, slip_x, slip_y, status, time, hole x, hole y, wall contacts,
#: and the next step's mid-point (x, y) + (u_x, u_y) dt/2 where a tabulated surface is read
STATE_SIZE = 13
_MID = 11
_STATUS = 6  # 0 while moving, 1 sunk, 2 out, 3 stopped

_KERNELS: dict = {}


def ball_kernel(field: Field, dt: float = 0.01) -> BallKernel:
    """The compiled ball model of ``field`` (built once per field specification and step)."""
    key = (json.dumps(field.spec, sort_keys=True, default=str), field.name, float(dt),
           tuple(field.bounds), field.hole_radius, field.rolling_resistance)
    k = _KERNELS.get(key)
    if k is None:
        k = _KERNELS[key] = BallKernel(field, dt)
    return k


# ------------------------------------------------------------------ the step, in pieces
def _surface_terms(field: Field, p, tabulated_input: bool):
    """Gradient, Hessian and friction factor at p (the step's mid-point); tabulated surfaces
    read them from a second input ``aux`` (looked up at the state's mid-point entries; returned
    with the lookup description and the table), else analytic."""
    if not tabulated_input:
        grad, hess, fr = field.surface.casadi_terms(p, field.bounds)
        return grad, hess, fr, None, None, None
    (xs, ys), values = field.surface.table(field.bounds)
    aux = ca.SX.sym("aux", 6)
    grad, fr = aux[0:2], aux[5]
    hess = ca.vertcat(ca.horzcat(aux[2], aux[3]), ca.horzcat(aux[3], aux[4]))
    lookup = dict(ix=_MID, iy=_MID + 1, x0=xs[0], dx=xs[1] - xs[0], nx=len(xs), y0=ys[0],
                  dy=ys[1] - ys[0], ny=len(ys), channels=6)
    return grad, hess, fr, aux, lookup, values


def _roll(field: Field, dt: float, p, u, sl, grad, hess, fr):
    """Skid, roll and rolling resistance over one step (the numpy engine's ``_step``, the
    surface terms read at the mid-step point p + u dt/2): the new position and velocity, the
    new slip, and whether the ball is at rest."""
    s2 = 1 + ca.dot(grad, grad)
    cos = 1 / ca.sqrt(s2)
    fric = MU_SLIDE * G * cos
    s_mag = ca.sqrt(ca.dot(sl, sl) + ca.dot(grad, sl) ** 2)  # along the surface
    slide = ca.fmin(ca.fmax(s_mag / (3.5 * fric * dt), 0.0), 1.0)
    rolling = slide <= 0
    s_hat = sl / ca.fmax(s_mag, 1e-12)
    k = (5.0 / 7.0 + (2.0 / 7.0) * slide) * G
    a0 = -((k + ca.mtimes([u.T, hess, u])) / s2) * grad
    um = u + 0.5 * dt * a0
    curv = ca.mtimes([um.T, hess, um])
    full = -((G + curv) / s2) * grad
    acc = -((k + curv) / s2) * grad
    vs = ca.sqrt(ca.dot(um, um) + ca.dot(grad, um) ** 2)
    unit = um / ca.fmax(vs, 1e-12)
    resist_roll = (1 - slide) * (5.0 / 7.0) * field.rolling_resistance * fr * G * cos
    slope = ca.norm_2(acc)
    rest = ca.logic_and(ca.logic_and(ca.norm_2(u) < STOP_SPEED, rolling),
                        slope <= resist_roll)
    dv = dt * (acc - resist_roll * unit - slide * fric * s_hat)
    new_s = sl + dt * (full - 3.5 * fric * s_hat)
    new_s = ca.if_else(ca.logic_or(slide < 1, ca.dot(new_s, sl) < 0), ca.DM.zeros(2), new_s)
    holds = slope <= resist_roll + slide * fric
    nu = u + dv
    reverse = ca.logic_and(ca.dot(nu, u) < 0, holds)
    nu = ca.if_else(ca.logic_or(reverse, rest), ca.DM.zeros(2), nu)
    speed = ca.norm_2(u)
    decel = ca.fmax(-ca.dot(dv, u) / ca.fmax(speed, 1e-12), 1e-12) / dt
    tau = ca.fmin(speed / decel, dt)
    npos = p + ca.if_else(reverse, 0.5 * tau, 0.5 * dt) * (u + nu)
    return npos, nu, new_s, rest


def _drop(field: Field, p, npos, nu, hole):
    """Whether the ball drops into the hole on its step from p to npos (capture speed at the
    segment's closest approach)."""
    seg = npos - p
    L2 = ca.fmax(ca.dot(seg, seg), 1e-300)
    lam = ca.fmin(ca.fmax(ca.dot(hole - p, seg) / L2, 0.0), 1.0)
    off = ca.norm_2(p + lam * seg - hole)
    R = field.hole_radius
    cap = 2 * ca.sqrt(ca.fmax(R**2 - off**2, 0.0)) / np.sqrt(2 * BALL_RADIUS / G)
    return ca.logic_and(off < R, ca.norm_2(nu) < cap)


def _boundary(field: Field, npos, nu, new_s, n_hit):
    """Walls reflect (position, velocity, slip; one more wall contact), edges lose the ball:
    returns the position, velocity and slip components, ``lost`` and the wall contacts."""
    b, r = field.bounds, BALL_RADIUS
    pos, vel, slip, lost = [], [], [], 0
    for j, (lo, hi) in enumerate(((b[0], b[1]), (b[2], b[3]))):
        low, high = npos[j] < lo + r, npos[j] > hi - r
        if field.boundary == "walls":
            hit = ca.logic_or(low, high)
            n_hit = n_hit + hit
            pos.append(ca.if_else(low, 2 * (lo + r) - npos[j],
                                  ca.if_else(high, 2 * (hi - r) - npos[j], npos[j])))
            vel.append(ca.if_else(hit, -field.wall_restitution * nu[j], nu[j]))
            slip.append(ca.if_else(hit, new_s[j] - (1 + field.wall_restitution) * nu[j],
                                   new_s[j]))
        else:
            pos.append(npos[j])
            vel.append(nu[j])
            slip.append(new_s[j])
            lost = ca.logic_or(lost, ca.logic_or(npos[j] < lo, npos[j] > hi))
    return pos, vel, slip, lost, n_hit


def ball_step(field: Field, dt: float, tabulated_input: bool = False):
    """The ball model's step as an SX Function of a shot's state (:data:`STATE_SIZE`; finished
    shots are left unchanged). With ``tabulated_input`` (tabulated surfaces), the surface's
    table values are a second input instead of an interpolant call; returns (step, lookup,
    table) for :class:`seds_casadi.codegen.simd.SimdLoop`."""
    s = ca.SX.sym("s", STATE_SIZE)
    p, u, sl, status, t = s[0:2], s[2:4], s[4:6], s[_STATUS], s[7]
    grad, hess, fr, aux, lookup, values = _surface_terms(field, p + 0.5 * dt * u,
                                                         tabulated_input)
    npos, nu, new_s, rest = _roll(field, dt, p, u, sl, grad, hess, fr)
    hole = s[8:10]
    drop = _drop(field, p, npos, nu, hole)
    pos, vel, slip, lost, n_hit = _boundary(field, npos, nu, new_s, s[10])
    new_status = ca.if_else(drop, 1, ca.if_else(lost, 2, ca.if_else(rest, 3, 0)))
    new = ca.vertcat(pos[0], pos[1], vel[0], vel[1], slip[0], slip[1], new_status, t + dt,
                     hole, n_hit, pos[0] + 0.5 * dt * vel[0], pos[1] + 0.5 * dt * vel[1])
    out = ca.if_else(status == 0, new, s)
    if tabulated_input:
        return ca.Function("ball_step", [s, aux], [out]), lookup, values
    return ca.Function("ball_step", [s], [out])


# ------------------------------------------------------------------ the engine
class BallKernel:
    """The ball model's step (:func:`ball_step`), run in compiled C over many shots on two
    threads. Same equations as the numpy engine (:mod:`seds_casadi.minigolf.ball`).

    Two backends run the same CasADi SX step: ``"simd"`` translates it into a C loop over
    blocks of 64 shots held in L1 cache, written for the compiler's ``omp simd`` vectoriser,
    that stops a block once all its shots are finished (:mod:`seds_casadi.codegen.simd`);
    ``"casadi"`` loops it ``steps_per_call`` times in CasADi's generated C and maps that over
    batches of shots (used when the step cannot be translated, e.g. a tabulated surface's
    interpolant call, or no compiler works). ``"auto"`` picks simd when it can.

    The state of a shot is (x, y, u_x, u_y, slip_x, slip_y, status, time, hole x, hole y,
    wall contacts, mid-point x, y) with status 0 while moving, 1 sunk, 2 out, 3 stopped;
    finished shots are frozen.
    Between calls the finished shots are dropped, so a batch costs what its longest shot needs.

    Parameters
    ----------
    field : Field
    dt : float
        Step [s].
    steps_per_call : int
        Steps per compiled call (0.5 s of play at the default step); finished shots are dropped
        between calls. 50 is 10 % faster than 100 on the shipped fields
        (``benchmarks/bench_ball.py``) with the same results.
    batches : (int, int)
        Shots per compiled call: large batches for the bulk of the shots, small ones for the
        rest (so that 30 shots do not cost a large batch). CasADi backend.
    backend : {"auto", "simd", "casadi"}
    """

    def __init__(self, field: Field, dt: float = 0.01, steps_per_call: int = 50,
                 batches: tuple[int, int] = (1024, 32), backend: str = "auto") -> None:
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
                    step, lookup, table = ball_step(field, self.dt, tabulated_input=True)
                else:
                    step, lookup, table = ball_step(field, self.dt), None, None
                self._simd = SimdLoop(step, "ball_steps", done_index=_STATUS, lookup=lookup,
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
        from ..codegen import compile_functions

        step = ball_step(self.field, self.dt)
        s = ca.MX.sym("s", STATE_SIZE)
        x = s
        for _ in range(self.steps_per_call):
            x = step(x)
        chunk = ca.Function("ball_chunk", [s], [x])
        big = chunk.map(self.batches[0], "thread", 2)
        small = chunk.map(self.batches[1])
        self._big, self._small = compile_functions([big, small], ("-O2",))
        self.compiled = self._big.class_name() == "External"

    def run(self, P: np.ndarray, U: np.ndarray, max_time: float = 20.0,
            hole: np.ndarray | None = None, stop_at_walls: bool = False) -> ShotResult:
        """Simulate shots from positions P (n, 2) with launch velocities U (n, 2) and holes
        ``hole`` (n, 2; default the field's); with ``stop_at_walls`` a shot ends at the first
        check (every ``steps_per_call`` steps) after a wall contact. Inputs are not validated
        here: use :func:`~seds_casadi.minigolf.ball.simulate_shots`."""
        n = len(P)
        S = np.zeros((STATE_SIZE, n))
        S[8:10] = (np.tile(self.field.hole, (n, 1)) if hole is None else hole).T
        S[0:2] = P.T
        S[2:4] = U.T
        S[4:6] = U.T  # no spin at the impact: the contact point slips at the ball's speed
        S[_MID:_MID + 2] = (P + 0.5 * self.dt * U).T
        if self._simd is not None:
            self._run_simd(S, max_time, stop_at_walls)
        else:
            self._run_casadi(S, max_time, stop_at_walls)
        return self._result(S, max_time, stop_at_walls)

    def _run_simd(self, S: np.ndarray, max_time: float, stop_at_walls: bool = False) -> None:
        # blocks stop once all their shots are done; between calls the finished shots are
        # dropped so that the blocks stay full of moving ones
        left = int(np.ceil(max_time / self.dt - 1e-9))
        active = np.arange(S.shape[1])
        while active.size and left > 0:
            k = min(left, self.steps_per_call)
            X = np.ascontiguousarray(S[:, active])
            self._simd.run(X, k)
            S[:, active] = X
            left -= k
            moving = X[_STATUS] == 0
            active = active[moving & (X[10] == 0) if stop_at_walls else moving]

    def _run_casadi(self, S: np.ndarray, max_time: float, stop_at_walls: bool = False) -> None:
        active = np.arange(S.shape[1])
        nb, ns = self.batches
        t_call = self.steps_per_call * self.dt
        elapsed = 0.0
        while active.size and elapsed < max_time - 1e-12:
            n_big = (active.size // nb) * nb
            m = n_big + int(np.ceil((active.size - n_big) / ns)) * ns
            X = np.zeros((STATE_SIZE, m))
            X[_STATUS] = 1.0  # padding: frozen
            X[:, :active.size] = S[:, active]
            out = np.empty_like(X)
            for c in range(0, n_big, nb):
                out[:, c:c + nb] = np.asarray(self._big(X[:, c:c + nb]))
            for c in range(n_big, m, ns):
                out[:, c:c + ns] = np.asarray(self._small(X[:, c:c + ns]))
            S[:, active] = out[:, :active.size]
            elapsed += t_call
            moving = S[_STATUS, active] == 0
            active = active[moving & (S[10, active] == 0) if stop_at_walls else moving]

    @staticmethod
    def _result(S: np.ndarray, max_time: float, stop_at_walls: bool = False) -> ShotResult:
        # a shot still rolling at the limit, or past it within the last call
        over = (S[7] > max_time + 1e-9) | (S[_STATUS] == 0)
        status = np.where(over, 0, S[_STATUS]).astype(int)
        # a shot ended by a wall contact keeps the time of the check that ended it
        walled = stop_at_walls & (S[_STATUS] == 0) & (S[10] > 0) & (S[7] <= max_time + 1e-9)
        return ShotResult(status == 1, status == 2, status == 3, S[0:2].T.copy(),
                          np.where(over & ~walled, max_time, S[7]), None, S[10].astype(int))
