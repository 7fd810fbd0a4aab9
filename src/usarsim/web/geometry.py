"""What the console's world view draws, as JSON: the world's static geometry seen from
above and the robot classes a client may spawn.

Footprints are polygons in the world's horizontal plane (USARSim frame: X forward/north,
Y right/east, metres): the outline of a shape after its roll, pitch and yaw, projected
straight down.  ``top`` is how high the shape reaches above the floor (Z is down), so a
viewer can draw higher things over lower ones.  ``bounds`` holds the floor and everything
on it (what the map shows when fitted); ``arena`` only what the world is made of, the floor
left out (what the 3-D view frames).
"""

from __future__ import annotations

import dataclasses
import math
import struct
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from usarsim.config.world import WorldConfig
from usarsim.sim.types import euler_to_mat

if TYPE_CHECKING:
    from usarsim.sim.types import VelocityLimits

CIRCLE_POINTS = 24  # points around a cylinder's end when its outline is drawn


def convex_hull(points: np.ndarray) -> list[list[float]]:
    """The convex hull of 2D points (Andrew's monotone chain), counter-clockwise."""
    pts = sorted({(round(float(x), 4), round(float(y), 4)) for x, y in points})
    if len(pts) <= 2:
        return [list(p) for p in pts]

    def cross(o, a, b) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list[tuple[float, float]] = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    upper: list[tuple[float, float]] = []
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return [list(p) for p in lower[:-1] + upper[:-1]]


def _mesh_vertices(path: str) -> np.ndarray:
    """The vertices of a Wavefront OBJ or binary STL file (its own frame); empty if unreadable."""
    p = Path(path)
    try:
        if p.suffix.lower() == ".obj":
            rows = [ln.split()[1:4] for ln in p.read_text(errors="replace").splitlines() if ln.startswith("v ")]
            return np.array([[float(v) for v in r] for r in rows if len(r) == 3], dtype=float).reshape(-1, 3)
        data = p.read_bytes()
        if len(data) < 84:
            return np.zeros((0, 3))
        (count,) = struct.unpack_from("<I", data, 80)
        tris = np.frombuffer(
            data,
            dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]),
            count=min(count, (len(data) - 84) // 50),
            offset=84,
        )
        return tris["v"].reshape(-1, 3).astype(float)
    except (OSError, ValueError):
        return np.zeros((0, 3))


def shape_points(
    shape: str,
    size=(0.0, 0.0, 0.0),
    radius: float = 0.0,
    length: float = 0.0,
    mesh_file: str = "",
    scale=(1.0, 1.0, 1.0),
) -> np.ndarray:
    """Points of a shape's outline in its own frame (N x 3)."""
    if shape == "cylinder":
        a = np.linspace(0.0, 2.0 * math.pi, CIRCLE_POINTS, endpoint=False)
        ring = np.stack([radius * np.cos(a), radius * np.sin(a)], axis=1)
        h = length / 2.0
        return np.concatenate(
            [np.column_stack([ring, np.full(len(a), -h)]), np.column_stack([ring, np.full(len(a), h)])]
        )
    if shape == "mesh":
        v = _mesh_vertices(mesh_file)
        return v * np.asarray(scale, dtype=float) if len(v) else np.zeros((1, 3))
    sx, sy, sz = (s / 2.0 for s in size)
    return np.array([[x, y, z] for x in (-sx, sx) for y in (-sy, sy) for z in (-sz, sz)], dtype=float)


def footprint(points: np.ndarray, center, rotation) -> tuple[list[list[float]], float, float]:
    """(outline seen from above, top and bottom heights above the floor) of a shape's
    points placed at ``center`` with ``rotation`` (roll, pitch, yaw)."""
    world = points @ euler_to_mat(*rotation).T + np.asarray(center, dtype=float)
    return convex_hull(world[:, :2]), float(-world[:, 2].min()), float(-world[:, 2].max())


def _rgba(world: WorldConfig, material: str) -> list[float]:
    m = world.materials.get(material)
    return [round(float(c), 3) for c in (m.rgba if m is not None else (0.7, 0.7, 0.7, 1.0))]


def _r(values) -> list[float]:
    return [round(float(v), 4) for v in values]


