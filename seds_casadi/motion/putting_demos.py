"""Synthetic, human-like putting demonstrations (club-head positions), for the hitting motion.

The project has no kinesthetic recordings, so it makes its own. Frame: the ball at the origin,
z up, the default hit along +x. Each demonstration starts at rest at a point behind and around the
ball (a backswing: behind, to the side, and raised), and reaches the ball at time T with a
horizontal velocity of about 1 m/s roughly along +x. Between the two the path is a cubic Hermite
curve along the target line (zero velocity at the start, the hitting velocity at the end), while
the sideways and vertical offsets fade as (1 - s)^3 (plus a bend ``b sin^2(pi s) (1 - s)``): the
club comes onto the target line behind the ball and runs nearly straight through it, as in a
putt. Speeds rise smoothly
from rest to the hit; durations, bends, hitting speeds (+-10 %) and directions (+-4 deg) differ
between demonstrations. Samples are taken at 20 Hz as in the paper's Katana experiment, the last one
exactly at the ball.
"""

from __future__ import annotations

import os

import numpy as np

from ..core._io import data_folder
from ..core.demo_files import load_demonstrations
from ..core.demonstrations import Demonstrations


def generate_putting_demos(n_demos: int = 7, rate: float = 20.0, hitting_speed: float = 1.0,
                           random_state: int | None = 0) -> Demonstrations:
    """Generate putting demonstrations ending at the ball (the origin).

    Parameters
    ----------
    n_demos : int
        Number of demonstrations.
    rate : float
        Sampling rate [Hz].
    hitting_speed : float
        Mean club-head speed at the ball [m/s].
    random_state : int or None

    Returns
    -------
    Demonstrations
        Positions [m] and exact velocities [m/s], target at the origin.
    """
    if int(n_demos) < 1:
        raise ValueError(f"n_demos must be at least 1, got {n_demos}")
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"rate must be positive, got {rate}")
    if not (np.isfinite(hitting_speed) and hitting_speed > 0):
        raise ValueError(f"hitting_speed must be positive, got {hitting_speed}")
    rng = np.random.default_rng(random_state)
    pos, vel = [], []
    for _ in range(int(n_demos)):
        start = np.array([rng.uniform(-0.55, -0.30), rng.uniform(-0.22, 0.22),
                          rng.uniform(0.08, 0.30)])
        T = rng.uniform(0.9, 1.3)
        heading = np.deg2rad(rng.uniform(-4.0, 4.0))
        v_end = hitting_speed * rng.uniform(0.9, 1.1) * np.array(
            [np.cos(heading), np.sin(heading), 0.0])
        bend = np.array([0.0, rng.uniform(-0.06, 0.06), rng.uniform(0.0, 0.06)])
        n = int(np.floor(T * rate)) + 1
        t = np.r_[np.arange(n) / rate, T] if (n - 1) / rate < T - 1e-9 else np.arange(n) / rate
        s = t / T
        # along the line (x): cubic Hermite from rest at x0 to the ball with the hitting speed
        h00 = 2 * s**3 - 3 * s**2 + 1
        h11 = s**3 - s**2
        dh00 = (6 * s**2 - 6 * s) / T
        dh11 = (3 * s**2 - 2 * s) / T
        # across the line (y, z): offsets that leave the start at rest and fade as (1 - s)^3, so
        # the club comes onto the target line behind the ball and runs straight through it
        fade = (1 - s) ** 3 * (1 + 3 * s)
        dfade = -12 * s * (1 - s) ** 2 / T
        bump = np.sin(np.pi * s) ** 2 * (1 - s)
        dbump = (2 * np.pi * np.sin(np.pi * s) * np.cos(np.pi * s) * (1 - s)
                 - np.sin(np.pi * s) ** 2) / T
        P = np.empty((len(s), 3))
        V = np.empty((len(s), 3))
        P[:, 0] = h00 * start[0] + T * h11 * v_end[0]
        V[:, 0] = dh00 * start[0] + T * dh11 * v_end[0]
        for j in (1, 2):
            P[:, j] = fade * start[j] + bump * bend[j] + T * h11 * v_end[j]
            V[:, j] = dfade * start[j] + dbump * bend[j] + T * dh11 * v_end[j]
        pos.append(P)
        vel.append(V)
    return Demonstrations(pos, velocities=vel, target=np.zeros(3), dt=1.0 / rate)


#: the shipped putting demonstrations (7 demos, 3-D, 20 Hz, ball at the origin, hit along +x),
#: made by ``generate_putting_demos(random_state=0)``
HITTING_DEMOS_FILE = os.path.join(data_folder("seds_casadi.data"), "hitting_demos.npz")


def load_hitting_demos(path: str | None = None) -> Demonstrations:
    """The default putting demonstrations shipped with the package (or a file of your own).

    Parameters
    ----------
    path : str, optional
        A ``.npz`` or ``.csv`` demonstrations file (formats in :mod:`seds_casadi.core.demonstrations`)
        with the ball at the origin. Default: the shipped set.
    """
    return load_demonstrations(path or HITTING_DEMOS_FILE, target=[0.0, 0.0, 0.0])
