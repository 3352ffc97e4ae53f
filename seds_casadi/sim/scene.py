"""The exudyn system of one shot, built in readable steps (:func:`build_scene`).

Ground, field mesh and walls with their contact (:func:`seds_casadi.sim.mesh.field_mesh`), the
ball held at its resting place until the club touches it, the club (a free head sphere, or the
robot arm with its club face, :mod:`seds_casadi.sim.arm`) and the loads that exudyn's contact
does not give: the rolling resistance on the ball and the brake on a free head. The result is a
:class:`Scene` holding the handles the run loop (:mod:`seds_casadi.sim.shot`) reads, and the
:class:`ShotState` that the loads and the run loop share.

Contact parameters: stiffnesses combine in series, dampings in parallel; ball-field
k ~ 4e4 N/m (the ball's weight sinks it 11 um), head-ball k = 2e5 N/m with the damping of the
impact's restitution (0.8 by default), walls damped for the field's wall restitution. Friction
(Coulomb, mu = 0.2) acts between field and ball only: walls and club are frictionless, as in
the fast model.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import exudyn as exu
import numpy as np
from exudyn.utilities import (
    InertiaSphere,
    LoadForceVector,
    MarkerBodyPosition,
    MarkerBodyRigid,
    ObjectConnectorCartesianSpringDamper,
)

from ..minigolf.ball import CLUB_MASS, RESTITUTION
from ..minigolf.ball_physics import MU_SLIDE
from ..minigolf.fields import Field
from ..motion.golf import BALL_MASS, BALL_RADIUS, G
from .arm import ExudynArm, add_arm
from .mesh import field_mesh, wall_mesh

__all__ = ["Scene", "ShotState", "FreeHead", "build_scene", "HEAD_RADIUS"]

HEAD_RADIUS = 0.008  # small enough to clear the field (the head only touches the ball)
# friction materials: 0 field, 1 ball, 2 club head, 3 walls
_FIELD, _BALL, _HEAD, _WALLS = 0, 1, 2, 3
K_BALL = K_HEAD = 4e5  # N/m, contact stiffness of the ball's and the head's spheres
K_FIELD = 4.4e4  # N/m, of the field's and the walls' triangles
_HOLDER_STIFFNESS = 2e3  # N/m, horizontal spring holding the ball until the club touches it


def damping_ratio(restitution: float) -> float:
    """Damping ratio zeta of a linear spring-damper contact with coefficient of restitution e:
    zeta = -ln(e) / sqrt(pi^2 + ln(e)^2)."""
    return -np.log(restitution) / np.sqrt(np.pi**2 + np.log(restitution) ** 2)


@dataclass
class ShotState:
    """The shot's progress: written by the run loop, read by the loads (which act only once
    the ball has left the club) and turned into the result."""

    launch: np.ndarray | None = None
    launch_time: float = np.nan
    contact: bool = False
    contact_time: float | None = None
    head_velocity: np.ndarray | None = None
    sunk: bool = False
    stopped: bool = False
    timed_out: bool = False
    slow: float = 0.0
    t_prev: float = 0.0
    rolling_from: float | None = None
    path: list = field(default_factory=list)
    heads: list = field(default_factory=list)

    @property
    def launched(self) -> bool:
        """The ball has left the club."""
        return self.launch is not None


@dataclass
class FreeHead:
    """A free club-head sphere of the impact model's effective mass (a shot without an arm)."""

    marker: int
    node: int
    give_up: float = np.inf

    def control(self, mbs, t: float) -> None:
        """Nothing to control: the head flies freely until the brake after the contact."""

    def head(self, mbs) -> tuple[np.ndarray, np.ndarray, None]:
        """The head's centre and velocity (no face normal: a sphere)."""
        return (np.asarray(mbs.GetNodeOutput(self.node, exu.OutputVariableType.Position)),
                np.asarray(mbs.GetNodeOutput(self.node, exu.OutputVariableType.Velocity)), None)


