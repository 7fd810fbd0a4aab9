"""The parts a robot file builds a robot from, with the readers of their sections: solid
pieces (the ``chassis`` boxes and the ``shapes`` of links), ``wheels``, ``links`` (articulated
parts on revolute or prismatic joints), the sensors and effecters of ``sensors``, and the
``look``: what cameras see of the robot beyond its solid pieces (tracks, tyres and hubs,
bumpers, decks, masts, in the real robot's colours; no mass, no contacts).

Coordinates are in the robot's USARSim frame (X forward, Y right, Z down) relative to the
chassis origin; metres, radians, kilograms.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from usarsim.config.reader import FieldDefaults, Section, did_you_mean

Vec3 = tuple[float, float, float]

STEER_GROUPS = ("none", "front", "rear", "free")
SHAPES = ("box", "sphere", "cylinder", "capsule")
JOINT_TYPES = ("revolute", "prismatic")


@dataclass(frozen=True, kw_only=True)
class ChassisBox:
    """A solid piece of a robot body (the chassis or a link): a box by default."""

    center: Vec3 = (0.0, 0.0, 0.0)
    size: Vec3 = (0.0, 0.0, 0.0)  # box: full extents
    mass_kg: float
    shape: str = "box"
    radius_m: float = 0.0  # sphere, cylinder, capsule
    length_m: float = 0.0  # cylinder, capsule: along the piece's own Z axis
    rotation: Vec3 = (0.0, 0.0, 0.0)
    friction: float | None = None  # None: the robot's default (1.0)


Shape = ChassisBox


@dataclass(frozen=True, kw_only=True)
class Link:
    """An articulated part (mission-package link, flipper, arm segment): a body joined
    to its parent (the chassis or another link) by one revolute or prismatic joint whose
    axis is given in the link's own frame.  ``min_range > max_range`` marks an unlimited
    (continuous) joint, as in USARSim's CONF."""

    name: str
    parent: str = "chassis"  # or a link name
    location: Vec3 = (0.0, 0.0, 0.0)  # joint origin in the parent's frame
    orientation: Vec3 = (0.0, 0.0, 0.0)
    joint: str = "revolute"  # JOINT_TYPES
    axis: Vec3 = (0.0, 0.0, 1.0)
    min_range: float = 1.0  # min_range > max_range: continuous unless a range is given
    max_range: float = 0.0
    max_speed: float
    max_torque: float
    shapes: tuple[ChassisBox, ...] = ()
    armature: float = 0.05  # reflected inertia of the geared drive, kg m^2 (or kg)
    collide: bool = True  # False: its shapes touch nothing (a small pan-tilt on top of a robot)
    # the joint frame USARSim's robot class gave the link, relative to its parent's, as GEO
    # {Type MisPkg}/{Type Actuator} report it (None: its orientation); reporting only
    geo_orientation: Vec3 | None = None

    @property
    def limited(self) -> bool:
        return self.min_range <= self.max_range


@dataclass(frozen=True, kw_only=True)
class Wheel:
    """An entry of a robot file's ``wheels``: a wheel on the chassis or on a link, with its position, size (metres)
    and mass, its side, whether it is driven, and how it is steered (Ackermann axle, or a holonomic wheel numbered
    for DRIVE, protocol.md 5.3c)."""

    name: str
    position: Vec3
    radius_m: float
    width_m: float
    mass_kg: float
    side: str  # "left" | "right"
    driven: bool = True
    parent: str = "chassis"  # or a link (a flipper's wheels)
    steer: str = "none"  # front/rear: Ackermann axles; free: steered alone (holonomic)
    number: int = -1  # WheelNumber of a holonomic DRIVE (protocol.md 5.3c)


@dataclass(frozen=True, kw_only=True)
class MountedItem:
    """A sensor (or effecter) entry: its type, name, pose and raw configuration keys.

    ``params`` keeps the keys as written (USARSim ini names or our own); the
    plugin's Config validates them when the robot is checked or spawned.
    """

    item_type: str
    name: str
    location: Vec3 = (0.0, 0.0, 0.0)
    orientation: Vec3 = (0.0, 0.0, 0.0)
    mount: str = "HARD"  # HARD (the chassis), a wheel or a link
    params: dict[str, Any]
    key_path: str = ""


def _vec3(v: tuple[float, ...]) -> Vec3:
    """A vector read with ``Section.vec(key, 3, ...)`` (three numbers) as a Vec3."""
    x, y, z = v
    return (x, y, z)


