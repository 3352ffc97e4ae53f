"""The club: a putter held rigidly at the robot's flange, and the clubs sized for each robot."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


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
