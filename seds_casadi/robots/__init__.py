"""Robots and control (extra ``[robots]``: Pinocchio and example-robot-data): robot models from
the shipped URDFs (Barrett WAM, Katana) and example-robot-data arms, the club, and the 500 Hz
controller (damped-least-squares IK, inverse dynamics) that executes the hitting motion. It
imports :mod:`seds_casadi.motion` and the layers below it.
"""

try:
    import pinocchio  # noqa: F401
except ImportError as exc:  # pragma: no cover - exercised in an environment without pin
    raise ImportError(
        "seds_casadi.robots needs Pinocchio and example-robot-data; install them with "
        "pip install 'seds_casadi[robots]'"
    ) from exc

from .control import (
    Gains,
    SwingController,
    SwingResult,
    default_base,
    place_head,
    place_robot,
    simulate_swing,
)
from .models import DEFAULT_CLUBS, Club, Robot, katana_urdf, load_robot, robot_names, wam_urdf

__all__ = ["Robot", "Club", "DEFAULT_CLUBS", "load_robot", "robot_names", "wam_urdf",
           "katana_urdf", "SwingController", "SwingResult", "Gains", "simulate_swing",
           "place_robot", "place_head", "default_base"]
