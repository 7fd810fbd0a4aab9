"""The ground-truth service's lines (protocol.md 12.4, the UDK USARTruth, TCP 3989).

A request ``{Class c} {Name n}`` (either may be left out; keys in any case) is answered
with one line per matching object, ``{Name n} {Class c} {Time t} {Location x,y,z}
{Rotation r,p,y}`` (world frame: metres, radians as roll, pitch, yaw), then ``{End}``.
"""

from __future__ import annotations

from dataclasses import dataclass

from usarsim.errors import ProtocolError

from .grammar import parse_line
from .numbers import f4, vec4

END = "{End}\r\n"


@dataclass(frozen=True, slots=True)
class TruthRequest:
    class_name: str | None = None
    name: str | None = None

    def matches(self, class_name: str, name: str) -> bool:
        return ((self.class_name is None or self.class_name.lower() == class_name.lower())
                and (self.name is None or self.name.lower() == name.lower()))


@dataclass(frozen=True, slots=True)
class TruthObject:
    name: str
    class_name: str
    time: float
    location: tuple[float, float, float]
    rotation: tuple[float, float, float]


def parse_truth_request(line: str) -> TruthRequest:
    """The Class and Name of a request (other keys are ignored).  A line that is not
    made of ``{Key Value}`` segments raises :class:`usarsim.errors.ProtocolError`."""
    text = line.strip()
    if not text.startswith("{"):
        raise ProtocolError(f"a ground-truth request is '{{Class c}} {{Name n}}', got {text[:80]!r}")
    raw = parse_line("TRUTH " + text)
    class_name = name = None
    for seg in raw.segments:
        key = seg.key.lower()
        if key == "class" and seg.value:
            class_name = seg.value.strip()
        elif key == "name" and seg.value:
            name = seg.value.strip()
    return TruthRequest(class_name, name)


def format_truth_object(o: TruthObject) -> str:
    return "{Name %s} {Class %s} {Time %s} {Location %s} {Rotation %s}\r\n" % (
        o.name, o.class_name, f4(o.time), vec4(o.location), vec4(o.rotation))
