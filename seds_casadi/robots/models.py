"""Robot arms holding a golf club, in Pinocchio: the Barrett WAM, the Katana 6M180 and arms from
example-robot-data.

* **Barrett WAM 7-DoF** and **Katana 6M180**: the shipped URDFs, generated from their reference
  tables (:mod:`seds_casadi.robots.urdf`).
* **example-robot-data** arms by name (``panda``, ``ur3``, ``ur5``, ``ur10``, ``kinova``, ``z1``),
  found offline in the installed package's files; gripper joints are locked.

A :class:`~seds_casadi.robots.club.Club` (shaft and head) is attached rigidly to the flange; the
frame ``club_head`` sits at the head's contact point with its x axis along the club face's
normal. A :class:`Robot` stands on the field with a base pose (translation and a turn about the
vertical; the arm stands upright); positions it reports are in the field's frame.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..core._io import open_regular
from .club import DEFAULT_CLUBS, Club
from .urdf import ROBOTS_FOLDER

#: the largest URDF file read [bytes] (the shipped ones and example-robot-data's are < 100 kB)
MAX_URDF_BYTES = 16 * 2**20

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
    effort_excludes_gravity : bool
        Whether the published effort limits bound the torques beyond gravity, tau - g(q),
        rather than tau (the Katana's: measured from a Gazebo controller with gravity off).
    """

    name: str
    model: object
    head_frame: int
    q_home: np.ndarray
    base: tuple = (0.0, 0.0, 0.0, 0.0)
    club: Club = field(default_factory=Club)
    effort_excludes_gravity: bool = False

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
    """A robot by name (:func:`robot_names`) or a URDF file (``FILE.urdf#LINK`` or ``flange``
    names the link that holds the club; default: the last link of the arm's only chain).

    Parameters
    ----------
    name_or_path : str
    club : Club, optional
        Default: :data:`~seds_casadi.robots.club.DEFAULT_CLUBS` for the robot (a 0.5 m, 0.4 kg
        putter otherwise).
    base : (x, y, z, yaw)
        The base's placement on the field [m, rad].
    flange, q_home : optional
        The frame the club is attached to (for a URDF path that is not one of the known
        robots: this, else ``#LINK`` after the path, else the tip of its only chain) and a home
        configuration (default: the middle of the limits).
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
    elif ".urdf" in s or os.sep in s:
        path, _, link = s.partition(".urdf#")  # FILE.urdf#LINK names the flange
        path, fl, home = (path + ".urdf" if link else s), flange or link or None, q_home
        name = os.path.splitext(os.path.basename(path))[0]
        if not os.path.exists(path):
            raise ValueError(f"no URDF file {path!r}")
    else:
        raise ValueError(f"unknown robot {s!r}; known: {', '.join(robot_names())}, or a path "
                         f"to a .urdf file")
    try:
        # a regular file of bounded size: a pipe or a device as the URDF is refused, not read
        with open_regular(path, MAX_URDF_BYTES, "URDF file", text=True, encoding="utf-8") as fh:
            model = pin.buildModelFromXML(_revolute_only(fh.read()))
    except (RuntimeError, ValueError, OSError) as exc:
        raise ValueError(f"{path}: the URDF failed to load ({exc})") from None
    # lock gripper/finger joints: only the arm swings
    lock = [j for j, n in enumerate(model.names) if j > 0 and ("finger" in n or "gripper" in
                                                               n.lower())]
    if lock:
        model = pin.buildReducedModel(model, lock, pin.neutral(model))
    fl = flange or fl or _tip_link(model, path)
    club = club or DEFAULT_CLUBS.get(name, Club())
    head = _attach_club(model, fl, club)
    if home is None:
        lo, hi = model.lowerPositionLimit, model.upperPositionLimit
        home = np.where(np.isfinite(lo) & np.isfinite(hi), 0.5 * (lo + hi), 0.0)
    home = np.asarray(home, float)
    if home.shape != (model.nq,):
        raise ValueError(f"q_home has {home.size} values for {model.nq} joints")
    robot = Robot(name, model, head, home, base, club, effort_excludes_gravity=name == "katana")
    _check_base(robot, field)
    return robot


def _tip_link(model, path: str) -> str:
    """The flange of a URDF given without one: the last link of its only chain's tip (a
    ``ValueError`` naming the tips when the arm branches)."""
    import pinocchio as pin

    parents = set(model.parents[1:])
    tips = [j for j in range(1, model.njoints) if j not in parents]
    if len(tips) != 1:
        names = [model.names[j] for j in tips]
        raise ValueError(f"{path}: the arm branches (tip joints {names}); name the link that "
                         f"holds the club: flange=LINK, or on the command line FILE.urdf#LINK")
    bodies = [f.name for f in model.frames
              if f.parentJoint == tips[0] and f.type == pin.FrameType.BODY]
    if not bodies:
        raise ValueError(f"{path}: no link after the joint {model.names[tips[0]]!r}; give "
                         "flange=LINK (FILE.urdf#LINK on the command line)")
    return bodies[-1]


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
