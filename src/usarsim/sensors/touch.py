"""The Touch contact sensor (protocol.md 7.2): True while a small sphere at the sensor's
mount touches anything but its own robot.  All Touch sensors of a robot are reported
together in one packed SEN line (protocol.md 6.3: ``{Name Touch Touch False}``).

Model: the sphere (``Diameter`` 0.01 m, protocol.md 7.2) touches a geom when the
distance from its centre to that geom's surface is at most its radius, or when the
centre is inside the geom.  MuJoCo finds that itself: the model builder puts the sphere at
the sensor's mount as a probe geom, whose contacts MuJoCo detects with everything
collidable but its own robot (world geometry, the floor, victims, other robots and their
wheels) while they overlap, and never acts on: its margin is far negative, so that its
contacts stay inactive ("in the gap", MuJoCo's contact gap), they push nothing.  A
measurement, at the sensor's ScanInterval only, looks the probe up among the contacts of
the last physics step: no geometry of its own, whatever the shapes (meshes included).
Without a probe (a model built otherwise) the sensor measures the distances itself:
signed distance functions of MuJoCo's plane, sphere, capsule, ellipsoid, cylinder and box
in the geom's own frame, other shapes as their local bounding box.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Self

import mujoco
import numpy as np

from usarsim.readings import TouchItem, TouchReading
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig
from usarsim.sim import frames
from usarsim.sim.constants import GROUP_WHEEL, SOLID_CONAFFINITY, SOLID_CONTYPE
from usarsim.sim.robotspec import mount_body

if TYPE_CHECKING:
    from usarsim.config.robot import MountedItem, RobotConfig
    from usarsim.sim.view import WorldView

_PLANE = int(mujoco.mjtGeom.mjGEOM_PLANE)
_SPHERE = int(mujoco.mjtGeom.mjGEOM_SPHERE)
_CAPSULE = int(mujoco.mjtGeom.mjGEOM_CAPSULE)
_ELLIPSOID = int(mujoco.mjtGeom.mjGEOM_ELLIPSOID)
_CYLINDER = int(mujoco.mjtGeom.mjGEOM_CYLINDER)
_BOX = int(mujoco.mjtGeom.mjGEOM_BOX)

# The probe geom (usarsim.sim.builder adds one per Touch item): the sensor's sphere (built
# at the default Diameter, given the sensor's own when it is configured), whose contacts
# MuJoCo detects while it overlaps anything (its gap makes up for its margin) and acts on
# only at a penetration deeper than -PROBE_MARGIN_M, which nothing reaches.
PROBE_RADIUS_M = 0.005  # protocol.md 7.2: Diameter 0.01 m
PROBE_MARGIN_M = -1.0


def probe_name(prefix: str, item_name: str) -> str:
    """The probe geom of the robot ``prefix``'s Touch item ``item_name``."""
    return f"{prefix}/touch/{item_name}"


def add_probe(spec: mujoco.MjSpec, chassis: mujoco.MjsBody, item: MountedItem, prefix: str) -> None:
    """A Touch sensor's probe: its sphere at its mount, whose contacts MuJoCo finds, never
    acting on them (a far negative margin).  It collides with what a solid does; its robot's
    own bodies are filtered out as the robot's parts are (same body, parent and child, the
    robot's exclusions)."""
    parent = mount_body(spec, chassis, item, prefix)
    g = parent.add_geom()
    g.name = probe_name(prefix, item.name)
    g.type = mujoco.mjtGeom.mjGEOM_SPHERE
    g.size = [PROBE_RADIUS_M, 0.0, 0.0]
    g.pos = frames.to_mj_vec(item.location).tolist()
    g.mass = 0.0
    g.density = 0.0
    g.margin = PROBE_MARGIN_M
    g.gap = -PROBE_MARGIN_M  # detected while it overlaps: distance below margin + gap = 0
    g.contype, g.conaffinity = SOLID_CONTYPE, SOLID_CONAFFINITY
    g.group = GROUP_WHEEL  # not seen by range sensors
    g.rgba = [0.0, 0.0, 0.0, 0.0]


