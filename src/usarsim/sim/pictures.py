"""Pictures beyond colour: what depth, thermal and label cameras see (the image server's
extension; docs/protocol.md, "Pictures beyond colour").

* **depth**: each pixel's distance along the camera's axis in millimetres, 16 bits (0: nothing
  within the camera's ``max_depth_m``), from the renderer's depth buffer;
* **thermal**: each pixel's temperature as 8-bit intensity, ``THERMAL_STEP_C`` degrees Celsius a
  level from 0 degrees (0 to 51 degrees), with the sensor's noise: victims at body temperature,
  warm false alarms, a live robot's motors hot, the rest at its material's temperature (the
  room's, ``AMBIENT_C``, unless a world file's material gives another);
* **label**: each pixel's class (``CLASSES``) and which one of that class it is (its instance:
  the victim's, false alarm's or world object's place in the world file, counting from 1, a
  robot's id), the ground truth a vision researcher trains and scores against.

Thermal and label pictures come from one segmentation rendering (each pixel's geom), looked up
in the :class:`SceneTables` of the model, built once per model on the simulation's side.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np

if TYPE_CHECKING:
    from usarsim.config.world import StaticObject, WorldConfig

PICTURES = ("colour", "depth", "thermal", "label")
CLASSES = ("none", "floor", "wall", "obstacle", "victim", "false_alarm", "robot")
NONE, FLOOR, WALL, OBSTACLE, VICTIM, FALSE_ALARM, ROBOT = range(len(CLASSES))

# Temperatures (degrees Celsius).  A room's surfaces at a comfortable 20.  A person at rest in
# thermal comfort has a mean skin temperature of about 34 (P. O. Fanger, Thermal Comfort, 1970;
# ISO 7730); the outer surface of clothes lies between skin and room (about 30, an estimate),
# shoes nearer the room.  A live robot's drive motors and gearboxes run warm under load (45, an
# estimate for small DC gear motors), its body above the room from its electronics (28, an
# estimate); a robot whose battery is empty cools to the room.  Where no surface is seen (an
# open sky, cold to a thermal camera) reads 0.
AMBIENT_C = 20.0
SKIN_C = 34.0
HAIR_C = 31.0
CLOTHES_C = 30.0
SHOES_C = 26.0
MOTOR_C = 45.0
ROBOT_BODY_C = 28.0
SKY_C = 0.0
SKIN_PARTS = ("Head", "Hand", "face")
SHOE_PARTS = ("Foot",)
# Thermal pictures: 8-bit intensity, 0.2 degrees a level from 0 (a FLIR Lepton's radiometric
# output in 8 bits would span a similar window); the sensor's noise: its thermal sensitivity,
# NETD below 50 mK (FLIR Lepton 3.5 data sheet, 2018), taken as a Gaussian of 0.05 degrees.
THERMAL_STEP_C = 0.2
NETD_C = 0.05

_ROBOT = re.compile(r"robot(\d+)/")


@dataclass
class SceneTables:
    """Per geom of a model, indexed by geom id + 1 (0: no geom, the sky): its class, its instance
    and its temperature in a world where every robot is alive; ``robot_parts`` the rows of each
    robot's geoms (by robot id), which cool to the room when its battery is empty."""

    classes: np.ndarray
    instances: np.ndarray
    temperature: np.ndarray
    robot_parts: dict[int, np.ndarray]

    def temperatures(self, cold_robots: frozenset[int]) -> np.ndarray:
        """The temperatures with the robots of ``cold_robots`` (empty batteries) at the room's."""
        if not cold_robots:
            return self.temperature
        t = self.temperature.copy()
        for uid in cold_robots:
            rows = self.robot_parts.get(uid)
            if rows is not None:
                t[rows] = AMBIENT_C
        return t


