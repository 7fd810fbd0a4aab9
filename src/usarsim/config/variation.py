"""A world file's ``variation`` section: the rules by which a variant of the world (``usarsim
serve --variant N``) places its victims, false alarms, RFID tags and movable debris from a
seed, and which doorways it may close or open (docs/world-files.md, "Variants").

Every key is optional; a world without the section varies under the defaults below.  The
placing itself is usarsim.maps.variation's.
"""

from __future__ import annotations

from dataclasses import dataclass

from usarsim.config.reader import FieldDefaults, Section
from usarsim.config.world import Vec3

Box2 = tuple[float, float, float, float]


@dataclass(frozen=True, kw_only=True)
class Doorway:
    """A doorway a variant may close or open: a gap to close with a panel (``center`` and full
    ``size``, USARSim frame) or an existing wall panel to take away (``object``, its name), each
    variant with probability ``chance``."""

    name: str
    chance: float = 0.5
    center: Vec3 | None = None
    size: Vec3 | None = None
    material: str = "wall"
    object: str = ""  # a wall panel of ``objects`` that a variant may remove


@dataclass(frozen=True, kw_only=True)
class VariationRules:
    """Where and how a variant places things (metres, the USARSim frame)."""

    # x min, y min, x max, y max of where victims, false alarms, tags and debris go (None: the
    # bounding box of the world's static solids, for an arena its outer walls)
    region: Box2 | None = None
    # what moves: victims (each RFID tag lying within tag_follow_m of a victim moves with it),
    # false alarms, the other RFID tags, movable objects (debris)
    victims: bool = True
    false_alarms: bool = True
    rfid_tags: bool = True
    debris: bool = True
    wall_clearance_m: float = 0.25  # a victim's or false alarm's footprint from any solid
    start_clearance_m: float = 2.0  # anything placed, from every start pose
    spacing_m: float = 1.5  # between two victims, and between a victim and a false alarm
    # a robot of this radius must be able to drive from a start pose to within reach_m of
    # every victim (a P2AT is 0.51 m wide and 0.63 m long, Pioneer 3-AT operations manual:
    # half its diagonal is 0.4 m; 0.3 m lets it pass a 0.8 m doorway)
    robot_radius_m: float = 0.3
    reach_m: float = 1.0
    tag_follow_m: float = 1.0
    doorways: tuple[Doorway, ...] = ()


def read_variation(s: Section, object_names: set[str]) -> VariationRules:
    """The ``variation`` section of a world file."""
    d = FieldDefaults(VariationRules)
    region = s.vec("region", 4, d.region)
    if region is not None and not (region[0] < region[2] and region[1] < region[3]):
        raise s.error("region", f"[x min, y min, x max, y max] with min < max, got {list(region)}")
    doors: list[Doorway] = []
    dd = FieldDefaults(Doorway)
    names: set[str] = set()
    for e in s.entries("doorways"):
        name = e.str("name")
        if name in names:
            raise e.error("name", f"duplicate doorway name {name!r}")
        names.add(name)
        obj = e.str("object", dd.object)
        center = e.vec("center", 3, None)
        size = e.vec("size", 3, None, positive=True) if e.has("size") else None
        if obj and (center is not None or size is not None):
            raise e.error(
                "object", "a doorway either names a wall panel to open (object) or a gap to close (center, size)"
            )
        if not obj and (center is None or size is None):
            raise e.error("center", "a doorway to close needs its center and size (or name a wall panel: object)")
        if obj and obj not in object_names:
            raise e.error("object", f"no object named {obj!r} in this world's objects")
        doors.append(
            Doorway(
                name=name,
                chance=e.float("chance", dd.chance, min=0.0, max=1.0),
                center=None if center is None else (center[0], center[1], center[2]),
                size=None if size is None else (size[0], size[1], size[2]),
                material=e.str("material", dd.material),
                object=obj,
            )
        )
    rules = VariationRules(
        region=None if region is None else (region[0], region[1], region[2], region[3]),
        victims=s.bool("victims", d.victims),
        false_alarms=s.bool("false_alarms", d.false_alarms),
        rfid_tags=s.bool("rfid_tags", d.rfid_tags),
        debris=s.bool("debris", d.debris),
        wall_clearance_m=s.float("wall_clearance_m", d.wall_clearance_m, min=0.0, max=5.0),
        start_clearance_m=s.float("start_clearance_m", d.start_clearance_m, min=0.0, max=50.0),
        spacing_m=s.float("spacing_m", d.spacing_m, min=0.0, max=50.0),
        robot_radius_m=s.float("robot_radius_m", d.robot_radius_m, min=0.05, max=5.0),
        reach_m=s.float("reach_m", d.reach_m, min=0.1, max=10.0),
        tag_follow_m=s.float("tag_follow_m", d.tag_follow_m, min=0.0, max=10.0),
        doorways=tuple(doors),
    )
    s.finish()
    return rules
