"""Validation in exudyn: the arm, its club and a ball rolling on the field's triangle mesh.

The independent judge of the robot simulation (:mod:`seds_casadi.control`) and of the fast ball
model (:mod:`seds_casadi.ball`): the same shot is simulated as a multibody system with contact,
and the two are compared (``seds-casadi validate``).

* **Arm**: an exudyn ``ObjectKinematicTree`` converted from the robot's Pinocchio model (same
  joint placements, masses, centres of mass, inertias, club included; free fall matches
  Pinocchio's ABA to 1e-13 rad), driven by the same :class:`~seds_casadi.control.SwingController`
  from a pre-step function: torques every 2 ms from exudyn's joint state, not prescribed motion.
* **Club face**: a flat 4 x 4 cm square (two contact triangles) on the club's link at the
  ``club_head`` frame, normal along the face normal: the ball leaves along the face's normal
  with whatever the arm's inertia and the controller give, not the fast model's formula.
  Face-ball contact damping is set for a restitution of 0.8.
* **Field**: a triangle mesh of z = H(x, y) (:func:`field_mesh`, normals up), plus vertical wall
  strips (damped for the field's wall restitution, frictionless as in the fast model, so the
  wall's impulse leaves the ball's spin alone) on fields with walls. Ball-field contact is
  exudyn's sphere-triangle contact with Coulomb friction (mu = 0.2): the skid after the impact
  and its turn into rolling come out of the contact.
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

Integration: Dormand-Prince 5(4) with Lie-group rotations and automatic steps: during the swing
and the impact at most 0.2 ms (tolerance 1e-7), from 20 ms after the launch at most 1 ms
(tolerance 1e-6). A fixed 0.2 ms Runge-Kutta 4 step (14 steps per period of the stiffest
contact, face on ball) lost up to 2 % of the ball's launch speed in the impact, depending on
where the contact fell between steps; adaptive steps throughout at up to 1 ms applied the
controller's torques up to a step late and moved launch speeds by up to 1 %.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from ..minigolf.ball import BALL_MASS, BALL_RADIUS, CLUB_MASS, MU_SLIDE, RESTITUTION, STOP_SPEED, G
from ..minigolf.ball import capture_speed as _capture_speed
from ..minigolf.fields import Field

__all__ = ["field_mesh", "ExudynShot", "simulate_shot_exudyn", "MAX_TRIANGLES"]

MAX_TRIANGLES = 60_000
HEAD_RADIUS = 0.008  # small enough to clear the field (the head only touches the ball)
ROLL_AFTER = 0.02  # s after the launch: the rolling phase's longer steps begin


def field_mesh(field: Field, spacing: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Triangle mesh of the field's surface over its bounds: points (n, 3), triangles (m, 3)
    with normals pointing up.

    ``spacing`` [m] defaults to 3 cm on curved fields and to the whole field on a plane.
    Raises ``ValueError`` when the mesh would exceed :data:`MAX_TRIANGLES`.
    """
    b = field.bounds
    if spacing is None:
        spacing = max(b[1] - b[0], b[3] - b[2]) if field.surface.shape == "plane" else 0.03
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"spacing must be positive, got {spacing}")
    nx = max(2, int(np.ceil((b[1] - b[0]) / spacing)) + 1)
    ny = max(2, int(np.ceil((b[3] - b[2]) / spacing)) + 1)
    n_trig = 2 * (nx - 1) * (ny - 1)
    if n_trig > MAX_TRIANGLES:
        raise ValueError(f"a {spacing:g} m mesh of the field {field.name!r} has {n_trig} "
                         f"triangles, more than the {MAX_TRIANGLES} the contact solver handles "
                         f"here: use a larger spacing (at least "
                         f"{spacing * np.sqrt(n_trig / MAX_TRIANGLES):.3f} m)")
    xs, ys = np.linspace(b[0], b[1], nx), np.linspace(b[2], b[3], ny)
    X, Y = np.meshgrid(xs, ys)  # rows along y
    P = np.column_stack([X.ravel(), Y.ravel()])
    pts = np.column_stack([P, field.surface.height(P)])
    i, j = np.meshgrid(np.arange(nx - 1), np.arange(ny - 1))
    a = (j * nx + i).ravel()
    tri = np.concatenate([np.column_stack([a, a + 1, a + nx + 1]),
                          np.column_stack([a, a + nx + 1, a + nx])])
    return pts, tri


