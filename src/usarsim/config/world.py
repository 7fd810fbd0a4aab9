"""World files: static geometry, materials and start poses (YAML).

Coordinates are in the USARSim frame (X forward/north, Y right/east, Z down),
metres and radians; the floor's top surface is the plane z = 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from usarsim.config.reader import Section, load_yaml
from usarsim.errors import ConfigError

Vec3 = tuple[float, float, float]

SHAPES = ("box", "cylinder")
# Sensor kinds a material can let rays through (glass: IR and cameras, manual 3.2.1).
SEE_THROUGH_KINDS = ("ir", "camera", "laser", "sonar")
# Body parts a victim is made of (protocol.md 7.9: the UT2004 victim model's collision boxes).
VICTIM_PARTS = ("Head", "Chest", "Pelvis", "Arm", "Hand", "Leg", "Foot")
VICTIM_POSTURES = ("lying", "sitting")


@dataclass(frozen=True, kw_only=True)
class Material:
    name: str
    rgba: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0)
    friction: float = 1.0
    see_through: tuple[str, ...] = ()  # sensor kinds whose rays pass through (SEE_THROUGH_KINDS)


@dataclass(frozen=True, kw_only=True)
class StaticObject:
    name: str
    shape: str
    center: Vec3
    size: Vec3 = (0.0, 0.0, 0.0)  # full extents (box)
    radius_m: float = 0.0  # cylinder
    length_m: float = 0.0  # cylinder, along its own Z axis
    rotation: Vec3 = (0.0, 0.0, 0.0)
    material: str = "default"
    mass_kg: float = 0.0  # > 0: a movable object (a brick, a pipe) that robots can push and lift


@dataclass(frozen=True, kw_only=True)
class StartPose:
    name: str
    location: Vec3
    rotation: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True, kw_only=True)
class Floor:
    center: tuple[float, float]
    size: tuple[float, float]
    material: str = "floor"


@dataclass(frozen=True, kw_only=True)
class GeoReference:
    """Geographic coordinate of the world origin, for GPS (protocol.md 7.6): world +X is
    north, +Y east.  Defaults: USARSim's ZeroZeroLocation (NIST Gaithersburg,
    39 deg 8.0273' N, 77 deg 12.998' W) and its scales, 111200 m per degree of latitude
    and 71670 m per degree of longitude."""

    latitude_deg: float = 39.0 + 8.0273 / 60.0
    longitude_deg: float = -(77.0 + 12.998 / 60.0)
    scale_latitude_m: float = 111200.0
    scale_longitude_m: float = 71670.0


@dataclass(frozen=True, kw_only=True)
class Victim:
    """A person to be found: body parts the victim sensor can see, optionally waving
    (its arm moves) and making sounds."""

    name: str
    location: Vec3  # the pelvis, on the floor: z is the height of the body's centre line
    rotation: Vec3 = (0.0, 0.0, 0.0)
    posture: str = "lying"
    waving: bool = False
    sound_loudness_db: float = 0.0  # 0: silent
    sound_period_s: float = 5.0
    sound_duration_s: float = 1.0


@dataclass(frozen=True, kw_only=True)
class FalseAlarm:
    """An object that fools the victim sensor: a box reported as a body part."""

    name: str
    center: Vec3
    size: Vec3
    rotation: Vec3 = (0.0, 0.0, 0.0)
    part: str = "Head"
    material: str = "default"


@dataclass(frozen=True, kw_only=True)
class WaterVolume:
    """A box of water (axis-aligned): robots in it float and are slowed down; robots not
    built for water lose their battery in it, as in UT2004 (protocol.md 5.3e)."""

    name: str
    center: Vec3
    size: Vec3
    density_kg_m3: float = 1000.0  # fresh water

    def depth_of(self, point) -> float:
        """How far below the surface ``point`` (USARSim frame, Z down) is; negative above
        it, -inf outside the box horizontally or below its bottom."""
        x, y, z = point
        cx, cy, cz = self.center
        sx, sy, sz = self.size
        if abs(x - cx) > sx / 2 or abs(y - cy) > sy / 2 or z > cz + sz / 2:
            return -math.inf
        return z - (cz - sz / 2)


@dataclass(frozen=True, kw_only=True)
class RfidTagConfig:
    tag_id: int
    location: Vec3
    memory: str = ""


@dataclass(frozen=True, kw_only=True)
class WorldConfig:
    name: str
    description: str
    path: str
    floor: Floor
    materials: dict[str, Material]
    objects: tuple[StaticObject, ...]
    start_poses: tuple[StartPose, ...]
    time_limit_min: int = 0
    timestep_s: float = 0.004
    gravity_m_s2: float = 9.81
    geo: GeoReference = field(default_factory=GeoReference)
    victims: tuple[Victim, ...] = ()
    false_alarms: tuple[FalseAlarm, ...] = ()
    rfid_tags: tuple[RfidTagConfig, ...] = ()
    water: tuple[WaterVolume, ...] = ()
    extra: dict = field(default_factory=dict)

    def start_pose(self, name: str) -> StartPose | None:
        """Look a start pose up by name, case-insensitively (protocol.md 5.1)."""
        low = name.lower()
        for p in self.start_poses:
            if p.name.lower() == low:
                return p
        return None


def load_world(path: str | Path) -> WorldConfig:
    path = str(path)
    top = Section(load_yaml(path), path=path)
    name = top.str("name")
    if any(c in name for c in "{} \t"):
        raise top.error("name", f"a world name may not contain spaces or braces, got {name!r}")
    description = top.str("description", "")
    time_limit = top.int("time_limit_min", 0, min=0)
    physics = top.section("physics", {})
    timestep = physics.float("timestep_s", 0.004, min=0.0005, max=0.02)
    gravity = physics.float("gravity_m_s2", 9.81, min=0.0, max=100.0)
    physics.finish()

    mats_sec = top.section("materials", {})
    materials: dict[str, Material] = {"default": Material(name="default")}
    for mname in list(mats_sec.data):
        ms = mats_sec.section(str(mname))
        rgba = ms.vec("rgba", 4, (0.7, 0.7, 0.7, 1.0))
        if any(c < 0 or c > 1 for c in rgba):
            raise ms.error("rgba", f"each colour component must be within [0, 1], got {list(rgba)}")
        see = ms.list("see_through", [])
        for k in see:
            if k not in SEE_THROUGH_KINDS:
                from usarsim.config.reader import did_you_mean

                raise ms.error("see_through", f"unknown sensor kind {k!r}{did_you_mean(str(k), SEE_THROUGH_KINDS)}; "
                                              f"allowed: {', '.join(SEE_THROUGH_KINDS)}")
        materials[str(mname)] = Material(name=str(mname), rgba=rgba, friction=ms.float("friction", 1.0, min=0.0, max=10.0),
                                         see_through=tuple(see))
        ms.finish()

    def check_material(sec: Section, key: str, value: str) -> None:
        if value not in materials:
            from usarsim.config.reader import did_you_mean

            raise sec.error(key, f"unknown material '{value}'{did_you_mean(value, materials)}")

    fl = top.section("floor")
    floor = Floor(center=fl.vec("center", 2), size=fl.vec("size", 2, positive=True), material=fl.str("material", "floor"))
    if floor.material not in materials:
        materials[floor.material] = Material(name=floor.material)
    fl.finish()

    objects: list[StaticObject] = []
    names: set[str] = set()
    for i, raw in enumerate(top.list("objects", [])):
        s = Section(raw, path=path, key=f"objects[{i}]")
        oname = s.str("name")
        if oname in names:
            raise s.error("name", f"duplicate object name '{oname}'")
        names.add(oname)
        shape = s.str("shape", choices=SHAPES)
        center = s.vec("center")
        rotation = s.vec("rotation", 3, (0.0, 0.0, 0.0))
        material = s.str("material", "default")
        check_material(s, "material", material)
        mass = s.float("mass_kg", 0.0, min=0.0)
        if shape == "box":
            obj = StaticObject(name=oname, shape=shape, center=center, size=s.vec("size", 3, positive=True),
                               rotation=rotation, material=material, mass_kg=mass)
        else:
            obj = StaticObject(name=oname, shape=shape, center=center, radius_m=s.float("radius", min=0.001),
                               length_m=s.float("length", min=0.001), rotation=rotation, material=material,
                               mass_kg=mass)
        s.finish()
        objects.append(obj)

    poses: list[StartPose] = []
    pnames: set[str] = set()
    for i, raw in enumerate(top.list("start_poses", [])):
        s = Section(raw, path=path, key=f"start_poses[{i}]")
        pname = s.str("name")
        if any(c in pname for c in "{} \t,"):
            raise s.error("name", f"a start pose name may not contain spaces, commas or braces, got {pname!r}")
        if pname.lower() in pnames:
            raise s.error("name", f"duplicate start pose name '{pname}'")
        pnames.add(pname.lower())
        poses.append(StartPose(name=pname, location=s.vec("location"), rotation=s.vec("rotation", 3, (0.0, 0.0, 0.0))))
        s.finish()

    g = top.section("geo_reference", {})
    geo = GeoReference(latitude_deg=g.float("latitude_deg", GeoReference.latitude_deg, min=-89.0, max=89.0),
                       longitude_deg=g.float("longitude_deg", GeoReference.longitude_deg, min=-180.0, max=180.0),
                       scale_latitude_m=g.float("scale_latitude_m", 111200.0, min=1.0),
                       scale_longitude_m=g.float("scale_longitude_m", 71670.0, min=1.0))
    g.finish()

    victims: list[Victim] = []
    for i, raw in enumerate(top.list("victims", [])):
        s = Section(raw, path=path, key=f"victims[{i}]")
        vname = s.str("name")
        if vname in names:
            raise s.error("name", f"duplicate name '{vname}'")
        names.add(vname)
        sound = s.section("sound", {})
        victims.append(Victim(name=vname, location=s.vec("location"), rotation=s.vec("rotation", 3, (0.0, 0.0, 0.0)),
                              posture=s.str("posture", "lying", choices=VICTIM_POSTURES),
                              waving=s.bool("waving", False),
                              sound_loudness_db=sound.float("loudness_db", 0.0, min=0.0, max=200.0),
                              sound_period_s=sound.float("period_s", 5.0, min=0.1),
                              sound_duration_s=sound.float("duration_s", 1.0, min=0.01)))
        sound.finish()
        s.finish()

    alarms: list[FalseAlarm] = []
    for i, raw in enumerate(top.list("false_alarms", [])):
        s = Section(raw, path=path, key=f"false_alarms[{i}]")
        aname = s.str("name")
        if aname in names:
            raise s.error("name", f"duplicate name '{aname}'")
        names.add(aname)
        material = s.str("material", "default")
        check_material(s, "material", material)
        alarms.append(FalseAlarm(name=aname, center=s.vec("center"), size=s.vec("size", 3, positive=True),
                                 rotation=s.vec("rotation", 3, (0.0, 0.0, 0.0)),
                                 part=s.str("part", "Head", choices=VICTIM_PARTS), material=material))
        s.finish()

    tags: list[RfidTagConfig] = []
    ids: set[int] = set()
    for i, raw in enumerate(top.list("rfid_tags", [])):
        s = Section(raw, path=path, key=f"rfid_tags[{i}]")
        tid = s.int("id", min=0)
        if tid in ids:
            raise s.error("id", f"duplicate RFID tag id {tid}")
        ids.add(tid)
        mem = s.str("memory", "")
        if any(c in mem for c in "{}\r\n"):
            raise s.error("memory", "tag memory may not contain braces or line breaks")
        tags.append(RfidTagConfig(tag_id=tid, location=s.vec("location"), memory=mem))
        s.finish()

    water: list[WaterVolume] = []
    for i, raw in enumerate(top.list("water", [])):
        s = Section(raw, path=path, key=f"water[{i}]")
        wname = s.str("name")
        if wname in names:
            raise s.error("name", f"duplicate name '{wname}'")
        names.add(wname)
        water.append(WaterVolume(name=wname, center=s.vec("center"), size=s.vec("size", 3, positive=True),
                                 density_kg_m3=s.float("density_kg_m3", 1000.0, min=1.0, max=20000.0)))
        s.finish()

    top.finish()
    return WorldConfig(name=name, description=description, path=path, floor=floor, materials=materials,
                       objects=tuple(objects), start_poses=tuple(poses), time_limit_min=time_limit,
                       timestep_s=timestep, gravity_m_s2=gravity, geo=geo, victims=tuple(victims),
                       false_alarms=tuple(alarms), rfid_tags=tuple(tags), water=tuple(water))


def check_world_file(path: str | Path) -> WorldConfig:
    cfg = load_world(path)
    if not cfg.start_poses:
        raise ConfigError("a world needs at least one start pose", path=str(path), key="start_poses")
    return cfg