def _box_sd(p: np.ndarray, half: np.ndarray) -> float:
    q = np.abs(p) - half
    outside = float(np.linalg.norm(np.maximum(q, 0.0)))
    return outside + min(float(q.max()), 0.0)


def signed_distance(gtype: int, size: np.ndarray, aabb: np.ndarray, p: np.ndarray) -> float:
    """Signed distance from ``p`` (in the geom's own frame) to the geom's surface:
    negative inside.  ``size`` is MuJoCo's geom_size, ``aabb`` its geom_aabb (centre,
    half sizes in the geom frame), used for shapes without a formula here."""
    if gtype == _PLANE:
        return float(p[2])  # the solid half-space below z = 0, as MuJoCo collides with it
    if gtype == _SPHERE:
        return float(np.linalg.norm(p)) - float(size[0])
    if gtype == _CAPSULE:
        h = float(size[1])
        z = min(max(float(p[2]), -h), h)
        return math.hypot(float(p[0]), float(p[1]), float(p[2]) - z) - float(size[0])
    if gtype == _CYLINDER:
        dr = math.hypot(float(p[0]), float(p[1])) - float(size[0])
        dz = abs(float(p[2])) - float(size[1])
        return math.hypot(max(dr, 0.0), max(dz, 0.0)) + min(max(dr, dz), 0.0)
    if gtype == _BOX:
        return _box_sd(p, np.asarray(size, dtype=float))
    if gtype == _ELLIPSOID:
        # a bound that is exact on the surface and close near it (Quilez's
        # ellipsoid approximation); the radii are all > 0
        r = np.asarray(size, dtype=float)
        k0 = float(np.linalg.norm(p / r))
        if k0 == 0.0:
            return -float(r.min())
        k1 = float(np.linalg.norm(p / (r * r)))
        return k0 * (k0 - 1.0) / k1
    # meshes, height fields, SDF geoms: their local bounding box
    return _box_sd(p - aabb[:3], aabb[3:])


@dataclass(frozen=True, kw_only=True)
class TouchConfig(SensorConfig):
    """A Touch sensor's settings in a robot file (protocol.md 7.2): its scan interval and the diameter, in metres, of
    the sphere at its mount that feels contact."""

    # Touch (protocol.md 7.2): Diameter 0.01 m, ScanInterval 0.1.
    scan_interval_s: float = 0.1
    diameter_m: float = 0.01

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (self.diameter_m > 0 and math.isfinite(self.diameter_m)):
            raise ValueError(f"diameter_m must be > 0, got {self.diameter_m}")


