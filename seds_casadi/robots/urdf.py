"""URDFs of the shipped arms, generated from the tables their numbers come from.

* **Barrett WAM 7-DoF**: libbarrett's standard DH table and inertials (:func:`wam_urdf`;
  shipped as ``robots/wam7.urdf``).
* **Katana 6M180**: the joint origins, limits and inertials (masses, centres of mass and
  inertia tensors computed from the meshes) of ``katana_description`` (five arm joints; the
  gripper and its fingers are one rigid body with link 5 here) (:func:`katana_urdf`;
  ``robots/katana_6m180.urdf``; sources in ``robots/README.md``).
"""

from __future__ import annotations

import numpy as np

from ..core._io import data_folder

__all__ = ["wam_urdf", "katana_urdf", "ROBOTS_FOLDER", "WAM_DH", "KATANA_ORIGINS", "KATANA_TOOL",
           "lump_inertials"]

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
#: joint speed limits [rad/s]: each motor's no-load speed at 48 V (Barrett's motor data: 100.218
#: rad/s for motors 1-4, 192.309 for 5-6, 569.022 for 7) through libbarrett's joint-to-motor
#: ratios (``wam7w.conf`` j2mp: 42, 28.25 (and 16.8155 for joint 3 on motors 2-3), 18, 9.7,
#: 14.93); the fastest each joint can turn at all (robots/README.md explains the choice)
WAM_MOTOR_NO_LOAD = (100.218, 100.218, 100.218, 100.218, 192.309, 192.309, 569.022)
WAM_RATIOS = (42.0, 28.25, 16.8155, 18.0, 9.7, 9.7, 14.93)
WAM_VELOCITY = [round(w / g, 3) for w, g in zip(WAM_MOTOR_NO_LOAD, WAM_RATIOS)]

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
#: katana_description's inertials (katana_300_6m180.urdf.xacro, "calculated from the meshes
#: using MeshLab"; uos/katana_driver at commit 84b0ff3, the file unchanged since e90da68, 2013):
#: (mass, centre of mass, (ixx, iyy, izz, ixy, ixz, iyz)) in each link's frame (the joint frames
#: above are the description's, so its link frames are ours)
KATANA_BASE_INERTIAL = (1.4047990875, (-0.000327, 0.000908, 0.058457),
                        (0.003000703, 0.002974822, 0.001434739, 0.000000864, -0.000011312,
                         0.000036294))
KATANA_INERTIALS = [
    (0.74793301875, (-0.000410, -0.001285, -0.016774),
     (0.001737241, 0.000998782, 0.001349170, 0.000000421, 0.000000650, 0.000016114)),
    (0.80174941875, (0.092420, 0.005283, 0.000172),
     (0.000478252, 0.004314636, 0.004625444, 0.000081166, 0.000003961, 0.000000332)),
    (0.79241664375, (0.058036, 0.008963, -0.000187),
     (0.001156089, 0.002305646, 0.003128648, 0.000112877, -0.000004398, -0.000000036)),
    (0.69149323125, (0.050401, 0.005807, 0.000000),
     (0.000765999, 0.001504115, 0.001887277, 0.000045260, -0.000001210, 0.000000147)),
    (0.25622555625, (-0.003140899, 0.000013920, 0.001680144),
     (0.000120481, 0.000132130, 0.000093522, 0.000000015, -0.000001089, -0.000000124)),
]
#: the gripper (a fixed joint (0, 0, -0.0323; 0, pi/2, 0) on link 5) and its two fingers
#: (joints (0.034, 0, 0; 0 or pi, 0, 0) on the gripper, held at 0 here): lumped into link 5
KATANA_GRIPPER = (0.0552136183596, (-0.014379, 0.0, 0.000006),
                  (0.000011468, 0.000013830, 0.000011290, 0.0, 0.000000007, 0.0))
KATANA_FINGER = (0.0251722230462, (0.034 - 0.032216, 0.025167, -0.001603),
                 (0.000005990, 0.000019757, 0.000023588, 0.000008473, 0.000001448,
                  -0.000000996))
KATANA_MASSES = [m for m, _, _ in KATANA_INERTIALS]


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
             '(limits, efforts); velocity limits: motor no-load speeds through libbarrett\'s '
             'transmission ratios (robots/README.md). -->\n'
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


def _ry(a) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _tensor(i6) -> np.ndarray:
    ixx, iyy, izz, ixy, ixz, iyz = i6
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


def lump_inertials(parts) -> tuple[float, np.ndarray, tuple]:
    """One rigid body's inertial from parts ``(mass, com, inertia6, R, p)``, each given in its
    own frame placed at (R, p) in the body's frame: total mass, centre of mass and the inertia
    about it (ixx, iyy, izz, ixy, ixz, iyz) (parallel-axis theorem)."""
    m = sum(float(part[0]) for part in parts)
    coms = [np.asarray(R) @ np.asarray(c) + np.asarray(p) for _, c, _, R, p in parts]
    com = sum(float(part[0]) * c for part, c in zip(parts, coms)) / m
    Itot = np.zeros((3, 3))
    for (mi, _, i6, R, _), c in zip(parts, coms):
        d = c - com
        Itot += R @ _tensor(i6) @ R.T + mi * (d @ d * np.eye(3) - np.outer(d, d))
    return m, com, (Itot[0, 0], Itot[1, 1], Itot[2, 2], Itot[0, 1], Itot[0, 2], Itot[1, 2])


def katana_link5_inertial() -> tuple[float, np.ndarray, tuple]:
    """Link 5 with the gripper and both fingers (at 0) as one body, in link 5's frame."""
    Rg, pg = _ry(np.pi / 2), np.array([0.0, 0.0, -0.0323])
    parts = [(*KATANA_INERTIALS[4], np.eye(3), np.zeros(3)), (*KATANA_GRIPPER, Rg, pg)]
    for roll in (0.0, np.pi):
        parts.append((*KATANA_FINGER, Rg @ _rx(roll), pg + Rg @ np.array([0.034, 0.0, 0.0])))
    return lump_inertials(parts)


def katana_urdf() -> str:
    """URDF of the Katana 6M180 (five arm joints about z; katana_description's origins, limits
    and inertials; the gripper and its fingers rigid and lumped into link 5)."""
    parts = ['<?xml version="1.0"?>\n<!-- generated by seds_casadi.robots.katana_urdf(); joint '
             'origins, limits, efforts, velocities, masses, centres of mass and inertias: '
             'katana_description (katana_300_6m180.urdf.xacro, uos/katana_driver 84b0ff3), the '
             'gripper and its fingers lumped into link 5. The efforts were measured from a '
             'Gazebo controller with gravity off. -->\n<robot name="katana_6m180">\n',
             '  <link name="katana_base">\n' + _inertial(*KATANA_BASE_INERTIAL) + '  </link>\n']
    parent = "katana_base"
    for i, ((xyz, rpy), lim) in enumerate(zip(KATANA_ORIGINS, KATANA_LIMITS)):
        link = f"katana_link{i + 1}"
        parts.append(_joint(f"katana_j{i + 1}", parent, link, xyz, rpy, lim, KATANA_EFFORT[i],
                            KATANA_VELOCITY[i]))
        inertial = katana_link5_inertial() if i == 4 else KATANA_INERTIALS[i]
        parts.append(f'  <link name="{link}">\n' + _inertial(*inertial) + '  </link>\n')
        parent = link
    parts.append(_joint("katana_flange_joint", parent, "katana_flange", *KATANA_TOOL))
    parts.append('  <link name="katana_flange"/>\n</robot>\n')
    return "".join(parts)
