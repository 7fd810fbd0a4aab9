"""What a sensor may look at: a read-only view of the world and of its own robot.

Sensors never keep MuJoCo ids or model references across rebuilds: they resolve
them in ``configure``, which runs after every (re)compilation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from usarsim.sim import frames

# Geom groups: which geoms ray-cast sensors can see.
GROUP_STATIC = 0  # world geometry
GROUP_ROBOT = 1  # robot bodies (chassis)
GROUP_MOVABLE = 2  # movable obstacles
GROUP_WHEEL = 3  # wheels and other small moving parts: not seen by range sensors
RAY_GROUPS = np.array([1, 1, 1, 0, 0, 0], dtype=np.uint8)


class RayCaster:
    """Batched ray casts (one ``mj_multiRay`` call per origin) with the caller's
    robot excluded and a cutoff at the sensor's maximum range."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData):
        self.m = model
        self.d = data
        self._buf: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self.rays_cast = 0

    def _buffers(self, n: int):
        b = self._buf.get(n)
        if b is None:
            b = (np.zeros(n, np.int32), np.zeros(n), np.zeros(3 * n))
            self._buf[n] = b
        return b

    def cast(self, origin: np.ndarray, dirs: np.ndarray, max_range: float, exclude_body: int,
             normals: bool = False) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """Cast ``dirs`` (n x 3 unit vectors, MuJoCo frame) from ``origin``.

        Returns (distance, normals, geom ids): distance is ``inf`` where nothing is
        hit within ``max_range``.
        """
        n = len(dirs)
        gid, dist, nrm = self._buffers(n)
        vec = np.ascontiguousarray(dirs, dtype=float).reshape(-1)
        mujoco.mj_multiRay(self.m, self.d, np.asarray(origin, dtype=float), vec, RAY_GROUPS, 1, exclude_body,
                           gid, dist, nrm if normals else None, n, float(max_range))
        self.rays_cast += n
        out = dist.copy()
        out[(gid < 0) | (out < 0) | (out > max_range)] = np.inf
        return out, (nrm.reshape(n, 3).copy() if normals else None), gid.copy()


@dataclass
class WorldView:
    model: mujoco.MjModel
    data: mujoco.MjData
    time: float
    caster: RayCaster


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

    def resolve(self, m: mujoco.MjModel, wheels) -> None:
        """Look the chassis, every wheel joint and every driven wheel's actuator up by name."""
        self.body_id = m.body(self.prefix).id
        j = m.joint(f"{self.prefix}/root")
        self.root_qpos = int(m.jnt_qposadr[j.id])
        self.root_qvel = int(m.jnt_dofadr[j.id])
        self.joint_qpos.clear()
        self.joint_qvel.clear()
        self.actuator.clear()
        for w in wheels:
            jid = m.joint(f"{self.prefix}/{w.name}").id
            self.joint_qpos[w.name] = int(m.jnt_qposadr[jid])
            self.joint_qvel[w.name] = int(m.jnt_dofadr[jid])
            if w.driven:
                self.actuator[w.name] = m.actuator(f"{self.prefix}/{w.name}").id

    # Pose of the chassis in the USARSim frame ------------------------------------
    def position_mj(self, d: mujoco.MjData) -> np.ndarray:
        return d.xpos[self.body_id]

    def rotation_mj(self, d: mujoco.MjData) -> np.ndarray:
        return d.xmat[self.body_id].reshape(3, 3)

    def location(self, d: mujoco.MjData) -> tuple[float, float, float]:
        return frames.from_mj_vec(d.xpos[self.body_id])

    def orientation(self, d: mujoco.MjData) -> tuple[float, float, float]:
        return frames.mj_mat_to_usar_euler(d.xmat[self.body_id])

    def sensor_frame(self, d: mujoco.MjData, location, orientation) -> tuple[np.ndarray, np.ndarray]:
        """World position and rotation (MuJoCo frame) of a mount given in the robot's USARSim frame."""
        rot = self.rotation_mj(d)
        pos = d.xpos[self.body_id] + rot @ frames.to_mj_vec(location)
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
