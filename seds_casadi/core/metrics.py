"""Accuracy metrics of the LASA evaluation protocol (LPV-DS evaluation, CoRL 2018).

All functions take arrays of shape (n, d) and are vectorised. The published protocol's own
definitions (nbfigueroa/ds-opt, commit 01072b6, 2018: ``utils/errror-estimation/rmse_error.m``,
``edot_error.m``, ``thirdparty/dtwd/.../dtw.m`` and ``thirdparty/seds-stripped/SEDS_lib/
Simulation.m``) are matched by :func:`velocity_rmse`, :func:`pointwise_direction_error` with
``min_norm_product=0``, :func:`dtw_distance` and :func:`simulate_until_slow`.
"""

from __future__ import annotations

import ctypes
import logging
import os
import threading

import casadi as ca
import numpy as np
from scipy.spatial.distance import cdist

_LOG = logging.getLogger(__name__)

__all__ = ["velocity_rmse", "direction_error", "pointwise_direction_error", "dtw_distance",
           "swept_error_area", "simulate_until_slow", "reproduction_dtw"]


def velocity_rmse(predicted: np.ndarray, demonstrated: np.ndarray) -> float:
    """Velocity RMSE: mean over points of sqrt((1/d) sum_j (xdot_hat_ij - xdot_ij)^2).

    This is ds-opt's ``mean(rmse_error(...))``: ``rmse_error.m`` returns
    ``sqrt(mean((xi_dot' - xi_dot_ref').^2, 2))``, one value per point, and the evaluation takes
    the mean over all points of the set (not the root of the pooled mean square).

    Parameters
    ----------
    predicted, demonstrated : array, shape (n, d)
    """
    p, q = _pair(predicted, demonstrated)
    return float(np.mean(np.sqrt(np.mean((p - q) ** 2, axis=1))))


def direction_error(predicted: np.ndarray, demonstrated: np.ndarray) -> float:
    """Direction error e_dot: mean over points of |1 - cos(xdot_hat_i, xdot_i)|.

    A point where the product of the norms is below 1e-10 contributes 0.
    """
    p, q = _pair(predicted, demonstrated)
    den = np.linalg.norm(p, axis=1) * np.linalg.norm(q, axis=1)
    ok = den > 1e-10
    cos = np.where(ok, np.sum(p * q, axis=1) / np.where(ok, den, 1.0), 1.0)
    return float(np.mean(np.abs(1.0 - cos)))


