"""The ground-truth service's lines (protocol.md 12.4, the UDK USARTruth, TCP 3989).

A request ``{Class c} {Name n}`` (either may be left out; keys in any case) is answered
with one line per matching object, ``{Name n} {Class c} {Time t} {Location x,y,z}
{Rotation r,p,y}`` (world frame: metres, radians as roll, pitch, yaw), then ``{End}``.
"""

from __future__ import annotations

from dataclasses import dataclass

from usarsim.errors import ProtocolError

from .grammar import parse_float, parse_line, parse_vector
from .numbers import f4, vec4

END = "{End}\r\n"


@dataclass(frozen=True, slots=True)
class TruthRequest:
    """A ground-truth request ``{Class c} {Name n}`` (protocol.md 12.4): the class and name of the objects asked for,
    case-insensitive; None matches any."""

    class_name: str | None = None
    name: str | None = None

    def matches(self, class_name: str, name: str) -> bool:
        return (self.class_name is None or self.class_name.lower() == class_name.lower()) and (
            self.name is None or self.name.lower() == name.lower()
        )


@dataclass(frozen=True, slots=True)
class TruthObject:
    """One object of a ground-truth answer (protocol.md 12.4): its name, class, the simulated time, and its location
    (m) and rotation (rad, roll, pitch, yaw) in the world frame."""

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
        o.name,
        o.class_name,
        f4(o.time),
        vec4(o.location),
        vec4(o.rotation),
    )


def format_truth_request(class_name: str | None = None, name: str | None = None) -> str:
    """A client's request line: ``{Class c} {Name n}`` (either left out: any)."""
    parts = []
    if class_name:
        parts.append("{Class %s}" % class_name)
    if name:
        parts.append("{Name %s}" % name)
    return " ".join(parts or ["{Class}"]) + "\r\n"


def parse_truth_object(line: str) -> TruthObject | None:
    """One object line of a reply (None for the closing ``{End}``); a line that is not one
    raises :class:`usarsim.errors.ProtocolError`."""
    text = line.strip()
    if text == END.strip():
        return None
    raw = parse_line("TRUTH " + text)
    fields = {seg.key.lower(): seg.value for seg in raw.segments}
    try:
        return TruthObject(
            name=fields["name"],
            class_name=fields["class"],
            time=parse_float(fields["time"]),
            location=parse_vector(fields["location"], 3),  # type: ignore[arg-type]
            rotation=parse_vector(fields["rotation"], 3),  # type: ignore[arg-type]
        )
    except KeyError as exc:
        raise ProtocolError(f"a ground-truth object line lacks {{{exc.args[0].title()} ...}}: {text[:120]!r}") from None