def scene_tables(model: mujoco.MjModel, world: WorldConfig, wheels: dict[int, frozenset[str]]) -> SceneTables:
    """The tables of ``model`` (built from ``world``; ``wheels``: each robot's wheel names)."""
    n = model.ngeom + 1
    classes = np.zeros(n, np.uint16)
    instances = np.zeros(n, np.uint16)
    temperature = np.full(n, AMBIENT_C, np.float32)
    temperature[0] = SKY_C
    robot_rows: dict[int, list[int]] = {}
    victims = {v.name: k + 1 for k, v in enumerate(world.victims)}
    alarms = {a.name: (k + 1, a) for k, a in enumerate(world.false_alarms)}
    objects = {o.name: (k + 1, o) for k, o in enumerate(world.objects)}

    def material_c(name: str) -> float:
        m = world.materials.get(name)
        return AMBIENT_C if m is None or m.temperature_c is None else m.temperature_c

    for g in range(model.ngeom):
        name = model.geom(g).name
        row = g + 1
        parts = name.split("/")
        if parts[0] == "look":  # a victim's (or false alarm's) face and hair
            parts = parts[1:]
            leaf = parts[-1]
        else:
            leaf = parts[2] if len(parts) > 2 else ""
        if name == "floor":
            classes[row], instances[row] = FLOOR, 1
            temperature[row] = material_c(world.floor.material)
        elif parts[0] == "victim" and len(parts) > 1:
            classes[row], instances[row] = VICTIM, victims.get(parts[1], 0)
            temperature[row] = victim_part_c(leaf)
        elif parts[0] == "falsealarm" and len(parts) > 1:
            k, alarm = alarms.get(parts[1], (0, None))
            classes[row], instances[row] = FALSE_ALARM, k
            temperature[row] = alarm.temperature_c if alarm is not None else AMBIENT_C
        elif (m := _ROBOT.match(name)) is not None:
            uid = int(m[1])
            classes[row], instances[row] = ROBOT, uid
            part = name[m.end() :].split("/")[0]
            temperature[row] = MOTOR_C if part in wheels.get(uid, ()) else ROBOT_BODY_C
            robot_rows.setdefault(uid, []).append(row)
        elif parts[0] == "debris":  # on a trapped victim
            classes[row] = OBSTACLE
        elif parts[0] == "world" and len(parts) > 1:
            k, obj = objects.get(parts[1], (0, None))
            classes[row], instances[row] = (WALL if obj is not None and is_wall(obj, world) else OBSTACLE), k
            if obj is not None:
                temperature[row] = material_c(obj.material)
    return SceneTables(classes, instances, temperature, {u: np.array(r) for u, r in robot_rows.items()})


def victim_part_c(part: str) -> float:
    """A victim's part's temperature: skin, hair, shoes, or clothes."""
    if part in SKIN_PARTS:
        return SKIN_C
    if part == "hair":
        return HAIR_C
    return SHOES_C if part in SHOE_PARTS else CLOTHES_C


def is_wall(obj: StaticObject, world: WorldConfig) -> bool:
    """A static object of a ``wall`` material, or standing at least 1 m tall and at most 0.3 m
    thin (a partition): a wall; anything else the world holds is an obstacle."""
    if obj.mass_kg > 0:
        return False
    if "wall" in obj.material.lower():
        return True
    if obj.shape != "box":
        return False
    x, y, z = obj.size
    return z >= 1.0 and min(x, y) <= 0.3


def geoms_seen(r: mujoco.Renderer) -> np.ndarray:
    """Each pixel's geom id + 1 (0: none) of ``r``'s scene, rows top to bottom."""
    r.enable_segmentation_rendering()
    try:
        seg = r.render()
    finally:
        r.disable_segmentation_rendering()
    ids = seg[..., 0]
    return np.where((seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM)) & (ids >= 0), ids + 1, 0)


def depth_picture(r: mujoco.Renderer, max_depth_m: float) -> np.ndarray:
    """Millimetres along the view axis, 16 bits (0 where nothing lies within ``max_depth_m``)."""
    r.enable_depth_rendering()
    try:
        depth = r.render()
    finally:
        r.disable_depth_rendering()
    mm = np.rint(depth * 1000.0)
    mm[(depth > max_depth_m) | ~np.isfinite(depth)] = 0
    return np.clip(mm, 0, 65535).astype(np.uint16)


def label_picture(ids: np.ndarray, tables: SceneTables) -> np.ndarray:
    """(rows, columns, 2): each pixel's class and instance."""
    return np.stack([tables.classes[ids], tables.instances[ids]], axis=-1)


def thermal_picture(ids: np.ndarray, temperatures: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """8-bit intensity, THERMAL_STEP_C a level from 0 degrees, with the sensor's noise."""
    t = temperatures[ids] + rng.normal(0.0, NETD_C, ids.shape).astype(np.float32)
    return np.clip(np.rint(t / THERMAL_STEP_C), 0, 255).astype(np.uint8)


# What a MultiView tile of a picture beyond colour shows, for people to look at: depth and
# temperature as grey (near and warm bright), labels by class
_PALETTE = np.array(
    [[0, 0, 0], [90, 90, 90], [230, 200, 80], [150, 100, 60], [230, 40, 40], [60, 120, 230], [60, 200, 90]], np.uint8
)


def as_colour(picture: np.ndarray) -> np.ndarray:
    """An RGB rendition of a depth, thermal or label picture (an RGB one as it is)."""
    if picture.ndim == 3 and picture.shape[2] == 3:
        return picture
    if picture.ndim == 3:  # labels
        return _PALETTE[np.minimum(picture[..., 0], len(_PALETTE) - 1)]
    if picture.dtype == np.uint16:  # depth: 0 to 10 m, near bright, nothing black
        level = np.where(picture > 0, 255 - np.minimum(picture // 40, 250), 0).astype(np.uint8)
    else:
        level = picture
    return np.repeat(level[..., None], 3, axis=2)
