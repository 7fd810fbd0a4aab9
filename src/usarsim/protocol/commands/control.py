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
from .common import _TYPE_NAME_KEYS, _Line, _read_fields, _Table, _text, _vec2or3

_BARE_NUMBER_RE = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)\Z")
_VIEWPORT_RE = re.compile(r"viewport([0-9]{1,3})\Z", re.IGNORECASE)


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
    type: str | None = None
    name: str | None = None
    opcode: str | None = None
    params: str | None = None
    robot: str | None = None
    client: str | None = None
    config: str | None = None
    viewports: tuple[tuple[int, str], ...] = ()
    value: str | None = None
    segments: tuple[Segment, ...] = ()

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
    type: str | None = None
    name: str | None = None
    segments: tuple[Segment, ...] = ()

    def get(self, key: str, default: str | None = None) -> str | None:
        """Value of the first segment with this key (case-insensitive)."""
        return _segment_value(self.segments, key, default)


@dataclass(frozen=True, slots=True, kw_only=True)
class Move:
    """``MOVE``: avatar walking (§5.8, UDK).  ``location`` has 2 (x,y) or 3 numbers."""

    keyword: ClassVar[str] = "MOVE"
    type: str | None = None
    action: str | None = None
    location: tuple[float, ...] | None = None
    pathnode: str | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class Goto:
    """``GOTO {Name pathnode}`` (§5.8, UDK)."""

    keyword: ClassVar[str] = "GOTO"
    name: str | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class Test:
    """``TEST``: UDK test mode; every segment is kept."""

    keyword: ClassVar[str] = "TEST"
    segments: tuple[Segment, ...] = ()


def _segment_value(segments: tuple[Segment, ...], key: str, default: str | None) -> str | None:
    wanted = key.lower()
    for seg in segments:
        if seg.key.lower() == wanted:
            return seg.value
    return default


ControlCommand = Set | Control | Move | Goto | Test


# ---- parsing


_SET_KEYS: _Table = {
    "type": ("type", _text),
    "name": ("name", _text),
    "opcode": ("opcode", _text),
    "params": ("params", _text),
    "robot": ("robot", _text),
    "client": ("client", _text),
    "config": ("config", _text),
    "value": ("value", _text),
}


def _parse_set(raw: RawMessage) -> Set:
    values: dict[str, Any] = {}
    viewports: list[tuple[int, str]] = []
    rest: list[Segment] = []
    bare_number: Segment | None = None
    for seg in raw.segments:
        entry = _SET_KEYS.get(seg.key.lower())
        if entry is not None and entry[0] not in values:
            values[entry[0]] = seg.value
            continue
        vm = _VIEWPORT_RE.match(seg.key)
        if vm is not None:
            viewports.append((int(vm.group(1)), seg.value))
            continue
        if bare_number is None and not seg.value and _BARE_NUMBER_RE.match(seg.key):
            bare_number = seg
        rest.append(seg)
    if "params" not in values and bare_number is not None:
        values["params"] = bare_number.key
        rest.remove(bare_number)
    return Set(viewports=tuple(viewports), segments=tuple(rest), **values)


def _parse_control(raw: RawMessage) -> Control:
    values: dict[str, Any] = {}
    rest: list[Segment] = []
    for seg in raw.segments:
        entry = _TYPE_NAME_KEYS.get(seg.key.lower())
        if entry is not None and entry[0] not in values:
            values[entry[0]] = seg.value
        else:
            rest.append(seg)
    return Control(segments=tuple(rest), **values)


_MOVE_KEYS: _Table = {
    "type": ("type", _text),
    "action": ("action", _text),
    "location": ("location", _vec2or3),
    "pathnode": ("pathnode", _text),
}


def _parse_move(raw: RawMessage) -> Move:
    return Move(**_read_fields(raw.type, raw.segments, _MOVE_KEYS))


_GOTO_KEYS: _Table = {"name": ("name", _text)}


def _parse_goto(raw: RawMessage) -> Goto:
    return Goto(**_read_fields(raw.type, raw.segments, _GOTO_KEYS))


def _parse_test(raw: RawMessage) -> Test:
    return Test(segments=raw.segments)


# ---- formatting


def _format_set(c: Set) -> str:
    line = (
        _Line("SET")
        .text("Type", c.type)
        .text("Name", c.name)
        .text("Robot", c.robot)
        .text("Client", c.client)
        .text("Opcode", c.opcode)
        .text("Params", c.params)
        .text("Value", c.value)
        .text("Config", c.config)
    )
    for index, camera in c.viewports:
        line.text("Viewport%d" % index, camera)
    return line.segments(c.segments).end()


def _format_control(c: Control) -> str:
    return _Line("CONTROL").text("Type", c.type).text("Name", c.name).segments(c.segments).end()


def _format_move(c: Move) -> str:
    return (
        _Line("MOVE")
        .text("Type", c.type)
        .text("Action", c.action)
        .vector("Location", c.location)
        .text("Pathnode", c.pathnode)
        .end()
    )


PARSERS: dict[str, Callable[[RawMessage], ControlCommand]] = {
    "SET": _parse_set,
    "CONTROL": _parse_control,
    "MOVE": _parse_move,
    "GOTO": _parse_goto,
    "TEST": _parse_test,
}

FORMATTERS: dict[type, Callable[[Any], str]] = {
    Set: _format_set,
    Control: _format_control,
    Move: _format_move,
    Goto: lambda c: _Line("GOTO").text("Name", c.name).end(),
    Test: lambda c: _Line("TEST").segments(c.segments).end(),
}
