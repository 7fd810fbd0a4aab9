"""Geometry and configuration of the articulated parts, with their formats and parsers: a
mission package's ``GEO`` and ``CONF`` (protocol.md §6.7, §6.8: ``{Type MisPkg}``) and an
actuator's (``{Type Actuator}``, UDK).  Mission-package locations and orientations are
truncated to 4 decimals, as in the UT output (§2.4).  The GEO and CONF lines of the other
items are in :mod:`.geometry`, which hands these types' lines to the parsers here."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..grammar import RawMessage
from ..numbers import f4, vec4, vec_t4
from .common import _CRLF, Vec3, _groups, _Reader

# ---- mission packages


@dataclass(frozen=True, slots=True)
class LinkGeometry:
    """One link of a mission package GEO: pose relative to ``parent_link`` (-1 = chassis)."""

    link: int
    parent_link: int
    location: Vec3
    orientation: Vec3


@dataclass(frozen=True, slots=True)
class PackageGeometry:
    """One mission package of a ``GEO {Type MisPkg}`` line (§6.8): its ``{Name P}`` and the geometry of its links,
    numbered from 1."""

    name: str
    links: tuple[LinkGeometry, ...] = ()


@dataclass(frozen=True, slots=True)
class MisPkgGeometry:
    """``GEO {Type MisPkg} {Name P} {Link 1} {ParentLink -1} {Location ...} {Orientation ...}``.

    Several packages follow each other in one line when the query named none.  Locations and
    orientations are truncated to 4 decimals, as in the UT output (``3.1415``, ``1.5707``).
    """

    packages: tuple[PackageGeometry, ...] = ()


@dataclass(frozen=True, slots=True)
class LinkConfiguration:
    """One link of a mission package CONF; ``min_range > max_range`` = unlimited joint."""

    link: int
    joint_type: str
    max_speed: float
    max_torque: float
    min_range: float
    max_range: float


@dataclass(frozen=True, slots=True)
class PackageConfiguration:
    """One mission package of a ``CONF {Type MisPkg}`` line (§6.7): its ``{Name P}`` and the joint configuration of
    its links."""

    name: str
    links: tuple[LinkConfiguration, ...] = ()


@dataclass(frozen=True, slots=True)
class MisPkgConfiguration:
    """``CONF {Type MisPkg} {Name P} {Link 1} {JointType Revolute} {MaxSpeed ...} ...``."""

    packages: tuple[PackageConfiguration, ...] = ()


# ---- actuators (UDK)


@dataclass(frozen=True, slots=True)
class ActuatorLinkConfiguration:
    """One link of an actuator CONF (UDK API): joint type, torque limit and the range of
    its Value (rad or m)."""

    link: int
    joint_type: str
    max_torque: float
    min_value: float
    max_value: float


@dataclass(frozen=True, slots=True)
class ActuatorConfig:
    """One actuator of a ``CONF {Type Actuator}`` line (§6.7, UDK): its ``{Name arm}`` and the joint configuration of
    its links."""

    name: str
    links: tuple[ActuatorLinkConfiguration, ...] = ()


@dataclass(frozen=True, slots=True)
class ActuatorConfiguration:
    """``CONF {Type Actuator} {Name arm} {Link 1} {JointType Revolute} {MaxTorque t}
    {MinValue a} {MaxValue b} ...`` (§6.7, UDK); several actuators follow each other."""

    actuators: tuple[ActuatorConfig, ...] = ()


@dataclass(frozen=True, slots=True)
class ActuatorLinkGeometry:
    """One link of an actuator GEO: its joint's pose relative to its parent; ``parent`` is
    the parent link's index plus one, 0 when the link sits on the actuator's base (as the UDK
    server printed it: ``{Link 2} {Parent 1}``)."""

    link: int
    parent: int
    location: Vec3
    orientation: Vec3


@dataclass(frozen=True, slots=True)
class ActuatorPose:
    """One actuator of a ``GEO {Type Actuator}`` line (§6.8, UDK): its name, its base's location (m) and orientation
    (rad) on the robot, what it is mounted on, and its links' geometry."""

    name: str
    location: Vec3
    orientation: Vec3
    mount: str
    links: tuple[ActuatorLinkGeometry, ...] = ()


@dataclass(frozen=True, slots=True)
class ActuatorGeometry:
    """``GEO {Type Actuator} {Name arm} {Location x,y,z} {Orientation r,p,y} {Mount Robot}
    {Link 1} {Parent -1} {Location ...} {Orientation ...} ...`` (§6.8, UDK)."""

    actuators: tuple[ActuatorPose, ...] = ()


# ---- formatting


def _fmt_mispkg_geometry(m: MisPkgGeometry) -> str:
    parts = ["GEO {Type MisPkg}"]
    for pkg in m.packages:
        parts.append("{Name %s}" % pkg.name)
        parts.extend(
            "{Link %d} {ParentLink %d} {Location %s} {Orientation %s}"
            % (k.link, k.parent_link, vec_t4(k.location), vec_t4(k.orientation))
            for k in pkg.links
        )
    return " ".join(parts) + _CRLF


def _fmt_mispkg_configuration(m: MisPkgConfiguration) -> str:
    parts = ["CONF {Type MisPkg}"]
    for pkg in m.packages:
        parts.append("{Name %s}" % pkg.name)
        parts.extend(
            "{Link %d} {JointType %s} {MaxSpeed %s} {MaxTorque %s} {MinRange %s} {MaxRange %s}"
            % (
                k.link,
                k.joint_type,
                f4(k.max_speed),
                f4(k.max_torque),
                f4(k.min_range),
                f4(k.max_range),
            )
            for k in pkg.links
        )
    return " ".join(parts) + _CRLF


