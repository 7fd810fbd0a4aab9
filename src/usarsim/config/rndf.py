"""DARPA Urban Challenge route network (RNDF) and mission (MDF) files.

Format: DARPA, "Urban Challenge Route Network Definition File (RNDF) and Mission Data File
(MDF) Formats", March 14, 2007.  Both are line-oriented text files, one keyword and its
values per line, separated by spaces or tabs; ``/*`` starts a comment that runs to the end
of the line.

RNDF::

    RNDF_name <name>            num_segments <n > 0>       num_zones <n >= 0>
    [format_version <text>]     [creation_date <text>]
    segment <m>                                   segments 1..M, in order
      num_lanes <n > 0>   [segment_name <text>]
      lane <m.n>                                  lanes m.1..m.N, in order
        num_waypoints <n > 0>
        [lane_width <feet>] [left_boundary <b>] [right_boundary <b>]
        [checkpoint <m.n.p> <checkpoint id>]* [stop <m.n.p>]* [exit <m.n.p> <entry>]*
        <m.n.p> <latitude> <longitude>            waypoints m.n.1.., in order
      end_lane
    end_segment
    zone <z>                                      zones M+1..M+N, in order
      num_spots <n >= 0>  [zone_name <text>]
      perimeter <z.0>
        num_perimeterpoints <n > 0>   [exit <z.0.p> <entry>]*
        <z.0.p> <latitude> <longitude>
      end_perimeter
      spot <z.s>                                  spots z.1..z.S, in order
        [spot_width <feet>]  [checkpoint <z.s.p> <checkpoint id>]*
        <z.s.1> <latitude> <longitude>
        <z.s.2> <latitude> <longitude>
      end_spot
    end_zone
    end_file

Lane boundaries are ``double_yellow``, ``solid_yellow``, ``solid_white`` or ``broken_white``.
An exit leads from a waypoint of its own lane (or a point of its own perimeter) to the entry
waypoint of a lane, or to a perimeter point, anywhere in the file.  Checkpoint ids are
positive integers unique in the file.  Latitude and longitude are decimal degrees (north
and east positive).

MDF::

    MDF_name <name>   RNDF <name of the RNDF>   [format_version <text>] [creation_date <text>]
    checkpoints
      num_checkpoints <n > 0>
      <checkpoint id>                             one a line, in the order to visit them
    end_checkpoints
    speed_limits
      num_speed_limits <n >= 0>
      <segment or zone id> <min mph> <max mph>
    end_speed_limits
    end_file

Every error is a :class:`~usarsim.errors.ConfigError` whose key is the line number
(``line 17``) and whose message says what was found and what was expected there.

:func:`to_world` maps a latitude and longitude into a world's local USARSim frame (X north,
Y east, metres) with the world's :class:`~usarsim.config.world.GeoReference`, the inverse of
the conversion the GPS sensor uses (:func:`usarsim.sensors.gps.world_to_geographic`).
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from usarsim.errors import ConfigError

if TYPE_CHECKING:
    from usarsim.config.world import GeoReference

FEET_TO_M = 0.3048  # international foot
BOUNDARIES = ("double_yellow", "solid_yellow", "solid_white", "broken_white")

_LANE_OPTIONS = ("lane_width", "left_boundary", "right_boundary", "checkpoint", "stop", "exit")
RNDF_KEYWORDS = (
    "RNDF_name",
    "num_segments",
    "num_zones",
    "format_version",
    "creation_date",
    "segment",
    "num_lanes",
    "segment_name",
    "lane",
    "num_waypoints",
    *_LANE_OPTIONS,
    "end_lane",
    "end_segment",
    "zone",
    "num_spots",
    "zone_name",
    "perimeter",
    "num_perimeterpoints",
    "end_perimeter",
    "spot",
    "spot_width",
    "end_spot",
    "end_zone",
    "end_file",
)
MDF_KEYWORDS = (
    "MDF_name",
    "RNDF",
    "format_version",
    "creation_date",
    "checkpoints",
    "num_checkpoints",
    "end_checkpoints",
    "speed_limits",
    "num_speed_limits",
    "end_speed_limits",
    "end_file",
)


# --------------------------------------------------------------------------- data


@dataclass(frozen=True)
class Waypoint:
    """A lane waypoint, perimeter point or spot waypoint: ``id`` is ``m.n.p``."""

    id: str
    lat: float
    lon: float


@dataclass(frozen=True)
class Checkpoint:
    """An RNDF ``checkpoint`` line: checkpoint ``id`` (a positive integer unique in the file) marks the waypoint
    ``waypoint`` (``m.n.p`` or ``z.s.p``), the places an MDF lists to visit."""

    id: int
    waypoint: str


@dataclass(frozen=True)
class Exit:
    """A legal transition from ``exit`` (a waypoint or perimeter point) to ``entry``."""

    exit: str
    entry: str


@dataclass(frozen=True, kw_only=True)
class Lane:
    """An RNDF ``lane`` block of a segment: its waypoints in order and its optional width (feet in the file),
    boundaries, checkpoints, stop waypoints and exits."""

    id: str  # "m.n"
    waypoints: tuple[Waypoint, ...]
    width_ft: float | None = None
    left_boundary: str | None = None
    right_boundary: str | None = None
    checkpoints: tuple[Checkpoint, ...] = ()
    stops: tuple[str, ...] = ()
    exits: tuple[Exit, ...] = ()

    @property
    def width_m(self) -> float | None:
        return None if self.width_ft is None else self.width_ft * FEET_TO_M


@dataclass(frozen=True, kw_only=True)
class Segment:
    """An RNDF ``segment`` block: segment ``id`` and its lanes in order, with its optional ``segment_name``."""

    id: int
    lanes: tuple[Lane, ...]
    name: str | None = None


@dataclass(frozen=True, kw_only=True)
class Perimeter:
    """The ``perimeter`` block of an RNDF zone (``z.0``): its points in order around the zone, and the exits that
    leave the zone from them."""

    id: str  # "z.0"
    points: tuple[Waypoint, ...]
    exits: tuple[Exit, ...] = ()


@dataclass(frozen=True, kw_only=True)
class Spot:
    """An RNDF parking ``spot`` block of a zone: its two waypoints, an optional width (feet in the file) and its
    checkpoints."""

    id: str  # "z.s"
    waypoints: tuple[Waypoint, ...]  # the two points of the spot: its entry and its far end
    width_ft: float | None = None
    checkpoints: tuple[Checkpoint, ...] = ()

    @property
    def width_m(self) -> float | None:
        return None if self.width_ft is None else self.width_ft * FEET_TO_M


@dataclass(frozen=True, kw_only=True)
class Zone:
    """An RNDF ``zone`` block (an open area such as a parking lot): zone ``id``, its perimeter, its parking spots and
    its optional ``zone_name``."""

    id: int
    perimeter: Perimeter
    spots: tuple[Spot, ...] = ()
    name: str | None = None


@dataclass(frozen=True, kw_only=True)
class Rndf:
    """A parsed RNDF (route network definition file): its segments and zones, with ``path`` the file it was read
    from; the methods collect its lanes, points, checkpoints, exits and stops across segments and zones."""

    name: str
    path: str
    segments: tuple[Segment, ...]
    zones: tuple[Zone, ...] = ()
    format_version: str | None = None
    creation_date: str | None = None

    def lanes(self) -> tuple[Lane, ...]:
        return tuple(lane for s in self.segments for lane in s.lanes)

    def lane(self, lane_id: str) -> Lane | None:
        return next((lane for lane in self.lanes() if lane.id == lane_id), None)

    def points(self) -> dict[str, Waypoint]:
        """Every lane waypoint, perimeter point and spot waypoint by id."""
        out = {w.id: w for lane in self.lanes() for w in lane.waypoints}
        for z in self.zones:
            out.update((w.id, w) for w in z.perimeter.points)
            out.update((w.id, w) for s in z.spots for w in s.waypoints)
        return out

    def checkpoints(self) -> dict[int, str]:
        """Checkpoint id -> the id of its waypoint."""
        cps = [c for lane in self.lanes() for c in lane.checkpoints]
        cps += [c for z in self.zones for s in z.spots for c in s.checkpoints]
        return {c.id: c.waypoint for c in sorted(cps, key=lambda c: c.id)}

    def exits(self) -> tuple[Exit, ...]:
        return tuple(e for lane in self.lanes() for e in lane.exits) + tuple(
            e for z in self.zones for e in z.perimeter.exits
        )

    def stops(self) -> tuple[str, ...]:
        return tuple(s for lane in self.lanes() for s in lane.stops)

    def summary(self) -> str:
        lanes = self.lanes()
        return (
            f"{len(self.segments)} segments, {len(lanes)} lanes, {sum(len(ln.waypoints) for ln in lanes)} "
            f"waypoints, {len(self.zones)} zones, {sum(len(z.spots) for z in self.zones)} spots, "
            f"{len(self.checkpoints())} checkpoints, {len(self.stops())} stops, {len(self.exits())} exits"
        )


@dataclass(frozen=True)
class SpeedLimit:
    """An MDF ``speed_limits`` entry: the minimum and maximum speed, in miles per hour, in segment or zone ``id``."""

    id: int  # a segment or zone id
    min_mph: float
    max_mph: float


@dataclass(frozen=True, kw_only=True)
class Mdf:
    """A parsed MDF (mission data file): the checkpoints of the named RNDF to visit, in order, and the speed limits
    of its segments and zones, with ``path`` the file it was read from."""

    name: str
    rndf_name: str
    path: str
    checkpoints: tuple[int, ...]  # in the order to visit them; one may come more than once
    speed_limits: tuple[SpeedLimit, ...] = ()
    format_version: str | None = None
    creation_date: str | None = None
    # line numbers, for errors found when the MDF is checked against its RNDF
    rndf_line: int = field(default=0, compare=False, repr=False)
    checkpoint_lines: tuple[int, ...] = field(default=(), compare=False, repr=False)
    speed_limit_lines: tuple[int, ...] = field(default=(), compare=False, repr=False)

    def summary(self) -> str:
        return f"{len(self.checkpoints)} checkpoints, {len(self.speed_limits)} speed limits"


# --------------------------------------------------------------------------- geography


def to_world(lat_deg: float, lon_deg: float, geo: GeoReference) -> tuple[float, float]:
    """The world point (x north, y east, metres) of a latitude and longitude (degrees, north
    and east positive) for the world's geographic reference: the inverse of the GPS sensor's
    conversion (:func:`usarsim.sensors.gps.world_to_geographic`, protocol.md 7.6), with the
    same origin and the same metres per degree."""
    return ((lat_deg - geo.latitude_deg) * geo.scale_latitude_m, (lon_deg - geo.longitude_deg) * geo.scale_longitude_m)


def waypoint_to_world(point: Waypoint, geo: GeoReference) -> tuple[float, float]:
    return to_world(point.lat, point.lon, geo)


# --------------------------------------------------------------------------- reading


@dataclass(frozen=True)
class _Line:
    number: int
    tokens: tuple[str, ...]

    @property
    def word(self) -> str:
        return self.tokens[0]


def _looks_like_id(word: str) -> bool:
    return bool(word) and word[0].isdigit()


class _Reader:
    """The significant lines of a file (comments and blank lines dropped), read in order."""

    def __init__(self, text: str, path: str, keywords: tuple[str, ...]):
        self.path = path
        self.keywords = keywords
        self.lines: list[_Line] = []
        raw_lines = text.splitlines()
        self.last_number = max(len(raw_lines), 1)
        for n, raw in enumerate(raw_lines, 1):
            cut = raw.find("/*")
            if cut >= 0:
                raw = raw[:cut]
            tokens = tuple(raw.split())
            if tokens:
                self.lines.append(_Line(n, tokens))
        self.i = 0

    def error(self, where: _Line | int | None, message: str) -> ConfigError:
        if where is None:
            return ConfigError(f"the file ends here; {message}", path=self.path, key=f"line {self.last_number}")
        n = where.number if isinstance(where, _Line) else where
        return ConfigError(message, path=self.path, key=f"line {n}")

    def peek(self) -> _Line | None:
        return self.lines[self.i] if self.i < len(self.lines) else None

    def peek_word(self) -> str | None:
        line = self.peek()
        return None if line is None else line.word

    def take(self) -> _Line:
        line = self.lines[self.i]
        self.i += 1
        return line

    def unexpected(self, line: _Line | None, expected: str) -> ConfigError:
        if line is None:
            return self.error(None, f"expected {expected}")
        word = line.word
        if word in self.keywords:
            return self.error(line, f"'{word}' is not allowed here; expected {expected}")
        if _looks_like_id(word):
            return self.error(line, f"unexpected point '{' '.join(line.tokens)}'; expected {expected}")
        close = difflib.get_close_matches(word, self.keywords, n=1, cutoff=0.6)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        return self.error(line, f"unknown keyword '{word}'{hint}; expected {expected}")

    def expect(self, keyword: str, nvalues: int | None = 1, what: str = "") -> _Line:
        """The next line, which must start with ``keyword`` and carry ``nvalues`` values
        (None: one or more, joined as text)."""
        line = self.peek()
        if line is None or line.word != keyword:
            raise self.unexpected(line, f"'{keyword}'{what}")
        self.take()
        return self.check_values(line, nvalues)

    def check_values(self, line: _Line, nvalues: int | None) -> _Line:
        got = len(line.tokens) - 1
        if nvalues is None:
            if got < 1:
                raise self.error(line, f"'{line.word}' needs a value")
        elif got != nvalues:
            vals = "a value" if nvalues == 1 else f"{nvalues} values"
            raise self.error(line, f"'{line.word}' takes {vals}, got {got}: '{' '.join(line.tokens)}'")
        return line

    def text(self, line: _Line) -> str:
        return " ".join(line.tokens[1:])

    def integer(self, line: _Line, token: str, what: str, *, min: int = 0) -> int:
        try:
            v = int(token)
        except ValueError:
            raise self.error(line, f"{what} must be an integer, got '{token}'") from None
        if v < min:
            raise self.error(line, f"{what} must be >= {min}, got {v}")
        return v

    def number(
        self, line: _Line, token: str, what: str, *, low: float | None = None, high: float | None = None
    ) -> float:
        try:
            v = float(token)
        except ValueError:
            v = float("nan")
        if not math.isfinite(v):
            raise self.error(line, f"{what} must be a number, got '{token}'")
        if (low is not None and v < low) or (high is not None and v > high):
            rng = f"within [{low:g}, {high:g}]" if high is not None else f">= {low:g}"
            raise self.error(line, f"{what} must be {rng}, got {token}")
        return v

    def ident(self, line: _Line, token: str, parts: int, what: str) -> tuple[int, ...]:
        """A dotted id of ``parts`` positive integers (the second of a perimeter id is 0)."""
        pieces = token.split(".")
        example = ".".join(str(i + 1) for i in range(parts))
        try:
            if len(pieces) != parts:
                raise ValueError
            out = tuple(int(p) for p in pieces)
            if any(p < 0 or not p_text.isdigit() for p, p_text in zip(out, pieces)):
                raise ValueError
        except ValueError:
            raise self.error(line, f"expected {what} id like {example}, got '{token}'") from None
        return out


def _dotted(ident: tuple[int, ...]) -> str:
    return ".".join(str(i) for i in ident)


def _read_text(path: str | Path) -> str:
    p = Path(path)
    try:
        return p.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"cannot read file ({exc.strerror})", path=str(p)) from exc
    except UnicodeDecodeError as exc:
        raise ConfigError(f"not a text file (byte {exc.start} is not UTF-8)", path=str(p)) from exc


# --------------------------------------------------------------------------- RNDF


class _RndfParser:
    def __init__(self, text: str, path: str):
        self.r = _Reader(text, path, RNDF_KEYWORDS)
        self.checkpoint_ids: dict[int, tuple[str, int]] = {}  # id -> (waypoint, line)
        self.pending_exits: list[tuple[Exit, _Line]] = []  # entries are resolved at the end

    def parse(self) -> Rndf:
        r = self.r
        name = r.text(r.expect("RNDF_name", None))
        ns_line = r.expect("num_segments")
        num_segments = r.integer(ns_line, ns_line.tokens[1], "num_segments", min=1)
        nz_line = r.expect("num_zones")
        num_zones = r.integer(nz_line, nz_line.tokens[1], "num_zones", min=0)
        line: _Line | None  # the line being read; None past the end of the file
        info: dict[str, str] = {}
        while r.peek_word() in ("format_version", "creation_date"):
            line = r.check_values(r.take(), None)
            if line.word in info:
                raise r.error(line, f"'{line.word}' is given twice")
            info[line.word] = r.text(line)

        segments: list[Segment] = []
        zones: list[Zone] = []
        while True:
            line = r.peek()
            word = None if line is None else line.word
            if word == "segment":
                if zones:
                    raise r.error(line, "segments must come before the zones")
                if len(segments) >= num_segments:
                    raise r.error(line, f"one segment too many: num_segments (line {ns_line.number}) is {num_segments}")
                segments.append(self.segment(len(segments) + 1))
            elif word == "zone":
                if len(segments) < num_segments:
                    raise r.error(
                        line,
                        f"num_segments (line {ns_line.number}) is {num_segments} but only "
                        f"{len(segments)} segments come before the first zone",
                    )
                if len(zones) >= num_zones:
                    raise r.error(line, f"one zone too many: num_zones (line {nz_line.number}) is {num_zones}")
                zones.append(self.zone(num_segments + len(zones) + 1))
            elif word == "end_file":
                if len(segments) < num_segments:
                    raise r.error(
                        line,
                        f"num_segments (line {ns_line.number}) is {num_segments} but the file "
                        f"has {len(segments)} segments",
                    )
                if len(zones) < num_zones:
                    raise r.error(
                        line, f"num_zones (line {nz_line.number}) is {num_zones} but the file has {len(zones)} zones"
                    )
                r.check_values(r.take(), 0)
                break
            else:
                expected = "'segment', 'zone' or 'end_file'" if not zones else "'zone' or 'end_file'"
                raise r.unexpected(line, expected)
        extra = r.peek()
        if extra is not None:
            raise r.error(extra, f"nothing may follow 'end_file', got '{' '.join(extra.tokens)}'")

        rndf = Rndf(
            name=name,
            path=r.path,
            segments=tuple(segments),
            zones=tuple(zones),
            format_version=info.get("format_version"),
            creation_date=info.get("creation_date"),
        )
        self.resolve_exits(rndf)
        return rndf

    # ---- segments and lanes

    def segment(self, sid: int) -> Segment:
        r = self.r
        head = r.expect("segment")
        got = r.integer(head, head.tokens[1], "the segment id", min=1)
        if got != sid:
            raise r.error(head, f"expected segment {sid} (segments are numbered 1, 2, ... in order), got {got}")
        nl_line = r.expect("num_lanes")
        num_lanes = r.integer(nl_line, nl_line.tokens[1], "num_lanes", min=1)
        name = None
        if r.peek_word() == "segment_name":
            name = r.text(r.check_values(r.take(), None))
        lanes = self.counted("segment", sid, nl_line, num_lanes, "lane", "end_segment", self.lane)
        return Segment(id=sid, lanes=tuple(lanes), name=name)

    def counted(self, kind: str, pid: int, count_line: _Line, count: int, child: str, end: str, read) -> list:
        """The ``child`` blocks of segment or zone ``pid`` up to its ``end`` line, each read by
        ``read(pid, n)``: exactly ``count`` of them, the number ``count_line`` gave."""
        r = self.r
        out: list = []
        while True:
            line = r.peek()
            word = None if line is None else line.word
            if word == child:
                if len(out) >= count:
                    raise r.error(
                        line,
                        f"one {child} too many: {count_line.word} of {kind} {pid} (line "
                        f"{count_line.number}) is {count}",
                    )
                out.append(read(pid, len(out) + 1))
            elif word == end:
                if len(out) < count:
                    raise r.error(
                        line,
                        f"{kind} {pid} has {len(out)} {child}s but {count_line.word} (line "
                        f"{count_line.number}) is {count}",
                    )
                r.check_values(r.take(), 0)
                return out
            else:
                raise r.unexpected(line, f"'{child} {pid}.{len(out) + 1}' or '{end}'")

    def lane(self, sid: int, lid: int) -> Lane:
        r = self.r
        head = r.expect("lane")
        got = r.ident(head, head.tokens[1], 2, "a lane")
        if got != (sid, lid):
            raise r.error(
                head,
                f"expected lane {sid}.{lid} (lanes of segment {sid} are numbered {sid}.1, "
                f"{sid}.2, ... in order), got {head.tokens[1]}",
            )
        lane_id = f"{sid}.{lid}"
        nw_line = r.expect("num_waypoints")
        count = r.integer(nw_line, nw_line.tokens[1], "num_waypoints", min=1)
        opts: dict[str, Any] = {}  # width_ft: feet (a float); left_boundary, right_boundary: a word
        checkpoints: list[tuple[Checkpoint, _Line]] = []
        stops: list[tuple[str, _Line]] = []
        exits: list[tuple[Exit, _Line]] = []
        while r.peek_word() in _LANE_OPTIONS:
            line = r.take()
            if line.word == "lane_width":
                self.once(opts, line)
                r.check_values(line, 1)
                opts["width_ft"] = r.number(line, line.tokens[1], "lane_width (feet)", low=0.0)
            elif line.word in ("left_boundary", "right_boundary"):
                self.once(opts, line)
                r.check_values(line, 1)
                if line.tokens[1] not in BOUNDARIES:
                    raise r.error(line, f"unknown lane boundary '{line.tokens[1]}'; allowed: {', '.join(BOUNDARIES)}")
                opts[line.word] = line.tokens[1]
            elif line.word == "checkpoint":
                checkpoints.append((self.checkpoint(line), line))
            elif line.word == "stop":
                r.check_values(line, 1)
                stops.append((_dotted(r.ident(line, line.tokens[1], 3, "a waypoint")), line))
            else:
                exits.append((self.exit(line), line))
        points = self.points(lambda n: (sid, lid, n), count, nw_line, f"lane {lane_id}", "end_lane")
        names = {w.id for w in points}
        where = f"lane {lane_id} ({len(points)} waypoints)"
        for c, line in checkpoints:
            self.member(c.waypoint, names, line, "checkpoint", where)
        for s, line in stops:
            self.member(s, names, line, "stop", where)
        for e, line in exits:
            self.member(e.exit, names, line, "exit", where)
        self.pending_exits += exits
        return Lane(
            id=lane_id,
            waypoints=points,
            width_ft=opts.get("width_ft"),
            left_boundary=opts.get("left_boundary"),
            right_boundary=opts.get("right_boundary"),
            checkpoints=tuple(c for c, _ in checkpoints),
            stops=tuple(s for s, _ in stops),
            exits=tuple(e for e, _ in exits),
        )

    # ---- zones

    def zone(self, zid: int) -> Zone:
        r = self.r
        head = r.expect("zone")
        got = r.integer(head, head.tokens[1], "the zone id", min=1)
        if got != zid:
            raise r.error(
                head, f"expected zone {zid} (zones are numbered on from the last segment, in order), got {got}"
            )
        ns_line = r.expect("num_spots")
        num_spots = r.integer(ns_line, ns_line.tokens[1], "num_spots", min=0)
        name = None
        if r.peek_word() == "zone_name":
            name = r.text(r.check_values(r.take(), None))
        perimeter = self.perimeter(zid)
        spots = self.counted("zone", zid, ns_line, num_spots, "spot", "end_zone", self.spot)
        return Zone(id=zid, perimeter=perimeter, spots=tuple(spots), name=name)

    def perimeter(self, zid: int) -> Perimeter:
        r = self.r
        head = r.expect("perimeter", 1, f" {zid}.0 (every zone has a perimeter)")
        if r.ident(head, head.tokens[1], 2, "a perimeter") != (zid, 0):
            raise r.error(head, f"expected perimeter {zid}.0, got {head.tokens[1]}")
        np_line = r.expect("num_perimeterpoints")
        count = r.integer(np_line, np_line.tokens[1], "num_perimeterpoints", min=1)
        exits: list[tuple[Exit, _Line]] = []
        while r.peek_word() == "exit":
            line = r.take()
            exits.append((self.exit(line), line))
        points = self.points(lambda n: (zid, 0, n), count, np_line, f"perimeter {zid}.0", "end_perimeter")
        names = {w.id for w in points}
        for e, line in exits:
            self.member(e.exit, names, line, "exit", f"perimeter {zid}.0 ({len(points)} points)")
        self.pending_exits += exits
        return Perimeter(id=f"{zid}.0", points=points, exits=tuple(e for e, _ in exits))

    def spot(self, zid: int, sid: int) -> Spot:
        r = self.r
        head = r.expect("spot")
        if r.ident(head, head.tokens[1], 2, "a spot") != (zid, sid):
            raise r.error(
                head,
                f"expected spot {zid}.{sid} (spots of zone {zid} are numbered {zid}.1, {zid}.2, ... "
                f"in order), got {head.tokens[1]}",
            )
        opts: dict[str, Any] = {}  # width_ft: feet (a float)
        checkpoints: list[tuple[Checkpoint, _Line]] = []
        while r.peek_word() in ("spot_width", "checkpoint"):
            line = r.take()
            if line.word == "spot_width":
                self.once(opts, line)
                r.check_values(line, 1)
                opts["width_ft"] = r.number(line, line.tokens[1], "spot_width (feet)", low=0.0)
            else:
                checkpoints.append((self.checkpoint(line), line))
        points = self.points(lambda n: (zid, sid, n), 2, head, f"spot {zid}.{sid}", "end_spot", fixed=True)
        names = {w.id for w in points}
        for c, line in checkpoints:
            self.member(c.waypoint, names, line, "checkpoint", f"spot {zid}.{sid} (2 waypoints)")
        return Spot(
            id=f"{zid}.{sid}",
            waypoints=points,
            width_ft=opts.get("width_ft"),
            checkpoints=tuple(c for c, _ in checkpoints),
        )

    # ---- pieces

    def once(self, seen: dict, line: _Line) -> None:
        key = "width_ft" if line.word in ("lane_width", "spot_width") else line.word
        if key in seen:
            raise self.r.error(line, f"'{line.word}' is given twice")

    def checkpoint(self, line: _Line) -> Checkpoint:
        r = self.r
        r.check_values(line, 2)
        wp = _dotted(r.ident(line, line.tokens[1], 3, "a waypoint"))
        cid = r.integer(line, line.tokens[2], "the checkpoint id", min=1)
        if cid in self.checkpoint_ids:
            other, at = self.checkpoint_ids[cid]
            raise r.error(line, f"checkpoint id {cid} is already given to waypoint {other} (line {at})")
        self.checkpoint_ids[cid] = (wp, line.number)
        return Checkpoint(id=cid, waypoint=wp)

    def exit(self, line: _Line) -> Exit:
        r = self.r
        r.check_values(line, 2)
        a = _dotted(r.ident(line, line.tokens[1], 3, "an exit waypoint"))
        b = _dotted(r.ident(line, line.tokens[2], 3, "an entry waypoint"))
        return Exit(exit=a, entry=b)

    def points(
        self, ident, count: int, count_line: _Line, owner: str, end: str, fixed: bool = False
    ) -> tuple[Waypoint, ...]:
        """The ``count`` point lines of ``owner``, then its ``end`` keyword."""
        r = self.r
        out: list[Waypoint] = []
        while True:
            line = r.peek()
            if line is not None and _looks_like_id(line.word):
                r.take()
                n = len(out) + 1
                want = _dotted(ident(n))
                if n > count:
                    told = (
                        "a spot has exactly 2 waypoints"
                        if fixed
                        else f"num_waypoints (line {count_line.number}) is {count}"
                        if end == "end_lane"
                        else f"num_perimeterpoints (line {count_line.number}) is {count}"
                    )
                    raise r.error(line, f"one point too many in {owner}: {told}; expected '{end}'")
                got = r.ident(line, line.word, 3, "a waypoint")
                if _dotted(got) != want:
                    raise r.error(
                        line,
                        f"expected waypoint {want} ({owner} numbers its points "
                        f"{_dotted(ident(1))}, {_dotted(ident(2))}, ... in order), got {line.word}",
                    )
                if len(line.tokens) != 3:
                    raise r.error(line, f"expected '{want} <latitude> <longitude>', got '{' '.join(line.tokens)}'")
                lat = r.number(line, line.tokens[1], f"the latitude of {want}", low=-90.0, high=90.0)
                lon = r.number(line, line.tokens[2], f"the longitude of {want}", low=-180.0, high=180.0)
                out.append(Waypoint(want, lat, lon))
            elif line is not None and line.word == end:
                if len(out) < count:
                    told = (
                        "a spot has exactly 2 waypoints"
                        if fixed
                        else f"num_waypoints (line {count_line.number}) is {count}"
                        if end == "end_lane"
                        else f"num_perimeterpoints (line {count_line.number}) is {count}"
                    )
                    raise r.error(line, f"{owner} has {len(out)} points but {told}")
                r.check_values(r.take(), 0)
                return tuple(out)
            else:
                nxt = _dotted(ident(len(out) + 1))
                expected = f"waypoint '{nxt} <latitude> <longitude>' or '{end}'" if len(out) < count else f"'{end}'"
                raise r.unexpected(line, expected)

    def member(self, point: str, names: set[str], line: _Line, what: str, where: str) -> None:
        if point not in names:
            raise self.r.error(line, f"{what} {point} is not a point of {where}")

    def resolve_exits(self, rndf: Rndf) -> None:
        """Every exit leads to a lane waypoint or a perimeter point that exists."""
        lanes = {lane.id: len(lane.waypoints) for lane in rndf.lanes()}
        perimeters = {z.id: len(z.perimeter.points) for z in rndf.zones}
        segs = {s.id for s in rndf.segments}
        for e, line in self.pending_exits:
            m, n, p = (int(x) for x in e.entry.split("."))
            if m in segs:
                if f"{m}.{n}" not in lanes:
                    why = f"segment {m} has no lane {m}.{n}"
                elif p > lanes[f"{m}.{n}"] or p < 1:
                    why = f"lane {m}.{n} has {lanes[f'{m}.{n}']} waypoints"
                else:
                    continue
            elif m in perimeters:
                if n != 0:
                    why = f"{m} is a zone: an exit may lead to its perimeter points {m}.0.p, not into a spot"
                elif p > perimeters[m] or p < 1:
                    why = f"perimeter {m}.0 has {perimeters[m]} points"
                else:
                    continue
            else:
                why = f"there is no segment or zone {m}"
            raise self.r.error(line, f"exit {e.exit} leads to {e.entry}, which does not exist: {why}")


def parse_rndf(text: str, path: str = "<rndf>") -> Rndf:
    """An RNDF from its text (``path`` names it in errors)."""
    return _RndfParser(text, path).parse()


def load_rndf(path: str | Path) -> Rndf:
    return parse_rndf(_read_text(path), str(path))


# --------------------------------------------------------------------------- MDF


def parse_mdf(text: str, path: str = "<mdf>", rndf: Rndf | None = None) -> Mdf:
    """An MDF from its text; with ``rndf``, also checked against it (:func:`check_mdf`)."""
    r = _Reader(text, path, MDF_KEYWORDS)
    name = r.text(r.expect("MDF_name", None))
    rndf_line = r.expect("RNDF", None)
    line: _Line | None  # the line being read; None past the end of the file
    info: dict[str, str] = {}
    while r.peek_word() in ("format_version", "creation_date"):
        line = r.check_values(r.take(), None)
        if line.word in info:
            raise r.error(line, f"'{line.word}' is given twice")
        info[line.word] = r.text(line)

    r.expect("checkpoints", 0)
    nc_line = r.expect("num_checkpoints")
    count = r.integer(nc_line, nc_line.tokens[1], "num_checkpoints", min=1)
    checkpoints: list[int] = []
    cp_lines: list[int] = []
    while r.peek() is not None and _looks_like_id(cast(str, r.peek_word())):  # a line: peek_word is its word
        line = r.take()
        if len(checkpoints) >= count:
            raise r.error(
                line,
                f"one checkpoint too many: num_checkpoints (line {nc_line.number}) is {count}; "
                "expected 'end_checkpoints'",
            )
        r.check_values(line, 0)
        checkpoints.append(r.integer(line, line.word, "a checkpoint id", min=1))
        cp_lines.append(line.number)
    line = r.peek()
    if line is None or line.word != "end_checkpoints":
        raise r.unexpected(line, "a checkpoint id or 'end_checkpoints'")
    if len(checkpoints) < count:
        raise r.error(
            line,
            f"the mission has {len(checkpoints)} checkpoints but num_checkpoints (line {nc_line.number}) is {count}",
        )
    r.check_values(r.take(), 0)

    r.expect("speed_limits", 0)
    nl_line = r.expect("num_speed_limits")
    count = r.integer(nl_line, nl_line.tokens[1], "num_speed_limits", min=0)
    limits: list[SpeedLimit] = []
    sl_lines: list[int] = []
    seen: dict[int, int] = {}
    while r.peek() is not None and _looks_like_id(cast(str, r.peek_word())):  # a line: peek_word is its word
        line = r.take()
        if len(limits) >= count:
            raise r.error(
                line,
                f"one speed limit too many: num_speed_limits (line {nl_line.number}) is {count}; "
                "expected 'end_speed_limits'",
            )
        if len(line.tokens) != 3:
            raise r.error(line, f"expected '<segment or zone id> <min mph> <max mph>', got '{' '.join(line.tokens)}'")
        sid = r.integer(line, line.tokens[0], "the segment or zone id", min=1)
        if sid in seen:
            raise r.error(line, f"segment or zone {sid} already has a speed limit (line {seen[sid]})")
        seen[sid] = line.number
        lo = r.number(line, line.tokens[1], "the minimum speed (mph)", low=0.0)
        hi = r.number(line, line.tokens[2], "the maximum speed (mph)", low=0.0)
        if lo > hi:
            raise r.error(line, f"the minimum speed {line.tokens[1]} mph is above the maximum {line.tokens[2]} mph")
        limits.append(SpeedLimit(sid, lo, hi))
        sl_lines.append(line.number)
    line = r.peek()
    if line is None or line.word != "end_speed_limits":
        raise r.unexpected(line, "'<segment or zone id> <min mph> <max mph>' or 'end_speed_limits'")
    if len(limits) < count:
        raise r.error(
            line, f"the file has {len(limits)} speed limits but num_speed_limits (line {nl_line.number}) is {count}"
        )
    r.check_values(r.take(), 0)
    line = r.peek()
    if line is None or line.word != "end_file":
        raise r.unexpected(line, "'end_file'")
    r.check_values(r.take(), 0)
    extra = r.peek()
    if extra is not None:
        raise r.error(extra, f"nothing may follow 'end_file', got '{' '.join(extra.tokens)}'")

    mdf = Mdf(
        name=name,
        rndf_name=r.text(rndf_line),
        path=path,
        checkpoints=tuple(checkpoints),
        speed_limits=tuple(limits),
        format_version=info.get("format_version"),
        creation_date=info.get("creation_date"),
        rndf_line=rndf_line.number,
        checkpoint_lines=tuple(cp_lines),
        speed_limit_lines=tuple(sl_lines),
    )
    if rndf is not None:
        check_mdf(mdf, rndf)
    return mdf


def load_mdf(path: str | Path, rndf: Rndf | None = None) -> Mdf:
    return parse_mdf(_read_text(path), str(path), rndf)


def check_mdf(mdf: Mdf, rndf: Rndf) -> None:
    """The MDF names this RNDF, its checkpoints are checkpoints of the RNDF and its speed
    limits are for segments or zones of the RNDF."""

    def error(line: int, message: str) -> ConfigError:
        return ConfigError(message, path=mdf.path, key=f"line {line}")

    if mdf.rndf_name != rndf.name:
        raise error(
            mdf.rndf_line,
            f"the mission is for the RNDF '{mdf.rndf_name}' but is checked against '{rndf.name}' ({rndf.path})",
        )
    known = rndf.checkpoints()
    for cid, line in zip(mdf.checkpoints, mdf.checkpoint_lines):
        if cid not in known:
            span = f"1..{max(known)}" if known else "none"
            raise error(
                line,
                f"checkpoint {cid} is not a checkpoint of the RNDF '{rndf.name}' "
                f"({len(known)} checkpoints, ids {span})",
            )
    ids = {s.id for s in rndf.segments} | {z.id for z in rndf.zones}
    for limit, line in zip(mdf.speed_limits, mdf.speed_limit_lines):
        if limit.id not in ids:
            raise error(
                line, f"{limit.id} is neither a segment nor a zone of the RNDF '{rndf.name}' (ids 1..{max(ids)})"
            )


# --------------------------------------------------------------------------- files


def route_file_kind(path: str | Path) -> str | None:
    """'rndf' or 'mdf' for a route network or mission file (by its suffix, or by its first
    keyword), None for anything else."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix in (".rndf", ".mdf"):
        return suffix[1:]
    if suffix in (".yaml", ".yml"):
        return None
    try:
        with open(p, encoding="utf-8", errors="replace") as f:
            head = f.read(4096)
    except OSError:
        return None
    for raw in head.splitlines():
        tokens = raw.split("/*", 1)[0].split()
        if tokens:
            return {"RNDF_name": "rndf", "MDF_name": "mdf"}.get(tokens[0])
    return None


def find_rndf(mdf: Mdf) -> Path | None:
    """The RNDF a mission file is for, when it lies beside it: ``<RNDF name>.rndf`` or a file
    with the MDF's own stem and the suffix ``.rndf``."""
    here = Path(mdf.path)
    for candidate in (here.with_name(f"{mdf.rndf_name}.rndf"), here.with_suffix(".rndf")):
        if candidate.is_file():
            return candidate
    return None


def describe_route_file(path: str | Path) -> str:
    """Check an RNDF or MDF file (an MDF against the RNDF beside it, when there is one) and
    return a one-line summary."""
    kind = route_file_kind(path)
    if kind == "rndf":
        rndf = load_rndf(path)
        return f"ok: rndf {rndf.name}: {rndf.summary()}"
    mdf = load_mdf(path)
    found = find_rndf(mdf)
    if found is None:
        return f"ok: mdf {mdf.name}: {mdf.summary()} (RNDF '{mdf.rndf_name}' not found beside it: not checked)"
    check_mdf(mdf, load_rndf(found))
    return f"ok: mdf {mdf.name}: {mdf.summary()}, checked against {found.name}"