def _vec3_or_none(v: tuple[float, ...] | None) -> Vec3 | None:
    return None if v is None else _vec3(v)


def read_shape(s: Section, *, solid: bool = True) -> ChassisBox:
    """One solid piece: ``{shape: box, center, size, mass_kg}``, ``{shape: sphere, center,
    radius, mass_kg}``, ``{shape: cylinder|capsule, center, radius, length, rotation, mass_kg}``
    (``solid`` False: a piece of the look, without ``mass_kg``)."""
    d = FieldDefaults(ChassisBox)
    shape = s.str("shape", d.shape, choices=SHAPES)
    center = _vec3(s.vec("center", 3, d.center))
    mass = s.float("mass_kg", min=0.001) if solid else 0.0
    rotation = _vec3(s.vec("rotation", 3, d.rotation))
    friction = s.float("friction", d.friction, min=0.0, max=10.0)
    if shape == "box":
        return ChassisBox(
            center=center, size=_vec3(s.vec("size", positive=True)), mass_kg=mass, rotation=rotation, friction=friction
        )
    if shape == "sphere":
        return ChassisBox(
            shape=shape, center=center, radius_m=s.float("radius", min=0.001), mass_kg=mass, friction=friction
        )
    return ChassisBox(
        shape=shape,
        center=center,
        radius_m=s.float("radius", min=0.001),
        length_m=s.float("length", min=0.0),
        mass_kg=mass,
        rotation=rotation,
        friction=friction,
    )


# The look's default colours: rubber tyres and tracks nearly black, hubs and rims grey
# aluminium (estimates from photographs of the robots; colours in pictures only).
RUBBER = (0.10, 0.10, 0.10)
ALUMINIUM = (0.62, 0.62, 0.64)


@dataclass(frozen=True, kw_only=True)
class LookPiece:
    """A piece of a robot's look: a shape (as a solid piece, without mass) on the chassis or a
    link, in a colour."""

    body: str = "chassis"  # or a link name: the piece moves with it
    shape: ChassisBox
    color: Vec3


@dataclass(frozen=True, kw_only=True)
class Look:
    """What cameras see of a robot beyond its solid pieces.  ``tracks``: a belt is drawn round
    the wheels of each side of the chassis and of each link (a flipper's), in ``track_color``;
    otherwise each wheel shows a tyre (``tyre_color``) and, with ``hub_color``, a hub on its
    outer face ``hub_ratio`` of its radius across, with a spoke that shows it turning."""

    tracks: bool = False
    track_color: Vec3 = RUBBER
    tyre_color: Vec3 = RUBBER
    hub_color: Vec3 | None = ALUMINIUM
    hub_ratio: float = 0.6
    pieces: tuple[LookPiece, ...] = ()


def _colour(s: Section, name: str, default: Any) -> Any:
    v = s.vec(name, 3, default)
    if v is not None and not all(0.0 <= c <= 1.0 for c in v):
        raise s.error(name, f"a colour is red, green, blue from 0 to 1, got {list(v)}")
    return _vec3_or_none(v)


def read_look(top: Section, bodies: list[str], body_color: Vec3) -> Look:
    """The ``look`` section: ``{tracks, track_color, tyre_color, hub_color (or null),
    hub_ratio, pieces: [{body, shape, center, size | radius, length, rotation, color}]}``; a
    piece's colour is the robot's ``color`` unless it gives its own."""
    d = FieldDefaults(Look)
    if not top.has("look"):
        return Look()
    s = top.section("look")
    hub = s.raw("hub_color", d.hub_color)
    look = Look(
        tracks=s.bool("tracks", d.tracks),
        track_color=_colour(s, "track_color", d.track_color),
        tyre_color=_colour(s, "tyre_color", d.tyre_color),
        hub_color=None if hub is None else _colour(s, "hub_color", d.hub_color),
        hub_ratio=s.float("hub_ratio", d.hub_ratio, min=0.05, max=1.0),
        pieces=tuple(_read_look_piece(p, bodies, body_color) for p in s.entries("pieces")),
    )
    s.finish()
    return look


def _read_look_piece(s: Section, bodies: list[str], body_color: Vec3) -> LookPiece:
    body = s.str("body", "chassis")
    if body not in bodies:
        raise s.error("body", f"unknown body '{body}'{did_you_mean(body, bodies)}")
    return LookPiece(body=body, shape=read_shape(s, solid=False), color=_colour(s, "color", body_color))


