"""Validation in exudyn (extra ``[sim]``): the arm, its club and a ball rolling on the field's
triangle mesh.

The independent judge of the robot simulation (:mod:`seds_casadi.robots.swing`) and of the
fast ball model (:mod:`seds_casadi.minigolf.ball`): the same shot is simulated as a multibody
system with contact, and the two are compared (``seds-casadi validate``).

* **Arm**: an exudyn ``ObjectKinematicTree`` converted from the robot's Pinocchio model (same
  joint placements, masses, centres of mass, inertias, club included; free fall matches
  Pinocchio's ABA to 1e-13 rad), driven by the same
  :class:`~seds_casadi.robots.controller.SwingController` from a pre-step function: torques every
  2 ms from exudyn's joint state, not prescribed motion (:mod:`seds_casadi.sim.arm`).
* **Club face**: a flat 4 x 4 cm square (two contact triangles) on the club's link at the
  ``club_head`` frame, normal along the face normal: the ball leaves along the face's normal
  with whatever the arm's inertia and the controller give, not the fast model's formula.
  Face-ball contact damping is set for a restitution of 0.8.
* **Field**: a triangle mesh of z = H(x, y) (:func:`~seds_casadi.sim.mesh.field_mesh`, normals
  up), plus vertical wall strips (damped for the field's wall restitution, frictionless as in
  the fast model, so the wall's impulse leaves the ball's spin alone) on fields with walls
  (:mod:`seds_casadi.sim.mesh`). Ball-field contact is exudyn's sphere-triangle contact with
  Coulomb friction (mu = 0.2): the skid after the impact and its turn into rolling come out of
  the contact.
* **Rolling resistance**: exudyn's contact has Coulomb friction only, so a force rho m g (times
  the field's local friction factor) against the ball's velocity acts at its centre while it
  rolls (contact point not slipping); on a rolling ball it decelerates it by (5/7) rho g.
* **Ball**: a rigid sphere (46 g, radius 21.35 mm, solid-sphere inertia 2/5 m r^2).
* **Ball at rest**: held at its place by a horizontal spring-damper until the club touches it
  (on a slope it would otherwise roll away while the arm swings), then released.
* **Hole**: a capture region: the ball drops when its centre is over the hole and its speed is
  below the capture speed for its offset (the fast model's chord criterion).
* Without an arm (``simulate_shot_exudyn(field, ball, club_velocity)``), a free club-head
  sphere of the impact model's effective mass (0.35 kg) strikes the ball, braked after the
  contact: a check of the impact and rolling models alone.

The system is built by :func:`seds_casadi.sim.scene.build_scene` and run by
:func:`seds_casadi.sim.shot.simulate_shot_exudyn`. Integration: Dormand-Prince 5(4) with
Lie-group rotations and automatic steps: during the swing and the impact at most 0.2 ms
(tolerance 1e-7), from 20 ms after the launch at most 1 ms (tolerance 1e-6). A fixed 0.2 ms
Runge-Kutta 4 step (14 steps per period of the stiffest contact, face on ball) lost up to 2 % of
the ball's launch speed in the impact, depending on where the contact fell between steps;
adaptive steps throughout at up to 1 ms applied the controller's torques up to a step late and
moved launch speeds by up to 1 %.

Modules: ``mesh`` meshes the field, ``arm`` converts the robot, ``scene`` builds the system of
one shot, ``shot`` runs it. The package imports :mod:`seds_casadi.robots`,
:mod:`seds_casadi.minigolf` and the layers below them.
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