@dataclass
class Scene:
    """The handles of a built shot (:func:`build_scene`).

    Attributes
    ----------
    system : exudyn.SystemContainer
        Keeps the system alive.
    mbs : exudyn.MainSystem
    field : Field
    hole : array, shape (2,)
    ball_node : int
    holder : int
        The connector that holds the ball at rest until the club touches it.
    club : FreeHead or ExudynArm
        ``head(mbs)`` gives the club head's point, velocity and face normal (None for a
        sphere), ``control(mbs, t)`` runs the arm's controller, ``give_up`` is the time after
        which a swing that never touched the ball is a miss.
    state : ShotState
    """

    system: object
    mbs: object
    field: Field
    hole: np.ndarray
    ball_node: int
    holder: int
    club: FreeHead | ExudynArm
    state: ShotState


class RollingResistance:
    """The rolling resistance, a load on the ball: a force rho m g cos(theta) (times the
    field's local friction factor) against the ball's velocity at its centre, while it rolls
    (its contact point, at -r n from the centre with n the surface normal, hardly slips) and
    only after the launch (exudyn's contact has Coulomb friction only)."""

    def __init__(self, field: Field, ball_node: int, state: ShotState) -> None:
        self.surface = field.surface
        self.rho = field.rolling_resistance
        self.ball_node = ball_node
        self.state = state
        self.flat = field.surface.shape == "plane" and not np.any(field.surface.gradient(
            np.zeros((1, 2))))
        self.constant_friction = field.surface.shape != "rough"
        self._normal = [np.inf, np.inf, 0.0, 0.0, 1.0]  # x, y where the normal was taken, n

    def _surface_normal(self, px: float, py: float) -> tuple[float, float, float]:
        """The surface normal near (px, py), refreshed every 2 mm."""
        if self.flat:
            return 0.0, 0.0, 1.0
        cx, cy, nx, ny, nz = self._normal
        if (px - cx) ** 2 + (py - cy) ** 2 > 4e-6:
            gx, gy = self.surface.gradient(np.array([[px, py]]))[0]
            inv = 1.0 / (1.0 + gx * gx + gy * gy) ** 0.5
            nx, ny, nz = -gx * inv, -gy * inv, inv
            self._normal[:] = [px, py, nx, ny, nz]
        return nx, ny, nz

    def force(self, mbs, t: float, load) -> list[float]:
        """exudyn load user function: the force on the ball now."""
        zero = [0.0, 0.0, 0.0]
        if not self.state.launched:
            return zero
        vel_t = exu.OutputVariableType.Velocity
        vx, vy, vz = mbs.GetNodeOutput(self.ball_node, vel_t)
        s = (vx * vx + vy * vy + vz * vz) ** 0.5
        if s < 1e-9:
            return zero
        px, py, _ = mbs.GetNodeOutput(self.ball_node, exu.OutputVariableType.Position)
        nx, ny, nz = self._surface_normal(px, py)
        wx, wy, wz = mbs.GetNodeOutput(self.ball_node, exu.OutputVariableType.AngularVelocity)
        r = BALL_RADIUS
        sx = vx - r * (wy * nz - wz * ny)
        sy = vy - r * (wz * nx - wx * nz)
        sz = vz - r * (wx * ny - wy * nx)
        if sx * sx + sy * sy + sz * sz > (0.02 * s + 0.005) ** 2:
            return zero  # the contact point slips: the ball skids, no rolling resistance
        fac = (1.0 if self.constant_friction
               else float(self.surface.friction_factor(np.array([[px, py]]))[0]))
        # rho m g cos(theta): the resistance scales with the normal force (nz = cos(theta))
        f = self.rho * fac * BALL_MASS * G * nz / s
        return [-f * vx, -f * vy, -f * vz]


class HeadBrake:
    """After the contact the arm's resting mode stops the club (time constant 20 ms), so a free
    head does not catch up with the ball again: a load on the head."""

    def __init__(self, head_node: int, state: ShotState) -> None:
        self.head_node = head_node
        self.state = state

    def force(self, mbs, t: float, load) -> list[float]:
        """exudyn load user function: the braking force on the head now."""
        if not self.state.launched:
            return [0.0, 0.0, 0.0]
        vh = np.asarray(mbs.GetNodeOutput(self.head_node, exu.OutputVariableType.Velocity))
        return (-CLUB_MASS / 0.02 * vh).tolist()