def _walls(field: Field, height: float = 0.1):
    """Vertical strips along the bounds, from below the lowest to above the highest point of
    the surface along each side; normals pointing into the field."""
    b = field.bounds
    corners = [(b[0], b[2]), (b[1], b[2]), (b[1], b[3]), (b[0], b[3])]
    pts, tri = [], []
    for k in range(4):
        (x0, y0), (x1, y1) = corners[k], corners[(k + 1) % 4]
        s = np.linspace(0, 1, 200)[:, None]
        h = field.surface.height((1 - s) * np.array([x0, y0]) + s * np.array([x1, y1]))
        z0, z1 = float(h.min()) - 0.05, float(h.max()) + height
        base = len(pts)
        pts += [(x0, y0, z0), (x1, y1, z0), (x1, y1, z1), (x0, y0, z1)]
        # counter-clockwise corners: (p1 - p0) x (p2 - p0) points inwards for (0, 2, 1)
        tri += [(base, base + 2, base + 1), (base, base + 3, base + 2)]
    return np.array(pts, float), np.array(tri, int)


@dataclass
class ExudynShot:
    """Result of one exudyn shot.

    Attributes
    ----------
    sunk, stopped : bool
    final_position : array (2,)
    launch_velocity : array (2,)
        Ball velocity (horizontal) just after the impact.
    path : array (k, 3)
        Ball centre every 10 ms: t, x, y.
    head_speed : array (k, 2)
        Club-head speed around the impact: t, |v|.
    simulated_time, wall_time : float
    hit : bool
        The club touched the ball (False: a miss, e.g. a swing too slow to arrive).
    head_velocity : array (3,)
        Club-head velocity at the first contact (NaN without one).
    contact_time : float
        When the club first touched the ball [s] (NaN without contact).
    """

    sunk: bool
    stopped: bool
    final_position: np.ndarray
    launch_velocity: np.ndarray
    path: np.ndarray
    head_speed: np.ndarray
    simulated_time: float
    wall_time: float
    hit: bool = False
    head_velocity: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    contact_time: float = np.nan

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        return self.simulated_time / max(self.wall_time, 1e-12)


