"""The solids of a world file: its ``materials``, its ``floor``, the ``objects`` section (boxes,
cylinders and meshes; a ramp or a flight of stairs is expanded into boxes) and the solids of
the sections that registered element kinds read (usarsim.config.elements).

Coordinates are in the USARSim frame (X forward/north, Y right/east, Z down), metres and
radians; the floor's top surface is the plane z = 0.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

from usarsim.config.elements import ELEMENT_KINDS, ElementKind, Landmark
from usarsim.config.reader import FieldDefaults, Section, did_you_mean
from usarsim.config.world import (
    MAX_SLOPE_DEG,
    MESH_SUFFIXES,
    OBJECT_SHAPES,
    RAMP_FOOT_SINK_M,
    SEE_THROUGH_KINDS,
    TEXTURE_NAMES,
    Floor,
    Material,
    StaticObject,
    Vec3,
)


def as_vec3(v: tuple[float, ...]) -> Vec3:
    """A vector read with ``Section.vec(key, 3, ...)`` (three numbers) as a Vec3."""
    x, y, z = v
    return (x, y, z)


def unique_name(s: Section, taken: set[str], what: str = "name") -> str:
    """The entry's ``name``, refused when ``taken`` has it already (then it has it)."""
    name = s.str("name")
    if name in taken:
        raise s.error("name", f"duplicate {what} '{name}'")
    taken.add(name)
    return name


def read_materials(top: Section) -> dict[str, Material]:
    """The ``materials`` section, by name, with the ``default`` material first."""
    mats_sec = top.section("materials", {})
    materials: dict[str, Material] = {"default": Material(name="default")}
    md = FieldDefaults(Material)
    for mname in list(mats_sec.data):
        ms = mats_sec.section(str(mname))
        red, green, blue, alpha = rgba = ms.vec("rgba", 4, md.rgba)
        if any(c < 0 or c > 1 for c in rgba):
            raise ms.error("rgba", f"each colour component must be within [0, 1], got {list(rgba)}")
        see = ms.list("see_through", [])
        for k in see:
            if k not in SEE_THROUGH_KINDS:
                raise ms.error(
                    "see_through",
                    f"unknown sensor kind {k!r}{did_you_mean(str(k), SEE_THROUGH_KINDS)}; "
                    f"allowed: {', '.join(SEE_THROUGH_KINDS)}",
                )
        mirror = ms.bool("mirror", md.mirror)
        porosity = ms.float("porosity", md.porosity, min=0.0, max=1.0)
        if mirror and porosity > 0:
            raise ms.error("porosity", "a mirror cannot be porous: give either mirror: true or a porosity")
        texture = ms.str("texture", md.texture)
        if texture and texture not in TEXTURE_NAMES:
            raise ms.error("texture", f"unknown texture '{texture}'{did_you_mean(texture, TEXTURE_NAMES)}")
        scale: tuple[float, float] | None = md.texture_scale
        if ms.has("texture_scale"):
            if not texture:
                raise ms.error("texture_scale", "a texture_scale needs a texture")
            raw = ms.raw("texture_scale")
            if isinstance(raw, list):
                across, up = ms.vec("texture_scale", 2)
            else:
                across = up = ms.float("texture_scale")
            if not all(0.001 <= c <= 1000.0 for c in (across, up)):
                raise ms.error("texture_scale", f"tiles per metre must be within [0.001, 1000], got {raw!r}")
            scale = (across, up)
        materials[str(mname)] = Material(
            name=str(mname),
            rgba=(red, green, blue, alpha),
            friction=ms.float("friction", md.friction, min=0.0, max=10.0),
            see_through=tuple(see),
            mirror=mirror,
            porosity=porosity,
            texture=texture,
            texture_scale=scale,
            temperature_c=ms.float("temperature_c", md.temperature_c, min=-50.0, max=500.0),
        )
        ms.finish()
    return materials


def check_material(sec: Section, key: str, value: str, materials: dict[str, Material]) -> None:
    if value not in materials:
        raise sec.error(key, f"unknown material '{value}'{did_you_mean(value, materials)}")


def check_flat(sec: Section, key: str, value: str, shape: str, materials: dict[str, Material]) -> None:
    # a mirror reflects about the face it is hit on: only boxes have flat faces here
    if materials[value].mirror and shape != "box":
        raise sec.error(
            key,
            f"material '{value}' is a mirror, which only box objects (and ramps and "
            f"stairs) may use; this object is a {shape}",
        )