def read_wheels(top: Section) -> list[Wheel]:
    d = FieldDefaults(Wheel)
    wheels: list[Wheel] = []
    for s in top.entries("wheels"):
        w = Wheel(
            name=s.str("name"),
            position=_vec3(s.vec("position")),
            radius_m=s.float("radius_m", min=0.001),
            width_m=s.float("width_m", min=0.001),
            mass_kg=s.float("mass_kg", min=0.001),
            side=s.str("side", choices=("left", "right")),
            driven=s.bool("driven", d.driven),
            parent=s.str("parent", d.parent),
            steer=s.str("steer", d.steer, choices=STEER_GROUPS),
            number=s.int("number", d.number, min=-1),
        )
        if any(w.name == other.name for other in wheels):
            raise s.error("name", f"duplicate wheel name '{w.name}'")
        wheels.append(w)
    return wheels


def read_links(top: Section, wnames: set[str]) -> list[Link]:
    """The ``links`` list, each after its parent; names unique among links and wheels."""
    d = FieldDefaults(Link)
    links: list[Link] = []
    lnames: set[str] = set()
    for s in top.entries("links"):
        lname = s.str("name")
        if any(c in lname for c in "{} \t/") or lname in lnames or lname in wnames or lname.lower() == "chassis":
            raise s.error("name", f"link names must be unique, without spaces, braces or '/', got {lname!r}")
        parent = s.str("parent", d.parent)
        if parent != "chassis" and parent not in lnames:
            raise s.error(
                "parent",
                f"unknown parent '{parent}' (links must come after their parent)"
                f"{did_you_mean(parent, ['chassis', *lnames])}",
            )
        axis = _vec3(s.vec("axis", 3, d.axis))
        if sum(a * a for a in axis) < 1e-12:
            raise s.error("axis", "the joint axis must not be zero")
        shapes = tuple(read_shape(sh) for sh in s.entries("shapes"))
        links.append(
            Link(
                name=lname,
                parent=parent,
                location=_vec3(s.vec("location", 3, d.location)),
                orientation=_vec3(s.vec("orientation", 3, d.orientation)),
                joint=s.str("joint", d.joint, choices=JOINT_TYPES),
                axis=axis,
                min_range=s.float("min_range", d.min_range),
                max_range=s.float("max_range", d.max_range),
                max_speed=s.float("max_speed", min=0.0, min_exclusive=True),
                max_torque=s.float("max_torque", min=0.0, min_exclusive=True),
                shapes=shapes,
                armature=s.float("armature", d.armature, min=0.0),
                collide=s.bool("collide", d.collide),
                geo_orientation=_vec3_or_none(s.vec("geo_orientation", 3, d.geo_orientation)),
            )
        )
        lnames.add(lname)
    return links


def read_items(top: Section, mounts: list[str]) -> list[MountedItem]:
    """The ``sensors`` list (sensors and effecters); keys other than the pose stay raw in
    ``params`` for the plugin's Config to check."""
    d = FieldDefaults(MountedItem)
    items: list[MountedItem] = []
    inames: set[tuple[str, str]] = set()
    for i, raw in enumerate(top.list("sensors", [])):
        key = f"sensors[{i}]"
        s = Section(raw, path=top.path, key=key)
        itype = s.str("type")
        iname = s.str("name")
        if any(c in iname for c in "{} \t"):
            raise s.error("name", f"an item name may not contain spaces or braces, got {iname!r}")
        if (itype.lower(), iname.lower()) in inames:
            raise s.error("name", f"duplicate {itype} name '{iname}'")
        inames.add((itype.lower(), iname.lower()))
        loc = _vec3(s.vec("location", 3, d.location))
        ori = _vec3(s.vec("orientation", 3, d.orientation))
        mount = s.str("mount", d.mount)
        if mount != "HARD" and mount not in mounts:
            raise s.error("mount", f"unknown mount '{mount}'{did_you_mean(mount, ['HARD', *mounts])}")
        params = {k: v for k, v in s.data.items() if k not in ("type", "name", "location", "orientation", "mount")}
        items.append(
            MountedItem(
                item_type=itype, name=iname, location=loc, orientation=ori, mount=mount, params=params, key_path=key
            )
        )
    return items