def _general_contact(mbs, field: Field):
    """exudyn's general contact over the field, with friction between field and ball only."""
    gc = mbs.AddGeneralContact()
    gc.verboseMode = 0
    mu = np.zeros((4, 4))
    mu[_FIELD, _BALL] = mu[_BALL, _FIELD] = MU_SLIDE
    gc.SetFrictionPairings(mu)
    b = field.bounds
    gc.SetSearchTreeBox(pMin=[b[0] - 0.1, b[2] - 0.1, -1.0], pMax=[b[1] + 0.1, b[3] + 0.1, 1.0])
    gc.SetSearchTreeCellSize(numberOfCells=[max(1, int((b[1] - b[0]) / 0.1)),
                                            max(1, int((b[3] - b[2]) / 0.1)), 1])
    gc.sphereSphereContact = True
    return gc


def _add_field(gc, ground_marker: int, field: Field, mesh_spacing: float | None) -> None:
    """The field's surface mesh, and on fields with walls the wall strips, damped for the
    field's wall restitution (the same rule as head on ball)."""
    pts, tri = field_mesh(field, mesh_spacing)
    gc.AddTrianglesRigidBodyBased(rigidBodyMarkerIndex=ground_marker, contactStiffness=K_FIELD,
                                  contactDamping=2 * 0.7 * np.sqrt(4e4 * BALL_MASS),
                                  frictionMaterialIndex=_FIELD,
                                  pointList=pts.tolist(), triangleList=tri.tolist(),
                                  staticTriangles=True)
    if field.boundary == "walls":
        zeta_w = damping_ratio(min(max(field.wall_restitution, 1e-3), 0.999))
        wp, wt = wall_mesh(field)
        gc.AddTrianglesRigidBodyBased(rigidBodyMarkerIndex=ground_marker, contactStiffness=K_FIELD,
                                      contactDamping=2 * zeta_w * np.sqrt(4e4 * BALL_MASS),
                                      frictionMaterialIndex=_WALLS,
                                      pointList=wp.tolist(), triangleList=wt.tolist(),
                                      staticTriangles=True)


def resting_position(field: Field, ball_xy: np.ndarray) -> np.ndarray:
    """The ball's centre lying on the surface at ``ball_xy`` (10 um above it), shape (3,)."""
    z0 = float(field.surface.height(ball_xy[None])[0])
    grad = field.surface.gradient(ball_xy[None])[0]
    nrm = np.array([-grad[0], -grad[1], 1.0]) / np.sqrt(1 + grad @ grad)
    return np.array([ball_xy[0], ball_xy[1], z0]) + (BALL_RADIUS + 1e-5) * nrm


def _add_ball(mbs, gc, ground: int, p_ball: np.ndarray) -> tuple[int, int, int]:
    """The ball at ``p_ball``, held there by a horizontal spring-damper until the club touches
    it (on a slope it would otherwise roll away while the arm swings). Returns (ball marker,
    ball node, holder connector)."""
    ball = mbs.CreateRigidBody(inertia=InertiaSphere(BALL_MASS, BALL_RADIUS),
                               referencePosition=p_ball.tolist(), gravity=[0, 0, -G],
                               nodeType=exu.NodeType.RotationRotationVector)
    m_ball = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ball))
    m_rest = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=p_ball.tolist()))
    m_ball_pos = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ball, localPosition=[0, 0, 0]))
    k = _HOLDER_STIFFNESS
    holder = mbs.AddObject(ObjectConnectorCartesianSpringDamper(
        markerNumbers=[m_rest, m_ball_pos], stiffness=[k, k, 0.0],
        damping=[2 * np.sqrt(k * BALL_MASS)] * 2 + [0.0]))
    gc.AddSphereWithMarker(m_ball, radius=BALL_RADIUS, contactStiffness=K_BALL,
                           contactDamping=0.0, frictionMaterialIndex=_BALL)
    return m_ball, mbs.GetObject(ball)["nodeNumber"], holder