def arena_box(world: WorldConfig, objects: list[dict]) -> list[float]:
    """The box that holds what a world is made of: [x0, y0, x1, y1, top] (metres; ``top`` is
    the height above the floor of the highest thing).  Its objects' outlines and its victims
    without the floor, which reaches far beyond them in most worlds; the floor alone when
    the world has nothing on it."""
    xs: list[float] = []
    ys: list[float] = []
    top = 0.0
    for e in objects:
        for x, y in e["poly"]:
            xs.append(x)
            ys.append(y)
        top = max(top, e["top"])
    for v in world.victims:
        xs.append(v.location[0])
        ys.append(v.location[1])
    if not xs:
        fl = world.floor
        xs = [fl.center[0] - fl.size[0] / 2, fl.center[0] + fl.size[0] / 2]
        ys = [fl.center[1] - fl.size[1] / 2, fl.center[1] + fl.size[1] / 2]
    return _r((min(xs), min(ys), max(xs), max(ys), top))


def world_json(world: WorldConfig) -> dict:
    """The world's static geometry, start poses, victims, tags and water, for the world view."""
    objects: list[dict[str, Any]] = []
    for o in world.objects:
        pts = shape_points(o.shape, o.size, o.radius_m, o.length_m, o.mesh_file, o.scale)
        poly, top, bottom = footprint(pts, o.center, o.rotation)
        entry: dict[str, Any] = {
            "name": o.name,
            "shape": o.shape,
            "poly": poly,
            "top": round(top, 3),
            "bottom": round(bottom, 3),
            "rgba": _rgba(world, o.material),
            "movable": o.mass_kg > 0,
        }
        if o.mass_kg > 0:  # drawn where the ground truth says it is now: its outline in its own frame
            local, _, _ = footprint(pts, (0.0, 0.0, 0.0), (o.rotation[0], o.rotation[1], 0.0))
            entry.update(local=local, center=_r(o.center), yaw=round(o.rotation[2], 4))
        objects.append(entry)
    objects.sort(key=lambda e: (e["movable"], e["top"]))
    alarms = []
    for a in world.false_alarms:
        poly, top, _ = footprint(shape_points("box", a.size), a.center, a.rotation)
        alarms.append({"name": a.name, "part": a.part, "poly": poly, "top": round(top, 3)})
    water = []
    for w in world.water:
        poly, top, _ = footprint(shape_points("box", w.size), w.center, (0.0, 0.0, 0.0))
        water.append({"name": w.name, "poly": poly, "top": round(top, 3)})
    fl = world.floor
    xs = [fl.center[0] - fl.size[0] / 2, fl.center[0] + fl.size[0] / 2]
    ys = [fl.center[1] - fl.size[1] / 2, fl.center[1] + fl.size[1] / 2]
    for e in objects:
        for x, y in e["poly"]:
            xs.append(x)
            ys.append(y)
    return {
        "name": world.name,
        "description": world.description,
        "floor": {"center": _r(fl.center), "size": _r(fl.size), "rgba": _rgba(world, fl.material)},
        "bounds": _r((min(xs), min(ys), max(xs), max(ys))),
        "arena": arena_box(world, objects),
        "objects": objects,
        "false_alarms": alarms,
        "water": water,
        "victims": [
            {
                "name": v.name,
                "location": _r(v.location),
                "rotation": _r(v.rotation),
                "posture": v.posture,
                "waving": v.waving,
            }
            for v in world.victims
        ],
        "rfid_tags": [{"id": t.tag_id, "location": _r(t.location)} for t in world.rfid_tags],
        "start_poses": [
            {"name": p.name, "location": _r(p.location), "rotation": _r(p.rotation)} for p in world.start_poses
        ],
    }


def robot_class_json(robot, lowest_point_m: float, velocities: VelocityLimits | None = None) -> dict:
    """What the console needs to know of a robot class: how it is driven (``velocities``: how
    fast a robot driven by velocities may go), its size, where it stands (``lowest_point_m``
    below its origin, by its drive), its cameras and mission packages."""
    cameras = [i.name for i in robot.items if i.item_type in ("Camera", "OmniCam", "OmniCamera")]
    return {
        "name": robot.class_name,
        "description": robot.description,
        "drive": robot.drive,
        "steering_type": robot.steering_type,
        "vehicle_type": robot.vehicle_type,
        "dimensions": _r(robot.geometry.dimensions),
        "max_speed": round(robot.max_speed_rad_s, 4),
        "max_front_steer": round(robot.max_front_steer_rad, 4),
        "velocities": None if velocities is None else dataclasses.asdict(velocities),
        # the Z (down) of a location where the robot stands on a floor at z = 0
        "spawn_z": round(-(lowest_point_m + robot.spawn_clearance_m), 3),
        "cameras": cameras,
        "packages": [{"name": p.name, "links": list(p.links)} for p in robot.mission_packages],
    }
