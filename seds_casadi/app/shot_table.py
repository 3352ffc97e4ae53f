"""The rows of ``shots.csv``: a played shot (:class:`~seds_casadi.game.shot.ShotResult`) as
one row of named, unit-suffixed columns."""

from __future__ import annotations

import numpy as np

from ..game.shot import ShotResult

__all__ = ["SHOT_COLUMNS", "shot_row"]

#: columns of ``shots.csv``; a unit ends the name (m, deg), dimensionless ones have none
#: (kappa, the gain; speed_error, relative to the commanded speed, signed: negative when the
#: club is slower). direction_error_deg is the
#: club velocity's error at the hit, launch_direction_error_deg the club face's (the ball
#: leaves along the face's normal); within_limits: no joint over a speed, torque or position
#: limit during the swing; miss: the kind of miss (:data:`~seds_casadi.game.shot.MISSES`),
#: miss_reason: why, in words (:attr:`~seds_casadi.game.shot.ShotResult.reason`); phase:
#: ``adapt`` for a shot of the adaptation budget (``play --adapt``), ``test`` for the round;
#: adapt_shots: the adaptation shots the model had learned from when it played this shot
SHOT_COLUMNS = ("method", "shot", "ball_x_m", "ball_y_m", "hole_x_m", "hole_y_m", "alpha_deg",
                "kappa", "hit", "sunk", "direction_error_deg", "speed_error",
                "launch_direction_error_deg", "within_limits", "final_x_m", "final_y_m",
                "sunk_exudyn", "strategy", "miss", "miss_reason", "phase", "adapt_shots")


def shot_row(res: ShotResult) -> dict:
    """A played shot as its row of ``shots.csv`` (:data:`SHOT_COLUMNS`: the angle in degrees),
    plus the ball's ``path`` when the robot hit it."""
    shot = res.shot
    row = {"method": shot.method, "shot": shot.index, "strategy": shot.strategy,
           "ball_x_m": float(shot.ball[0]), "ball_y_m": float(shot.ball[1]),
           "hole_x_m": float(shot.hole[0]), "hole_y_m": float(shot.hole[1]),
           "alpha_deg": float(np.rad2deg(shot.alpha)), "kappa": shot.kappa, "hit": res.hit,
           "sunk": res.sunk, "direction_error_deg": res.direction_error_deg,
           "speed_error": res.speed_error,
           "launch_direction_error_deg": res.launch_direction_error_deg,
           "within_limits": "" if res.within_limits is None else res.within_limits,
           "final_x_m": float(res.final_position[0]), "final_y_m": float(res.final_position[1]),
           "sunk_exudyn": "", "miss": res.miss, "miss_reason": res.reason,
           "phase": "test", "adapt_shots": 0}
    if res.path is not None:
        row["path"] = res.path
    return row
