"""The world and its robots as Foxglove scene entities (``foxglove.SceneUpdate``) and frame
transforms (``foxglove.FrameTransforms``).

Foxglove draws in a right-handed frame with Z up; USARSim's is X forward, Y right, Z down.
Everything here is given in MuJoCo's frame (X forward, Y left, Z up: a half turn about X
from USARSim's, :mod:`usarsim.sim.frames`), which is what Foxglove expects.  The frames:

* ``world``: the world's origin;
* ``<robot>``: each robot's chassis (its ground-truth pose);
* ``<robot>/<item>``: each mounted sensor, effecter and camera (its GEO mount);
* ``<robot>/odom``: where the robot's odometry starts (its pose when it first appeared).
"""

from __future__ import annotations

import math
import struct
from pathlib import Path

from foxglove.messages import (
    Color,
    CubePrimitive,
    CylinderPrimitive,
    Duration,
    FrameTransform,
    Pose,
    Quaternion,
    SceneEntity,
    SceneEntityDeletion,
    SceneUpdate,
    SpherePrimitive,
    TextPrimitive,
    Timestamp,
    TriangleListPrimitive,
    Vector3,
)
from foxglove.messages import Point3 as FPoint3

from usarsim.config.world import StaticObject, WorldConfig

WORLD_FRAME = "world"
# Half a turn about X as a quaternion (w, x, y, z): a mesh file's vertices are in the object's
# USARSim axes (the simulation's builder turns them the same way).
MESH_FRAME_QUAT = (0.0, 1.0, 0.0, 0.0)

VICTIM_RGBA = (0.95, 0.55, 0.35, 1.0)
TAG_RGBA = (0.2, 0.8, 1.0, 1.0)
ALARM_RGBA = (0.9, 0.8, 0.2, 0.8)
WATER_RGBA = (0.2, 0.4, 0.9, 0.35)
ROBOT_RGBA = (0.95, 0.75, 0.1, 0.9)
START_RGBA = (0.3, 0.9, 0.3, 0.6)


def timestamp(t: float) -> Timestamp:
    sec = int(math.floor(t))
    return Timestamp(sec=sec, nsec=min(999_999_999, int(round((t - sec) * 1e9))))


def to_ns(t: float) -> int:
    """A simulated time as an MCAP log time (nanoseconds, never negative)."""
    return max(0, int(round(t * 1e9)))


def vec(v) -> Vector3:
    """A USARSim-frame position as a Foxglove (MuJoCo-frame) vector."""
    return Vector3(x=float(v[0]), y=-float(v[1]), z=-float(v[2]))


def quat_wxyz(rpy) -> tuple[float, float, float, float]:
    """A USARSim roll, pitch and yaw as a MuJoCo-frame unit quaternion (w, x, y, z): the
    rotation ``usarsim.sim.frames.usar_euler_to_mj_quat`` gives (yaw, then pitch, then roll,
    pitch and yaw negated), in closed form (a recording converts thousands a second)."""
    hr, hp, hy = 0.5 * rpy[0], -0.5 * rpy[1], -0.5 * rpy[2]
    cr, sr = math.cos(hr), math.sin(hr)
    cp, sp = math.cos(hp), math.sin(hp)
    cy, sy = math.cos(hy), math.sin(hy)
    return (
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    )


def quat(rpy) -> Quaternion:
    """A USARSim roll, pitch and yaw as a Foxglove (MuJoCo-frame) quaternion."""
    w, x, y, z = quat_wxyz(rpy)
    return Quaternion(x=x, y=y, z=z, w=w)


def pose(location, rotation) -> Pose:
    return Pose(position=vec(location), orientation=quat(rotation))


def color(rgba) -> Color:
    return Color(r=float(rgba[0]), g=float(rgba[1]), b=float(rgba[2]), a=float(rgba[3]))