def _add_free_head(mbs, gc, p_ball: np.ndarray, club_velocity: np.ndarray, gap: float,
                   damping: float) -> FreeHead:
    """A head sphere ``gap`` behind the ball moving at ``club_velocity``; it meets the ball at
    the ball's height (the face's contact point), held by the arm against gravity."""
    u = club_velocity / np.linalg.norm(club_velocity)
    p_head = p_ball - (BALL_RADIUS + HEAD_RADIUS + gap) * u
    head = mbs.CreateRigidBody(inertia=InertiaSphere(CLUB_MASS, HEAD_RADIUS),
                               referencePosition=p_head.tolist(),
                               initialVelocity=club_velocity.tolist(), gravity=[0, 0, 0],
                               nodeType=exu.NodeType.RotationRotationVector)
    m_head = mbs.AddMarker(MarkerBodyRigid(bodyNumber=head))
    club = FreeHead(m_head, mbs.GetObject(head)["nodeNumber"])
    gc.AddSphereWithMarker(m_head, radius=HEAD_RADIUS, contactStiffness=K_HEAD,
                           contactDamping=damping, frictionMaterialIndex=_HEAD)
    return club


def _add_club_face(gc, arm: ExudynArm, damping: float) -> None:
    """A flat putter face (4 x 4 cm, two triangles) on the club's link: the ball leaves along
    the face's normal, as from a real putter."""
    gc.AddTrianglesRigidBodyBased(rigidBodyMarkerIndex=arm.marker, contactStiffness=K_HEAD,
                                  contactDamping=damping, frictionMaterialIndex=_HEAD,
                                  pointList=arm.face_points, triangleList=[[0, 1, 2], [0, 2, 3]])


def build_scene(field: Field, ball_xy, club_velocity=None, hole=None,
                mesh_spacing: float | None = None, gap: float = 0.01,
                restitution: float = RESTITUTION, arm: dict | None = None) -> Scene:
    """Build the exudyn system of one shot (module docstring); not yet assembled.

    Parameters are those of :func:`~seds_casadi.sim.shot.simulate_shot_exudyn`. Raises
    ``ValueError`` for a ball outside the field's ball region, or a free club head without a
    horizontal velocity.
    """
    ball_xy = np.asarray(field.check_situation(ball_xy)[0], float)
    hole = field.hole if hole is None else np.asarray(hole, float)
    if arm is None:
        vc = np.asarray(club_velocity, float).reshape(3)
        if not float(np.linalg.norm(vc[:2])) > 0:
            raise ValueError("the club velocity has no horizontal part: the ball is never hit")
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.CreateGround(referencePosition=[0, 0, 0])
    m_ground = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground))
    gc = _general_contact(mbs, field)
    m_eff = BALL_MASS * CLUB_MASS / (BALL_MASS + CLUB_MASS)
    d_hit = 2 * damping_ratio(restitution) * np.sqrt(K_BALL * K_HEAD / (K_BALL + K_HEAD) * m_eff)
    _add_field(gc, m_ground, field, mesh_spacing)
    p_ball = resting_position(field, ball_xy)
    m_ball, ball_node, holder = _add_ball(mbs, gc, ground, p_ball)
    if arm is None:
        club = _add_free_head(mbs, gc, p_ball, vc, gap, d_hit)
    else:
        club = add_arm(mbs, arm, p_ball)
        _add_club_face(gc, club, d_hit)
    state = ShotState()
    mbs.AddLoad(LoadForceVector(markerNumber=m_ball, loadVector=[0, 0, 0],
                                loadVectorUserFunction=RollingResistance(field, ball_node,
                                                                         state).force))
    if arm is None:
        mbs.AddLoad(LoadForceVector(markerNumber=club.marker, loadVector=[0, 0, 0],
                                    loadVectorUserFunction=HeadBrake(club.node, state).force))
    return Scene(SC, mbs, field, hole, ball_node, holder, club, state)
