"""The game (needs the ``[robots]`` extra; exudyn only for the ``"exudyn"`` engine): where the
minigolf layer meets the robot. A :class:`~seds_casadi.game.scene.Scene` is the robot (standing
beside the ball, holding its club), the field and the hitting motion, loaded once per worker
process; a :class:`~seds_casadi.game.shot.Shot` is one situation with its hitting parameters;
:func:`~seds_casadi.game.shot.play_shot` plays a shot in a scene on an engine (the fast ball
model after the arm's simulated swing, or exudyn's multibody model) and returns a
:class:`~seds_casadi.game.shot.ShotResult` that says what happened and, for a miss, why. The
arm's launch of the ball (:func:`~seds_casadi.game.shot.swing_launch`) is defined once: the
round's shots use it directly, and :func:`~seds_casadi.game.launch.calibrate_launch` measures it
over (alpha, kappa) so that the teacher searches the arm's own launch. It imports
:mod:`seds_casadi.sim`, :mod:`seds_casadi.robots`, :mod:`seds_casadi.minigolf` and the layers
below them; :mod:`seds_casadi.app` builds on it.
"""

from .launch import calibrate_launch
from .scene import Scene, SceneSpec
from .shot import (
    ENGINES,
    MISSES,
    Shot,
    ShotResult,
    play_round,
    play_shot,
    play_shots,
    swing_launch,
)

__all__ = ["Scene", "SceneSpec", "Shot", "ShotResult", "play_shot", "play_shots", "play_round",
           "swing_launch", "calibrate_launch", "ENGINES", "MISSES"]