def simulate_shot_exudyn(field: Field, ball_xy, club_velocity=None, hole=None,
                         max_time: float = 12.0, step: float = 1e-3, tolerance: float = 1e-6,
                         impact_step: float = 2e-4, impact_tolerance: float = 1e-7,
                         mesh_spacing: float | None = None, gap: float = 0.01,
                         restitution: float = RESTITUTION, arm: dict | None = None,
                         max_wall_time: float = 600.0) -> ExudynShot:
    """One shot in exudyn (module docstring); the ball rolls until it drops, stops or the time
    runs out.

    Without ``arm``: a free club head of the impact model's effective mass starts ``gap``
    behind the ball moving with ``club_velocity`` (3,). With ``arm`` (a dict with ``robot``,
    ``motion``, ``alpha``, ``kappa`` and optionally ``gains``): the robot is an exudyn
    kinematic tree converted from its Pinocchio model, driven by :class:`SwingController`'s
    torques every 2 ms from exudyn's joint state, and the ball is struck by a contact sphere at
    the club face on its last link: the impact then involves the whole arm, not a formula.

    ``impact_step`` and ``impact_tolerance`` are the largest integration step [s] and the step
    control's tolerance for the swing and the impact, ``step`` and ``tolerance`` for the roll
    that follows (from 20 ms after the ball leaves the club). Raises ``RuntimeError`` naming
    the time when exudyn's solver fails, or when the shot has taken more than ``max_wall_time``
    seconds of computing (the step control shrinking its steps without end; a run with
    tolerance 1e-7 through the whole roll once took 44 minutes for one shot); never a silently
    truncated result.
    """
    import time

    if not (max_wall_time > 0 and step > 0 and impact_step > 0 and tolerance > 0
            and impact_tolerance > 0):
        raise ValueError("max_wall_time, step, impact_step, tolerance and impact_tolerance "
                         "must be positive")

    import exudyn as exu
    from exudyn.utilities import InertiaSphere, LoadForceVector, MarkerBodyRigid

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
    gc = mbs.AddGeneralContact()
    gc.verboseMode = 0
    # materials: 0 field, 1 ball, 2 club head, 3 walls (frictionless, as in the fast model:
    # the wall's normal impulse passes through the ball's centre and leaves its spin alone)
    mu = np.zeros((4, 4))
    mu[0, 1] = mu[1, 0] = MU_SLIDE
    gc.SetFrictionPairings(mu)
    b = field.bounds
    gc.SetSearchTreeBox(pMin=[b[0] - 0.1, b[2] - 0.1, -1.0], pMax=[b[1] + 0.1, b[3] + 0.1, 1.0])
    gc.SetSearchTreeCellSize(numberOfCells=[max(1, int((b[1] - b[0]) / 0.1)),
                                            max(1, int((b[3] - b[2]) / 0.1)), 1])
    # contact stiffnesses combine in series, dampings in parallel: ball-field k ~ 4e4 N/m
    # (ball weight sinks 11 um), head-ball k = 2e5 N/m with the damping of restitution e
    k_ball = k_head = 4e5
    k_field = 4.4e4
    m_eff = BALL_MASS * CLUB_MASS / (BALL_MASS + CLUB_MASS)
    zeta = -np.log(restitution) / np.sqrt(np.pi**2 + np.log(restitution) ** 2)
    d_hit = 2 * zeta * np.sqrt(k_ball * k_head / (k_ball + k_head) * m_eff)
    d_field = 2 * 0.7 * np.sqrt(4e4 * BALL_MASS)
    gc.sphereSphereContact = True
    pts, tri = field_mesh(field, mesh_spacing)
    gc.AddTrianglesRigidBodyBased(rigidBodyMarkerIndex=m_ground, contactStiffness=k_field,
                                  contactDamping=d_field, frictionMaterialIndex=0,
                                  pointList=pts.tolist(), triangleList=tri.tolist(),
                                  staticTriangles=True)
    if field.boundary == "walls":
        # wall damping for the field's wall restitution (the same rule as head on ball)
        e_w = min(max(field.wall_restitution, 1e-3), 0.999)
        zeta_w = -np.log(e_w) / np.sqrt(np.pi**2 + np.log(e_w) ** 2)
        wp, wt = _walls(field)
        gc.AddTrianglesRigidBodyBased(rigidBodyMarkerIndex=m_ground, contactStiffness=k_field,
                                      contactDamping=2 * zeta_w * np.sqrt(4e4 * BALL_MASS),
                                      frictionMaterialIndex=3,
                                      pointList=wp.tolist(), triangleList=wt.tolist(),
                                      staticTriangles=True)
    z0 = float(field.surface.height(ball_xy[None])[0])
    grad = field.surface.gradient(ball_xy[None])[0]
    nrm = np.array([-grad[0], -grad[1], 1.0]) / np.sqrt(1 + grad @ grad)
    p_ball = np.array([ball_xy[0], ball_xy[1], z0]) + (BALL_RADIUS + 1e-5) * nrm
    ball = mbs.CreateRigidBody(inertia=InertiaSphere(BALL_MASS, BALL_RADIUS),
                               referencePosition=p_ball.tolist(), gravity=[0, 0, -G],
                               nodeType=exu.NodeType.RotationRotationVector)
    m_ball = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ball))
    # the ball lies still until the club touches it (on a slope it would roll away while the
    # arm swings): a spring-damper to its resting place, released at the first contact
    from exudyn.utilities import MarkerBodyPosition, ObjectConnectorCartesianSpringDamper

    m_rest = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=p_ball.tolist()))
    m_ball_pos = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ball, localPosition=[0, 0, 0]))
    holder = mbs.AddObject(ObjectConnectorCartesianSpringDamper(
        markerNumbers=[m_rest, m_ball_pos], stiffness=[2e3, 2e3, 0.0],
        damping=[2 * np.sqrt(2e3 * BALL_MASS)] * 2 + [0.0]))
    gc.AddSphereWithMarker(m_ball, radius=BALL_RADIUS, contactStiffness=k_ball,
                           contactDamping=0.0, frictionMaterialIndex=1)
    if arm is None:
        u = vc / np.linalg.norm(vc)
        # the head meets the ball at the ball's height (the face's contact point), held by
        # the arm against gravity; it only touches the ball
        p_head = p_ball - (BALL_RADIUS + HEAD_RADIUS + gap) * u
        head = mbs.CreateRigidBody(inertia=InertiaSphere(CLUB_MASS, HEAD_RADIUS),
                                   referencePosition=p_head.tolist(),
                                   initialVelocity=vc.tolist(), gravity=[0, 0, 0],
                                   nodeType=exu.NodeType.RotationRotationVector)
        m_head = mbs.AddMarker(MarkerBodyRigid(bodyNumber=head))
        head_node = mbs.GetObject(head)["nodeNumber"]
        arm_state = None
        gc.AddSphereWithMarker(m_head, radius=HEAD_RADIUS, contactStiffness=k_head,
                               contactDamping=d_hit, frictionMaterialIndex=2)
    else:
        m_head, head_node, arm_state = _add_arm(mbs, arm, p_ball)
        # a flat putter face (4 x 4 cm, two triangles) on the club's link: the ball leaves
        # along the face's normal, as from a real putter
        gc.AddTrianglesRigidBodyBased(rigidBodyMarkerIndex=m_head, contactStiffness=k_head,
                                      contactDamping=d_hit, frictionMaterialIndex=2,
                                      pointList=arm_state["face_points"],
                                      triangleList=[[0, 1, 2], [0, 2, 3]])
    ball_node = mbs.GetObject(ball)["nodeNumber"]
    rho, ff = field.rolling_resistance, field.surface.friction_factor
    state = {"sunk": False, "stopped": False, "slow": 0.0, "launch": None, "contact": False,
             "t_prev": 0.0, "rolling_phase": None, "phase_two": False}
    vel_t, pos_t = exu.OutputVariableType.Velocity, exu.OutputVariableType.Position
    path, heads = [], []

    surf = field.surface
    zero = [0.0, 0.0, 0.0]
    ang_t = exu.OutputVariableType.AngularVelocity

    def resistance(mbs_, t, load):
        if state["launch"] is None:
            return zero
        vx, vy, vz = mbs_.GetNodeOutput(ball_node, vel_t)
        s = (vx * vx + vy * vy + vz * vz) ** 0.5
        if s < 1e-9:
            return zero
        # only while rolling (as in the fast model): the contact point, at -r n from the
        # centre (n the surface normal), hardly slips
        px, py, _ = mbs_.GetNodeOutput(ball_node, pos_t)
        if flat:
            nx = ny = 0.0
            nz = 1.0
        else:
            cx, cy, nx, ny, nz = normal_cache
            if (px - cx) ** 2 + (py - cy) ** 2 > 4e-6:  # the normal, refreshed every 2 mm
                gx, gy = surf.gradient(np.array([[px, py]]))[0]
                inv = 1.0 / (1.0 + gx * gx + gy * gy) ** 0.5
                nx, ny, nz = -gx * inv, -gy * inv, inv
                normal_cache[:] = [px, py, nx, ny, nz]
        wx, wy, wz = mbs_.GetNodeOutput(ball_node, ang_t)
        r = BALL_RADIUS
        sx = vx - r * (wy * nz - wz * ny)
        sy = vy - r * (wz * nx - wx * nz)
        sz = vz - r * (wx * ny - wy * nx)
        if sx * sx + sy * sy + sz * sz > (0.02 * s + 0.005) ** 2:
            return zero
        fac = 1.0 if ff_const else float(ff(np.array([[px, py]]))[0])
        f = rho * fac * BALL_MASS * G / s
        return [-f * vx, -f * vy, -f * vz]

    flat = field.surface.shape == "plane" and not np.any(field.surface.gradient(
        np.zeros((1, 2))))
    normal_cache = [np.inf, np.inf, 0.0, 0.0, 1.0]
    ff_const = field.surface.shape != "rough"
    mbs.AddLoad(LoadForceVector(markerNumber=m_ball, loadVector=[0, 0, 0],
                                loadVectorUserFunction=resistance))

    def head_brake(mbs_, t, load):
        # after the contact the arm's resting mode stops the club (time constant 20 ms), so
        # the head does not catch up with the ball again
        if state["launch"] is None:
            return [0.0, 0.0, 0.0]
        vh = np.asarray(mbs_.GetNodeOutput(head_node, exu.OutputVariableType.Velocity))
        return (-CLUB_MASS / 0.02 * vh).tolist()

    if arm_state is None:
        mbs.AddLoad(LoadForceVector(markerNumber=m_head, loadVector=[0, 0, 0],
                                    loadVectorUserFunction=head_brake))

    def head_state(mbs_):
        """Club-head point, velocity and face normal (None for the free sphere)."""
        if arm_state is None:
            return (np.asarray(mbs_.GetNodeOutput(head_node, pos_t)),
                    np.asarray(mbs_.GetNodeOutput(head_node, vel_t)), None)
        return arm_state["head"](mbs_)
    R = field.hole_radius
    t_rec = [0.0]

    def pre_step(mbs_, t):
        dt_step, state["t_prev"] = t - state["t_prev"], t
        if time.perf_counter() - t0 > max_wall_time:
            state["timed_out"] = True
            return False
        if arm_state is not None and t < state.get("contact_time", np.inf) + 0.5:
            arm_state["control"](mbs_, t)  # the swing, then the resting mode for 0.5 s
        p = mbs_.GetNodeOutput(ball_node, pos_t)
        v = mbs_.GetNodeOutput(ball_node, vel_t)
        if state["launch"] is None:
            # the head is needed only until the ball leaves the club
            ph, vh, nrm = head_state(mbs_)
            d = np.asarray(p) - ph
            touching = (d @ d < (BALL_RADIUS + HEAD_RADIUS) ** 2 if nrm is None
                        else float(d @ nrm) < BALL_RADIUS)
            if touching:
                if not state["contact"]:
                    state["head_velocity"] = vh.copy()
                    state["contact_time"] = t
                    mbs_.SetObjectParameter(holder, "activeConnector", False)
                state["contact"] = True
            elif state["contact"]:
                state["launch"] = np.array(v[:2])
                state["launch_time"] = t
            heads.append((t, float(np.linalg.norm(vh))))
        if t >= t_rec[0] - 1e-12:
            path.append((t, p[0], p[1]))
            t_rec[0] += 0.01
        if state["launch"] is None:
            if arm_state is not None and t > arm_state["give_up"]:
                return False  # the swing never reached the ball: a miss, not a crash
            return True
        if (state["rolling_phase"] is None and not state["phase_two"]
                and t > state["launch_time"] + ROLL_AFTER):
            state["rolling_phase"], state["phase_two"] = t, True
            return False  # continue with the rolling phase's settings
        p, v = np.asarray(p), np.asarray(v)
        off = float(np.linalg.norm(p[:2] - hole))
        sp = float(np.linalg.norm(v))
        if off < R and sp < float(_capture_speed(off, R)):
            state["sunk"] = True
            return False
        # (steps are adaptive: accumulate the time actually spent slow)
        state["slow"] = state["slow"] + dt_step if sp < STOP_SPEED else 0.0
        if state["slow"] > 0.05:
            state["stopped"] = True
            return False
        if not (b[0] - 0.05 <= p[0] <= b[1] + 0.05 and b[2] - 0.05 <= p[1] <= b[3] + 0.05):
            return False
        return True

    mbs.SetPreStepUserFunction(pre_step)
    mbs.Assemble()

    def settings(start: float, largest_step: float, tol: float):
        so = exu.SimulationSettings()
        with warnings.catch_warnings():  # exudyn renamed some settings; old names still work
            warnings.simplefilter("ignore", DeprecationWarning)
            so.timeIntegration.startTime = start
            so.timeIntegration.endTime = max_time
            so.timeIntegration.numberOfSteps = max(1, int(np.ceil((max_time - start)
                                                                  / largest_step)))
            so.timeIntegration.automaticStepSize = True
            so.timeIntegration.absoluteTolerance = tol
            so.timeIntegration.relativeTolerance = tol
            so.timeIntegration.explicitIntegration.useLieGroupIntegration = True
            so.timeIntegration.verboseMode = 0
            so.solutionSettings.writeSolutionToFile = False
            so.displayComputationTime = False
        return so

    t0 = time.perf_counter()
    exu.SetWriteToConsole(False)  # its note on per-step allocations by user functions
    try:
        # the swing and the impact with short steps; the roll, once the ball is clear of the
        # club, continues from the same state with longer ones
        exu.SolveDynamic(mbs, settings(0.0, impact_step, impact_tolerance),
                         solverType=exu.DynamicSolverType.DOPRI5)
        if state["rolling_phase"] is not None:
            sd = mbs.systemData
            sd.SetSystemState(sd.GetSystemState(exu.ConfigurationType.Current),
                              exu.ConfigurationType.Initial)
            exu.SolveDynamic(mbs, settings(state["rolling_phase"], step, tolerance),
                             solverType=exu.DynamicSolverType.DOPRI5)
    except Exception as exc:  # noqa: BLE001 - exudyn raises its own error types
        t_fail = path[-1][0] if path else 0.0
        raise RuntimeError(f"exudyn failed near t = {t_fail:.3f} s of the shot: {exc}") from None
    finally:
        exu.SetWriteToConsole(True)
    if state.get("timed_out"):
        raise RuntimeError(
            f"exudyn took more than {max_wall_time:g} s of computing and reached only "
            f"t = {state['t_prev']:.3f} s of the shot (its step control is taking tiny steps); "
            "loosen tolerance or raise max_wall_time")
    wall = time.perf_counter() - t0
    p = np.asarray(mbs.GetNodeOutput(ball_node, exu.OutputVariableType.Position))
    t_end = path[-1][0] if path else 0.0
    launch = state["launch"] if state["launch"] is not None else np.zeros(2)
    return ExudynShot(state["sunk"], state["stopped"], p[:2].copy(), launch, np.array(path),
                      np.array(heads), t_end, wall, hit=state["launch"] is not None,
                      head_velocity=state.get("head_velocity", np.full(3, np.nan)),
                      contact_time=state.get("contact_time", np.nan))