def read_floor(top: Section, materials: dict[str, Material]) -> Floor:
    """The ``floor`` section; a floor material the file does not define is added to
    ``materials`` with the defaults."""
    fl = top.section("floor")
    cx, cy = fl.vec("center", 2)
    sx, sy = fl.vec("size", 2, positive=True)
    floor = Floor(center=(cx, cy), size=(sx, sy), material=fl.str("material", FieldDefaults(Floor).material))
    if floor.material not in materials:
        materials[floor.material] = Material(name=floor.material)
    check_flat(fl, "material", floor.material, "plane", materials)
    fl.finish()
    return floor


def read_objects(top: Section, names: set[str], materials: dict[str, Material], world_dir: Path) -> list[StaticObject]:
    """The ``objects`` section (a ramp or stairs as the boxes it is made of); their names
    are added to ``names``, which must not have them yet."""
    objects: list[StaticObject] = []
    od = FieldDefaults(StaticObject)
    for s in top.entries("objects"):
        oname = unique_name(s, names, "object name")
        shape = s.str("shape", choices=OBJECT_SHAPES)
        material = s.str("material", od.material)
        check_material(s, "material", material, materials)
        if shape in ("ramp", "stairs"):
            parts = _ramp(s, oname, material) if shape == "ramp" else _stairs(s, oname, material)
            for part in parts:
                if part.name != oname and part.name in names:
                    raise s.error("name", f"object '{part.name}' (a part of '{oname}') has the name of another object")
                names.add(part.name)
            objects.extend(parts)
            continue
        check_flat(s, "material", material, shape, materials)
        center = as_vec3(s.vec("center"))
        rotation = as_vec3(s.vec("rotation", 3, od.rotation))
        mass = s.float("mass_kg", od.mass_kg, min=0.0)
        if shape == "box":
            obj = StaticObject(
                name=oname,
                shape=shape,
                center=center,
                size=as_vec3(s.vec("size", 3, positive=True)),
                rotation=rotation,
                material=material,
                mass_kg=mass,
            )
        elif shape == "cylinder":
            obj = StaticObject(
                name=oname,
                shape=shape,
                center=center,
                radius_m=s.float("radius", min=0.001),
                length_m=s.float("length", min=0.001),
                rotation=rotation,
                material=material,
                mass_kg=mass,
            )
        else:
            obj = StaticObject(
                name=oname,
                shape=shape,
                center=center,
                rotation=rotation,
                material=material,
                mass_kg=mass,
                mesh_file=_mesh_file(s, world_dir),
                scale=as_vec3(s.vec("scale", 3, od.scale, positive=True)),
            )
        objects.append(obj)
    return objects


def read_elements(
    top: Section, names: set[str], objects: list[StaticObject], materials: dict[str, Material]
) -> tuple[tuple[tuple[str, tuple[Any, ...]], ...], tuple[Landmark, ...]]:
    """The sections of the registered element kinds (usarsim.config.elements): each entry
    parsed by its kind, its solids added to ``objects`` (named ``<kind>/<entry>/<solid>``), its
    landmarks collected."""
    elements = []
    landmarks: list[Landmark] = []
    for kind_name in ELEMENT_KINDS.names():
        if not top.has(kind_name):
            continue
        kind: type[ElementKind] = ELEMENT_KINDS.get(kind_name)
        entries = []
        taken: set[str] = set()
        for s in top.entries(kind_name):
            element = kind.parse(s)
            if element.name in taken:
                raise s.error("name", f"two {kind_name} entries are called '{element.name}'")
            taken.add(element.name)
            for solid in kind.solids(element):
                solid = dataclasses.replace(solid, name=f"{kind_name}/{element.name}/{solid.name}")
                if solid.name in names:
                    raise s.error("name", f"object '{solid.name}' has the name of another object")
                if solid.material not in materials:
                    raise s.error(
                        "name",
                        f"{kind_name} '{element.name}': its solid names no material of the "
                        f"world: '{solid.material}'{did_you_mean(solid.material, materials)}",
                    )
                names.add(solid.name)
                objects.append(solid)
            landmarks.extend(kind.landmarks(element))
            entries.append(element)
        elements.append((kind_name, tuple(entries)))
    return tuple(elements), tuple(landmarks)


def _slope_check(s: Section, key: str, rise: float, run: float, what: str) -> None:
    slope = math.degrees(math.atan2(rise, run))
    if slope >= MAX_SLOPE_DEG:
        raise s.error(
            key,
            f"{what} is {slope:.1f} degrees steep; allowed: below {MAX_SLOPE_DEG:g} degrees "
            f"(rise < {math.tan(math.radians(MAX_SLOPE_DEG)):.3f} x run)",
        )


