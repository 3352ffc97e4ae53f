"""Simulation in exudyn (extra ``[sim]``): the arm as a kinematic tree driven by the same 500 Hz
controller, a club face, and a ball in contact with the field's triangle mesh, to check that a
hit really sinks the ball. ``mesh`` meshes the field, ``arm`` converts the robot, ``scene``
builds the system of one shot, ``shot`` runs it (``exudyn_shot`` describes the model and gathers
the names). It imports :mod:`seds_casadi.robots`, :mod:`seds_casadi.minigolf` and the layers
below them.
"""

try:
    import exudyn  # noqa: F401
except ImportError as exc:  # pragma: no cover - exercised in an environment without exudyn
    raise ImportError(
        "seds_casadi.sim needs exudyn; install it with pip install 'seds_casadi[sim]'"
    ) from exc

from .arm import free_fall
from .mesh import field_mesh
from .scene import Scene, build_scene
from .shot import ExudynShot, simulate_shot_exudyn

__all__ = ["ExudynShot", "simulate_shot_exudyn", "field_mesh", "free_fall", "build_scene",
           "Scene"]
