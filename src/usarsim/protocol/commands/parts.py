"""Commands of the robot's articulated parts, with their parsers and formats: a mission
package's ``MISPKG`` (protocol.md §5.6), the legacy pan/tilt/zoom ``CAMERA`` (§5.7) and an
actuator's ``ACT`` (§5.8, UDK)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from usarsim.errors import ProtocolError

from ..grammar import RawMessage, Segment
from .common import Vec3, _choice, _float, _int, _Line, _read_fields, _Table, _text, _vec3

LINK_ORDERS = frozenset({0, 1, 2})
"""Order codes of MISPKG/ACT link groups (§5.6): 0 position, 1 velocity, 2 torque."""


_ORDER_TEXT_LINK = "one of 0 (position), 1 (velocity), 2 (torque)"


@dataclass(frozen=True, slots=True)
class LinkCommand:
    """One ``{Link n} {Value v} [{Order o}]`` group of MISPKG or ACT (§5.6, §5.8).

    ``order`` is one of :data:`LINK_ORDERS` (0 when not sent).
    """

    link: int
    value: float
    order: int = 0


@dataclass(frozen=True, slots=True, kw_only=True)
class MisPkg:
    """``MISPKG``: mission package control (§5.6).

    ``links`` holds the ``Link``/``Value``/``Order`` groups.  The older API sends
    ``{Rotation roll,tilt,pan}`` with an ``{Order 0|1}`` that is not inside a link group;
    that order is ``order``.
    """

    keyword: ClassVar[str] = "MISPKG"
    name: str | None = None
    type: str | None = None
    links: tuple[LinkCommand, ...] = ()
    rotation: Vec3 | None = None
    order: int | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class Camera:
    """``CAMERA {Rotation r,p,y} {Zoom fov}``: legacy pan/tilt/zoom (§5.7)."""

    keyword: ClassVar[str] = "CAMERA"
    rotation: Vec3 | None = None
    zoom: float | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class Act:
    """``ACT``: actuator control (§5.8, UDK).  ``gripper`` 1 closes, 0 opens.

    ``Seq`` is accepted for ``Sequence``.
    """

    keyword: ClassVar[str] = "ACT"
    name: str | None = None
    links: tuple[LinkCommand, ...] = ()
    gripper: int | None = None
    sequence: int | None = None


# ---- parsing


_link_order = _choice(_int, LINK_ORDERS, _ORDER_TEXT_LINK)


_gripper = _choice(_int, frozenset({0, 1}), "1 (close) or 0 (open)")


def _read_links(
    cmd: str, segments: tuple[Segment, ...], table: _Table
) -> tuple[tuple[LinkCommand, ...], dict[str, Any]]:
    """Link groups plus the first-wins fields of ``table``.

    An ``Order`` inside a link group belongs to that link; one before any link goes to the
    ``order`` field of ``table`` when it has one (the legacy MISPKG Rotation form).
    """
    values: dict[str, Any] = {}
    links: list[LinkCommand] = []
    group: dict[str, Any] | None = None

    def close(group: dict[str, Any]) -> None:
        if "value" not in group:
            raise ProtocolError(
                f"{cmd}: {{Link {group['link']}}} has no {{Value v}}: "
                "each link group is {Link n} {Value v} [{Order o}]"
            )
        links.append(LinkCommand(**group))

    for seg in segments:
        key = seg.key.lower()
        if key == "link":
            if group is not None:
                close(group)
            group = {"link": _int(cmd, seg)}
        elif key == "value":
            if group is None:
                raise ProtocolError(
                    f"{cmd}: {{{seg.key} {seg.value}}} comes before any {{Link n}}: "
                    "each link group must start with Link"
                )
            group["value"] = _float(cmd, seg)
        elif key == "order" and group is not None:
            group["order"] = _link_order(cmd, seg)
        else:
            entry = table.get(key)
            if entry is not None and entry[0] not in values:
                values[entry[0]] = entry[1](cmd, seg)
    if group is not None:
        close(group)
    return tuple(links), values


_MISPKG_KEYS: _Table = {
    "name": ("name", _text),
    "type": ("type", _text),
    "rotation": ("rotation", _vec3),
    "order": ("order", _link_order),
}


def _parse_mispkg(raw: RawMessage) -> MisPkg:
    links, values = _read_links(raw.type, raw.segments, _MISPKG_KEYS)
    return MisPkg(links=links, **values)


_ACT_KEYS: _Table = {
    "name": ("name", _text),
    "gripper": ("gripper", _gripper),
    "sequence": ("sequence", _int),
    "seq": ("sequence", _int),
}


def _parse_act(raw: RawMessage) -> Act:
    links, values = _read_links(raw.type, raw.segments, _ACT_KEYS)
    return Act(links=links, **values)


_CAMERA_KEYS: _Table = {"rotation": ("rotation", _vec3), "zoom": ("zoom", _float)}


def _parse_camera(raw: RawMessage) -> Camera:
    return Camera(**_read_fields(raw.type, raw.segments, _CAMERA_KEYS))


# ---- formatting


def _format_mispkg(c: MisPkg) -> str:
    return (
        _Line("MISPKG")
        .text("Name", c.name)
        .text("Type", c.type)
        .vector("Rotation", c.rotation)
        .integer("Order", c.order)
        .links(c.links)
        .end()
    )


def _format_act(c: Act) -> str:
    return (
        _Line("ACT")
        .text("Name", c.name)
        .links(c.links)
        .integer("Gripper", c.gripper)
        .integer("Sequence", c.sequence)
        .end()
    )


PARSERS: dict[str, Callable[[RawMessage], MisPkg | Camera | Act]] = {
    "MISPKG": _parse_mispkg,
    "CAMERA": _parse_camera,
    "ACT": _parse_act,
}

FORMATTERS: dict[type, Callable[[Any], str]] = {
    MisPkg: _format_mispkg,
    Camera: lambda c: _Line("CAMERA").vector("Rotation", c.rotation).number("Zoom", c.zoom).end(),
    Act: _format_act,
}
