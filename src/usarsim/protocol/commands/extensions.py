"""The extensions, with their parsers and formats: the lock-step ``STEP`` (protocol.md §18),
``PING`` and ``REPORT`` of this project, and any line of an unknown command word, which
servers ignore."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from usarsim.errors import ProtocolError

from ..grammar import RawMessage, Segment
from .common import Vec3, _Line, _positive_float, _read_fields, _Table, _text, _vec3, _word


@dataclass(frozen=True, slots=True, kw_only=True)
class Step:
    """``STEP {Time s}``: advance the lock-step clock by ``time_s`` > 0 seconds (§18)."""

    keyword: ClassVar[str] = "STEP"
    time_s: float


@dataclass(frozen=True, slots=True)
class Ping:
    """``PING [{Id text}]``: answered ``PONG [{Id text}] {Time t}`` (an extension) once every
    request sent before it was carried out (an INIT's spawn or its ERROR) and every message
    produced so far was written to this connection: a client that waits for it has read
    everything (usarsim.client does after INIT and after each lock-step STEP)."""

    keyword: ClassVar[str] = "PING"
    id: str | None = None


@dataclass(frozen=True, slots=True)
class Report:
    """``REPORT {Type Victim} {Location x,y,z} [{Name label}]`` (an extension): the controller
    reports a victim where it believes one lies (world frame, metres), for the score
    (docs/scoring.md); answered ``RES {Time t} {Type Victim} {Name label} {Status OK}
    {Location x,y,z}``.  ``Victim`` is the only type."""

    keyword: ClassVar[str] = "REPORT"
    type: str = "Victim"
    location: Vec3 = (0.0, 0.0, 0.0)
    name: str | None = None


REPORT_TYPES = ("Victim",)


@dataclass(frozen=True, slots=True)
class UnknownCommand:
    """A line whose command word is not known; servers ignore it.  ``type`` is upper-cased."""

    type: str
    segments: tuple[Segment, ...] = ()


# ---- parsing


_STEP_KEYS: _Table = {"time": ("time_s", _positive_float)}


def _parse_step(raw: RawMessage) -> Step:
    values = _read_fields(raw.type, raw.segments, _STEP_KEYS)
    if "time_s" not in values:
        raise ProtocolError(f"{raw.type}: missing {{Time seconds}}: expected for example STEP {{Time 0.2}}")
    return Step(**values)


_REPORT_KEYS: _Table = {"type": ("type", _text), "location": ("location", _vec3), "name": ("name", _text)}


def _parse_report(raw: RawMessage) -> Report:
    values = _read_fields(raw.type, raw.segments, _REPORT_KEYS)
    if "type" not in values:
        raise ProtocolError(f"{raw.type}: missing {{Type Victim}}")
    kind = next((t for t in REPORT_TYPES if t.lower() == values["type"].lower()), None)
    if kind is None:
        raise ProtocolError(
            f"{raw.type}: {{Type {values.get('type', '')}}} is not a kind of report: expected {{Type Victim}}"
        )
    if "location" not in values:
        raise ProtocolError(
            f"{raw.type}: missing {{Location x,y,z}}: expected for example "
            f"REPORT {{Type Victim}} {{Location 3.1,6.0,0.1}}"
        )
    return Report(type=kind, location=values["location"], name=values.get("name"))


PARSERS: dict[str, Callable[[RawMessage], Step | Ping | Report]] = {
    "STEP": _parse_step,
    "PING": lambda raw: Ping(id=raw.get("Id")),
    "REPORT": _parse_report,
}

# ---- formatting

FORMATTERS: dict[type, Callable[[Any], str]] = {
    Step: lambda c: _Line("STEP").number("Time", c.time_s).end(),
    Ping: lambda c: _Line("PING").text("Id", c.id).end(),
    Report: lambda c: _Line("REPORT").text("Type", c.type).vector("Location", c.location).text("Name", c.name).end(),
    UnknownCommand: lambda c: _Line(_word(c.type, "command word")).segments(c.segments).end(),
}
