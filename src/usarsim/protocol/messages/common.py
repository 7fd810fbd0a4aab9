"""What every server message shares (protocol.md §2 and §6): the line's end and its length
limit, the typed values of CONF, RES and EFF fields (§2.4, §6.7), and the reader of a parsed
line's segments, whose errors name the message."""

from __future__ import annotations

from usarsim.errors import ProtocolError
from usarsim.readings import FieldValue

from ..grammar import RawMessage, Segment, format_segment, parse_bool, parse_float, parse_int, parse_vector
from ..numbers import bool_str, f4

Vec3 = tuple[float, float, float]

_CRLF = "\r\n"

# Lines are kept shorter than this many bytes, CR LF included (protocol.md 1: the Player
# driver reads a line into a 4096-byte buffer).  A 3D scanner's configuration is refused when
# its sweep (or, in the opt-in split form, its row) would make a longer line
# (usarsim.sensors.scanner.LINE_LIMIT, the same bound).
LINE_LIMIT = 4096


def format_value(v: FieldValue) -> str:
    """A typed CONF field or RES/EFF key value as USARSim printed it (§2.4, §6.7): ``True`` /
    ``False``, an integer as it is, any other number at 4 decimals, a sequence comma-joined
    (its numbers at 4 decimals, integers included), text as it is."""
    if isinstance(v, bool):
        return bool_str(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return f4(v)
    if isinstance(v, (tuple, list)):
        return ",".join(
            format_value(float(x)) if isinstance(x, (int, float)) and not isinstance(x, bool) else format_value(x)
            for x in v
        )
    return str(v)


def _fields(pairs: tuple[tuple[str, FieldValue], ...]) -> list[str]:
    return [format_segment(k, format_value(v)) for k, v in pairs]


class _Reader:
    """Typed access to the segments of one message, with errors naming the message."""

    __slots__ = ("raw", "what")

    def __init__(self, raw: RawMessage, what: str):
        self.raw = raw
        self.what = what

    def error(self, key: str, value: str, expected: str) -> ProtocolError:
        return ProtocolError(f"{self.what}: bad value {value!r} for key {key}: expected {expected}")

    def missing(self, key: str) -> ProtocolError:
        return ProtocolError(f"{self.what}: missing {{{key} ...}}")

    def text(self, key: str) -> str:
        v = self.raw.get(key)
        if v is None:
            raise self.missing(key)
        return v

    def number(self, seg: Segment) -> float:
        try:
            return parse_float(seg.value)
        except ProtocolError as exc:
            raise self.error(seg.key, seg.value, "a number") from exc

    def integer(self, seg: Segment) -> int:
        try:
            return parse_int(seg.value)
        except ProtocolError as exc:
            raise self.error(seg.key, seg.value, "an integer") from exc

    def bool(self, seg: Segment) -> bool:
        try:
            return parse_bool(seg.value)
        except ProtocolError as exc:
            raise self.error(seg.key, seg.value, "True or False") from exc

    def vector(self, key: str, value: str, n: int | None = 3) -> tuple[float, ...]:
        if n is None and not value:
            return ()
        try:
            return parse_vector(value, n)
        except ProtocolError as exc:
            raise self.error(key, value, f"{n or 'some'} comma-separated numbers") from exc

    def seg(self, key: str) -> Segment:
        wanted = key.lower()
        for s in self.raw.segments:
            if s.key.lower() == wanted:
                return s
        raise self.missing(key)

    def opt_float(self, key: str) -> float | None:
        v = self.raw.get(key)
        return None if v is None else self.number(Segment(key, v))

    def req_float(self, key: str) -> float:
        return self.number(self.seg(key))

    def req_int(self, key: str) -> int:
        return self.integer(self.seg(key))

    def req_vec3(self, key: str) -> Vec3:
        return self.vector(key, self.text(key))  # type: ignore[return-value]

    def opt_time(self) -> float | None:
        return self.opt_float("Time")


def _groups(segments: tuple[Segment, ...], start: str) -> list[list[Segment]]:
    """Split segments into groups, each beginning with a segment keyed ``start``."""
    groups: list[list[Segment]] = []
    wanted = start.lower()
    for s in segments:
        if s.key.lower() == wanted:
            groups.append([s])
        elif groups:
            groups[-1].append(s)
    return groups
