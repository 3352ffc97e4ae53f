"""The robot arm in exudyn: a kinematic tree converted from the Pinocchio model, its club face,
and the 500 Hz controller applied from a pre-step function.

The arm is an exudyn ``ObjectKinematicTree`` with the same joint placements, masses, centres of
mass and inertias as the robot's Pinocchio model, club included (:func:`add_kinematic_tree`;
free fall matches Pinocchio's ABA to 1e-13 rad, :func:`free_fall`). :class:`ExudynArm` holds the
arm of one shot: the club face's contact marker and corners, and the
:class:`~seds_casadi.robots.controller.SwingController` that sets its joint torques every 2 ms from
exudyn's joint state (not prescribed motion). Pinocchio and the robot layer are imported only
when an arm is used, so a shot with a free club head needs exudyn alone.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import exudyn as exu
import numpy as np
from exudyn.utilities import MarkerKinematicTreeRigid, NodeGenericODE2, ObjectKinematicTree

from ..motion.golf import G

__all__ = ["add_kinematic_tree", "free_fall", "ExudynArm", "add_arm", "FACE_HALF_WIDTH",
           "GIVE_UP_TIME"]

_JOINT_TYPES = {"JointModelRX": "RevoluteX", "JointModelRY": "RevoluteY",
                "JointModelRZ": "RevoluteZ", "JointModelPX": "PrismaticX",
                "JointModelPY": "PrismaticY", "JointModelPZ": "PrismaticZ"}
FACE_HALF_WIDTH = 0.02  # m: the club face is a 4 x 4 cm square
GIVE_UP_TIME = 3.0  # s: a swing that has not reached the ball by then is a miss


def add_kinematic_tree(mbs, robot, q0=None, qd0=None, gravity=(0.0, 0.0, -G)):
    """Add the robot as an exudyn ``ObjectKinematicTree`` converted from its Pinocchio model
    (same joint placements, masses, centres of mass and inertias, including the club), placed
    at the robot's base on the field. Returns (object index, node index).
    """
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


@dataclass
class ExudynArm:
    """The arm of one exudyn shot (:func:`add_arm`): what the scene and the run loop use.

    Attributes
    ----------
    marker : int
        Rigid marker on the club's link that carries the face's contact triangles.
    face_points : list of [x, y, z]
        The face's corners in that link's frame, counter-clockwise seen from the ball.
    give_up : float
        Time [s] after which a swing that has not touched the ball is a miss.
    """

    marker: int
    face_points: list
    robot: object = field(repr=False)
    controller: object = field(repr=False)
    tree: int = field(repr=False)
    node: int = field(repr=False)
    ball: np.ndarray = field(repr=False)
    alpha: float = 0.0
    kappa: float = 1.0
    give_up: float = GIVE_UP_TIME
    _next_tick: float = field(default=0.0, repr=False)

    def control(self, mbs, t: float) -> None:
        """Called every step: the controller's torques from the joint state, every period."""
        if t + 1e-12 >= self._next_tick:
            q = np.asarray(mbs.GetNodeOutput(self.node, exu.OutputVariableType.Coordinates))
            qd = np.asarray(mbs.GetNodeOutput(self.node, exu.OutputVariableType.Coordinates_t))
            tau = self.controller.tick(q, qd, self.ball, self.alpha, self.kappa, t)
            mbs.SetObjectParameter(self.tree, "jointForceVector", tau.tolist())
            self._next_tick += self.controller.period

    def head(self, mbs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The club head's point, velocity and face normal (the head frame's x axis) now."""
        import pinocchio as pin

        robot = self.robot
        q = np.asarray(mbs.GetNodeOutput(self.node, exu.OutputVariableType.Coordinates))
        qd = np.asarray(mbs.GetNodeOutput(self.node, exu.OutputVariableType.Coordinates_t))
        pin.computeJointJacobians(robot.model, robot.data, q)
        pin.updateFramePlacements(robot.model, robot.data)
        M = robot.base_placement * robot.data.oMf[robot.head_frame]
        J = pin.getFrameJacobian(robot.model, robot.data, robot.head_frame,
                                 pin.LOCAL_WORLD_ALIGNED)
        v = robot.base_placement.rotation @ (J[:3] @ qd)
        return M.translation.copy(), v, M.rotation[:, 0].copy()


def _face_corners(robot) -> list[list[float]]:
    """The club face: a square around the face's contact point in the plane of the head
    frame's y and z axes (its normal the head frame's x axis), in the club link's frame."""
    fr = robot.model.frames[robot.head_frame]
    c, Rf = fr.placement.translation, fr.placement.rotation
    a = FACE_HALF_WIDTH
    # corners counter-clockwise seen from the ball (normal +x): (p1-p0) x (p2-p0) along +x
    face = [c + a * (sy * Rf[:, 1] + sz * Rf[:, 2])
            for sy, sz in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    return [list(map(float, f)) for f in face]


def add_arm(mbs, arm: dict, p_ball: np.ndarray) -> ExudynArm:
    """Add the robot of ``arm`` (a dict with ``robot``, ``motion``, ``alpha``, ``kappa`` and
    optionally ``gains``) as a kinematic tree whose club starts behind the ball at ``p_ball``
    (3,), with its controller reset there."""
    from ..motion.rotation import rotation_z
    from ..robots.controller import SwingController
    from ..robots.placement import place_head

    robot, motion = arm["robot"], arm["motion"]
    alpha, kappa = float(arm["alpha"]), float(arm["kappa"])
    ctl = SwingController(robot, motion, gains=arm.get("gains"))
    start = rotation_z(alpha) @ np.array([-0.3, 0.0, 0.05])
    psi = rotation_z(alpha) @ motion.hitting_direction
    q0 = place_head(robot, ctl.contact_point(p_ball, alpha) + start, psi)
    ctl.reset(q0)
    obj, node = add_kinematic_tree(mbs, robot, q0)
    fr = robot.model.frames[robot.head_frame]
    marker = mbs.AddMarker(MarkerKinematicTreeRigid(objectNumber=obj,
                                                    linkNumber=fr.parentJoint - 1,
                                                    localPosition=[0.0, 0.0, 0.0]))
    return ExudynArm(marker, _face_corners(robot), robot, ctl, obj, node, p_ball.copy(),
                     alpha, kappa)