_JOINT_TYPES = {"JointModelRX": "RevoluteX", "JointModelRY": "RevoluteY",
                "JointModelRZ": "RevoluteZ", "JointModelPX": "PrismaticX",
                "JointModelPY": "PrismaticY", "JointModelPZ": "PrismaticZ"}


def add_kinematic_tree(mbs, robot, q0=None, qd0=None, gravity=(0.0, 0.0, -G)):
    """Add the robot as an exudyn ``ObjectKinematicTree`` converted from its Pinocchio model
    (same joint placements, masses, centres of mass and inertias, including the club), placed
    at the robot's base on the field. Returns (object index, node index).
    """
    import exudyn as exu
    from exudyn.utilities import NodeGenericODE2, ObjectKinematicTree

    model = robot.model
    n = model.nv
    types, parents, rots, offs, inertias, coms, masses = [], [], [], [], [], [], []
    Mb = robot.base_placement
    for j in range(1, model.njoints):
        short = model.joints[j].shortname()
        if short not in _JOINT_TYPES:
            raise ValueError(f"{robot.name}: joint {model.names[j]!r} ({short}) has no exudyn "
                             f"kinematic-tree counterpart (only joints about x, y or z)")
        types.append(getattr(exu.JointType, _JOINT_TYPES[short]))
        parent = model.parents[j]
        M = model.jointPlacements[j]
        if parent == 0:
            M = Mb * M  # the base's placement on the field goes into the root joints
        parents.append(parent - 1)
        rots.append(M.rotation.copy())
        offs.append(M.translation.copy())
        inert = model.inertias[j]
        masses.append(float(inert.mass))
        coms.append(np.array(inert.lever))
        inertias.append(np.array(inert.inertia))
    q0 = robot.q_home if q0 is None else np.asarray(q0, float)
    qd0 = np.zeros(n) if qd0 is None else np.asarray(qd0, float)
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * n,
                                       initialCoordinates=list(q0),
                                       initialCoordinates_t=list(qd0),
                                       numberOfODE2Coordinates=n))
    obj = mbs.AddObject(ObjectKinematicTree(
        nodeNumber=node, jointTypes=types, linkParents=parents,
        jointTransformations=exu.Matrix3DList(rots), jointOffsets=exu.Vector3DList(offs),
        linkInertiasCOM=exu.Matrix3DList(inertias), linkCOMs=exu.Vector3DList(coms),
        linkMasses=masses,
        baseOffset=[0.0, 0.0, 0.0], gravity=list(gravity), jointForceVector=[0.0] * n))
    return obj, node


