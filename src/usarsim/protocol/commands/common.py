"""What the parsers and formatters of every client command share (protocol.md §5): the
readers of a key's value, which say what the key allows when the value is wrong, and the
builder of a line that a client sends (the declarations that use them: :mod:`.declare`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from usarsim.errors import ProtocolError

from ..grammar import Segment, format_segment, parse_bool, parse_float, parse_int, parse_vector
from ..numbers import bool_str, num

Vec3 = tuple[float, float, float]

# --------------------------------------------------------------------------- value readers

_Reader = Callable[[str, Segment], Any]


def _bad(cmd: str, seg: Segment, allowed: str) -> ProtocolError:
    return ProtocolError(f"{cmd}: bad value {seg.value!r} for key {seg.key}: expected {allowed}")


def _text(cmd: str, seg: Segment) -> str:
    return seg.value


def _float(cmd: str, seg: Segment) -> float:
    try:
        x = parse_float(seg.value)
    except ProtocolError as exc:
        raise _bad(cmd, seg, "a number such as 1.5") from exc
    if not math.isfinite(x):
        raise _bad(cmd, seg, "a finite number (NaN and infinity are not allowed)")
    return x


def _positive_float(cmd: str, seg: Segment) -> float:
    x = _float(cmd, seg)
    if x <= 0.0:
        raise _bad(cmd, seg, "a number greater than 0")
    return x


def _int(cmd: str, seg: Segment) -> int:
    try:
        return parse_int(seg.value)
    except ProtocolError as exc:
        raise _bad(cmd, seg, "an integer such as 1") from exc


def _non_negative_int(cmd: str, seg: Segment) -> int:
    n = _int(cmd, seg)
    if n < 0:
        raise _bad(cmd, seg, "an integer of 0 or more")
    return n


def _bool(cmd: str, seg: Segment) -> bool:
    try:
        return parse_bool(seg.value)
    except ProtocolError as exc:
        raise _bad(cmd, seg, "True, False, 1 or 0 (any letter case)") from exc


def _vec(cmd: str, seg: Segment, n: int | None) -> tuple[float, ...]:
    what = f"{n} numbers such as 1.0,2.0,3.0" if n else "numbers separated by commas"
    try:
        v = parse_vector(seg.value, n)
    except ProtocolError as exc:
        raise _bad(cmd, seg, what + " (commas and/or spaces between them)") from exc
    if not all(map(math.isfinite, v)):
        raise _bad(cmd, seg, what + ", all finite (NaN and infinity are not allowed)")
    return v


def _vec3(cmd: str, seg: Segment) -> Vec3:
    return _vec(cmd, seg, 3)  # type: ignore[return-value]


def _vec2or3(cmd: str, seg: Segment) -> tuple[float, ...]:
    v = _vec(cmd, seg, None)
    if len(v) not in (2, 3):
        raise _bad(cmd, seg, "2 or 3 numbers such as 1.0,2.0")
    return v


def _choice(reader: _Reader, allowed: frozenset[int], text: str) -> _Reader:
    def read(cmd: str, seg: Segment) -> Any:
        value = reader(cmd, seg)
        if value not in allowed:
            raise _bad(cmd, seg, text)
        return value

    return read


# --------------------------------------------------------------------------- formatting


def _check(text: str, what: str) -> str:
    if "{" in text or "}" in text or "\r" in text or "\n" in text:
        raise ProtocolError(f"cannot send {what} {text!r}: braces and line breaks are not allowed")
    return text


def _word(text: str, what: str) -> str:
    _check(text, what)
    if not text or text != text.strip() or len(text.split()) != 1:
        raise ProtocolError(f"cannot send {what} {text!r}: it must be one word without spaces")
    return text


class _Line:
    """Builds ``TYPE {Key Value} ...\\r\\n``, skipping fields that are None."""

    __slots__ = ("parts",)

    def __init__(self, keyword: str):
        self.parts = [keyword]

    def text(self, key: str, value: str | None) -> _Line:
        if value is not None:
            self.parts.append(format_segment(key, _check(value, key)))
        return self

    def number(self, key: str, value: float | None) -> _Line:
        if value is not None:
            self.parts.append("{%s %s}" % (key, num(value)))
        return self

    def integer(self, key: str, value: int | None) -> _Line:
        if value is not None:
            self.parts.append("{%s %d}" % (key, value))
        return self

    def boolean(self, key: str, value: bool | None) -> _Line:
        if value is not None:
            self.parts.append("{%s %s}" % (key, bool_str(value)))
        return self

    def vector(self, key: str, value: tuple[float, ...] | None) -> _Line:
        if value is not None:
            self.parts.append("{%s %s}" % (key, ",".join(map(num, value))))
        return self

    def segments(self, segments: tuple[Segment, ...]) -> _Line:
        for seg in segments:
            self.parts.append(format_segment(_word(seg.key, "key"), _check(seg.value, seg.key)))
        return self

    def end(self) -> str:
        return " ".join(self.parts) + "\r\n"
