"""What a sensor may look at: a read-only view of the world and of its own robot.

Sensors never keep MuJoCo ids or model references across rebuilds: they resolve
them in ``configure``, which runs after every (re)compilation.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

import mujoco
import numpy as np

from usarsim.sim import frames

if TYPE_CHECKING:
    from usarsim.config.world import GeoReference, WorldConfig
    from usarsim.sim.entities import Entities

# Geom groups: which geoms ray-cast sensors can see.
GROUP_STATIC = 0  # world geometry
GROUP_ROBOT = 1  # robot bodies (chassis)
GROUP_MOVABLE = 2  # movable obstacles
GROUP_WHEEL = 3  # wheels and other small moving parts: not seen by range sensors
RAY_GROUPS = np.array([1, 1, 1, 0, 0, 0], dtype=np.uint8)


class RayCaster:
    """Batched ray casts with the caller's robot excluded and a cutoff at the
    sensor's maximum range.

    Rays are cast by the compiled kernel of :mod:`usarsim.sim.raycast` (one call
    for a whole batch, one origin per ray, geoms out of reach culled); models
    with shapes it does not handle, or ``USARSIM_RAYCAST=mujoco`` in the
    environment, use ``mj_multiRay`` (one call per distinct origin).  Both give
    the same distances.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, backend: str | None = None,
                 see_through: dict[str, np.ndarray] | None = None):
        self.m = model
        self.d = data
        self.rays_cast = 0
        m = model
        alpha = np.where(m.geom_matid >= 0, m.mat_rgba[np.maximum(m.geom_matid, 0), 3] if m.nmat else 0.0,
                         m.geom_rgba[:, 3])
        group = np.clip(m.geom_group, 0, 5)
        self._visible = (RAY_GROUPS[group] != 0) & (alpha != 0)
        # per sensor kind (ir, camera, laser, sonar): the geoms its rays pass through (glass)
        self._see_through = {k: v for k, v in (see_through or {}).items() if len(v) == m.ngeom and v.any()}
        self._masks = {k: self._visible & ~v for k, v in self._see_through.items()}
        self._gtype = np.ascontiguousarray(m.geom_type, dtype=np.int64)
        self._gbody = np.ascontiguousarray(m.geom_bodyid, dtype=np.int64)
        backend = backend or os.environ.get("USARSIM_RAYCAST", "") or "compiled"
        if backend not in ("compiled", "mujoco"):
            raise ValueError(f"USARSIM_RAYCAST must be 'compiled' or 'mujoco', got {backend!r}")
        if backend == "compiled":
            from usarsim.sim import raycast

            if not np.isin(self._gtype[self._visible], raycast.SUPPORTED).all():
                backend = "mujoco"
            else:
                raycast.warm_up()
        self.backend = backend

    def cast(self, origin: np.ndarray, dirs: np.ndarray, max_range: float, exclude_body: int,
             normals: bool = False, kind: str | None = None) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """Cast ``dirs`` (n x 3 unit vectors, MuJoCo frame) from ``origin``.

        Returns (distance, normals, geom ids): distance is ``inf`` where nothing is
        hit within ``max_range``.  ``kind`` (``ir``, ``camera``, ``laser``, ``sonar``)
        lets the rays pass through the materials that kind sees through.
        """
        dirs = np.ascontiguousarray(dirs, dtype=float).reshape(-1, 3)
        origins = np.broadcast_to(np.asarray(origin, dtype=float), dirs.shape)
        return self.cast_from(origins, dirs, max_range, exclude_body, normals, kind)

    def cast_from(self, origins: np.ndarray, dirs: np.ndarray, max_range: float, exclude_body: int,
                  normals: bool = False, kind: str | None = None) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """Cast ray i from ``origins[i]`` along ``dirs[i]`` (n x 3 each, MuJoCo frame)."""
        dirs = np.ascontiguousarray(dirs, dtype=float).reshape(-1, 3)
        origins = np.ascontiguousarray(origins, dtype=float).reshape(-1, 3)
        n = len(dirs)
        self.rays_cast += n
        dist = np.empty(n)
        gid = np.empty(n, np.int32)
        nrm = np.zeros((n, 3))
        if self.backend == "compiled":
            from usarsim.sim.raycast import cast_kernel

            m, d = self.m, self.d
            mask = self._masks.get(kind, self._visible) if kind else self._visible
            cast_kernel(origins, dirs, float(max_range), self._gtype, m.geom_size, m.geom_rbound, self._gbody,
                        mask, d.geom_xpos, d.geom_xmat, int(exclude_body), normals, dist, gid, nrm)
        elif kind in self._see_through:
            # mj_multiRay filters by group only: hide the see-through geoms in an unseen group
            hide = self._see_through[kind]
            saved = self.m.geom_group[hide].copy()
            self.m.geom_group[hide] = 5
            try:
                self._cast_mujoco(origins, dirs, float(max_range), int(exclude_body), normals, dist, gid, nrm)
            finally:
                self.m.geom_group[hide] = saved
        else:
            self._cast_mujoco(origins, dirs, float(max_range), int(exclude_body), normals, dist, gid, nrm)
        return dist, (nrm if normals else None), gid

    def _cast_mujoco(self, origins, dirs, max_range, exclude_body, normals, dist, gid, nrm) -> None:
        starts = np.flatnonzero(np.any(origins[1:] != origins[:-1], axis=1)) + 1
        bounds = [0, *starts.tolist(), len(dirs)]
        for a, b in zip(bounds[:-1], bounds[1:]):
            k = b - a
            g = np.zeros(k, np.int32)
            dd = np.zeros(k)
            nn = np.zeros(3 * k)
            mujoco.mj_multiRay(self.m, self.d, origins[a].copy(), dirs[a:b].reshape(-1).copy(), RAY_GROUPS, 1,
                               exclude_body, g, dd, nn if normals else None, k, max_range)
            miss = (g < 0) | (dd < 0) | (dd > max_range)
            dd[miss] = np.inf
            g[miss] = -1
            dist[a:b] = dd
            gid[a:b] = g
            if normals:
                nrm[a:b] = nn.reshape(k, 3)