def pointwise_direction_error(predicted: np.ndarray, demonstrated: np.ndarray,
                              min_norm_product: float = 1e-10) -> np.ndarray:
    """Direction error of each point: |1 - cos(xdot_hat_i, xdot_i)|.

    A point where the product of the norms is at most ``min_norm_product``, or where the
    cosine is not finite (NaN in either velocity), contributes 0. With the default 1e-10 the
    mean of this is :func:`direction_error`; with ``min_norm_product=0`` it is ds-opt's
    ``edot_error.m`` exactly, where 0/0 gives NaN and ``if isnan(...) ... = 0``.

    Parameters
    ----------
    predicted, demonstrated : array, shape (n, d)
    min_norm_product : float, default 1e-10
        ``||xdot_hat_i|| ||xdot_i||`` at or below this counts as an undefined direction.

    Returns
    -------
    array, shape (n,)
        Values in [0, 2].
    """
    p, q = _pair(predicted, demonstrated)
    if not (np.isfinite(min_norm_product) and min_norm_product >= 0):
        raise ValueError(f"min_norm_product must be a finite number >= 0, got {min_norm_product}")
    den = np.linalg.norm(p, axis=1) * np.linalg.norm(q, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.sum(p * q, axis=1) / den
    ok = (den > min_norm_product) & np.isfinite(cos)
    return np.where(ok, np.abs(1.0 - np.where(ok, cos, 1.0)), 0.0)


def dtw_distance(s: np.ndarray, t: np.ndarray) -> float:
    """Dynamic time warping distance (unnormalised sum of Euclidean point distances).

    D(i, j) = ||s_i - t_j|| + min(D(i-1, j), D(i, j-1), D(i-1, j-1)); returns D(n, m). No
    window: this is ds-opt's DTWD (``thirdparty/dtwd/dynamic_time_warping_v2.1/dtw.m`` by Quan
    Wang, called with two arguments, so its window ``w = Inf``).

    Parameters
    ----------
    s : array, shape (n, d)
    t : array, shape (m, d)
    """
    s = np.atleast_2d(np.asarray(s, dtype=float))
    t = np.atleast_2d(np.asarray(t, dtype=float))
    if s.shape[1] != t.shape[1]:
        raise ValueError(f"dimension mismatch: {s.shape} vs {t.shape}")
    if len(s) == 0 or len(t) == 0:
        raise ValueError("dtw_distance needs two non-empty sequences")
    kernel = _dtw_kernel() if np.all(np.isfinite(s)) and np.all(np.isfinite(t)) else None
    if kernel is not None:
        s, t = np.ascontiguousarray(s), np.ascontiguousarray(t)
        rows = np.empty(3 * (len(t) + 1))  # two rows of D and one of distances
        ptr = ctypes.POINTER(ctypes.c_double)
        return float(kernel(s.ctypes.data_as(ptr), len(s), t.ctypes.data_as(ptr), len(t),
                            s.shape[1], rows.ctypes.data_as(ptr)))
    return _dtw_numpy(s, t)


def _dtw_numpy(s: np.ndarray, t: np.ndarray) -> float:
    """:func:`dtw_distance` in numpy (the reference; used without a C compiler, and for
    sequences with non-finite values, where it propagates NaN as the published code does)."""
    cost = cdist(s, t)  # (n, m) without the (n, m, d) differences: 7-D demos stay small
    n, m = cost.shape
    D = np.full((n + 1, m + 1), np.inf)
    D[0, 0] = 0.0
    # anti-diagonal sweep: all cells with i + j = k depend only on diagonals k-1 and k-2
    for k in range(2, n + m + 1):
        i = np.arange(max(1, k - m), min(n, k - 1) + 1)
        j = k - i
        D[i, j] = cost[i - 1, j - 1] + np.minimum(np.minimum(D[i - 1, j], D[i, j - 1]),
                                                  D[i - 1, j - 1])
    return float(D[n, m])


#: :func:`dtw_distance` in C: row by row, the same operations in the same order as
#: :func:`_dtw_numpy` (squared differences summed over the dimensions, the root, the minimum of
#: the three neighbours), so both give the same number
_DTW_SOURCE = b"""
#include <math.h>
/* each row's point distances first (a loop without dependences, which the compiler
   vectorises: sqrt is exact, so the distances are the same numbers), then the recurrence */
static void costs(const double *si, const double *t, long m, long d, double *cost)
{
    long j, k;
    if (d == 2) {
        for (j = 0; j < m; ++j) {
            double e0 = si[0] - t[2 * j], e1 = si[1] - t[2 * j + 1];
            cost[j] = sqrt(e0 * e0 + e1 * e1);
        }
        return;
    }
    for (j = 0; j < m; ++j) {
        const double *tj = t + j * d;
        double acc = 0.0;
        for (k = 0; k < d; ++k) {
            double e = si[k] - tj[k];
            acc += e * e;
        }
        cost[j] = sqrt(acc);
    }
}

double seds_dtw(const double *s, long n, const double *t, long m, long d, double *rows)
{
    double *prev = rows, *cur = rows + (m + 1), *cost = rows + 2 * (m + 1), *swap;
    long i, j;
    prev[0] = 0.0;
    for (j = 1; j <= m; ++j) prev[j] = INFINITY;
    for (i = 1; i <= n; ++i) {
        costs(s + (i - 1) * d, t, m, d, cost);
        cur[0] = INFINITY;
        for (j = 1; j <= m; ++j) {
            double a = prev[j], b = cur[j - 1], c = prev[j - 1];
            a = b < a ? b : a;
            a = c < a ? c : a;
            cur[j] = cost[j - 1] + a;
        }
        swap = prev; prev = cur; cur = swap;
    }
    return prev[m];
}
"""
_DTW_LOCK = threading.Lock()
_DTW: list = []  # [the ctypes function or None], once tried


def _dtw_kernel():
    """The compiled DTW (built once into the package's cache, :mod:`seds_casadi.codegen.cache`),
    or None without a compiler (then numpy's anti-diagonal sweep is used, about 20x slower on
    LASA's 500-point paths)."""
    with _DTW_LOCK:
        if not _DTW:
            from ..codegen.cache import CompileError, compiler_available, shared_library
            from ..codegen.simd import load_library

            fn = None
            if compiler_available():
                try:
                    fn = load_library(shared_library(
                        _DTW_SOURCE, "dtw", ("-O2", "-ftree-vectorize", "-fno-math-errno"),
                        ("-lm",)))
                    fn = fn.seds_dtw
                    fn.restype = ctypes.c_double
                    p = ctypes.POINTER(ctypes.c_double)
                    fn.argtypes = [p, ctypes.c_long, p, ctypes.c_long, ctypes.c_long, p]
                except (CompileError, OSError, AttributeError) as exc:
                    _LOG.warning("compiling the DTW kernel failed (%s); using numpy", exc)
                    fn = None
            _DTW.append(fn)
        return _DTW[0]


def swept_error_area(reproduction: np.ndarray, demonstration: np.ndarray) -> float:
    """Swept error area (2-D): sum over t of the quadrilateral (x_t, x_t+1, xhat_t+1, xhat_t).

    Both sequences are resampled to the same length by linear interpolation in their index.
    """
    r = np.asarray(reproduction, dtype=float)
    q = np.asarray(demonstration, dtype=float)
    if r.ndim != 2 or q.ndim != 2 or r.shape[1] != 2 or q.shape[1] != 2:
        raise ValueError("swept_error_area is defined for 2-D trajectories of shape (n, 2)")
    n = max(len(r), len(q))
    r = _resample(r, n)
    q = _resample(q, n)
    a, b, c, d = q[:-1], q[1:], r[1:], r[:-1]
    # shoelace formula for each quadrilateral (a, b, c, d)
    xs = np.stack([a[:, 0], b[:, 0], c[:, 0], d[:, 0]], axis=1)
    ys = np.stack([a[:, 1], b[:, 1], c[:, 1], d[:, 1]], axis=1)
    area = 0.5 * np.abs(np.sum(xs * np.roll(ys, -1, axis=1) - ys * np.roll(xs, -1, axis=1), axis=1))
    return float(np.sum(area))


def simulate_until_slow(field, starts: np.ndarray, dt: float = 0.01, speed_tol: float = 0.1,
                        max_steps: int = 3000, window: int = 4, substeps: int = 1,
                        return_peaks: bool = False, method: str = "euler"):
    """Forward-Euler reproductions from several starts, integrated together until all are slow.

    The reproduction rule of the published LASA evaluation (ds-opt's ``Simulation.m`` from the
    SEDS library, called with ``dt = 0.01``, ``i_max = 3000``, ``tol = 0.1``): with
    x_0 = the starts, v_i = f(x_i) and x_{i+1} = x_i + dt v_i, stop at the first step i >= 3
    where every component of v_{i-3}, ..., v_i of *every* start is below ``speed_tol`` in
    magnitude, or when i reaches ``max_steps - 2``; the point x_{i+1} just computed is dropped,
    so the result holds x_0, ..., x_i (at most ``max_steps - 1`` points). The target is where
    ``field`` vanishes (ds-opt passes x - x* with x* = 0 for LASA).

    Parameters
    ----------
    field : callable
        f(X) for an array X of shape (m, d), returning the velocities, shape (m, d).
    starts : array, shape (m, d)
    dt : float, default 0.01
        Time step [s].
    speed_tol : float, default 0.1
        Per-component speed threshold (the data's units per second; mm/s for LASA).
    max_steps : int, default 3000
        ds-opt's ``i_max``.
    window : int, default 4
        Number of consecutive slow steps required (ds-opt: ``xd(:, end-3:end, :)``, 4).
    substeps : int, default 1
        Euler steps of ``dt / substeps`` per recorded step (the protocol: 1). The result is still
        sampled every ``dt`` and the stop rule reads the velocity at the recorded points, so a
        stiff model (``dt * stiffness > 1``, where explicit Euler at ``dt`` overshoots) can be
        reproduced faithfully and compared with the same DTW as a soft one.
    method : {"euler", "rk4"}, default "euler"
        The sub-steps' scheme (the protocol: Euler). With ``"rk4"`` each sub-step of
        ``dt / substeps`` is a classical Runge-Kutta step; the stop rule still reads f at the
        recorded points.
    return_peaks : bool, default False
        Also return each reproduction's peak speed: the largest ||f|| over every point the
        integration visited up to its last kept point, sub-steps included (the recorded points
        alone can miss a sharp peak: a hitting motion sampled at 20 Hz read 1.06 for a peak
        of 1.29).

    Returns
    -------
    array, shape (T, m, d)
        The positions; T is the same for every start.
    peaks : array, shape (m,)
        Only with ``return_peaks``.
    """
    x = np.atleast_2d(np.asarray(starts, dtype=float)).copy()
    if not np.all(np.isfinite(x)):
        raise ValueError("starts contain NaN or infinite values")
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a positive time step, got {dt}")
    if not (np.isfinite(speed_tol) and speed_tol > 0):
        raise ValueError(f"speed_tol must be positive, got {speed_tol}")
    window, max_steps = int(window), int(max_steps)
    if window < 1:
        raise ValueError(f"window must be at least 1, got {window}")
    if max_steps < window + 1:
        raise ValueError(f"max_steps must be at least window + 1 = {window + 1}, got {max_steps}")
    substeps = int(substeps)
    if substeps < 1:
        raise ValueError(f"substeps must be a positive integer, got {substeps}")
    h = dt / substeps
    if method not in ("euler", "rk4"):
        raise ValueError(f"method must be 'euler' or 'rk4', got {method!r}")
    rk4 = method == "rk4"
    if isinstance(field, ca.Function):
        paths, peaks = _simulate_function(field, x, h, substeps, float(speed_tol), window,
                                          max_steps, rk4)
        return (paths, peaks) if return_peaks else paths

    def f(y):
        return np.asarray(field(y), dtype=float).reshape(y.shape)

    def step(y, v):  # one sub-step from y, where f(y) = v
        if not rk4:
            return y + h * v
        k2 = f(y + 0.5 * h * v)
        k3 = f(y + 0.5 * h * k2)
        return y + (h / 6.0) * (v + 2.0 * k2 + 2.0 * k3 + f(y + h * k3))

    traj = [x]
    slow = []  # per step: every component of every start below speed_tol
    peaks = np.zeros(len(x))
    i = 0
    while True:
        v = f(x)
        slow.append(bool(np.all(np.abs(v) < speed_tol)))
        peaks = np.fmax(peaks, np.linalg.norm(v, axis=1))
        x = step(x, v)
        sub = np.zeros(len(x))
        for _ in range(substeps - 1):
            v = f(x)
            sub = np.fmax(sub, np.linalg.norm(v, axis=1))
            x = step(x, v)
        if i >= window - 1 and (all(slow[-window:]) or i >= max_steps - 2):
            break  # x (x_{i+1}) is not kept
        peaks = np.fmax(peaks, sub)
        traj.append(x)
        i += 1
    return (np.stack(traj), peaks) if return_peaks else np.stack(traj)


#: recorded steps per call of :func:`_simulate_function`'s compiled loop
_CHUNK = 128


def reproduction_threads(n_starts: int) -> int:
    """Threads that integrate ``n_starts`` reproductions side by side: the environment
    variable ``SEDS_CASADI_THREADS`` if set (worker processes set 1), else up to two, no
    more than the starts nor the cores this process may run on."""
    env = os.environ.get("SEDS_CASADI_THREADS")
    if env is not None:
        try:
            return max(1, min(int(env), n_starts))
        except ValueError:
            raise ValueError(f"SEDS_CASADI_THREADS must be a positive integer, got {env!r}") \
                from None
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    return max(1, min(2, n_starts, cores))


def _simulate_function(f: ca.Function, x: np.ndarray, h: float, substeps: int,
                       speed_tol: float, window: int, max_steps: int, rk4: bool = False
                       ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`simulate_until_slow` for a CasADi Function f: x (d,) -> f(x) (d,): the same
    steps, the same stop rule and the same peaks, with ``_CHUNK`` recorded steps of every
    start integrated by one call (``map`` over the starts, ``mapaccum`` over the steps)
    instead of one Python call per step; the steps computed past the stop are dropped."""
    m, d = x.shape
    if f.n_in() != 1 or f.n_out() < 1 or f.nnz_in(0) != d or f.nnz_out(0) != d:
        raise ValueError(f"the field must map a point of {d} coordinates to a velocity of {d}")
    def step(y, v):  # one sub-step from y, where f(y) = v (as the loop's)
        if not rk4:
            return y + h * v
        k2 = f(y + 0.5 * h * v)
        k3 = f(y + 0.5 * h * k2)
        return y + (h / 6.0) * (v + 2.0 * k2 + 2.0 * k3 + f(y + h * k3))

    xs = ca.MX.sym("x", d)
    v = f(xs)
    x1 = step(xs, v)
    sub = ca.MX(0)
    if substeps > 1:  # the sub-steps carry the largest speed met between recorded points
        z = ca.MX.sym("z", d + 1)
        fz = f(z[:d])
        one = ca.Function("substep", [z], [ca.vertcat(step(z[:d], fz),
                                                      ca.fmax(z[d], ca.norm_2(fz)))])
        out = one.fold(substeps - 1)(ca.vertcat(x1, 0))
        x1, sub = out[:d], out[d]
    n = _CHUNK
    threads = reproduction_threads(m)
    # each start's chunk of steps (mapaccum), the starts side by side (map), on `threads`
    # threads of CasADi's own (the starts are independent: the same numbers on any number)
    step = ca.Function("step", [xs], [x1, v, sub]).mapaccum(n)
    steps = step.map(m, "thread", threads) if threads > 1 else step.map(m)
    traj = [x[None]]
    slow_count = [0]  # slow_count[j]: how many of steps 0 .. j-1 were slow
    peaks = np.zeros(m)
    cur = ca.DM(x.T)
    i = 0  # the index of the chunk's first step
    while True:
        X, V, S = steps(cur)  # start by start: columns [start 0's n steps, start 1's, ...]
        Xn = np.asarray(X).T.reshape(m, n, d).transpose(1, 0, 2)
        Vn = np.asarray(V).T.reshape(m, n, d).transpose(1, 0, 2)
        Sn = np.asarray(S).reshape(m, n).T
        slow = np.all(np.abs(Vn) < speed_tol, axis=(1, 2))
        slow_count.extend((slow_count[-1] + np.cumsum(slow)).tolist())
        # the loop's stop rule at each step j = i + s, all at once: the last `window` steps
        # slow, or the step limit
        j = i + np.arange(n)
        counts = np.asarray(slow_count)
        in_window = counts[j + 1] - counts[np.maximum(j - window + 1, 0)]
        stop = (j >= window - 1) & ((in_window == window) | (j >= max_steps - 2))
        first = int(np.argmax(stop)) if stop.any() else n
        speeds = np.linalg.norm(Vn[:first + 1 if first < n else n], axis=2)
        peaks = np.fmax(peaks, np.fmax.reduce(speeds, axis=0)) if len(speeds) else peaks
        if first > 0:
            peaks = np.fmax(peaks, np.fmax.reduce(Sn[:first], axis=0))
            traj.append(Xn[:first])
        if first < n:
            return np.concatenate(traj), peaks
        i += n
        cur = ca.DM(Xn[-1].T)


def reproduction_dtw(field, starts: np.ndarray, references, return_paths: bool = False,
                     **simulate_kw) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """DTW distance of each reproduction to its reference trajectory (ds-opt's DTWD).

    The starts are integrated together by :func:`simulate_until_slow` (keyword arguments go
    there) and each reproduction is compared with its whole reference by :func:`dtw_distance`.

    Parameters
    ----------
    field : callable
        f(X), X of shape (m, d) -> velocities (m, d).
    starts : array, shape (m, d)
    references : sequence of m arrays, each shape (T_n, d)
    return_paths : bool, default False
        Also return the reproductions.

    Returns
    -------
    array, shape (m,)
        The DTW distances (units of the positions; mm for LASA).
    paths : array, shape (T, m, d)
        Only with ``return_paths``: the output of :func:`simulate_until_slow`.
    """
    starts = np.atleast_2d(np.asarray(starts, dtype=float))
    if len(references) != len(starts):
        raise ValueError(f"{len(starts)} starts for {len(references)} reference trajectories; "
                         "give one start per reference")
    out = simulate_until_slow(field, starts, **simulate_kw)
    paths = out[0] if simulate_kw.get("return_peaks") else out
    threads = reproduction_threads(len(references))
    if threads > 1 and _dtw_kernel() is not None:  # the compiled DTW runs without the GIL
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(threads) as pool:
            dtw = np.array(list(pool.map(lambda n: dtw_distance(paths[:, n], references[n]),
                                         range(len(references)))))
    else:
        dtw = np.array([dtw_distance(paths[:, n], ref) for n, ref in enumerate(references)])
    if not return_paths:
        return dtw
    return (dtw, *out) if simulate_kw.get("return_peaks") else (dtw, paths)


def _resample(x: np.ndarray, n: int) -> np.ndarray:
    if len(x) == n:
        return x
    u = np.linspace(0, len(x) - 1, n)
    return np.stack([np.interp(u, np.arange(len(x)), x[:, j]) for j in range(x.shape[1])], axis=1)


def _pair(p, q) -> tuple[np.ndarray, np.ndarray]:
    p = np.atleast_2d(np.asarray(p, dtype=float))
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if p.shape != q.shape:
        raise ValueError(f"shape mismatch: predicted {p.shape} vs demonstrated {q.shape}")
    return p, q
