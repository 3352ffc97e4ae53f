"""Executing the hitting motion on a robot (paper Sections 6 and 7.1-7.2): the names of the
controller, the swing simulation and the start placement in one place.

The code lives in modules of one concept each, and is re-exported here (this module held all
of it before the package was split):

* :mod:`~seds_casadi.robots.controller`: the 500 Hz controller (damped-least-squares IK,
  inverse dynamics) and its compiled tick;
* :mod:`~seds_casadi.robots.swing`: swings simulated on the robot's forward dynamics;
* :mod:`~seds_casadi.robots.placement`: the base beside the ball and the start configuration;
* :mod:`~seds_casadi.robots.orientation`: the face orientation and the orientation error;
* :mod:`~seds_casadi.robots.dynamics`: gravity load and the effective mass at the club face.
"""

from .controller import Gains, SwingController, tick_function
from .dynamics import effective_mass, gravity_ratio
from .orientation import face_orientation, orientation_error
from .placement import default_base, place_head, place_robot
from .swing import SwingResult, simulate_swing

__all__ = ["SwingController", "SwingResult", "Gains", "simulate_swing", "place_head",
           "default_base", "place_robot", "gravity_ratio", "face_orientation",
           "effective_mass", "orientation_error", "tick_function"]