@SENSORS.register("Touch")
class Touch(Sensor[TouchConfig]):
    """True while the sphere of ``Diameter`` at the mount touches (or has its centre
    inside) anything other than the robot's own bodies."""

    PACKED = True
    ALIASES = {"Diameter": "diameter_m"}

    def __init__(self, item: MountedItem, config: TouchConfig, robot: RobotConfig, seed: int) -> None:
        super().__init__(item, config, robot, seed)
        self._radius = self.config.diameter_m / 2.0

    def build(self, spec: mujoco.MjSpec, chassis: mujoco.MjsBody, prefix: str) -> None:
        add_probe(spec, chassis, self.item, prefix)

    def configure(self, view: WorldView) -> None:
        m = view.model
        self._probe = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, probe_name(self.handle.prefix, self.name))
        if self._probe >= 0:
            # the probe is the sensor's sphere: its contacts are detected while it overlaps
            # (distance below margin + gap = 0)
            g = self._probe
            m.geom_size[g, 0] = m.geom_rbound[g] = self._radius
            m.geom_aabb[g, 3:] = self._radius
            m.geom_gap[g] = -m.geom_margin[g]
            return
        own = m.body_rootid[m.geom_bodyid] == self.handle.body_id
        collides = (m.geom_contype != 0) | (m.geom_conaffinity != 0)
        cand = np.flatnonzero(collides & ~own)
        is_plane = m.geom_type[cand] == _PLANE
        self._planes = cand[is_plane]
        self._solids = cand[~is_plane]
        self._reach = m.geom_rbound[self._solids] + self._radius
        # the sphere's centre on its mount (a wheel or link it follows, else the chassis)
        mount = self.item.mount
        self._body = self.handle.body_id if mount == "HARD" else self.handle.part_body.get(mount, self.handle.body_id)
        self._offset = frames.to_mj_vec(self.item.location)

    def _centre(self, view: WorldView) -> np.ndarray:
        d = view.data
        centre: np.ndarray = d.xpos[self._body] + d.xmat[self._body].reshape(3, 3) @ self._offset
        return centre

    def touching(self, view: WorldView, near: np.ndarray | None = None, centre: np.ndarray | None = None) -> bool:
        """Whether the sphere touches anything; ``near`` (the candidates within reach) and
        ``centre`` when the caller has them already."""
        m, d = view.model, view.data
        if centre is None:
            centre = self._centre(view)
        r = self._radius
        for g in self._planes:
            local = d.geom_xmat[g].reshape(3, 3).T @ (centre - d.geom_xpos[g])
            if local[2] <= r:
                return True
        if near is None and len(self._solids):
            gap = np.linalg.norm(d.geom_xpos[self._solids] - centre, axis=1)
            near = self._solids[gap <= self._reach]
        for g in near if near is not None else ():
            local = d.geom_xmat[g].reshape(3, 3).T @ (centre - d.geom_xpos[g])
            if signed_distance(int(m.geom_type[g]), m.geom_size[g], m.geom_aabb[g], local) <= r:
                return True
        return False

    # the geoms in the gap contacts of the last physics step (the probes' contacts among
    # them), worked out once for every robot's touch sensors at one instant: ((data, time,
    # contacts), geom ids), replaced as a whole (simulations in other threads see either)
    _gap_geoms: tuple[tuple[int, float, int], frozenset[int]] = ((0, -1.0, -1), frozenset())

    @classmethod
    def _touched(cls, view: WorldView) -> frozenset[int]:
        d = view.data
        key = (id(d), view.time, d.ncon)
        cached = cls._gap_geoms
        if cached[0] == key:
            return cached[1]
        n = d.ncon
        gap = d.contact.exclude[:n] == 1
        geoms = frozenset(d.contact.geom[:n][gap].ravel().tolist())
        cls._gap_geoms = (key, geoms)
        return geoms

    def measure(self, view: WorldView) -> TouchItem:
        if self._probe >= 0:
            return TouchItem(self.name, self._probe in self._touched(view))
        return TouchItem(self.name, self.touching(view))

    @classmethod
    def measure_group(cls, sensors: list[Self], view: WorldView) -> list[TouchItem]:
        """Every touch sensor of a robot at once: with probes, each looks itself up among the
        last step's contacts (gathered once an instant for every robot); else they share
        their candidates (everything but the robot), so the distances to all of them are one
        array operation."""
        first = sensors[0]
        if any(s._probe >= 0 for s in sensors) or not len(first._solids):
            return [s.measure(view) for s in sensors]
        d = view.data
        centres = np.array([s._centre(view) for s in sensors])
        delta = d.geom_xpos[first._solids][None, :, :] - centres[:, None, :]
        gap2 = np.einsum("ijk,ijk->ij", delta, delta)
        radii = np.array([s._radius for s in sensors])
        within = gap2 <= (first._reach[None, :] - first._radius + radii[:, None]) ** 2
        out = []
        for i, s in enumerate(sensors):
            near = first._solids[within[i]]
            out.append(TouchItem(s.name, s.touching(view, near, centres[i])))
        return out

    @classmethod
    def combine(cls, parts: list[TouchItem]) -> TouchReading:
        return TouchReading(tuple(parts))