def _ramp(s: Section, name: str, material: str) -> list[StaticObject]:
    """A ramp: one plate (a box) whose top face runs from the foot (the middle of its bottom
    edge, on the surface it stands on) up ``length`` m of run and ``rise`` m of height along
    ``heading``, reaching RAMP_FOOT_SINK_M below the surface at its foot."""
    foot = s.vec("foot")
    heading = s.float("heading", 0.0)
    length = s.float("length", min=0.0, min_exclusive=True)
    width = s.float("width", min=0.0, min_exclusive=True)
    rise = s.float("rise", min=0.0, min_exclusive=True)
    thickness = s.float("thickness", 0.05, min=0.0, min_exclusive=True)
    _slope_check(s, "rise", rise, length, f"the ramp (rise {rise:g} m over a run of {length:g} m)")
    theta = math.atan2(rise, length)
    # the top face's line, extended past the foot until it is RAMP_FOOT_SINK_M below the surface
    ext = RAMP_FOOT_SINK_M / math.sin(theta)
    slope_len = math.hypot(length, rise) + ext
    ux, uy = math.cos(heading), math.sin(heading)
    su, sz = math.cos(theta), -math.sin(theta)  # along the slope, upwards (Z down)
    top_mid = (math.hypot(length, rise) - ext) / 2.0  # the top face's middle, from the foot along the slope
    # the plate's centre is half its thickness below the top face (normal up: (-sin u, -cos))
    nu, nz = -math.sin(theta), -math.cos(theta)
    center = (
        foot[0] + ux * (top_mid * su - thickness / 2.0 * nu),
        foot[1] + uy * (top_mid * su - thickness / 2.0 * nu),
        foot[2] + top_mid * sz - thickness / 2.0 * nz,
    )
    # the box's own X along the slope: pitch up by theta (positive pitch raises X), then yaw
    return [
        StaticObject(
            name=name,
            shape="box",
            center=center,
            size=(slope_len, width, thickness),
            rotation=(0.0, theta, heading),
            material=material,
            part_of=name,
        )
    ]


def _stairs(s: Section, name: str, material: str) -> list[StaticObject]:
    """A flight of stairs: ``steps`` boxes along ``heading`` from the foot (the middle of the
    bottom step's front edge, on the surface it stands on); step k (1 = the lowest) is
    ``k * step_rise`` high and solid down to that surface."""
    foot = s.vec("foot")
    heading = s.float("heading", 0.0)
    width = s.float("width", min=0.0, min_exclusive=True)
    steps = s.int("steps", min=1)
    if steps > 200:
        raise s.error("steps", f"at most 200 steps, got {steps}")
    rise = s.float("step_rise", min=0.0, min_exclusive=True)
    run = s.float("step_run", min=0.0, min_exclusive=True)
    _slope_check(s, "step_rise", rise, run, f"the flight (step rise {rise:g} m over a run of {run:g} m)")
    ux, uy = math.cos(heading), math.sin(heading)
    out = []
    for k in range(1, steps + 1):
        along = (k - 0.5) * run
        out.append(
            StaticObject(
                name=f"{name}/step{k}",
                shape="box",
                center=(foot[0] + ux * along, foot[1] + uy * along, foot[2] - k * rise / 2.0),
                size=(run, width, k * rise),
                rotation=(0.0, 0.0, heading),
                material=material,
                part_of=name,
            )
        )
    return out


def _mesh_file(s: Section, world_dir: Path) -> str:
    rel = s.str("file")
    p = Path(rel)
    p = p if p.is_absolute() else world_dir / p
    if p.suffix.lower() not in MESH_SUFFIXES:
        raise s.error("file", f"'{rel}' is not a mesh file MuJoCo reads; allowed: {', '.join(MESH_SUFFIXES)} files")
    if not p.is_file():
        raise s.error("file", f"mesh file '{rel}' not found (looked for {p}; paths are relative to the world file)")
    if p.suffix.lower() == ".stl":
        size = p.stat().st_size
        with p.open("rb") as f:
            head = f.read(84)
        count = int.from_bytes(head[80:84], "little") if len(head) == 84 else -1
        if count < 0 or size != 84 + 50 * count:
            raise s.error(
                "file",
                f"'{rel}' is not a binary STL file (MuJoCo reads binary STL only); convert it or use an OBJ file",
            )
    return str(p.resolve())
