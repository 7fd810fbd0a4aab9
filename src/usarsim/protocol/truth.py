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
    # ``{Map}``: the ground-truth occupancy map instead (MapRequest)
    map: MapRequest | None = None

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
    fields: dict[str, str] = {}
    for seg in raw.segments:
        key = seg.key.lower()
        if key == "class" and seg.value:
            class_name = seg.value.strip()
        elif key == "name" and seg.value:
            name = seg.value.strip()
        else:
            fields[key] = (seg.value or "").strip()
    if "map" in fields:
        resolution = parse_float(fields["resolution"]) if fields.get("resolution") else DEFAULT_MAP_RESOLUTION_M
        height = parse_float(fields["height"]) if fields.get("height") else DEFAULT_MAP_HEIGHT_M
        if not (MIN_MAP_RESOLUTION_M <= resolution <= 10.0):
            raise ProtocolError(f"a map's {{Resolution}} is {MIN_MAP_RESOLUTION_M:g} to 10 m, got {resolution:g}")
        if not (0.0 < height <= 100.0):
            raise ProtocolError(f"a map's {{Height}} is above the floor, up to 100 m, got {height:g}")
        return TruthRequest(map=MapRequest(resolution, height))
    return TruthRequest(class_name, name)


# ``{Map}`` (our extension, README "Ground-truth maps"): the world's ground-truth occupancy grid
# (usarsim.maps.truth), answered with a header line, the cells in ``{Data ...}`` lines and ``{End}``
DEFAULT_MAP_RESOLUTION_M = 0.05
DEFAULT_MAP_HEIGHT_M = 0.3
MIN_MAP_RESOLUTION_M = 0.01
MAP_CHUNK_CHARS = 4000  # base64 characters per {Data} line: every line stays below 4096 bytes


@dataclass(frozen=True, slots=True)
class MapRequest:
    """``{Map} {Resolution r} {Height h}``: the ground-truth occupancy map at ``r`` metres a cell,
    ``h`` metres above the floor."""

    resolution: float = DEFAULT_MAP_RESOLUTION_M
    height: float = DEFAULT_MAP_HEIGHT_M


@dataclass(frozen=True, slots=True)
class MapHeader:
    """The first line of a map answer: the world (and variant, -1: as written), the cell size,
    the map-frame origin of the grid's lower-left corner (ROS's map frame: x north, y west),
    its width (columns) and height (rows) in cells, and the sensing height."""

    world: str
    variant: int
    resolution: float
    origin: tuple[float, float]
    width: int
    height: int
    sensing_height: float


def format_map_request(resolution: float = DEFAULT_MAP_RESOLUTION_M, height: float = DEFAULT_MAP_HEIGHT_M) -> str:
    return "{Map} {Resolution %s} {Height %s}\r\n" % (f4(resolution), f4(height))


def format_map_answer(header: MapHeader, payload: bytes) -> str:
    """The answer to ``{Map}``: ``{Map world} {Variant v} {Resolution r} {Origin x,y} {Width w}
    {Height h} {SensingHeight s} {Encoding zlib+base64}``, then the cells (one signed byte each,
    row by row from the lowest: 0 free, 100 occupied, -1 unknown, zlib-compressed, base64) in
    ``{Data ...}`` lines, then ``{End}``."""
    import base64

    text = base64.b64encode(payload).decode("ascii")
    lines = [
        "{Map %s} {Variant %d} {Resolution %s} {Origin %s,%s} {Width %d} {Height %d} {SensingHeight %s} "
        "{Encoding zlib+base64}\r\n"
        % (
            header.world,
            header.variant,
            f4(header.resolution),
            f4(header.origin[0]),
            f4(header.origin[1]),
            header.width,
            header.height,
            f4(header.sensing_height),
        )
    ]
    lines += ["{Data %s}\r\n" % text[i : i + MAP_CHUNK_CHARS] for i in range(0, len(text), MAP_CHUNK_CHARS)]
    return "".join(lines) + END


def parse_map_answer(lines: list[str]) -> tuple[MapHeader, bytes]:
    """The header and the compressed cells of a map answer's lines (without ``{End}``)."""
    import base64

    if not lines:
        raise ProtocolError("an empty map answer: the server has no ground-truth map")
    raw = parse_line("TRUTH " + lines[0].strip())
    f = {seg.key.lower(): (seg.value or "").strip() for seg in raw.segments}
    try:
        ox, oy = parse_vector(f["origin"], 2)
        header = MapHeader(
            world=f["map"],
            variant=int(f["variant"]),
            resolution=parse_float(f["resolution"]),
            origin=(ox, oy),
            width=int(f["width"]),
            height=int(f["height"]),
            sensing_height=parse_float(f["sensingheight"]),
        )
    except (KeyError, ValueError) as exc:
        raise ProtocolError(f"not a map answer's first line: {lines[0][:120]!r} ({exc})") from None
    chunks = []
    for line in lines[1:]:
        text = line.strip()
        if not (text.startswith("{Data ") and text.endswith("}")):
            raise ProtocolError(f"a map answer's line is not {{Data ...}}: {text[:80]!r}")
        chunks.append(text[6:-1])
    return header, base64.b64decode("".join(chunks))


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
