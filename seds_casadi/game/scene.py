"""A scene: the robot with its base and club, the field and the hitting motion of a game.

A :class:`Scene` holds loaded objects (a Pinocchio model per ball position on demand, the
field, the fitted motion). To run shots in worker processes, a scene travels as its
:class:`SceneSpec` (the robot's name, the field's specification, the motion's folder and the
launch table as text: small, hashable and picklable), and :meth:`SceneSpec.load` builds the
scene once per process and reuses it for every later shot of that process.
"""

from __future__ import annotations

import functools
import json
import os
from dataclasses import dataclass

import numpy as np

from ..minigolf.fields import Field
from ..minigolf.stroke import LaunchTable, Stroke
from ..motion.golf import BALL_RADIUS
from ..motion.hitting import HittingMotion
from ..robots.models import Robot, robot_names
from ..robots.placement import place_robot


@dataclass(frozen=True, eq=False)
class Scene:
    """The robot, the field and the hitting motion of a game.

    Attributes
    ----------
    robot : str
        A robot name (:func:`~seds_casadi.robots.models.robot_names`) or a URDF file; it stands
        at its default base beside each ball (:func:`~seds_casadi.robots.placement.place_robot`).
    field : Field
    motion : HittingMotion
    launch_table : LaunchTable or None
        The robot's measured launch (:func:`~seds_casadi.game.launch.calibrate_launch`), for
        the teacher; None until it is measured.
    motion_folder : str or None
        Where the motion is saved (needed to send the scene to other processes).
    """

    robot: str
    field: Field
    motion: HittingMotion
    launch_table: LaunchTable | None = None
    motion_folder: str | None = None

    def __post_init__(self) -> None:
        name = str(self.robot)
        if name.lower() not in robot_names() and ".urdf" not in name:
            raise ValueError(f"unknown robot {name!r}; known: {', '.join(robot_names())}, or a "
                             ".urdf file")

    @property
    def stroke(self) -> Stroke:
        """The motion's default hit with the robot's launch (the ideal club's until the launch
        is measured): what the teacher searches."""
        return Stroke.from_motion(self.motion).with_launch(self.launch_table)

    def with_launch(self, table: LaunchTable | None) -> Scene:
        """The same scene with a measured launch."""
        return Scene(self.robot, self.field, self.motion, table, self.motion_folder)

    def robot_at(self, ball_xy) -> Robot:
        """The robot standing at its default base beside the ball at ``ball_xy``."""
        return place_robot(self.robot, np.asarray(ball_xy, float)[:2], self.field)

    def ball_position(self, ball_xy) -> np.ndarray:
        """The ball's centre (x, y, z) resting on the field's surface at ``ball_xy``."""
        b = np.asarray(ball_xy, float)[:2]
        return np.array([b[0], b[1], float(self.field.surface.height(b[None])[0]) + BALL_RADIUS])

    def spec(self) -> SceneSpec:
        """The scene as a picklable, hashable value (the motion must be saved in a folder)."""
        if self.motion_folder is None:
            raise ValueError("save the motion first (Scene(..., motion_folder=FOLDER) after "
                             "motion.save(FOLDER)): other processes load it from there")
        table = None if self.launch_table is None else json.dumps(self.launch_table.to_dict())
        return SceneSpec(str(self.robot), json.dumps(self.field.spec, sort_keys=True),
                         self.field.name, os.path.abspath(self.motion_folder), table)


@dataclass(frozen=True)
class SceneSpec:
    """A :class:`Scene` as text: what a worker process needs to load it.

    Attributes
    ----------
    robot : str
    field_json : str
        The field's specification (:attr:`Field.spec`) as JSON.
    field_name : str
    motion_folder : str
        An absolute folder written by :meth:`HittingMotion.save`.
    launch_table_json : str or None
    """

    robot: str
    field_json: str
    field_name: str
    motion_folder: str
    launch_table_json: str | None = None

    def load(self) -> Scene:
        """The scene, built once per process for each spec (later calls return the same
        object)."""
        return _load_scene(self)


@functools.lru_cache(maxsize=8)
def _load_scene(spec: SceneSpec) -> Scene:
    field = Field.from_dict(json.loads(spec.field_json), source=spec.field_name)
    motion = HittingMotion.load(spec.motion_folder)
    table = (None if spec.launch_table_json is None
             else LaunchTable.from_dict(json.loads(spec.launch_table_json)))
    return Scene(spec.robot, field, motion, table, spec.motion_folder)
