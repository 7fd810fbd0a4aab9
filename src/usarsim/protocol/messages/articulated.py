"""Geometry and configuration of the articulated parts, with their formats and parsers: a
mission package's ``GEO`` and ``CONF`` (protocol.md §6.7, §6.8: ``{Type MisPkg}``) and an
actuator's (``{Type Actuator}``, UDK).  Mission-package locations and orientations are
truncated to 4 decimals, as in the UT output (§2.4).  The GEO and CONF lines of the other
items are in :mod:`.geometry`, which hands these types' lines to the parsers here."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .common import Vec3, _Reader
from .declare import group, key, message
from .kinds import F4, INT, TEXT, VEC4, VT4

# ---- mission packages


@dataclass(frozen=True, slots=True)
class LinkGeometry:
    """One link of a mission package GEO: pose relative to ``parent_link`` (-1 = chassis)."""

    link: int = key("Link", INT)
    parent_link: int = key("ParentLink", INT)
    location: Vec3 = key("Location", VT4)
    orientation: Vec3 = key("Orientation", VT4)


@dataclass(frozen=True, slots=True)
class PackageGeometry:
    """One mission package of a ``GEO {Type MisPkg}`` line (§6.8): its ``{Name P}`` and the geometry of its links,
    numbered from 1."""

    name: str = key("Name", TEXT)
    links: tuple[LinkGeometry, ...] = group(LinkGeometry)


@dataclass(frozen=True, slots=True)
class MisPkgGeometry:
    """``GEO {Type MisPkg} {Name P} {Link 1} {ParentLink -1} {Location ...} {Orientation ...}``.

    Several packages follow each other in one line when the query named none.  Locations and
    orientations are truncated to 4 decimals, as in the UT output (``3.1415``, ``1.5707``).
    """

    packages: tuple[PackageGeometry, ...] = group(PackageGeometry)


@dataclass(frozen=True, slots=True)
class LinkConfiguration:
    """One link of a mission package CONF; ``min_range > max_range`` = unlimited joint."""

    link: int = key("Link", INT)
    joint_type: str = key("JointType", TEXT)
    max_speed: float = key("MaxSpeed", F4)
    max_torque: float = key("MaxTorque", F4)
    min_range: float = key("MinRange", F4)
    max_range: float = key("MaxRange", F4)


@dataclass(frozen=True, slots=True)
class PackageConfiguration:
    """One mission package of a ``CONF {Type MisPkg}`` line (§6.7): its ``{Name P}`` and the joint configuration of
    its links."""

    name: str = key("Name", TEXT)
    links: tuple[LinkConfiguration, ...] = group(LinkConfiguration)


@dataclass(frozen=True, slots=True)
class MisPkgConfiguration:
    """``CONF {Type MisPkg} {Name P} {Link 1} {JointType Revolute} {MaxSpeed ...} ...``."""

    packages: tuple[PackageConfiguration, ...] = group(PackageConfiguration)


# ---- actuators (UDK)


@dataclass(frozen=True, slots=True)
class ActuatorLinkConfiguration:
    """One link of an actuator CONF (UDK API): joint type, torque limit and the range of
    its Value (rad or m)."""

    link: int = key("Link", INT)
    joint_type: str = key("JointType", TEXT)
    max_torque: float = key("MaxTorque", F4)
    min_value: float = key("MinValue", F4)
    max_value: float = key("MaxValue", F4)


@dataclass(frozen=True, slots=True)
class ActuatorConfig:
    """One actuator of a ``CONF {Type Actuator}`` line (§6.7, UDK): its ``{Name arm}`` and the joint configuration of
    its links."""

    name: str = key("Name", TEXT)
    links: tuple[ActuatorLinkConfiguration, ...] = group(ActuatorLinkConfiguration)


@dataclass(frozen=True, slots=True)
class ActuatorConfiguration:
    """``CONF {Type Actuator} {Name arm} {Link 1} {JointType Revolute} {MaxTorque t}
    {MinValue a} {MaxValue b} ...`` (§6.7, UDK); several actuators follow each other."""

    actuators: tuple[ActuatorConfig, ...] = group(ActuatorConfig)


@dataclass(frozen=True, slots=True)
class ActuatorLinkGeometry:
    """One link of an actuator GEO: its joint's pose relative to its parent; ``parent`` is
    the parent link's index plus one, 0 when the link sits on the actuator's base (as the UDK
    server printed it: ``{Link 2} {Parent 1}``)."""

    link: int = key("Link", INT)
    parent: int = key("Parent", INT)
    location: Vec3 = key("Location", VEC4)
    orientation: Vec3 = key("Orientation", VEC4)


@dataclass(frozen=True, slots=True)
class ActuatorPose:
    """One actuator of a ``GEO {Type Actuator}`` line (§6.8, UDK): its name, its base's location (m) and orientation
    (rad) on the robot, what it is mounted on, and its links' geometry."""

    name: str = key("Name", TEXT)
    location: Vec3 = key("Location", VEC4)
    orientation: Vec3 = key("Orientation", VEC4)
    mount: str = key("Mount", TEXT)
    links: tuple[ActuatorLinkGeometry, ...] = group(ActuatorLinkGeometry)


@dataclass(frozen=True, slots=True)
class ActuatorGeometry:
    """``GEO {Type Actuator} {Name arm} {Location x,y,z} {Orientation r,p,y} {Mount Robot}
    {Link 1} {Parent -1} {Location ...} {Orientation ...} ...`` (§6.8, UDK)."""

    actuators: tuple[ActuatorPose, ...] = group(ActuatorPose)


# ---- formatting and parsing, from the declarations above

_MISPKG_GEO = message(MisPkgGeometry, "GEO", fixed=(("Type", "MisPkg"),))
_MISPKG_CONF = message(MisPkgConfiguration, "CONF", fixed=(("Type", "MisPkg"),))
_ACTUATOR_GEO = message(ActuatorGeometry, "GEO", fixed=(("Type", "Actuator"),))
_ACTUATOR_CONF = message(ActuatorConfiguration, "CONF", fixed=(("Type", "Actuator"),))

FORMATTERS: dict[type, Callable[[Any], str]] = {
    MisPkgGeometry: _MISPKG_GEO.format,
    MisPkgConfiguration: _MISPKG_CONF.format,
    ActuatorConfiguration: _ACTUATOR_CONF.format,
    ActuatorGeometry: _ACTUATOR_GEO.format,
}

# the GEO and CONF parsers of .geometry, by the lower-cased {Type T} of the line
GEO_PARSERS: dict[str, Callable[[_Reader], MisPkgGeometry | ActuatorGeometry]] = {
    "mispkg": _MISPKG_GEO.parse,
    "actuator": _ACTUATOR_GEO.parse,
}

CONF_PARSERS: dict[str, Callable[[_Reader], MisPkgConfiguration | ActuatorConfiguration]] = {
    "mispkg": _MISPKG_CONF.parse,
    "actuator": _ACTUATOR_CONF.parse,
}
