"""Accuracy metrics of the LASA evaluation protocol (LPV-DS evaluation, CoRL 2018).

All functions take arrays of shape (n, d) and are vectorised.
"""

from __future__ import annotations

import numpy as np

__all__ = ["velocity_rmse", "direction_error", "dtw_distance", "swept_error_area"]


def velocity_rmse(predicted: np.ndarray, demonstrated: np.ndarray) -> float:
    """Velocity RMSE: mean over points of sqrt((1/d) sum_j (xdot_hat_ij - xdot_ij)^2).

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


def dtw_distance(s: np.ndarray, t: np.ndarray) -> float:
    """Dynamic time warping distance (unnormalised sum of Euclidean point distances).

    D(i, j) = ||s_i - t_j|| + min(D(i-1, j), D(i, j-1), D(i-1, j-1)); returns D(n, m).

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
    cost = np.linalg.norm(s[:, None, :] - t[None, :, :], axis=2)
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
