"""The extensions, with their parsers and formats: the lock-step ``STEP`` (protocol.md §18),
``PING`` and ``REPORT`` of this project, and any line of an unknown command word, which
servers ignore."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from usarsim.errors import ProtocolError

from ..grammar import RawMessage, Segment
from .common import Vec3, _Line, _word
from .declare import POSITIVE, TEXT, VEC3, command, key


@dataclass(frozen=True, slots=True, kw_only=True)
class Step:
    """``STEP {Time s}``: advance the lock-step clock by ``time_s`` > 0 seconds (§18)."""

    keyword: ClassVar[str] = "STEP"
    time_s: float = key("Time", POSITIVE, default=dataclasses.MISSING)


@dataclass(frozen=True, slots=True)
class Ping:
    """``PING [{Id text}]``: answered ``PONG [{Id text}] {Time t}`` (an extension) once every
    request sent before it was carried out (an INIT's spawn or its ERROR) and every message
    produced so far was written to this connection: a client that waits for it has read
    everything (usarsim.client does after INIT and after each lock-step STEP)."""

    keyword: ClassVar[str] = "PING"
    id: str | None = key("Id", TEXT)


@dataclass(frozen=True, slots=True)
class Report:
    """``REPORT {Type Victim} {Location x,y,z} [{Name label}]`` (an extension): the controller
    reports a victim where it believes one lies (world frame, metres), for the score
    (docs/scoring.md); answered ``RES {Time t} {Type Victim} {Name label} {Status OK}
    {Location x,y,z}``.  ``Victim`` is the only type."""

    keyword: ClassVar[str] = "REPORT"
    type: str = key("Type", TEXT, default="Victim")
    location: Vec3 = key("Location", VEC3, default=(0.0, 0.0, 0.0))
    name: str | None = key("Name", TEXT)


REPORT_TYPES = ("Victim",)


@dataclass(frozen=True, slots=True)
class UnknownCommand:
    """A line whose command word is not known; servers ignore it.  ``type`` is upper-cased."""

    type: str
    segments: tuple[Segment, ...] = ()


# ---- parsing and formatting, from the declarations above


def _step_time(cmd: str, values: dict[str, Any], rest: list[Segment]) -> None:
    if "time_s" not in values:
        raise ProtocolError(f"{cmd}: missing {{Time seconds}}: expected for example STEP {{Time 0.2}}")


def _report_checks(cmd: str, values: dict[str, Any], rest: list[Segment]) -> None:
    if "type" not in values:
        raise ProtocolError(f"{cmd}: missing {{Type Victim}}")
    kind = next((t for t in REPORT_TYPES if t.lower() == values["type"].lower()), None)
    if kind is None:
        raise ProtocolError(
            f"{cmd}: {{Type {values.get('type', '')}}} is not a kind of report: expected {{Type Victim}}"
        )
    if "location" not in values:
        raise ProtocolError(
            f"{cmd}: missing {{Location x,y,z}}: expected for example REPORT {{Type Victim}} {{Location 3.1,6.0,0.1}}"
        )
    values["type"] = kind


_STEP = command(Step, _step_time)
_PING = command(Ping)
_REPORT = command(Report, _report_checks)

PARSERS: dict[str, Callable[[RawMessage], Step | Ping | Report]] = {
    "STEP": _STEP.parse,
    "PING": _PING.parse,
    "REPORT": _REPORT.parse,
}

FORMATTERS: dict[type, Callable[[Any], str]] = {
    Step: _STEP.format,
    Ping: _PING.format,
    Report: _REPORT.format,
    UnknownCommand: lambda c: _Line(_word(c.type, "command word")).segments(c.segments).end(),
}
