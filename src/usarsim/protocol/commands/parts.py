"""Commands of the robot's articulated parts, with their parsers and formats: a mission
package's ``MISPKG`` (protocol.md §5.6), the legacy pan/tilt/zoom ``CAMERA`` (§5.7) and an
actuator's ``ACT`` (§5.8, UDK)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from ..grammar import RawMessage
from .common import Vec3
from .declare import INTEGER, NUMBER, TEXT, VEC3, choice, command, group, key

LINK_ORDERS = frozenset({0, 1, 2})
"""Order codes of MISPKG/ACT link groups (§5.6): 0 position, 1 velocity, 2 torque."""


_ORDER_TEXT_LINK = "one of 0 (position), 1 (velocity), 2 (torque)"
_LINK_ORDER = choice(INTEGER, LINK_ORDERS, _ORDER_TEXT_LINK)
_GRIPPER = choice(INTEGER, frozenset({0, 1}), "1 (close) or 0 (open)")


@dataclass(frozen=True, slots=True)
class LinkCommand:
    """One ``{Link n} {Value v} [{Order o}]`` group of MISPKG or ACT (§5.6, §5.8).

    ``order`` is one of :data:`LINK_ORDERS` (0 when not sent).
    """

    link: int = key("Link", INTEGER, hint="n", default=dataclasses.MISSING)
    value: float = key("Value", NUMBER, hint="v", default=dataclasses.MISSING)
    # an Order before any Link is not a link's: MISPKG's own (the legacy Rotation form)
    order: int = key("Order", _LINK_ORDER, default=0, hint="o", outside="ignore")


@dataclass(frozen=True, slots=True, kw_only=True)
class MisPkg:
    """``MISPKG``: mission package control (§5.6).

    ``links`` holds the ``Link``/``Value``/``Order`` groups.  The older API sends
    ``{Rotation roll,tilt,pan}`` with an ``{Order 0|1}`` that is not inside a link group;
    that order is ``order``.
    """

    keyword: ClassVar[str] = "MISPKG"
    name: str | None = key("Name", TEXT)
    type: str | None = key("Type", TEXT)
    rotation: Vec3 | None = key("Rotation", VEC3)
    order: int | None = key("Order", _LINK_ORDER)
    links: tuple[LinkCommand, ...] = group(LinkCommand, "link")


@dataclass(frozen=True, slots=True, kw_only=True)
class Camera:
    """``CAMERA {Rotation r,p,y} {Zoom fov}``: legacy pan/tilt/zoom (§5.7)."""

    keyword: ClassVar[str] = "CAMERA"
    rotation: Vec3 | None = key("Rotation", VEC3)
    zoom: float | None = key("Zoom", NUMBER)


@dataclass(frozen=True, slots=True, kw_only=True)
class Act:
    """``ACT``: actuator control (§5.8, UDK).  ``gripper`` 1 closes, 0 opens.

    ``Seq`` is accepted for ``Sequence``.
    """

    keyword: ClassVar[str] = "ACT"
    name: str | None = key("Name", TEXT)
    links: tuple[LinkCommand, ...] = group(LinkCommand, "link")
    gripper: int | None = key("Gripper", _GRIPPER)
    sequence: int | None = key("Sequence", INTEGER, "Seq")


# ---- parsing and formatting, from the declarations above

_MISPKG = command(MisPkg)
_CAMERA = command(Camera)
_ACT = command(Act)

PARSERS: dict[str, Callable[[RawMessage], MisPkg | Camera | Act]] = {
    "MISPKG": _MISPKG.parse,
    "CAMERA": _CAMERA.parse,
    "ACT": _ACT.parse,
}

FORMATTERS: dict[type, Callable[[Any], str]] = {
    MisPkg: _MISPKG.format,
    Camera: _CAMERA.format,
    Act: _ACT.format,
}
