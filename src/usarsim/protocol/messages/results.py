"""Results and the other messages, with their formats and parsers: the outcome of a SET
(``RES``, protocol.md §6.5; a camera zoom and the viewports), an effecter's state (``EFF``,
§6.6), ``DIE`` (§6.9), the lock-step ``STEPPED`` (§18), the extensions ``PONG`` and
``ERROR``, and any line of an unknown type, kept as it came."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from usarsim.readings import FieldValue

from ..grammar import Segment, format_segment
from ..numbers import f2
from .common import _CRLF, _Reader
from .declare import group, key, message, pairs
from .kinds import F2, F4, FIELD, FIELD_SPACED, TEXT


@dataclass(frozen=True, slots=True)
class Result:
    """``RES {Time t} {Type T} {Name N} {Status S}`` plus item-specific ``extra`` segments.

    ``extra`` holds ``(key, value)`` pairs printed after Status by :func:`format_value`, e.g.
    an RFID read ``(("ID", 11137), ("Mem", "hello"))``.  ``name`` None leaves the Name
    segment out.
    """

    time: float = key("Time", F2)
    item_type: str = key("Type", TEXT)
    name: str | None = key("Name", TEXT, optional=True)
    status: str = key("Status", TEXT, default="OK")
    # {key value} even when the value is empty: a blank tag reads {Mem } (protocol.md 5.4,
    # "{Mem <data>}" with no data), which a client looking for "{Mem " still finds
    extra: tuple[tuple[str, FieldValue], ...] = pairs(FIELD_SPACED)


@dataclass(frozen=True, slots=True)
class CameraZoom:
    """One camera of a zoom result (:class:`CameraZoomResult`, §5.4): its name, its horizontal field of view in
    radians, and its Status (``Failed`` when the requested field of view was clamped or reset)."""

    name: str = key("Name", TEXT)
    fov: float = key("FOV", F4)
    status: str = key("Status", TEXT, default="OK")


@dataclass(frozen=True, slots=True)
class CameraZoomResult:
    """``RES {Time t} {Type Camera} {Name cam} {FOV f} {Status OK|Failed}``.

    One Name/FOV/Status triple per camera; ``camera_type`` is the zoomed item's type
    (``Camera``, or ``OmniCam`` for an omnidirectional camera).
    """

    time: float = key("Time", F2)
    cameras: tuple[CameraZoom, ...] = group(CameraZoom)
    camera_type: str = key("Type", TEXT, default="Camera")


@dataclass(frozen=True, slots=True)
class ViewportState:
    """``{ViewportN camera} {Status s}``: camera is a name, ``Disabled`` or ``None``."""

    index: int
    camera: str
    status: str = "OK"


@dataclass(frozen=True, slots=True)
class ViewportsResult:
    """``RES {Time t} {Type Viewports} {Config c} {Status s} {Viewport1 cam} {Status s} ...``."""

    time: float
    config: str
    config_status: str = "OK"
    viewports: tuple[ViewportState, ...] = ()


@dataclass(frozen=True, slots=True)
class EffecterStatus:
    """``EFF {Time t} {Type T} {Name N} {Status S}`` plus ``extra`` (§6.6).

    ``extra`` pairs are printed by :func:`format_value`; an empty value prints as a bare
    segment (``{On}``).
    """

    time: float | None = key("Time", F4, optional=True)
    effecter_type: str = key("Type", TEXT)
    name: str = key("Name", TEXT)
    status: str | None = key("Status", TEXT, default=None, optional=True)
    extra: tuple[tuple[str, FieldValue], ...] = pairs(FIELD)


@dataclass(frozen=True, slots=True)
class Die:
    """``DIE {Killer name} {DamageType type}`` (§6.9)."""

    killer: str = key("Killer", TEXT)
    damage_type: str = key("DamageType", TEXT)


@dataclass(frozen=True, slots=True)
class Stepped:
    """``STEPPED {Time t}``: the lock-step interval is done (§18), 4 decimals."""

    time: float = key("Time", F4)


@dataclass(frozen=True, slots=True)
class Pong:
    """``PONG [{Id text}] [{Time t}]``: the answer to ``PING`` (an extension), after every
    request sent before it was carried out and everything it produced was written; ``time``
    the simulated time then (4 decimals)."""

    id: str | None = key("Id", TEXT, default=None, optional=True)
    time: float | None = key("Time", F4, default=None, optional=True)


@dataclass(frozen=True, slots=True)
class ErrorReply:
    """``ERROR {Command c} {Reason r}``: the request ``c`` (its command word) could not be
    carried out, and why.  An extension of this project, like STEPPED: an INIT that spawns
    nothing, a query before INIT, a bad STEP, a SET to a robot without power get it instead
    of silence; clients that do not know it skip it as an unknown message.  The reason names
    the problem and what is allowed; braces and line breaks in it are sent as parentheses
    and spaces (:func:`error_reply`)."""

    command: str = key("Command", TEXT)
    reason: str = key("Reason", TEXT)


def error_reply(command: str, reason: str) -> ErrorReply:
    """An :class:`ErrorReply` whose reason is safe on the wire (no braces, no line breaks)."""
    safe = reason.replace("{", "(").replace("}", ")").replace("\r", " ").replace("\n", " ")
    return ErrorReply(command=command.upper(), reason=" ".join(safe.split()))


@dataclass(frozen=True, slots=True)
class UnknownMessage:
    """A line :func:`parse_message` does not know; formatted back as it was."""

    type: str
    segments: tuple[Segment, ...] = ()


ResultMessage = (
    Result | CameraZoomResult | ViewportsResult | EffecterStatus | Die | Stepped | Pong | ErrorReply | UnknownMessage
)

# ---- formatting and parsing: the messages of fixed layout from their declarations above; a
# RES's and an EFF's item-specific segments, and the viewports' numbered keys, by hand

_ZOOM = message(CameraZoomResult, "RES", wire_first=("time", "camera_type"), read_first=("time", "camera_type"))
_DIE = message(Die, "DIE")
_STEPPED = message(Stepped, "STEPPED")
_PONG = message(Pong, "PONG")
_ERROR = message(ErrorReply, "ERROR")
# formats from the declarations; read by the rules below (an item's own segments after the
# first Status of a RES, or after the first of each head key of an EFF)
_RESULT = message(Result, "RES")
_EFFECTER = message(EffecterStatus, "EFF")


def _fmt_viewports(m: ViewportsResult) -> str:
    views = "".join(" {Viewport%d %s} {Status %s}" % (v.index, v.camera, v.status) for v in m.viewports)
    return "RES {Time %s} {Type Viewports} {Config %s} {Status %s}%s\r\n" % (
        f2(m.time),
        m.config,
        m.config_status,
        views,
    )


def _fmt_unknown(m: UnknownMessage) -> str:
    return " ".join([m.type, *(format_segment(s.key, s.value) for s in m.segments)]) + _CRLF


# ---- parsing

_VIEWPORT_KEY = re.compile(r"viewport([0-9]+)\Z", re.IGNORECASE)


def _parse_res(r: _Reader) -> Result | CameraZoomResult | ViewportsResult:
    raw = r.raw
    time = r.req_float("Time")
    item_type = r.text("Type")
    if item_type in ("Camera", "OmniCam") and raw.has("FOV"):
        zoom: CameraZoomResult = _ZOOM.parse(r)
        return zoom
    if item_type == "Viewports":
        views = []
        segs = raw.segments
        for i, s in enumerate(segs):
            m = _VIEWPORT_KEY.match(s.key)
            if m is not None:
                has_status = i + 1 < len(segs) and segs[i + 1].key == "Status"
                status = segs[i + 1].value if has_status else ""
                views.append(ViewportState(index=int(m.group(1)), camera=s.value, status=status))
        return ViewportsResult(
            time=time,
            config=r.text("Config"),
            config_status=r.text("Status"),
            viewports=tuple(views),
        )
    # Everything after the first Status is item-specific.
    rest = list(raw.segments)
    head: dict[str, str] = {}
    extra: list[tuple[str, str]] = []
    for s in rest:
        k = s.key.lower()
        if "status" not in head and k in ("time", "type", "name", "status") and k not in head:
            head[k] = s.value
        else:
            extra.append((s.key, s.value))
    if "status" not in head:
        raise r.missing("Status")
    return Result(
        time=time,
        item_type=item_type,
        name=head.get("name"),
        status=head["status"],
        extra=tuple(extra),
    )


def _parse_eff(r: _Reader) -> EffecterStatus:
    head: dict[str, str] = {}
    extra: list[tuple[str, str]] = []
    for s in r.raw.segments:
        k = s.key.lower()
        if k in ("time", "type", "name", "status") and k not in head:
            head[k] = s.value
        else:
            extra.append((s.key, s.value))
    return EffecterStatus(
        time=r.opt_time(),
        effecter_type=r.text("Type"),
        name=r.text("Name"),
        status=head.get("status"),
        extra=tuple(extra),
    )


FORMATTERS: dict[type, Callable[[Any], str]] = {
    Result: _RESULT.format,
    CameraZoomResult: _ZOOM.format,
    ViewportsResult: _fmt_viewports,
    EffecterStatus: _EFFECTER.format,
    Die: _DIE.format,
    Stepped: _STEPPED.format,
    Pong: _PONG.format,
    ErrorReply: _ERROR.format,
    UnknownMessage: _fmt_unknown,
}

PARSERS: dict[str, Callable[[_Reader], ResultMessage]] = {
    "RES": _parse_res,
    "EFF": _parse_eff,
    "DIE": _DIE.parse,
    "STEPPED": _STEPPED.parse,
    "PONG": _PONG.parse,
    "ERROR": _ERROR.parse,
}
