"""Geometry and configuration of the robot and its items, with their formats and parsers:
the replies to ``GETGEO`` (``GEO``, protocol.md §6.8) and ``GETCONF`` (``CONF``, §6.7) for
the robot itself, its sensors and effecters, and the empty reply when nothing matched the
query (§5.5).  The parsers of ``GEO`` and ``CONF`` hand the lines of mission packages and
actuators to :mod:`.articulated`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from usarsim.readings import FieldValue

from ..grammar import RawMessage
from .articulated import (
    CONF_PARSERS,
    GEO_PARSERS,
    ActuatorConfiguration,
    ActuatorGeometry,
    MisPkgConfiguration,
    MisPkgGeometry,
)
from .common import Vec3, _groups, _Reader
from .declare import Key, Layout, Pairs, items, key, message, packed
from .kinds import F4, FIELD, TEXT, VEC4


@dataclass(frozen=True, slots=True, kw_only=True)
class RobotGeometry:
    """Reply to ``GETGEO {Type Robot}`` (§6.8); ``Name`` carries the robot class.

    The wheel keys are left out when None (robots without wheels).
    """

    vehicle_type: str = key("Type", TEXT, default="GroundVehicle")
    class_name: str = key("Name", TEXT)
    dimensions: Vec3 = key("Dimensions", VEC4)
    cog: Vec3 = key("COG", VEC4, default=(0.0, 0.0, 0.0))
    wheel_radius: float | None = key("WheelRadius", F4, default=None, optional=True)
    wheel_separation: float | None = key("WheelSeparation", F4, default=None, optional=True)
    wheel_base: float | None = key("WheelBase", F4, default=None, optional=True)


@dataclass(frozen=True, slots=True, kw_only=True)
class RobotConfiguration:
    """Reply to ``GETCONF {Type Robot}`` (§6.7); ``Name`` carries the robot class."""

    vehicle_type: str = key("Type", TEXT, default="GroundVehicle")
    class_name: str = key("Name", TEXT)
    steering_type: str = key("SteeringType", TEXT)
    mass_kg: float = key("Mass", F4)
    max_speed: float = key("MaxSpeed", F4)
    max_torque: float = key("MaxTorque", F4)
    max_front_steer: float = key("MaxFrontSteer", F4, default=0.0, absent=0.0)
    max_rear_steer: float = key("MaxRearSteer", F4, default=0.0, absent=0.0)


@dataclass(frozen=True, slots=True)
class ItemPose:
    """Mount pose of one sensor or effecter, relative to ``mount`` (``HARD`` = chassis)."""

    name: str
    location: Vec3
    orientation: Vec3
    mount: str = "HARD"


@dataclass(frozen=True, slots=True)
class ItemGeometry:
    """``GEO {Type T} {Name N Location ... Orientation ... Mount M} ...`` (packed, §6.8)."""

    item_type: str
    items: tuple[ItemPose, ...] = ()


@dataclass(frozen=True, slots=True)
class EmptyGeometry:
    """``GEO {Type T}`` or ``GEO {Type T} {Name N}``: nothing matched the query (§5.5)."""

    item_type: str = key("Type", TEXT)
    name: str | None = key("Name", TEXT, default=None, optional=True)


@dataclass(frozen=True, slots=True)
class ItemConf:
    """Configuration of one item: typed ``(key, value)`` pairs in order, printed by
    :func:`format_value` (a value read back from a line is its text, printed as it is)."""

    name: str
    fields: tuple[tuple[str, FieldValue], ...] = ()


@dataclass(frozen=True, slots=True)
class ItemConfiguration:
    """``CONF {Type T} {Name N1} {Key v} ... {Name N2} ...`` (repeated-key groups, §6.7).

    Every item type has its own keys; their typed values are printed by
    :func:`format_value`.  A single item without fields prints exactly like
    :class:`EmptyConfiguration` with a name, and is read back as one.
    """

    item_type: str
    items: tuple[ItemConf, ...] = ()


@dataclass(frozen=True, slots=True)
class EmptyConfiguration:
    """``CONF {Type T}`` or ``CONF {Type T} {Name N}``: nothing matched the query (§5.5)."""

    item_type: str = key("Type", TEXT)
    name: str | None = key("Name", TEXT, default=None, optional=True)


GeometryMessage = RobotGeometry | ItemGeometry | EmptyGeometry | MisPkgGeometry | ActuatorGeometry
ConfigurationMessage = (
    RobotConfiguration | ItemConfiguration | EmptyConfiguration | MisPkgConfiguration | ActuatorConfiguration
)

# ---- formatting, from the declarations

_ROBOT_GEO = message(RobotGeometry, "GEO")
_ROBOT_CONF = message(RobotConfiguration, "CONF")
_EMPTY_GEO = message(EmptyGeometry, "GEO")
_EMPTY_CONF = message(EmptyConfiguration, "CONF")


# the items' lines: several items of a type, each its pose in one packed segment, or its own
# CONF keys after its Name; read by the rules below (UT's packed and UDK's separate layouts)
_ITEM_GEO = Layout(
    ItemGeometry,
    "GEO",
    keys={
        "item_type": Key("Type", TEXT),
        "items": packed(ItemPose, "Location", VEC4, ("Orientation", VEC4), ("Mount", TEXT)),
    },
)
_ITEM_CONF = Layout(
    ItemConfiguration,
    "CONF",
    keys={"item_type": Key("Type", TEXT), "items": items(ItemConf, name=Key("Name", TEXT), fields=Pairs(FIELD))},
)


# ---- parsing


def _only_type_and_name(raw: RawMessage) -> bool:
    keys = [s.key.lower() for s in raw.segments]
    if keys == ["type"]:
        return True
    return keys == ["type", "name"] and len(raw.segments[1].value.split()) == 1


def _parse_geo(r: _Reader) -> GeometryMessage:
    raw = r.raw
    item_type = r.text("Type")
    if _only_type_and_name(raw):
        empty: EmptyGeometry = _EMPTY_GEO.parse(r)
        return empty
    if raw.has("Dimensions"):
        robot: RobotGeometry = _ROBOT_GEO.parse(r)
        return robot
    articulated = GEO_PARSERS.get(item_type.lower())
    if articulated is not None:
        return articulated(r)
    items = []
    for group in _groups(raw.segments, "Name"):
        tokens = group[0].value.split()
        if len(tokens) > 1 and len(tokens) % 2:  # packed UT layout: name, then key value pairs
            fields = {tokens[i].lower(): tokens[i + 1] for i in range(1, len(tokens), 2)}
            name = tokens[0]
        else:  # separate UDK layout: {Name n} {Location ...} {Orientation ...} {Mount m}
            fields = {s.key.lower(): s.value for s in group[1:]}
            name = group[0].value
        if "location" not in fields or "orientation" not in fields:
            raise r.error("Name", group[0].value, "'name Location x,y,z Orientation r,p,y Mount m'")
        location = r.vector("Location", fields["location"])
        orientation = r.vector("Orientation", fields["orientation"])
        items.append(
            ItemPose(
                name=name,
                location=location,  # type: ignore[arg-type]
                orientation=orientation,  # type: ignore[arg-type]
                mount=fields.get("mount", "HARD"),
            )
        )
    return ItemGeometry(item_type=item_type, items=tuple(items))


def _parse_conf(r: _Reader) -> ConfigurationMessage:
    raw = r.raw
    item_type = r.text("Type")
    if _only_type_and_name(raw):
        empty: EmptyConfiguration = _EMPTY_CONF.parse(r)
        return empty
    if raw.has("SteeringType"):
        robot: RobotConfiguration = _ROBOT_CONF.parse(r)
        return robot
    articulated = CONF_PARSERS.get(item_type.lower())
    if articulated is not None:
        return articulated(r)
    items = tuple(
        ItemConf(name=g[0].value, fields=tuple((s.key, s.value) for s in g[1:])) for g in _groups(raw.segments, "Name")
    )
    return ItemConfiguration(item_type=item_type, items=items)


FORMATTERS: dict[type, Callable[[Any], str]] = {
    RobotGeometry: _ROBOT_GEO.format,
    RobotConfiguration: _ROBOT_CONF.format,
    ItemGeometry: _ITEM_GEO.format,
    EmptyGeometry: _EMPTY_GEO.format,
    ItemConfiguration: _ITEM_CONF.format,
    EmptyConfiguration: _EMPTY_CONF.format,
}

PARSERS: dict[str, Callable[[_Reader], GeometryMessage | ConfigurationMessage]] = {
    "GEO": _parse_geo,
    "CONF": _parse_conf,
}
