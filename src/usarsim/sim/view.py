"""What a sensor may look at: a read-only view of the world and of its own robot.

Sensors never keep MuJoCo ids or model references across rebuilds: they resolve
them in ``configure``, which runs after every (re)compilation.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from usarsim.sim import frames

if TYPE_CHECKING:
    from usarsim.config.world import GeoReference, WorldConfig
    from usarsim.sim.entities import Entities
    from usarsim.sim.raycaster import RayCaster


@dataclass
class WorldView:
    """What a sensor or effecter is handed when it measures or acts: the model and the physics state, the simulated
    time (s), the ray caster, the world file and its entities, and for an effecter the operating robot's joints and
    name."""

    model: mujoco.MjModel
    data: mujoco.MjData
    time: float
    caster: RayCaster
    world: WorldConfig | None = None
    entities: Entities | None = None
    # for effecters: drive_joint(name, value, order) on the operating robot's joints
    drive_joint: Callable[[str, float, int], bool] | None = None
    robot_name: str = ""  # for effecters: the operating robot's name (its INIT's)

    @property
    def geo(self) -> GeoReference:
        from usarsim.config.world import GeoReference

        return self.world.geo if self.world is not None else GeoReference()


class RobotHandle:
    """Ids of one robot inside the current model, resolved by name after each build."""

    def __init__(self, prefix: str):
        self.prefix = prefix
        self.body_id = -1
        self.root_qpos = -1
        self.root_qvel = -1
        self.joint_qpos: dict[str, int] = {}
        self.joint_qvel: dict[str, int] = {}
        self.actuator: dict[str, int] = {}
        self.part_body: dict[str, int] = {}  # named parts items can be mounted on (wheels, links)
        self.light = -1  # the headlight
        self.steer_qpos: dict[str, int] = {}  # steered wheels: steering joint position
        self.steer_actuator: dict[str, int] = {}

    def resolve(self, m: mujoco.MjModel, wheels, links=()) -> None:
        """Look the chassis, every wheel and link joint and their actuators up by name."""
        self.body_id = m.body(self.prefix).id
        j = m.joint(f"{self.prefix}/root")
        self.root_qpos = int(m.jnt_qposadr[j.id])
        self.root_qvel = int(m.jnt_dofadr[j.id])
        self.joint_qpos.clear()
        self.joint_qvel.clear()
        self.actuator.clear()
        self.part_body.clear()
        self.light = m.light(f"{self.prefix}/headlight").id
        self.steer_qpos.clear()
        self.steer_actuator.clear()
        for w in wheels:
            self.part_body[w.name] = m.body(f"{self.prefix}/{w.name}").id
            if w.steer != "none":
                sj = m.joint(f"{self.prefix}/{w.name}/steer").id
                self.steer_qpos[w.name] = int(m.jnt_qposadr[sj])
                self.steer_actuator[w.name] = m.actuator(f"{self.prefix}/{w.name}/steer").id
            jid = m.joint(f"{self.prefix}/{w.name}").id
            self.joint_qpos[w.name] = int(m.jnt_qposadr[jid])
            self.joint_qvel[w.name] = int(m.jnt_dofadr[jid])
            if w.driven:
                self.actuator[w.name] = m.actuator(f"{self.prefix}/{w.name}").id
        for ln in links:
            self.part_body[ln.name] = m.body(f"{self.prefix}/{ln.name}").id
            jid = m.joint(f"{self.prefix}/{ln.name}").id
            self.joint_qpos[ln.name] = int(m.jnt_qposadr[jid])
            self.joint_qvel[ln.name] = int(m.jnt_dofadr[jid])
            self.actuator[ln.name] = m.actuator(f"{self.prefix}/{ln.name}").id

    # Pose of the chassis in the USARSim frame ------------------------------------
    def position_mj(self, d: mujoco.MjData) -> np.ndarray:
        return d.xpos[self.body_id]

    def rotation_mj(self, d: mujoco.MjData) -> np.ndarray:
        return d.xmat[self.body_id].reshape(3, 3)

    def location(self, d: mujoco.MjData) -> tuple[float, float, float]:
        return frames.from_mj_vec(d.xpos[self.body_id])

    def orientation(self, d: mujoco.MjData) -> tuple[float, float, float]:
        return frames.mj_mat_to_usar_euler(d.xmat[self.body_id])

    def sensor_frame(
        self, d: mujoco.MjData, location, orientation, mount: str = "HARD"
    ) -> tuple[np.ndarray, np.ndarray]:
        """World position and rotation (MuJoCo frame) of an item mounted at ``location``
        / ``orientation`` (USARSim frame) relative to its mount: the chassis (``HARD``)
        or a named part of the robot, which it then follows (a wheel turns it)."""
        body = self.body_id if mount == "HARD" else self.part_body.get(mount, self.body_id)
        rot = d.xmat[body].reshape(3, 3)
        pos = d.xpos[body] + rot @ frames.to_mj_vec(location)
        return pos, rot @ frames.usar_euler_to_mj_mat(orientation)


def unit_dirs_yaw_pitch(yaws: np.ndarray, pitches: np.ndarray) -> np.ndarray:
    """Unit vectors in a sensor's own USARSim frame for (yaw right+, pitch) offsets,
    returned in the sensor's MuJoCo-frame coordinates (x, -y, -z)."""
    cp = np.cos(pitches)
    x = cp * np.cos(yaws)
    y = cp * np.sin(yaws)
    z = -np.sin(pitches)  # positive pitch raises the beam; Z is down
    return np.stack([x, -y, -z], axis=-1)


def angle_between(a: float, b: float) -> float:
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)
