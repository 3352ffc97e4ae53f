"""Robot arms holding a golf club, in Pinocchio: the Barrett WAM, the Katana 6M180 and arms from
example-robot-data.

* **Barrett WAM 7-DoF**: URDF generated from libbarrett's standard DH table and inertials
  (:func:`wam_urdf`; shipped as ``robots/wam7.urdf``).
* **Katana 6M180**: URDF from the joint origins of ``katana_description`` (five arm joints; the
  gripper is a rigid body here) (:func:`katana_urdf`; ``robots/katana_6m180.urdf``). The public
  description gives link masses but no centres of mass or inertias: those are estimated as
  solid cylinders along each link (documented in ``robots/README.md``).
* **example-robot-data** arms by name (``panda``, ``ur3``, ``ur5``, ``ur10``, ``kinova``, ``z1``),
  found offline in the installed package's files; gripper joints are locked.

A :class:`Club` (shaft and head) is attached rigidly to the flange; the frame ``club_head`` sits
at the head's contact point with its x axis along the club face's normal. A :class:`Robot`
stands on the field with a base pose (translation and a turn about the vertical; the arm
stands upright); positions it reports are in the field's frame.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..core._io import data_folder

__all__ = ["Club", "Robot", "load_robot", "robot_names", "wam_urdf", "katana_urdf",
           "ROBOTS_FOLDER", "WAM_DH", "DEFAULT_CLUBS"]

# ----------------------------------------------------------------------------- data files


#: folder of the shipped URDFs (the repository's ``robots/``, installed as package data)
ROBOTS_FOLDER = data_folder("seds_casadi._robots")

#: libbarrett ``wam7w.conf``: standard DH (alpha, a, d) per joint, theta = q.
WAM_DH = np.array([[-np.pi / 2, 0.0, 0.0], [np.pi / 2, 0.0, 0.0], [-np.pi / 2, 0.045, 0.55],
                   [np.pi / 2, -0.045, 0.0], [-np.pi / 2, 0.0, 0.30], [np.pi / 2, 0.0, 0.0],
                   [-np.pi / 2, 0.0, 0.0609]])
WAM_SHOULDER_HEIGHT = 0.346
WAM_MASSES = [10.7677, 3.8749, 1.8023, 2.1727, 0.3566, 0.4092, 0.0755]
WAM_COMS = [(-0.00443, 0.12189, -0.00066), (-0.00237, 0.03106, 0.01542),
            (-0.03826, 0.20751, 0.00003), (0.00553, 0.00007, 0.11928),
            (0.00005, 0.02886, 0.00148), (-0.00006, -0.01686, 0.02419),
            (0.00015, 0.00007, -0.00335)]
WAM_INERTIAS = [(0.13488, 0.11328, 0.09046, -0.00213, -0.00012, 0.00069),
                (0.02141, 0.01378, 0.01559, 0.00027, 0.00002, -0.00182),
                (0.05911, 0.00325, 0.05927, -0.00250, 0.00001, -0.00002),
                (0.01067, 0.01059, 0.00282, 0.00005, -0.00136, -0.00011),
                (0.00037, 0.00019, 0.00038, 0.0, 0.0, -0.00002),
                (0.00055, 0.00024, 0.00045, 0.0, 0.0, -0.00004),
                (0.00004, 0.00004, 0.00008, 0.0, 0.0, 0.0)]
WAM_LIMITS = [(-2.6, 2.6), (-1.985, 1.985), (-2.8, 2.8), (-0.9, np.pi), (-4.8, 1.3),
              (-1.5707, 1.5707), (-2.95, 2.95)]
WAM_EFFORT = [60.0, 60.0, 45.0, 20.0, 5.0, 5.0, 5.0]
WAM_VELOCITY = [3.0, 3.0, 4.0, 4.0, 8.0, 8.0, 8.0]  # not in the reference: ours, documented

KATANA_ORIGINS = [((0, 0, 0.2015), (0, 0, 0)), ((0, 0, 0), (np.pi / 2, 0, 0)),
                  ((0.19, 0, 0), (0, 0, 0)), ((0.139, 0, 0), (np.pi, 0, 0)),
                  ((0.1523, 0, 0), (np.pi / 2, 0, -np.pi / 2))]
# the description's tool frame is (0, 0, -0.1505; 0, pi/2, 0); the flange here is turned about
# its y axis by another pi/2 so that its z axis points along the gripper (the club's shaft)
KATANA_TOOL = ((0, 0, -0.1505), (0, np.pi, 0))
KATANA_LIMITS = [(-3.0255, 2.8911), (-0.1352, 2.1686), (-2.2218, 2.0542), (-2.0333, 1.8761),
                 (-2.9932, 2.8710)]
KATANA_EFFORT = [1.5, 0.6, 0.25, 0.1, 0.01]
KATANA_VELOCITY = [2.209, 1.191, 1.191, 2.209, 2.209]
# link masses: links 1-4, and link 5 with the gripper body (0.256) and fingers (0.055)
KATANA_MASSES = [0.748, 0.802, 0.792, 0.691, 0.256 + 0.055]
# estimated centres of mass along each link (half way to the next joint) and cylinder radii
KATANA_COMS = [(0, 0, 0), (0.095, 0, 0), (0.0695, 0, 0), (0.076, 0, 0), (0, 0, -0.075)]
KATANA_RADIUS = 0.03


def _rpy_matrix(r, p, y) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _rx(a) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _f(v) -> str:
    return " ".join(f"{float(x):.10g}" for x in v)


def _inertial(mass, com, inertia) -> str:
    ixx, iyy, izz, ixy, ixz, iyz = inertia
    return (f'    <inertial>\n      <origin xyz="{_f(com)}" rpy="0 0 0"/>\n'
            f'      <mass value="{mass:.10g}"/>\n'
            f'      <inertia ixx="{ixx:.10g}" ixy="{ixy:.10g}" ixz="{ixz:.10g}" iyy="{iyy:.10g}" '
            f'iyz="{iyz:.10g}" izz="{izz:.10g}"/>\n    </inertial>\n')


def _joint(name, parent, child, xyz, rpy, lim=None, effort=None, vel=None) -> str:
    if lim is None:
        return (f'  <joint name="{name}" type="fixed">\n    <parent link="{parent}"/>\n'
                f'    <child link="{child}"/>\n    <origin xyz="{_f(xyz)}" rpy="{_f(rpy)}"/>\n'
                f'  </joint>\n')
    return (f'  <joint name="{name}" type="revolute">\n    <parent link="{parent}"/>\n'
            f'    <child link="{child}"/>\n    <origin xyz="{_f(xyz)}" rpy="{_f(rpy)}"/>\n'
            f'    <axis xyz="0 0 1"/>\n    <limit lower="{lim[0]:.10g}" upper="{lim[1]:.10g}" '
            f'effort="{effort:.10g}" velocity="{vel:.10g}"/>\n  </joint>\n')


def wam_urdf() -> str:
    """URDF of the Barrett WAM 7-DoF from libbarrett's DH table and inertials (REFERENCE).

    Standard DH T_i = Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i): URDF joint i+1 sits at the fixed
    part of T_i, so link i's URDF frame is DH frame i-1 turned by q_i; centres of mass and
    inertias given in DH frame i are moved into it by that fixed part. The tool plate
    (``wam_flange``) adds alpha = +pi/2 after DH frame 7: its z axis is joint 7's axis.
    """
    parts = ['<?xml version="1.0"?>\n<!-- generated by seds_casadi.robots.wam_urdf(); numbers: '
             'libbarrett config/wam7w.conf (DH, masses, COMs, inertias), barrett_model URDF '
             '(limits, efforts). Velocity limits are not in either: generous values. -->\n'
             '<robot name="wam7">\n',
             '  <link name="wam_base">\n' + _inertial(9.97, (0, 0, 0.1), (0.1, 0.1, 0.1, 0, 0, 0))
             + '  </link>\n']
    parent, xyz, rpy = "wam_base", (0, 0, WAM_SHOULDER_HEIGHT), (0, 0, 0)
    for i in range(7):
        alpha, a, d = WAM_DH[i]
        R = _rx(alpha)
        com = np.array([a, 0, d]) + R @ np.array(WAM_COMS[i])
        ixx, iyy, izz, ixy, ixz, iyz = WAM_INERTIAS[i]
        Ic = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        Iu = R @ Ic @ R.T
        link = f"wam_link{i + 1}"
        parts.append(_joint(f"wam_j{i + 1}", parent, link, xyz, rpy, WAM_LIMITS[i], WAM_EFFORT[i],
                            WAM_VELOCITY[i]))
        parts.append(f'  <link name="{link}">\n'
                     + _inertial(WAM_MASSES[i], com, (Iu[0, 0], Iu[1, 1], Iu[2, 2], Iu[0, 1],
                                                      Iu[0, 2], Iu[1, 2])) + '  </link>\n')
        parent, xyz, rpy = link, (a, 0, d), (alpha, 0, 0)
    # tool plate: DH frame 7 then alpha = +pi/2
    parts.append(_joint("wam_flange_joint", parent, "wam_flange", xyz, (rpy[0] + np.pi / 2, 0, 0)))
    parts.append('  <link name="wam_flange"/>\n</robot>\n')
    return "".join(parts)


def _cylinder_inertia(m, length, r, axis) -> tuple:
    ia = 0.5 * m * r * r
    it = m * (3 * r * r + length * length) / 12
    d = [it, it, it]
    d[axis] = ia
    return (d[0], d[1], d[2], 0.0, 0.0, 0.0)


def katana_urdf() -> str:
    """URDF of the Katana 6M180 (five arm joints about z; katana_description's origins).

    Centres of mass and inertias are estimates (solid cylinders of radius 3 cm along each
    link, mass from the description); the gripper is rigid and lumped into link 5.
    """
    parts = ['<?xml version="1.0"?>\n<!-- generated by seds_casadi.robots.katana_urdf(); joint '
             'origins, limits, efforts, velocities and masses: katana_description '
             '(katana_300_6m180.urdf.xacro); centres of mass and inertias: estimated as solid '
             'cylinders (radius 3 cm) along each link. -->\n<robot name="katana_6m180">\n',
             '  <link name="katana_base">\n'
             + _inertial(1.405, (0, 0, 0.1), _cylinder_inertia(1.405, 0.2, 0.06, 2))
             + '  </link>\n']
    lengths = [0.05, 0.19, 0.139, 0.1523, 0.15]
    axes = [2, 0, 0, 0, 2]
    parent = "katana_base"
    for i, ((xyz, rpy), lim) in enumerate(zip(KATANA_ORIGINS, KATANA_LIMITS)):
        link = f"katana_link{i + 1}"
        parts.append(_joint(f"katana_j{i + 1}", parent, link, xyz, rpy, lim, KATANA_EFFORT[i],
                            KATANA_VELOCITY[i]))
        inertia = _cylinder_inertia(KATANA_MASSES[i], lengths[i], KATANA_RADIUS, axes[i])
        parts.append(f'  <link name="{link}">\n' + _inertial(KATANA_MASSES[i], KATANA_COMS[i], inertia)
                     + '  </link>\n')
        parent = link
    parts.append(_joint("katana_flange_joint", parent, "katana_flange", *KATANA_TOOL))
    parts.append('  <link name="katana_flange"/>\n</robot>\n')
    return "".join(parts)


# ----------------------------------------------------------------------------- club
@dataclass(frozen=True)
class Club:
    """A putter held rigidly at the flange.

    The shaft leaves the flange along the flange's z axis (the approach direction of the tool
    flanges of the WAM, Katana, UR, Panda); the head is a point mass at its end.
    The ``club_head`` frame is at the head's centre, with x along the face's normal (the
    flange's x axis) and z along the shaft towards the flange.

    Attributes
    ----------
    length : float
        Flange to head centre [m].
    shaft_mass, head_mass : float
        [kg]; the shaft is a thin rod.
    """

    length: float = 0.5
    shaft_mass: float = 0.1
    head_mass: float = 0.3

    def __post_init__(self) -> None:
        if not (self.length > 0 and self.shaft_mass >= 0 and self.head_mass > 0):
            raise ValueError("club length and head mass must be positive, shaft mass >= 0")

    @property
    def mass(self) -> float:
        return self.shaft_mass + self.head_mass

    def inertia(self):
        """Spatial inertia of shaft + head in the flange frame (pinocchio.Inertia)."""
        import pinocchio as pin

        L, ms, mh = self.length, self.shaft_mass, self.head_mass
        m = ms + mh
        com = np.array([0, 0, (ms * L / 2 + mh * L) / m])
        # rod about its own centre, and the head as a point, both moved to the common COM
        rot = np.diag([ms * L * L / 12, ms * L * L / 12, 0.0])
        for mass, z in ((ms, L / 2), (mh, L)):
            dz = z - com[2]
            rot += mass * np.diag([dz * dz, dz * dz, 0.0])
        rot += np.diag([1e-6, 1e-6, 1e-6])  # a head has some size: keep it positive definite
        return pin.Inertia(m, com, rot)

    def head_placement(self):
        """Placement of the ``club_head`` frame in the flange frame (pinocchio.SE3)."""
        import pinocchio as pin

        R = np.array([[1.0, 0, 0], [0, -1.0, 0], [0, 0, -1.0]])  # x: face normal; z: to flange
        return pin.SE3(R, np.array([0, 0, self.length]))


#: Clubs sized for each robot: the Katana's motors are small (0.6 N m at the shoulder).
DEFAULT_CLUBS = {"wam": Club(0.5, 0.1, 0.3), "katana": Club(0.2, 0.01, 0.03)}


# ----------------------------------------------------------------------------- registry
_ERD_ARMS = {
    # name: (urdf path under example-robot-data's robots/, flange frame, home configuration)
    "panda": ("panda_description/urdf/panda.urdf", "panda_link8",
              [0, -0.6, 0, -2.2, 0, 1.6, 0.8]),
    "ur3": ("ur_description/urdf/ur3_robot.urdf", "tool0", [0, -1.6, 1.8, -1.8, -1.57, 0]),
    "ur5": ("ur_description/urdf/ur5_robot.urdf", "tool0", [0, -1.6, 1.8, -1.8, -1.57, 0]),
    "ur10": ("ur_description/urdf/ur10_robot.urdf", "tool0", [0, -1.6, 1.8, -1.8, -1.57, 0]),
    "kinova": ("kinova_description/robots/kinova.urdf", "j2s6s200_end_effector",
               [0, 3.6, 1.2, 0, 1.2, 0]),
    "z1": ("z1_description/urdf/z1.urdf", "link06", [0, 1.2, -1.2, 0, 0, 0]),
}
_OWN = {"wam": ("wam7.urdf", "wam_flange", [0, -0.6, 0, 2.4, 0, 0.9, 0]),
        "katana": ("katana_6m180.urdf", "katana_flange", [-0.27, 0.99, -1.066, 0.812, -1.321])}


def robot_names() -> list[str]:
    """Known robot names: the shipped WAM and Katana, and example-robot-data arms."""
    return list(_OWN) + list(_ERD_ARMS)


def _erd_root() -> str:
    import importlib.metadata as md

    try:
        dist = md.distribution("example-robot-data")
    except md.PackageNotFoundError:
        raise ValueError("example-robot-data is not installed: pip install example-robot-data") \
            from None
    return str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots"))


@dataclass
class Robot:
    """An arm with a club, standing on the field.

    Attributes
    ----------
    name : str
    model : pinocchio.Model
        Joints of the arm only; the club is part of the last link.
    head_frame : int
        Frame id of ``club_head``.
    q_home : array, shape (nv,)
        A configuration to start swings from.
    base : (x, y, z, yaw)
        Placement of the robot's base in the field frame (z up).
    club : Club
    """

    name: str
    model: object
    head_frame: int
    q_home: np.ndarray
    base: tuple = (0.0, 0.0, 0.0, 0.0)
    club: Club = field(default_factory=Club)

    def __post_init__(self) -> None:
        import pinocchio as pin

        b = np.asarray(self.base, dtype=float).ravel()
        if b.shape != (4,) or not np.all(np.isfinite(b)):
            raise ValueError(f"base must be (x, y, z, yaw), got {self.base!r}")
        self.base = tuple(b)
        c, s = np.cos(b[3]), np.sin(b[3])
        self.base_placement = pin.SE3(np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]]), b[:3])
        self.data = self.model.createData()
        self.lower = self.model.lowerPositionLimit.copy()
        self.upper = self.model.upperPositionLimit.copy()
        self.effort = self.model.effortLimit.copy()
        self.velocity_limit = self.model.velocityLimit.copy()

    @property
    def nv(self) -> int:
        return self.model.nv

    def head_pose(self, q) -> tuple[np.ndarray, np.ndarray]:
        """Club-head position (3,) and rotation (3, 3) in the field frame at ``q``."""
        import pinocchio as pin

        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, float))
        M = self.base_placement * self.data.oMf[self.head_frame]
        return M.translation.copy(), M.rotation.copy()

    def head_jacobian(self, q) -> np.ndarray:
        """6 x nv Jacobian of the club head (linear; angular), field-aligned axes."""
        import pinocchio as pin

        J = pin.computeFrameJacobian(self.model, self.data, np.asarray(q, float),
                                     self.head_frame, pin.LOCAL_WORLD_ALIGNED)
        R = self.base_placement.rotation
        return np.vstack([R @ J[:3], R @ J[3:]])

    def reach(self) -> float:
        """An upper bound of the club head's distance from the first joint's axis origin [m]."""
        import pinocchio as pin

        q = np.clip(np.zeros(self.nv), self.lower, self.upper)
        pin.framesForwardKinematics(self.model, self.data, q)
        pts = [self.data.oMi[j].translation for j in range(1, self.model.njoints)]
        pts.append(self.data.oMf[self.head_frame].translation)
        return float(sum(np.linalg.norm(b - a) for a, b in zip(pts[:-1], pts[1:])))

    def check_reach(self, point, margin: float = 0.02) -> None:
        """Raise ``ValueError`` when ``point`` (field frame) is out of the club's reach."""
        p = np.asarray(point, float)
        shoulder = self.base_placement.act(self._shoulder())
        dist = float(np.linalg.norm(p - shoulder))
        if dist > self.reach() - margin:
            raise ValueError(f"{self.name}: the point {np.round(p, 3).tolist()} is "
                             f"{dist:.2f} m from the shoulder, beyond the club's reach "
                             f"({self.reach():.2f} m): move the robot's base closer")

    def _shoulder(self) -> np.ndarray:
        import pinocchio as pin

        pin.forwardKinematics(self.model, self.data, np.zeros(self.nv))
        j = min(2, self.model.njoints - 1)
        return self.data.oMi[j].translation.copy()


def _attach_club(model, flange: str, club: Club):
    import pinocchio as pin

    if not model.existFrame(flange):
        raise ValueError(f"the robot has no frame {flange!r}")
    fid = model.getFrameId(flange)
    fr = model.frames[fid]
    jid = fr.parentJoint
    model.appendBodyToJoint(jid, fr.placement.act(club.inertia()), pin.SE3.Identity())
    head = fr.placement * club.head_placement()
    return model.addFrame(pin.Frame("club_head", jid, fid, head, pin.FrameType.OP_FRAME))


def load_robot(name_or_path: str, club: Club | None = None, base=(0.0, 0.0, 0.0, 0.0),
               flange: str | None = None, q_home=None, field=None) -> Robot:
    """A robot by name (:func:`robot_names`) or a URDF file (then give ``flange``).

    Parameters
    ----------
    name_or_path : str
    club : Club, optional
        Default: :data:`DEFAULT_CLUBS` for the robot (a 0.5 m, 0.4 kg putter otherwise).
    base : (x, y, z, yaw)
        The base's placement on the field [m, rad].
    flange, q_home : optional
        The frame the club is attached to and a home configuration (required for a URDF path
        that is not one of the known robots; q_home defaults to the middle of the limits).
    field : Field, optional
        The field the robot stands on: its base must not be below the field's surface there.
    """
    import pinocchio as pin

    s = os.fspath(name_or_path)
    name = s.lower()
    if name in _OWN:
        file, fl, home = _OWN[name]
        path = os.path.join(ROBOTS_FOLDER, file)
    elif name in _ERD_ARMS:
        rel, fl, home = _ERD_ARMS[name]
        path = os.path.join(_erd_root(), rel)
    elif s.endswith(".urdf") or os.sep in s:
        path, fl, home = s, flange, q_home
        name = os.path.splitext(os.path.basename(s))[0]
        if fl is None:
            raise ValueError("a URDF file needs flange=FRAME, the frame that holds the club")
        if not os.path.exists(path):
            raise ValueError(f"no URDF file {path!r}")
    else:
        raise ValueError(f"unknown robot {s!r}; known: {', '.join(robot_names())}, or a path "
                         f"to a .urdf file")
    try:
        with open(path, encoding="utf-8") as fh:
            model = pin.buildModelFromXML(_revolute_only(fh.read()))
    except (RuntimeError, ValueError, OSError) as exc:
        raise ValueError(f"{path}: the URDF failed to load ({exc})") from None
    # lock gripper/finger joints: only the arm swings
    lock = [j for j, n in enumerate(model.names) if j > 0 and ("finger" in n or "gripper" in
                                                               n.lower())]
    if lock:
        model = pin.buildReducedModel(model, lock, pin.neutral(model))
    fl = flange or fl
    club = club or DEFAULT_CLUBS.get(name, Club())
    head = _attach_club(model, fl, club)
    if home is None:
        lo, hi = model.lowerPositionLimit, model.upperPositionLimit
        home = np.where(np.isfinite(lo) & np.isfinite(hi), 0.5 * (lo + hi), 0.0)
    home = np.asarray(home, float)
    if home.shape != (model.nq,):
        raise ValueError(f"q_home has {home.size} values for {model.nq} joints")
    robot = Robot(name, model, head, home, base, club)
    _check_base(robot, field)
    return robot


def _revolute_only(text: str) -> str:
    """Continuous joints become revolute joints limited to +-2 pi (one angle per joint, so
    that configurations and velocities have the same size)."""
    import re

    def fix(m):
        block = m.group(0).replace('type="continuous"', 'type="revolute"')
        if "lower=" not in block:
            if "<limit" in block:
                block = block.replace("<limit", '<limit lower="-6.2832" upper="6.2832"', 1)
            else:
                block = block.replace("</joint>", '<limit lower="-6.2832" upper="6.2832" '
                                      'effort="100" velocity="3"/></joint>')
        return block

    return re.sub(r'<joint[^>]*type="continuous"[^>]*>.*?</joint>', fix, text, flags=re.S)


def _check_base(robot: Robot, field=None) -> None:
    x, y, z = robot.base[:3]
    ground = 0.0 if field is None else float(field.surface.height(np.array([[x, y]]))[0])
    if z < ground - 1e-9:
        raise ValueError(f"{robot.name}: the base at z = {z:.3f} m is inside the field surface "
                         f"(z = {ground:.3f} m there): raise it to at least the surface")
