"""The kinds of value a declared message's keys hold (:mod:`.declare`): how each is printed
(2 or 4 decimals, truncated, an integer, ``True``/``False``, text, a vector) and read back."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..grammar import Segment
from ..numbers import bool_str, f2, f4, ints, t4, vec2, vec3d, vec4, vec_angle4, vec_t4
from .common import _Reader, format_value


@dataclass(frozen=True, slots=True)
class Kind:
    """A kind of value: ``spec``, its place in a ``%`` format (``%d``, ``%s``), ``fmt`` what
    turns the value into that (None: the value itself), and ``read`` how a segment is read
    back."""

    spec: str
    fmt: Callable[[Any], Any] | None  # to a str for %s, an int for %d
    read: Callable[[_Reader, Segment, str], Any]  # (reader, segment, the key as declared)
    empty: str | None = None  # what follows the key, for an empty value, instead of " value"


def _text(r: _Reader, seg: Segment, wire: str) -> str:
    return seg.value


def _number(r: _Reader, seg: Segment, wire: str) -> float:
    return r.number(seg)


def _integer(r: _Reader, seg: Segment, wire: str) -> int:
    return r.integer(seg)


def _bool(r: _Reader, seg: Segment, wire: str) -> bool:
    return r.bool(seg)


def _vec3(r: _Reader, seg: Segment, wire: str) -> tuple[float, ...]:
    return r.vector(wire, seg.value)


def _values(r: _Reader, seg: Segment, wire: str) -> tuple[float, ...]:
    return r.vector(wire, seg.value, None)


TEXT = Kind("%s", None, _text)
F2 = Kind("%s", f2, _number)
F4 = Kind("%s", f4, _number)
INT = Kind("%d", None, _integer)
BOOL = Kind("%s", bool_str, _bool)
VEC2 = Kind("%s", vec2, _vec3)  # x,y,z with 2 decimals
VEC4 = Kind("%s", vec4, _vec3)  # x,y,z with 4 decimals
VT4 = Kind("%s", vec_t4, _vec3)  # x,y,z truncated to 4 decimals
T4 = Kind("%s", t4, _number)  # truncated to 4 decimals
ANGLES4 = Kind("%s", vec_angle4, _vec3)  # roll,pitch,yaw in [0, 2 pi), 4 decimals
VALUES4 = Kind("%s", vec4, _values)  # any number of values, 4 decimals
RANGES4 = Kind("%s", vec4, _values, empty="")  # a sweep's ranges; none: a bare {Range}
RANGES3 = Kind("%s", vec3d, _values, empty="")  # a depth picture's ranges, in millimetres


def _ints(r: _Reader, seg: Segment, wire: str) -> tuple[int, ...]:
    values = r.vector(wire, seg.value, None)
    if not all(math.isfinite(v) and v == int(v) for v in values):
        raise r.error(wire, seg.value, "whole numbers such as 320,240")
    return tuple(int(v) for v in values)


def _pair(r: _Reader, seg: Segment, wire: str) -> tuple[float, ...]:
    return r.vector(wire, seg.value, 2)


# a free-form field of an item (CONF, EFF, RES; protocol.md 6.7) as USARSim printed it:
# {Key value}, or {Key} when the value is empty; FIELD_SPACED keeps the space, {Key }
FIELD = Kind("%s", format_value, _text, empty="")
FIELD_SPACED = Kind("%s", format_value, _text)
PAIR_T4 = Kind("%s", vec_t4, _pair)  # two values truncated to 4 decimals (a picture's FOV)
INTS = Kind("%s", ints, _ints)  # whole numbers, comma-joined (a picture's columns and rows)
