"""Shared fixtures: small, seeded data sets for real IPOPT solves."""

import os

import numpy as np
import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

from seds_casadi import Demonstrations  # noqa: E402


def linear_demos(A: np.ndarray, starts: np.ndarray, dt: float = 0.02, steps: int = 60,
                 target=None) -> Demonstrations:
    """Demonstrations integrated exactly from xdot = A (x - x*) (a known stable system)."""
    from scipy.linalg import expm

    target = np.zeros(A.shape[0]) if target is None else np.asarray(target, float)
    E = expm(A * dt)
    pos, vel = [], []
    for x0 in starts:
        xs = [np.asarray(x0, float) - target]
        for _ in range(steps - 1):
            xs.append(E @ xs[-1])
        X = np.array(xs)
        pos.append(X + target)
        vel.append(X @ A.T)
    return Demonstrations(pos, velocities=vel, target=target)


@pytest.fixture(scope="session")
def spiral_demos() -> Demonstrations:
    A = np.array([[-1.0, -2.0], [2.0, -1.0]])
    starts = np.array([[2.0, 0.5], [1.5, 1.8], [-0.3, 2.2]])
    return linear_demos(A, starts, dt=0.05, steps=40)


@pytest.fixture(scope="session")
def curved_demos_3d() -> Demonstrations:
    """Three 3-D demonstrations that curve and end at a target with zero velocity."""
    rng = np.random.default_rng(3)
    t = np.linspace(0, 1, 40)[:, None]
    pos = []
    for _ in range(3):
        start = np.array([-0.5, 0.2, 0.3]) + 0.05 * rng.standard_normal(3)
        bend = np.array([0.0, 0.25, 0.0]) + 0.03 * rng.standard_normal(3)
        s = 3 * t**2 - 2 * t**3  # smooth start and stop
        pos.append(start * (1 - s) + bend * np.sin(np.pi * s) + np.array([0.1, 0.0, 0.05]) * s)
    return Demonstrations(pos, dt=0.025)


# Speed classes: a test that takes more than a few seconds (robots, exudyn, command-line runs,
# examples, Dask clusters, 50-swing figures) carries ``@pytest.mark.slow`` (a whole module:
# ``pytestmark = pytest.mark.slow``); ``pytest -m "not slow"`` runs the fast suite.