def free_fall(robot, q0, duration: float = 0.3, step: float = 1e-4) -> tuple[np.ndarray, ...]:
    """The arm falling under gravity with zero torques, in exudyn and in Pinocchio (RK4 on
    ABA with the same step): returns (q_exudyn, q_pinocchio) at ``duration``."""
    import exudyn as exu
    import pinocchio as pin

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _, node = add_kinematic_tree(mbs, robot, q0)
    mbs.Assemble()
    so = exu.SimulationSettings()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        so.timeIntegration.numberOfSteps = int(round(duration / step))
        so.timeIntegration.endTime = duration
        so.timeIntegration.verboseMode = 0
        so.solutionSettings.writeSolutionToFile = False
    exu.SolveDynamic(mbs, so, solverType=exu.DynamicSolverType.RK44)
    q_ex = np.asarray(mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinates))
    # the same system in Pinocchio, RK4 on (q, qd)
    m, d = robot.model, robot.data
    tau = np.zeros(m.nv)

    def f(x):
        q, qd = x[:m.nv], x[m.nv:]
        return np.concatenate([qd, pin.aba(m, d, q, qd, tau)])

    x = np.concatenate([np.asarray(q0, float), np.zeros(m.nv)])
    for _ in range(int(round(duration / step))):
        k1 = f(x)
        k2 = f(x + 0.5 * step * k1)
        k3 = f(x + 0.5 * step * k2)
        k4 = f(x + step * k3)
        x = x + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return q_ex, x[:m.nv]


