"""Robots and control (extra ``[robots]``: Pinocchio and example-robot-data): robot models from
the shipped URDFs (Barrett WAM, Katana; :mod:`.urdf`) and example-robot-data arms
(:mod:`.models`), the club (:mod:`.club`), and the 500 Hz controller (damped-least-squares IK,
inverse dynamics; :mod:`.controller`, with :mod:`.orientation`) that executes the hitting
motion, the start placement (:mod:`.placement`), swings simulated on the forward dynamics
(:mod:`.swing`, :mod:`.dynamics`) and the joints' velocity limits' bound on the club speed at a
hit (:mod:`.speed_bound`, a linear program). It imports :mod:`seds_casadi.motion` and the layers
below it.
"""

try:
    import pinocchio  # noqa: F401
except ImportError as exc:  # pragma: no cover - exercised in an environment without pin
    raise ImportError(
        "seds_casadi.robots needs Pinocchio and example-robot-data; install them with "
        "pip install 'seds_casadi[robots]'"
    ) from exc

from .club import DEFAULT_CLUBS, Club
from .controller import Gains, SwingController
from .dynamics import effective_mass, gravity_ratio
from .models import Robot, load_robot, robot_names
from .orientation import face_orientation, orientation_error
from .placement import default_base, place_head, place_robot
from .swing import SwingResult, simulate_swing
from .urdf import katana_urdf, wam_urdf

__all__ = ["Robot", "Club", "DEFAULT_CLUBS", "load_robot", "robot_names", "wam_urdf",
           "katana_urdf", "SwingController", "SwingResult", "Gains", "simulate_swing",
           "place_robot", "place_head", "default_base", "effective_mass", "gravity_ratio",
           "face_orientation", "orientation_error"]
