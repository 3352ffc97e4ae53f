"""Simulation in exudyn (extra ``[sim]``): the arm as a kinematic tree driven by the same 500 Hz
controller, a club face, and a ball in contact with the field's triangle mesh, to check that a
hit really sinks the ball. It imports :mod:`seds_casadi.robots`, :mod:`seds_casadi.minigolf`
and the layers below them.
"""

try:
    import exudyn  # noqa: F401
except ImportError as exc:  # pragma: no cover - exercised in an environment without exudyn
    raise ImportError(
        "seds_casadi.sim needs exudyn; install it with pip install 'seds_casadi[sim]'"
    ) from exc

from .exudyn_shot import ExudynShot, field_mesh, free_fall, simulate_shot_exudyn

__all__ = ["ExudynShot", "simulate_shot_exudyn", "field_mesh", "free_fall"]