@dataclass
class WorldView:
    model: mujoco.MjModel
    data: mujoco.MjData
    time: float
    caster: RayCaster
    world: "WorldConfig | None" = None
    entities: "Entities | None" = None
    # for effecters: drive_joint(name, value, order) on the operating robot's joints
    drive_joint: "Callable[[str, float, int], bool] | None" = None

    @property
    def geo(self) -> "GeoReference":
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
        self.rotor: dict[str, int] = {}  # aerial robots: actuator per axis
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
        self.rotor.clear()
        if _has_site(m, f"{self.prefix}/rotors"):
            from usarsim.sim.builder import AERIAL_AXES

            for axis in AERIAL_AXES:
                self.rotor[axis] = m.actuator(f"{self.prefix}/{axis}").id
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

    def sensor_frame(self, d: mujoco.MjData, location, orientation,
                     mount: str = "HARD") -> tuple[np.ndarray, np.ndarray]:
        """World position and rotation (MuJoCo frame) of an item mounted at ``location``
        / ``orientation`` (USARSim frame) relative to its mount: the chassis (``HARD``)
        or a named part of the robot, which it then follows (a wheel turns it)."""
        body = self.body_id if mount == "HARD" else self.part_body.get(mount, self.body_id)
        rot = d.xmat[body].reshape(3, 3)
        pos = d.xpos[body] + rot @ frames.to_mj_vec(location)
        return pos, rot @ frames.usar_euler_to_mj_mat(orientation)


def _has_site(m: mujoco.MjModel, name: str) -> bool:
    return mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, name) >= 0


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
