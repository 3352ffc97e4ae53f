"""What the ball model's two engines share: its rolling constants and the outcome of a batch
of shots.

The equations are in :mod:`seds_casadi.minigolf.ball` (the numpy reference, and
:func:`~seds_casadi.minigolf.ball.simulate_shots`, which picks an engine) and
:mod:`seds_casadi.minigolf.ball_kernel` (the compiled engine); the golf ball's mass and radius
and g are in :mod:`seds_casadi.motion.golf`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ShotResult", "MU_SLIDE", "STOP_SPEED"]

#: kinetic friction coefficient of the ball sliding on the green (the skid after the impact)
MU_SLIDE = 0.2
#: speed [m/s] below which a rolling ball that gravity cannot move comes to rest
STOP_SPEED = 0.005


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
