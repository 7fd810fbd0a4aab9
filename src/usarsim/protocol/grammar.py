"""The generic line grammar shared by every message (protocol.md §2).

``TYPE {Key Value} {Key Value} ...``:

* ``TYPE`` is the text before the first ``{`` or the first whitespace (``NFO{A 1}`` is
  valid); it is upper-cased, since command words are case-insensitive.
* A segment is ``{`` key, whitespace, value ``}``.  The key is the first word, the value is
  the rest, trimmed, and may contain spaces and commas.  A segment holding a single word
  (``{0.87}``, ``{None}``) has that word as key and an empty value.
* There is no escaping and no nesting: a ``}`` always ends a segment, and a ``{`` inside a
  segment is an error.
* Segments are separated by zero or more whitespace characters.
* Keys may repeat; segments keep their order.

This module also holds the value parsers used by :mod:`usarsim.protocol.commands` and
:mod:`usarsim.protocol.messages`: numbers, integers, booleans and vectors.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from usarsim.errors import ProtocolError

__all__ = [
    "RawMessage",
    "Segment",
    "format_segment",
    "parse_bool",
    "parse_float",
    "parse_int",
    "parse_line",
    "parse_vector",
]

_TYPE_RE = re.compile(r"\s*([^\s{}]+)")
_SEGMENT_RE = re.compile(r"\s*\{([^{}]*)\}")
_FLOAT_RE = re.compile(
    r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|inf|infinity|nan)\Z",
    re.IGNORECASE,
)
_INT_RE = re.compile(r"[+-]?[0-9]{1,18}\Z")
_VECTOR_SEPARATOR_RE = re.compile(r"\s*,\s*|\s+")
_TRUE = frozenset({"true", "1"})
_FALSE = frozenset({"false", "0"})

_SHOWN = 80  # characters of an offending line quoted in error messages


def _shorten(text: str) -> str:
    return repr(text if len(text) <= _SHOWN else text[:_SHOWN] + "...")


@dataclass(frozen=True, slots=True)
class Segment:
    """One ``{Key Value}`` segment, key as written (a bare ``{word}`` has value ``""``)."""

    key: str
    value: str


@dataclass(frozen=True, slots=True)
class RawMessage:
    """A line split into its upper-cased type and its segments, in order."""

    type: str
    segments: tuple[Segment, ...] = ()

    def get(self, key: str, default: str | None = None) -> str | None:
        """Value of the first segment whose key matches ``key`` case-insensitively."""
        wanted = key.lower()
        for seg in self.segments:
            if seg.key.lower() == wanted:
                return seg.value
        return default

    def get_all(self, key: str) -> list[str]:
        """Values of every segment whose key matches ``key`` case-insensitively, in order."""
        wanted = key.lower()
        return [seg.value for seg in self.segments if seg.key.lower() == wanted]

    def has(self, key: str) -> bool:
        """True when a segment with this key (case-insensitive) is present."""
        wanted = key.lower()
        return any(seg.key.lower() == wanted for seg in self.segments)


def parse_line(line: str) -> RawMessage:
    """Split one line (without its terminator) into type and segments.

    Raises :class:`ProtocolError` for an empty line, a line without a type, an unclosed or
    nested ``{``, a stray ``}``, an empty segment ``{}`` or text outside braces.
    """
    m = _TYPE_RE.match(line)
    if m is None:
        if not line or line.isspace():
            raise ProtocolError("empty line: expected 'TYPE {Key Value} ...'")
        raise ProtocolError(
            f"line {_shorten(line)} has no message type: expected a word such as INIT or DRIVE before the first '{{'"
        )
    msg_type = m.group(1).upper()
    pos = m.end()
    segments: list[Segment] = []
    match_segment = _SEGMENT_RE.match
    while True:
        sm = match_segment(line, pos)
        if sm is None:
            break
        content = sm.group(1).strip()
        if not content:
            raise ProtocolError(f"{msg_type}: empty segment '{{}}' in {_shorten(line)}: expected '{{Key Value}}'")
        parts = content.split(None, 1)
        segments.append(Segment(parts[0], parts[1] if len(parts) == 2 else ""))
        pos = sm.end()
    rest = line[pos:].strip()
    if rest:
        raise ProtocolError(f"{msg_type}: {_describe_trailing(rest)} in {_shorten(line)}")
    return RawMessage(msg_type, tuple(segments))


def _describe_trailing(rest: str) -> str:
    """Explain why the unparsed remainder of a line is not a sequence of segments."""
    if rest[0] == "{":
        close = rest.find("}")
        inner_open = rest.find("{", 1)
        if inner_open != -1 and (close == -1 or inner_open < close):
            return (
                f"'{{' inside a segment at {_shorten(rest)}: segments cannot nest, "
                "each '{' must be closed by '}' first"
            )
        return f"unclosed '{{' at {_shorten(rest)}: every segment must end with '}}'"
    if rest[0] == "}":
        return f"'}}' without a matching '{{' at {_shorten(rest)}"
    return f"text outside braces {_shorten(rest)}: expected '{{Key Value}}' segments only"


def format_segment(key: str, value: str) -> str:
    """``{key value}``, or ``{key}`` when the value is empty."""
    return "{%s %s}" % (key, value) if value else "{%s}" % key


def parse_float(text: str) -> float:
    """A decimal number (optional sign, optional exponent).

    ``nan`` and ``inf`` are returned as floats; callers that need finite values check.
    Raises :class:`ProtocolError` for anything else.
    """
    t = text.strip()
    if _FLOAT_RE.match(t) is None:
        raise ProtocolError(f"expected a number such as 1.5 or -0.25, got {_shorten(text)}")
    return float(t)


def parse_int(text: str) -> int:
    """An integer; a decimal with no fractional part (``2.0``) is also accepted."""
    t = text.strip()
    if _INT_RE.match(t) is not None:
        return int(t)
    if _FLOAT_RE.match(t) is not None:
        x = float(t)
        if x.is_integer() and abs(x) < 2**63:
            return int(x)
    raise ProtocolError(f"expected an integer such as 3 or -1, got {_shorten(text)}")


def parse_bool(text: str) -> bool:
    """``True``/``False``/``1``/``0`` in any letter case."""
    t = text.strip().lower()
    if t in _TRUE:
        return True
    if t in _FALSE:
        return False
    raise ProtocolError(f"expected a boolean True, False, 1 or 0, got {_shorten(text)}")


def parse_vector(text: str, n: int | None = 3) -> tuple[float, ...]:
    """Numbers separated by commas and/or whitespace: ``1,2,3``, ``1, 2, 3``, ``1 2 3``.

    With ``n`` set, exactly ``n`` numbers are required; with ``n=None`` any positive count.
    Non-finite values are returned as they are; callers that need finite values check.
    """
    t = text.strip()
    parts = _VECTOR_SEPARATOR_RE.split(t) if t else []
    if n is not None and len(parts) != n:
        raise ProtocolError(f"expected {n} numbers separated by commas (x,y,z), got {_shorten(text)}")
    if not parts:
        raise ProtocolError("expected numbers separated by commas, got an empty value")
    try:
        return tuple(parse_float(p) for p in parts)
    except ProtocolError as exc:
        raise ProtocolError(
            f"expected {n or 'some'} numbers separated by commas (x,y,z), got {_shorten(text)}"
        ) from exc