def _mul(a, b) -> tuple[float, float, float, float]:
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def mesh_triangles(path: str, scale=(1.0, 1.0, 1.0)) -> list[tuple[float, float, float]]:
    """The triangles of a Wavefront OBJ or binary STL file, three points each (the file's own
    frame, scaled); empty when the file cannot be read."""
    p = Path(path)
    sx, sy, sz = scale
    out: list[tuple[float, float, float]] = []
    try:
        if p.suffix.lower() == ".obj":
            verts: list[tuple[float, float, float]] = []
            faces: list[list[int]] = []
            for ln in p.read_text(errors="replace").splitlines():
                parts = ln.split()
                if not parts:
                    continue
                if parts[0] == "v" and len(parts) >= 4:
                    verts.append((float(parts[1]) * sx, float(parts[2]) * sy, float(parts[3]) * sz))
                elif parts[0] == "f" and len(parts) >= 4:
                    idx = [int(t.split("/")[0]) for t in parts[1:]]
                    faces.append([i - 1 if i > 0 else len(verts) + i for i in idx])
            for f in faces:  # a polygon as a fan of triangles
                for k in range(1, len(f) - 1):
                    out += [verts[f[0]], verts[f[k]], verts[f[k + 1]]]
            return out
        data = p.read_bytes()
        if len(data) < 84:
            return []
        (count,) = struct.unpack_from("<I", data, 80)
        for i in range(min(count, (len(data) - 84) // 50)):
            v = struct.unpack_from("<9f", data, 84 + 50 * i + 12)
            out += [
                (v[0] * sx, v[1] * sy, v[2] * sz),
                (v[3] * sx, v[4] * sy, v[5] * sz),
                (v[6] * sx, v[7] * sy, v[8] * sz),
            ]
        return out
    except (OSError, ValueError, IndexError, struct.error):
        return []


def _object_primitives(o: StaticObject, rgba, location=None, rotation=None) -> dict:
    """The primitive of one world object at its place in the world file, or at ``location``
    and ``rotation`` (a movable object where it is now)."""
    loc = o.center if location is None else location
    rot = o.rotation if rotation is None else rotation
    p = pose(loc, rot)
    c = color(rgba)
    if o.shape == "box":
        return {"cubes": [CubePrimitive(pose=p, size=Vector3(x=o.size[0], y=o.size[1], z=o.size[2]), color=c)]}
    if o.shape == "cylinder":
        d = 2.0 * o.radius_m
        return {
            "cylinders": [
                CylinderPrimitive(
                    pose=p, size=Vector3(x=d, y=d, z=o.length_m), bottom_scale=1.0, top_scale=1.0, color=c
                )
            ]
        }
    pts = mesh_triangles(o.mesh_file, o.scale)
    w, x, y, z = _mul(quat_wxyz(rot), MESH_FRAME_QUAT)
    turned = Pose(position=vec(loc), orientation=Quaternion(x=x, y=y, z=z, w=w))
    return {
        "triangles": [TriangleListPrimitive(pose=turned, points=[FPoint3(x=a, y=b, z=cc) for a, b, cc in pts], color=c)]
    }


def _rgba(world: WorldConfig, material: str):
    m = world.materials.get(material)
    return m.rgba if m is not None else (0.7, 0.7, 0.7, 1.0)


def world_scene(world: WorldConfig, t: float = 0.0) -> SceneUpdate:
    """The world's static geometry, victims, false alarms, RFID tags, water and start poses:
    one entity per kind (``floor``, ``static``, ``victims``, ...), in the ``world`` frame."""
    ts = timestamp(t)
    fl = world.floor
    floor = SceneEntity(
        timestamp=ts,
        frame_id=WORLD_FRAME,
        id="floor",
        cubes=[
            CubePrimitive(
                pose=pose((fl.center[0], fl.center[1], 0.005), (0.0, 0.0, 0.0)),
                size=Vector3(x=fl.size[0], y=fl.size[1], z=0.01),
                color=color(_rgba(world, fl.material)),
            )
        ],
    )
    cubes, cylinders, triangles = [], [], []
    for o in world.objects:
        if o.mass_kg > 0:
            continue
        prims = _object_primitives(o, _rgba(world, o.material))
        cubes += prims.get("cubes", [])
        cylinders += prims.get("cylinders", [])
        triangles += prims.get("triangles", [])
    static = SceneEntity(
        timestamp=ts, frame_id=WORLD_FRAME, id="static", cubes=cubes, cylinders=cylinders, triangles=triangles
    )
    victims = SceneEntity(
        timestamp=ts,
        frame_id=WORLD_FRAME,
        id="victims",
        # a person lying (1.7 m x 0.5 m x 0.25 m) or standing; the pelvis is at the location
        cubes=[
            CubePrimitive(
                pose=pose(v.location, v.rotation),
                color=color(VICTIM_RGBA),
                size=Vector3(x=0.5, y=0.5, z=1.7) if v.posture == "standing" else Vector3(x=1.7, y=0.5, z=0.25),
            )
            for v in world.victims
        ],
        texts=[
            TextPrimitive(
                pose=pose((v.location[0], v.location[1], v.location[2] - 0.5), (0.0, 0.0, 0.0)),
                billboard=True,
                font_size=14.0,
                scale_invariant=True,
                color=color(VICTIM_RGBA),
                text=v.name,
            )
            for v in world.victims
        ],
    )
    alarms = SceneEntity(
        timestamp=ts,
        frame_id=WORLD_FRAME,
        id="false_alarms",
        cubes=[
            CubePrimitive(
                pose=pose(a.center, a.rotation),
                size=Vector3(x=a.size[0], y=a.size[1], z=a.size[2]),
                color=color(ALARM_RGBA),
            )
            for a in world.false_alarms
        ],
    )
    tags = SceneEntity(
        timestamp=ts,
        frame_id=WORLD_FRAME,
        id="rfid_tags",
        spheres=[
            SpherePrimitive(
                pose=pose(g.location, (0.0, 0.0, 0.0)), size=Vector3(x=0.08, y=0.08, z=0.08), color=color(TAG_RGBA)
            )
            for g in world.rfid_tags
        ],
    )
    water = SceneEntity(
        timestamp=ts,
        frame_id=WORLD_FRAME,
        id="water",
        cubes=[
            CubePrimitive(
                pose=pose(w.center, (0.0, 0.0, 0.0)),
                size=Vector3(x=w.size[0], y=w.size[1], z=w.size[2]),
                color=color(WATER_RGBA),
            )
            for w in world.water
        ],
    )
    starts = SceneEntity(
        timestamp=ts,
        frame_id=WORLD_FRAME,
        id="start_poses",
        texts=[
            TextPrimitive(
                pose=pose(p.location, (0.0, 0.0, 0.0)),
                billboard=True,
                font_size=12.0,
                scale_invariant=True,
                color=color(START_RGBA),
                text=p.name,
            )
            for p in world.start_poses
        ],
    )
    return SceneUpdate(entities=[floor, static, victims, alarms, tags, water, starts])


def objects_scene(world: WorldConfig, frames_, t: float) -> SceneUpdate:
    """The movable objects where the frame says they are now (``frames_``: ObjectFrame)."""
    by_name = {o.name: o for o in world.objects if o.mass_kg > 0}
    ents = []
    ts = timestamp(t)
    for f in frames_:
        o = by_name.get(f.name)
        if o is not None:
            ents.append(
                SceneEntity(
                    timestamp=ts,
                    frame_id=WORLD_FRAME,
                    id=f"movable/{o.name}",
                    **_object_primitives(o, _rgba(world, o.material), f.location, f.rotation),
                )
            )
    return SceneUpdate(entities=ents)


def robot_entity(name: str, class_name: str, dimensions, t: float) -> SceneEntity:
    """A robot drawn as its bounding box (GEO's dimensions) with its name above it, in its
    own frame: it moves with the frame transform."""
    dx, dy, dz = dimensions
    return SceneEntity(
        timestamp=timestamp(t),
        frame_id=name,
        id=f"robot/{name}",
        frame_locked=True,
        cubes=[
            CubePrimitive(
                pose=pose((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)), size=Vector3(x=dx, y=dy, z=dz), color=color(ROBOT_RGBA)
            )
        ],
        texts=[
            TextPrimitive(
                pose=pose((0.0, 0.0, -dz / 2 - 0.3), (0.0, 0.0, 0.0)),
                billboard=True,
                font_size=14.0,
                scale_invariant=True,
                color=color(ROBOT_RGBA),
                text=f"{name} ({class_name})",
            )
        ],
        lifetime=Duration(sec=0, nsec=0),
    )


# A dropped radio relay as recordings draw it: an orange box 0.15 m across with its antenna
# (the size of a breadcrumb is an estimate)
RELAY_RGBA = (1.0, 0.55, 0.0, 1.0)
RELAY_SIZE_M = 0.15


def relays_scene(relays, t: float) -> SceneUpdate:
    """The relays robots dropped (:class:`usarsim.sim.types.RelayFrame`), each a box on the
    ground under its antenna and its name, in the world frame."""
    ents = []
    for r in relays:
        x, y, z = r.location
        ground = (x, y, z + ANTENNA_ABOVE_GROUND_M - RELAY_SIZE_M / 2)  # USARSim's Z is down
        ents.append(
            SceneEntity(
                timestamp=timestamp(t),
                frame_id=WORLD_FRAME,
                id=f"relay/{r.name}",
                cubes=[
                    CubePrimitive(
                        pose=pose(ground, (0.0, 0.0, 0.0)),
                        size=Vector3(x=RELAY_SIZE_M, y=RELAY_SIZE_M, z=RELAY_SIZE_M),
                        color=color(RELAY_RGBA),
                    )
                ],
                texts=[
                    TextPrimitive(
                        pose=pose((x, y, z - 0.3), (0.0, 0.0, 0.0)),
                        billboard=True,
                        font_size=12.0,
                        scale_invariant=True,
                        color=color(RELAY_RGBA),
                        text=r.name,
                    )
                ],
            )
        )
    return SceneUpdate(entities=ents)


# where a relay's antenna stands above the ground (usarsim.effecters.relay_dropper)
ANTENNA_ABOVE_GROUND_M = 0.2


def robot_deletion(name: str, t: float) -> SceneUpdate:
    return SceneUpdate(deletions=[SceneEntityDeletion(timestamp=timestamp(t), id=f"robot/{name}")])


def transform(parent: str, child: str, location, rotation, t: float) -> FrameTransform:
    return FrameTransform(
        timestamp=timestamp(t),
        parent_frame_id=parent,
        child_frame_id=child,
        translation=vec(location),
        rotation=quat(rotation),
    )
