"""Commands that operate items and the UDK world, with their parsers and formats: ``SET``
(protocol.md §5.4), the world controller's ``CONTROL``, the avatar's ``MOVE`` and ``GOTO``,
and ``TEST`` (§5.8, UDK)."""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from usarsim.errors import ProtocolError

from ..grammar import RawMessage, Segment, parse_float
from .declare import TEXT, VEC2OR3, command, key, numbered, rest

_BARE_NUMBER_RE = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)\Z")


@dataclass(frozen=True, slots=True, kw_only=True)
class Set:
    """``SET``: operate a mounted item (§5.4).

    Values are kept as sent (text), so that a command formats back as it came: their meaning
    depends on the item (``params`` is a FOV for a camera, ``<tagID> <data...>`` for an RFID
    write, ``value,steer`` for a joint).  :attr:`values` gives the numbers of ``params``.
    The Player driver sends a camera zoom as a bare segment (``{Opcode Zoom} {0.87}``); a
    bare number stands for ``params`` when no ``Params`` key is present.
    ``viewports`` holds ``{ViewportN cam}`` pairs as ``(N, cam)``.  ``segments`` holds the
    segments not turned into a field above (item-specific keys), in order.
    """

    keyword: ClassVar[str] = "SET"
    type: str | None = key("Type", TEXT)
    name: str | None = key("Name", TEXT)
    robot: str | None = key("Robot", TEXT)
    client: str | None = key("Client", TEXT)
    opcode: str | None = key("Opcode", TEXT)
    params: str | None = key("Params", TEXT)
    value: str | None = key("Value", TEXT)
    config: str | None = key("Config", TEXT)
    viewports: tuple[tuple[int, str], ...] = numbered("Viewport")
    segments: tuple[Segment, ...] = rest()

    def get(self, key: str, default: str | None = None) -> str | None:
        """Value of the first item-specific segment with this key (case-insensitive)."""
        return _segment_value(self.segments, key, default)

    @property
    def values(self) -> tuple[float, ...] | None:
        """The numbers of ``params``, split on commas and blanks (``{Params 0.5,0}`` ->
        ``(0.5, 0.0)``); None when Params was not sent, is empty, or holds anything but
        finite numbers (an RFID write's text)."""
        words = (self.params or "").replace(",", " ").split()
        if not words:
            return None
        try:
            numbers = tuple(parse_float(w) for w in words)
        except ProtocolError:
            return None
        return numbers if all(math.isfinite(x) for x in numbers) else None


@dataclass(frozen=True, slots=True, kw_only=True)
class Control:
    """``CONTROL``: world-controller request (§5.8, UDK).

    ``segments`` holds every segment other than the first ``Type`` and ``Name``, in order;
    their meaning depends on ``type`` (Create, Kill, KillAll, AbsMove, ...).
    """

    keyword: ClassVar[str] = "CONTROL"
    type: str | None = key("Type", TEXT)
    name: str | None = key("Name", TEXT)
    segments: tuple[Segment, ...] = rest()

    def get(self, key: str, default: str | None = None) -> str | None:
        """Value of the first segment with this key (case-insensitive)."""
        return _segment_value(self.segments, key, default)


@dataclass(frozen=True, slots=True, kw_only=True)
class Move:
    """``MOVE``: avatar walking (§5.8, UDK).  ``location`` has 2 (x,y) or 3 numbers."""

    keyword: ClassVar[str] = "MOVE"
    type: str | None = key("Type", TEXT)
    action: str | None = key("Action", TEXT)
    location: tuple[float, ...] | None = key("Location", VEC2OR3)
    pathnode: str | None = key("Pathnode", TEXT)


@dataclass(frozen=True, slots=True, kw_only=True)
class Goto:
    """``GOTO {Name pathnode}`` (§5.8, UDK)."""

    keyword: ClassVar[str] = "GOTO"
    name: str | None = key("Name", TEXT)


@dataclass(frozen=True, slots=True, kw_only=True)
class Test:
    """``TEST``: UDK test mode; every segment is kept."""

    keyword: ClassVar[str] = "TEST"
    segments: tuple[Segment, ...] = rest()


def _segment_value(segments: tuple[Segment, ...], key: str, default: str | None) -> str | None:
    wanted = key.lower()
    for seg in segments:
        if seg.key.lower() == wanted:
            return seg.value
    return default


ControlCommand = Set | Control | Move | Goto | Test


# ---- parsing and formatting, from the declarations above


def _bare_params(cmd: str, values: dict[str, Any], rest: list[Segment]) -> None:
    """The Player driver's camera zoom, ``{Opcode Zoom} {0.87}``: the first bare number of the
    segments no key took stands for Params when no Params key came."""
    if "params" in values:
        return
    for seg in rest:
        if not seg.value and _BARE_NUMBER_RE.match(seg.key):
            values["params"] = seg.key
            rest.remove(seg)
            return


_LAYOUTS = [command(Set, _bare_params), *(command(c) for c in (Control, Move, Goto, Test))]

PARSERS: dict[str, Callable[[RawMessage], ControlCommand]] = {layout.keyword: layout.parse for layout in _LAYOUTS}

FORMATTERS: dict[type, Callable[[Any], str]] = {layout.cls: layout.format for layout in _LAYOUTS}
