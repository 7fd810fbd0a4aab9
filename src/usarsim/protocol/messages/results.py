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

from ..grammar import RawMessage, Segment, format_segment
from ..numbers import f2, f4
from .common import _CRLF, _fields, _groups, _Reader, format_value


@dataclass(frozen=True, slots=True)
class Result:
    """``RES {Time t} {Type T} {Name N} {Status S}`` plus item-specific ``extra`` segments.

    ``extra`` holds ``(key, value)`` pairs printed after Status by :func:`format_value`, e.g.
    an RFID read ``(("ID", 11137), ("Mem", "hello"))``.  ``name`` None leaves the Name
    segment out.
    """

    time: float
    item_type: str
    name: str | None
    status: str = "OK"
    extra: tuple[tuple[str, FieldValue], ...] = ()


@dataclass(frozen=True, slots=True)
class CameraZoom:
    """One camera of a zoom result (:class:`CameraZoomResult`, §5.4): its name, its horizontal field of view in
    radians, and its Status (``Failed`` when the requested field of view was clamped or reset)."""

    name: str
    fov: float
    status: str = "OK"


@dataclass(frozen=True, slots=True)
class CameraZoomResult:
    """``RES {Time t} {Type Camera} {Name cam} {FOV f} {Status OK|Failed}``.

    One Name/FOV/Status triple per camera; ``camera_type`` is the zoomed item's type
    (``Camera``, or ``OmniCam`` for an omnidirectional camera).
    """

    time: float
    cameras: tuple[CameraZoom, ...] = ()
    camera_type: str = "Camera"


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

    time: float | None
    effecter_type: str
    name: str
    status: str | None = None
    extra: tuple[tuple[str, FieldValue], ...] = ()


@dataclass(frozen=True, slots=True)
class Die:
    """``DIE {Killer name} {DamageType type}`` (§6.9)."""

    killer: str
    damage_type: str


@dataclass(frozen=True, slots=True)
class Stepped:
    """``STEPPED {Time t}``: the lock-step interval is done (§18), 4 decimals."""

    time: float


@dataclass(frozen=True, slots=True)
class Pong:
    """``PONG [{Id text}] [{Time t}]``: the answer to ``PING`` (an extension), after every
    request sent before it was carried out and everything it produced was written; ``time``
    the simulated time then (4 decimals)."""

    id: str | None = None
    time: float | None = None


@dataclass(frozen=True, slots=True)
class ErrorReply:
    """``ERROR {Command c} {Reason r}``: the request ``c`` (its command word) could not be
    carried out, and why.  An extension of this project, like STEPPED: an INIT that spawns
    nothing, a query before INIT, a bad STEP, a SET to a robot without power get it instead
    of silence; clients that do not know it skip it as an unknown message.  The reason names
    the problem and what is allowed; braces and line breaks in it are sent as parentheses
    and spaces (:func:`error_reply`)."""

    command: str
    reason: str


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

# ---- formatting


def _fmt_result(m: Result) -> str:
    parts = ["RES {Time %s} {Type %s}" % (f2(m.time), m.item_type)]
    if m.name is not None:
        parts.append("{Name %s}" % m.name)
    parts.append("{Status %s}" % m.status)
    # {key value} even when the value is empty: a blank tag reads {Mem } (protocol.md 5.4,
    # "{Mem <data>}" with no data), which a client looking for "{Mem " still finds
    parts.extend(["{%s %s}" % (k, format_value(v)) for k, v in m.extra])
    return " ".join(parts) + _CRLF


def _fmt_camera_zoom(m: CameraZoomResult) -> str:
    cams = "".join(" {Name %s} {FOV %s} {Status %s}" % (c.name, f4(c.fov), c.status) for c in m.cameras)
    return "RES {Time %s} {Type %s}%s\r\n" % (f2(m.time), m.camera_type, cams)


def _fmt_viewports(m: ViewportsResult) -> str:
    views = "".join(" {Viewport%d %s} {Status %s}" % (v.index, v.camera, v.status) for v in m.viewports)
    return "RES {Time %s} {Type Viewports} {Config %s} {Status %s}%s\r\n" % (
        f2(m.time),
        m.config,
        m.config_status,
        views,
    )


def _fmt_effecter(m: EffecterStatus) -> str:
    parts = ["EFF"]
    if m.time is not None:
        parts.append("{Time %s}" % f4(m.time))
    parts.append("{Type %s} {Name %s}" % (m.effecter_type, m.name))
    if m.status is not None:
        parts.append("{Status %s}" % m.status)
    parts.extend(_fields(m.extra))
    return " ".join(parts) + _CRLF


def _fmt_unknown(m: UnknownMessage) -> str:
    return " ".join([m.type, *(format_segment(s.key, s.value) for s in m.segments)]) + _CRLF


# ---- parsing

_VIEWPORT_KEY = re.compile(r"viewport([0-9]+)\Z", re.IGNORECASE)


def _parse_res(r: _Reader) -> Result | CameraZoomResult | ViewportsResult:
    raw = r.raw
    time = r.req_float("Time")
    item_type = r.text("Type")
    if item_type in ("Camera", "OmniCam") and raw.has("FOV"):
        cams = []
        for g in _groups(raw.segments, "Name"):
            gr = _Reader(RawMessage(raw.type, tuple(g)), r.what)
            cams.append(CameraZoom(name=g[0].value, fov=gr.req_float("FOV"), status=gr.text("Status")))
        return CameraZoomResult(time=time, cameras=tuple(cams), camera_type=item_type)
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
    Result: _fmt_result,
    CameraZoomResult: _fmt_camera_zoom,
    ViewportsResult: _fmt_viewports,
    EffecterStatus: _fmt_effecter,
    Die: lambda m: "DIE {Killer %s} {DamageType %s}\r\n" % (m.killer, m.damage_type),
    Stepped: lambda m: "STEPPED {Time %s}\r\n" % f4(m.time),
    Pong: lambda m: (
        "PONG%s%s\r\n"
        % ("" if m.id is None else " {Id %s}" % m.id, "" if m.time is None else " {Time %s}" % f4(m.time))
    ),
    ErrorReply: lambda m: "ERROR {Command %s} {Reason %s}\r\n" % (m.command, m.reason),
    UnknownMessage: _fmt_unknown,
}

PARSERS: dict[str, Callable[[_Reader], ResultMessage]] = {
    "RES": _parse_res,
    "EFF": _parse_eff,
    "DIE": lambda r: Die(killer=r.text("Killer"), damage_type=r.text("DamageType")),
    "STEPPED": lambda r: Stepped(time=r.req_float("Time")),
    "PONG": lambda r: Pong(id=r.raw.get("Id"), time=r.opt_float("Time")),
    "ERROR": lambda r: ErrorReply(command=r.text("Command"), reason=r.text("Reason")),
}
