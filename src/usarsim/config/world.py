"""World files: static geometry, materials and start poses (YAML).

Coordinates are in the USARSim frame (X forward/north, Y right/east, Z down),
metres and radians; the floor's top surface is the plane z = 0.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from usarsim.config.reader import Section, load_yaml
from usarsim.errors import ConfigError

Vec3 = tuple[float, float, float]

SHAPES = ("box", "cylinder")


@dataclass(frozen=True, kw_only=True)
class Material:
    name: str
    rgba: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0)
    friction: float = 1.0


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
        materials[str(mname)] = Material(name=str(mname), rgba=rgba, friction=ms.float("friction", 1.0, min=0.0, max=10.0))
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
        if shape == "box":
            obj = StaticObject(name=oname, shape=shape, center=center, size=s.vec("size", 3, positive=True),
                               rotation=rotation, material=material)
        else:
            obj = StaticObject(name=oname, shape=shape, center=center, radius_m=s.float("radius", min=0.001),
                               length_m=s.float("length", min=0.001), rotation=rotation, material=material)
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

    top.finish()
    return WorldConfig(name=name, description=description, path=path, floor=floor, materials=materials,
                       objects=tuple(objects), start_poses=tuple(poses), time_limit_min=time_limit,
                       timestep_s=timestep, gravity_m_s2=gravity)


def check_world_file(path: str | Path) -> WorldConfig:
    cfg = load_world(path)
    if not cfg.start_poses:
        raise ConfigError("a world needs at least one start pose", path=str(path), key="start_poses")
    return cfg