def _fmt_actuator_configuration(m: ActuatorConfiguration) -> str:
    parts = ["CONF {Type Actuator}"]
    for act in m.actuators:
        parts.append("{Name %s}" % act.name)
        parts.extend(
            "{Link %d} {JointType %s} {MaxTorque %s} {MinValue %s} {MaxValue %s}"
            % (k.link, k.joint_type, f4(k.max_torque), f4(k.min_value), f4(k.max_value))
            for k in act.links
        )
    return " ".join(parts) + _CRLF


def _fmt_actuator_geometry(m: ActuatorGeometry) -> str:
    parts = ["GEO {Type Actuator}"]
    for act in m.actuators:
        parts.append(
            "{Name %s} {Location %s} {Orientation %s} {Mount %s}"
            % (act.name, vec4(act.location), vec4(act.orientation), act.mount)
        )
        parts.extend(
            "{Link %d} {Parent %d} {Location %s} {Orientation %s}"
            % (k.link, k.parent, vec4(k.location), vec4(k.orientation))
            for k in act.links
        )
    return " ".join(parts) + _CRLF


# ---- parsing


def _parse_mispkg_geometry(r: _Reader) -> MisPkgGeometry:
    raw = r.raw
    packages = []
    for group in _groups(raw.segments, "Name"):
        links = []
        for link in _groups(tuple(group[1:]), "Link"):
            lr = _Reader(RawMessage(raw.type, tuple(link)), r.what)
            links.append(
                LinkGeometry(
                    link=lr.req_int("Link"),
                    parent_link=lr.req_int("ParentLink"),
                    location=lr.req_vec3("Location"),
                    orientation=lr.req_vec3("Orientation"),
                )
            )
        packages.append(PackageGeometry(name=group[0].value, links=tuple(links)))
    return MisPkgGeometry(packages=tuple(packages))


def _parse_mispkg_configuration(r: _Reader) -> MisPkgConfiguration:
    raw = r.raw
    packages = []
    for group in _groups(raw.segments, "Name"):
        links = []
        for link in _groups(tuple(group[1:]), "Link"):
            lr = _Reader(RawMessage(raw.type, tuple(link)), r.what)
            links.append(
                LinkConfiguration(
                    link=lr.req_int("Link"),
                    joint_type=lr.text("JointType"),
                    max_speed=lr.req_float("MaxSpeed"),
                    max_torque=lr.req_float("MaxTorque"),
                    min_range=lr.req_float("MinRange"),
                    max_range=lr.req_float("MaxRange"),
                )
            )
        packages.append(PackageConfiguration(name=group[0].value, links=tuple(links)))
    return MisPkgConfiguration(packages=tuple(packages))


def _parse_actuator_geometry(r: _Reader) -> ActuatorGeometry:
    raw = r.raw
    actuators = []
    for group in _groups(raw.segments, "Name"):
        links = _groups(tuple(group[1:]), "Link")
        head = _Reader(RawMessage(raw.type, tuple(group[1 : len(group) - sum(len(g) for g in links)])), r.what)
        parsed = []
        for link in links:
            lr = _Reader(RawMessage(raw.type, tuple(link)), r.what)
            parsed.append(
                ActuatorLinkGeometry(
                    link=lr.req_int("Link"),
                    parent=lr.req_int("Parent"),
                    location=lr.req_vec3("Location"),
                    orientation=lr.req_vec3("Orientation"),
                )
            )
        actuators.append(
            ActuatorPose(
                name=group[0].value,
                location=head.req_vec3("Location"),
                orientation=head.req_vec3("Orientation"),
                mount=head.text("Mount"),
                links=tuple(parsed),
            )
        )
    return ActuatorGeometry(actuators=tuple(actuators))


def _parse_actuator_configuration(r: _Reader) -> ActuatorConfiguration:
    actuators = []
    for group in _groups(r.raw.segments, "Name"):
        links = []
        for link in _groups(tuple(group[1:]), "Link"):
            lr = _Reader(RawMessage(r.raw.type, tuple(link)), r.what)
            links.append(
                ActuatorLinkConfiguration(
                    link=lr.req_int("Link"),
                    joint_type=lr.text("JointType"),
                    max_torque=lr.req_float("MaxTorque"),
                    min_value=lr.req_float("MinValue"),
                    max_value=lr.req_float("MaxValue"),
                )
            )
        actuators.append(ActuatorConfig(name=group[0].value, links=tuple(links)))
    return ActuatorConfiguration(actuators=tuple(actuators))


FORMATTERS: dict[type, Callable[[Any], str]] = {
    MisPkgGeometry: _fmt_mispkg_geometry,
    MisPkgConfiguration: _fmt_mispkg_configuration,
    ActuatorConfiguration: _fmt_actuator_configuration,
    ActuatorGeometry: _fmt_actuator_geometry,
}

# the GEO and CONF parsers of .geometry, by the lower-cased {Type T} of the line
GEO_PARSERS: dict[str, Callable[[_Reader], MisPkgGeometry | ActuatorGeometry]] = {
    "mispkg": _parse_mispkg_geometry,
    "actuator": _parse_actuator_geometry,
}

CONF_PARSERS: dict[str, Callable[[_Reader], MisPkgConfiguration | ActuatorConfiguration]] = {
    "mispkg": _parse_mispkg_configuration,
    "actuator": _parse_actuator_configuration,
}