def _add_arm(mbs, arm: dict, p_ball: np.ndarray):
    """The robot as a kinematic tree with the controller in a pre-step function; returns the
    club-head contact marker, None (no head node) and the callbacks used by the shot."""
    import exudyn as exu
    from exudyn.utilities import MarkerKinematicTreeRigid

    from ..motion.hitting import rotation_z
    from ..robots.control import SwingController, place_head

    robot, motion = arm["robot"], arm["motion"]
    alpha, kappa = float(arm["alpha"]), float(arm["kappa"])
    ctl = SwingController(robot, motion, gains=arm.get("gains"))
    start = rotation_z(alpha) @ np.array([-0.3, 0.0, 0.05])
    psi = rotation_z(alpha) @ motion.hitting_direction
    q0 = place_head(robot, ctl.contact_point(p_ball, alpha) + start, psi)
    ctl.reset(q0)
    obj, node = add_kinematic_tree(mbs, robot, q0)
    # the club face on the club's link: a square around the face's contact point in the
    # plane of the head frame's y and z axes, its normal the head frame's x axis
    fr = robot.model.frames[robot.head_frame]
    marker = mbs.AddMarker(MarkerKinematicTreeRigid(objectNumber=obj,
                                                    linkNumber=fr.parentJoint - 1,
                                                    localPosition=[0.0, 0.0, 0.0]))
    c, Rf = fr.placement.translation, fr.placement.rotation
    a = 0.02
    # corners counter-clockwise seen from the ball (normal +x): (p1-p0) x (p2-p0) along +x
    face = [c + a * (sy * Rf[:, 1] + sz * Rf[:, 2])
            for sy, sz in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    coords, coords_t = exu.OutputVariableType.Coordinates, exu.OutputVariableType.Coordinates_t
    nxt = [0.0]
    ball = p_ball.copy()

    def control(mbs_, t):
        if t + 1e-12 >= nxt[0]:
            q = np.asarray(mbs_.GetNodeOutput(node, coords))
            qd = np.asarray(mbs_.GetNodeOutput(node, coords_t))
            tau = ctl.tick(q, qd, ball, alpha, kappa, t)
            mbs_.SetObjectParameter(obj, "jointForceVector", tau.tolist())
            nxt[0] += ctl.period

    import pinocchio as pin

    def head(mbs_):
        q = np.asarray(mbs_.GetNodeOutput(node, coords))
        qd = np.asarray(mbs_.GetNodeOutput(node, coords_t))
        pin.computeJointJacobians(robot.model, robot.data, q)
        pin.updateFramePlacements(robot.model, robot.data)
        M = robot.base_placement * robot.data.oMf[robot.head_frame]
        J = pin.getFrameJacobian(robot.model, robot.data, robot.head_frame,
                                 pin.LOCAL_WORLD_ALIGNED)
        v = robot.base_placement.rotation @ (J[:3] @ qd)
        return M.translation.copy(), v, M.rotation[:, 0].copy()

    return marker, None, {"control": control, "head": head, "give_up": 3.0,
                          "face_points": [list(map(float, f)) for f in face]}
