#!/usr/bin/env python3
"""Write the road world DM-Road_UrbanChallenge: its world file (.yaml), its DARPA route
network (.rndf) and a mission on it (.mdf), all from the one street plan below, so that the
RNDF waypoints map (through the world's geo_reference) onto the lane centre lines.

    python tools/make_road_world.py [--out DIR]     (default: src/usarsim/data/worlds)

The output is deterministic: the same script writes byte-identical files.

The town: a 3 x 3 grid of blocks between four north-south avenues and four east-west
streets, every street a two-way, two-lane road with a parking strip along each kerb.  Eight
blocks are raised sidewalk slabs with buildings; the ninth is a parking lot, the RNDF's
zone, entered through a driveway gap in its sidewalk.  Every intersection is an all-way
stop.  Frames and units: see the header this script writes into the world file.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "src"))

from usarsim.config.world import GeoReference  # noqa: E402
from usarsim.sensors.gps import world_to_geographic  # noqa: E402

NAME = "DM-Road_UrbanChallenge"
FT = 0.3048  # international foot, m

# --------------------------------------------------------------------------- street plan
# Lane width 12 ft: DARPA Urban Challenge RNDF lane_width is given in feet; 12 ft (3.66 m)
# is the standard US travel lane (AASHTO Green Book, 10-12 ft on urban streets).
LANE_FT = 12
LANE = LANE_FT * FT  # 3.6576 m
# Parking strip 8 ft (2.44 m): the width usually recommended for parallel parking lanes
# (estimate).
PARKING = 8 * FT
ROAD = 2 * (LANE + PARKING)  # 40 ft = 12.192 m kerb to kerb
HALF_ROAD = ROAD / 2
# Street centre lines every 82 m: blocks of 69.8 m kerb to kerb (estimate: a small-town
# block of 60-80 m).
STREETS = (-123.0, -41.0, 41.0, 123.0)
ROAD_END = STREETS[-1] + HALF_ROAD  # the outer kerb line of the outer streets
SIDEWALK = 3.0  # m, estimate
KERB = 0.15  # m: a 6 in vertical kerb, a common height (estimate)
SETBACK = 8.0  # m from the kerb to the building fronts (sidewalk plus front yard), estimate
ROAD_TOP = -0.005  # road surfaces stand 5 mm above the ground plane (Z down)
ROAD_THICK = 0.04
STOP_BACK = 7.5  # m from the crossing street's centre line to a stop (or entry) waypoint
MID = 8.0  # m either side of a block's middle: the two mid-block waypoints
CAR = (4.6, 1.8, 1.45)  # parked car: length, width, height (estimate, a mid-size sedan)
START_Z = -0.25  # start poses a little above the road: robots are set down from there

# Geographic reference: the town is placed near the 2007 Urban Challenge final site, the
# former George Air Force Base, Victorville, California (about 34.58 N, 117.37 W).  The
# street plan is invented, not a survey of that site.
LAT0 = 34.585
LON0 = -117.365
# Metres per degree at LAT0 on the WGS84 ellipsoid (a = 6378137 m, f = 1/298.257223563):
# latitude  pi/180 * a (1 - e^2) / (1 - e^2 sin^2 phi)^1.5,
# longitude pi/180 * a cos phi / (1 - e^2 sin^2 phi)^0.5.
_A = 6378137.0
_E2 = (1 / 298.257223563) * (2 - 1 / 298.257223563)
_S2 = math.sin(math.radians(LAT0)) ** 2
SCALE_LAT = round(math.pi / 180 * _A * (1 - _E2) / (1 - _E2 * _S2) ** 1.5, 1)
SCALE_LON = round(math.pi / 180 * _A * math.cos(math.radians(LAT0)) / math.sqrt(1 - _E2 * _S2), 1)
GEO = GeoReference(latitude_deg=LAT0, longitude_deg=LON0, scale_latitude_m=SCALE_LAT, scale_longitude_m=SCALE_LON)

# Daylight.  The sun of an equinox noon (NOAA, "General Solar Position Calculations": the
# noon zenith angle is the latitude minus the declination, 0 at the equinoxes) stands
# 90 - LAT0 degrees above the southern horizon; its light travels north (+X) and down (+Z).
SUN_ELEVATION_DEG = 90.0 - LAT0
_EL = math.radians(SUN_ELEVATION_DEG)
SUN_DIRECTION = (math.cos(_EL), 0.0, math.sin(_EL))
# The renderer's levels (estimates): the sun's diffuse light and the sky's ambient light, a
# fraction of full white each; the asphalt (reflectance 0.22 here) shows mid-grey in a
# camera picture, and walls facing away from the sun stay visible.
SUN_INTENSITY = 0.8
SKY_AMBIENT = 0.35

AVENUES = ("Avenue_A", "Avenue_B", "Avenue_C", "Avenue_D")  # north-south, west to east: segments 1-4
STREET_NAMES = ("First_Street", "Second_Street", "Third_Street", "Fourth_Street")  # east-west, south to north: 5-8
LOT_BLOCK = (1, 2)  # (row from the south, column from the west): the parking lot, zone 9
ZONE_ID = 9

# Speed limits (MDF, mph): the Urban Challenge rules capped speeds at 30 mph; 25 mph on the
# town streets and 10 mph in the lot are estimates of posted limits.
STREET_MPH = (5, 25)
LOT_MPH = (3, 10)


def fmt(v: float) -> str:
    s = f"{v:.4f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def vec(values) -> str:
    return "[" + ", ".join(fmt(v) for v in values) + "]"


# --------------------------------------------------------------------------- lanes


class Lane:
    """One lane of a straight street, its waypoints in the order of travel.

    Along a north-south avenue at y = c, lane 1 runs north on the east half (y = c + half a
    lane) and lane 2 south on the west half; along an east-west street at x = c, lane 1 runs
    east on the south half and lane 2 west on the north half (right-hand traffic)."""

    def __init__(self, segment: int, number: int, axis: str, centre: float, forward: bool):
        self.segment, self.number, self.axis, self.centre, self.forward = segment, number, axis, centre, forward
        sign = 1.0 if forward else -1.0
        # right of the direction of travel: east of a northbound lane, south of an eastbound one
        right = (0.0, 1.0) if axis == "x" else (-1.0, 0.0)
        self.offset = (right[0] * sign * LANE / 2, right[1] * sign * LANE / 2)
        self.nodes = list(range(4)) if forward else list(range(3, -1, -1))  # crossings in travel order
        self.s: list[float] = []  # travel coordinate along the street axis of each waypoint
        for b in range(3):
            a, z = STREETS[self.nodes[b]], STREETS[self.nodes[b + 1]]
            mid = (a + z) / 2
            self.s += [a + sign * STOP_BACK, mid - sign * MID, mid + sign * MID, z - sign * STOP_BACK]
        self.heading = (sign, 0.0) if axis == "x" else (0.0, sign)

    @property
    def id(self) -> str:
        return f"{self.segment}.{self.number}"

    def point(self, s: float) -> tuple[float, float]:
        """World (x, y) of the lane centre at travel coordinate ``s``."""
        if self.axis == "x":
            return (s, self.centre + self.offset[1])
        return (self.centre + self.offset[0], s)

    def waypoints(self) -> list[tuple[str, float, float]]:
        return [(f"{self.id}.{k + 1}", *self.point(s)) for k, s in enumerate(self.s)]

    def arrives(self, node: int) -> int | None:
        """Number of the waypoint that stops before crossing ``node`` (None: not arriving)."""
        for b in range(3):
            if self.nodes[b + 1] == node:
                return 4 * b + 4
        return None

    def departs(self, node: int) -> int | None:
        for b in range(3):
            if self.nodes[b] == node:
                return 4 * b + 1
        return None

    @property
    def yaw(self) -> float:
        """USARSim yaw of the direction of travel (clockwise from north seen from above)."""
        return math.atan2(self.heading[1], self.heading[0]) % (2 * math.pi)


def build_lanes() -> dict[int, list[Lane]]:
    segs: dict[int, list[Lane]] = {}
    for j, c in enumerate(STREETS):  # avenues: along x at y = c
        segs[j + 1] = [Lane(j + 1, 1, "x", c, True), Lane(j + 1, 2, "x", c, False)]
    for i, c in enumerate(STREETS):  # streets: along y at x = c
        segs[5 + i] = [Lane(5 + i, 1, "y", c, True), Lane(5 + i, 2, "y", c, False)]
    return segs


def intersection_exits(segs: dict[int, list[Lane]]) -> list[tuple[str, str]]:
    """At every crossing (row i, column j), each lane that stops there may turn onto each
    lane of the crossing road that leaves it (straight on is its own next waypoint)."""
    exits = []
    for i in range(4):
        for j in range(4):
            here = {j + 1: i, 5 + i: j}  # segment -> node index along it
            for sa, na in here.items():
                for a in segs[sa]:
                    wa = a.arrives(na)
                    if wa is None:
                        continue
                    for sb, nb in here.items():
                        if sb == sa:
                            continue
                        for b in segs[sb]:
                            wb = b.departs(nb)
                            if wb is not None:
                                exits.append((f"{a.id}.{wa}", f"{b.id}.{wb}"))
    return exits


# --------------------------------------------------------------------------- the lot (zone)


def block_bounds(i: int, j: int) -> tuple[float, float, float, float]:
    """x0, x1, y0, y1 of block (row i, column j), kerb to kerb."""
    return (STREETS[i] + HALF_ROAD, STREETS[i + 1] - HALF_ROAD, STREETS[j] + HALF_ROAD, STREETS[j + 1] - HALF_ROAD)


LX0, LX1, LY0, LY1 = block_bounds(*LOT_BLOCK)
LOT_MX = (LX0 + LX1) / 2
DRIVEWAY = 10.0  # half width of the driveway gap in the lot's west sidewalk, m
PERIMETER = [  # zone perimeter points (x, y): along the inner edge of the lot's sidewalks,
    (LX0 + 3.5, LY0 + 3.5),  # with the driveway's two points at the kerb line of Avenue C
    (LOT_MX - DRIVEWAY, LY0 + 3.5),
    (LOT_MX - 4.0, LY0 + 1.5),
    (LOT_MX + 4.0, LY0 + 1.5),
    (LOT_MX + DRIVEWAY, LY0 + 3.5),
    (LX1 - 3.5, LY0 + 3.5),
    (LX1 - 3.5, LY1 - 3.5),
    (LX0 + 3.5, LY1 - 3.5),
]
# Parking spots: 10 ft wide (estimate; 8.5-10 ft is usual), nose-in against the east
# sidewalk; waypoint 1 at the spot's mouth, 2 at its far end (where a car stops).
SPOT_FT = 10
SPOT_X = (-4.5, -1.5, 1.5, 4.5)
SPOT_Y = (LY1 - 13.0, LY1 - 7.0)


def zone_exits(segs: dict[int, list[Lane]]) -> list[tuple[str, str]]:
    """Into the lot from both lanes of Avenue C beside it and out again onto both."""
    north, south = segs[3]  # Avenue C: lane 1 northbound, lane 2 southbound (block row 1: waypoints 5-8)
    return [
        (f"{north.id}.6", f"{ZONE_ID}.0.3"),
        (f"{south.id}.6", f"{ZONE_ID}.0.4"),  # turning in
        (f"{ZONE_ID}.0.4", f"{north.id}.7"),
        (f"{ZONE_ID}.0.3", f"{south.id}.7"),  # turning out
    ]


# --------------------------------------------------------------------------- world objects


def objects() -> list[tuple[str, dict]]:
    """(comment or '', object) in file order; a comment line precedes a group."""
    out: list[tuple[str, dict]] = []

    def box(name, center, size, material, rot=None, comment=""):
        o = {"name": name, "shape": "box", "center": center, "size": size, "material": material}
        if rot is not None:
            o["rotation"] = rot
        out.append((comment, o))

    def cyl(name, center, radius, length, material, comment=""):
        out.append(
            (
                comment,
                {
                    "name": name,
                    "shape": "cylinder",
                    "center": center,
                    "radius": radius,
                    "length": length,
                    "material": material,
                },
            )
        )

    zc = ROAD_TOP + ROAD_THICK / 2
    length = 2 * ROAD_END
    for j, c in enumerate(STREETS):
        box(
            f"road_{AVENUES[j]}",
            (0.0, c, zc),
            (length, ROAD, ROAD_THICK),
            "asphalt",
            comment="road surfaces: avenues (north-south), then streets (east-west)" if j == 0 else "",
        )
    for i, c in enumerate(STREETS):
        box(f"road_{STREET_NAMES[i]}", (c, 0.0, zc), (ROAD, length, ROAD_THICK), "asphalt")

    # blocks: sidewalk slabs with buildings set back from the kerb
    heights = (
        (5.0, 8.5, 6.0, 4.0),
        (7.0, 4.5),
        (9.0,),
        (6.5, 5.5, 4.5, 8.0),
        (4.0, 7.5),
        (5.0, 6.0, 9.0, 4.5),
        (8.0,),
        (6.0, 4.0),
    )
    patterns = ("2x2", "2x1", "1", "2x2", "1x2", "2x2", "1", "2x1")
    k = 0
    for i in range(3):
        for j in range(3):
            if (i, j) == LOT_BLOCK:
                continue
            x0, x1, y0, y1 = block_bounds(i, j)
            cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
            tag = f"b{i + 1}{j + 1}"
            box(
                f"{tag}_sidewalk",
                (cx, cy, -KERB / 2),
                (x1 - x0, y1 - y0, KERB),
                "sidewalk",
                comment=f"block {tag} (row {i + 1} from the south, column {j + 1} from the west)",
            )
            bx0, bx1, by0, by1 = x0 + SETBACK, x1 - SETBACK, y0 + SETBACK, y1 - SETBACK
            nx, ny = {"2x2": (2, 2), "2x1": (2, 1), "1x2": (1, 2), "1": (1, 1)}[patterns[k]]
            gap = 6.0  # alleys between buildings of a block
            w = (bx1 - bx0 - gap * (nx - 1)) / nx
            d = (by1 - by0 - gap * (ny - 1)) / ny
            n = 0
            for a in range(nx):
                for b in range(ny):
                    h = heights[k][n]
                    x = bx0 + w / 2 + a * (w + gap)
                    y = by0 + d / 2 + b * (d + gap)
                    box(f"{tag}_building{n + 1}", (x, y, -KERB - h / 2), (w, d, h), "building")
                    n += 1
            for n, (px, py) in enumerate(
                ((x0 + 1.0, y0 + 1.0), (x0 + 1.0, y1 - 1.0), (x1 - 1.0, y0 + 1.0), (x1 - 1.0, y1 - 1.0))
            ):
                cyl(f"{tag}_pole{n + 1}", (px, py, -KERB - 3.0), 0.12, 6.0, "metal")  # street light poles
            k += 1

    # the parking lot: asphalt at road level, sidewalks on its edges, the driveway gap on the west
    tag = f"b{LOT_BLOCK[0] + 1}{LOT_BLOCK[1] + 1}"
    box(
        f"{tag}_lot",
        ((LX0 + LX1) / 2, (LY0 + LY1) / 2, zc),
        (LX1 - LX0, LY1 - LY0, ROAD_THICK),
        "asphalt",
        comment=f"block {tag}: the parking lot (zone {ZONE_ID}), driveway from Avenue C",
    )
    sw = SIDEWALK
    for name, (x0, x1, y0, y1) in (
        ("south", (LX0, LX0 + sw, LY0, LY1)),
        ("north", (LX1 - sw, LX1, LY0, LY1)),
        ("east", (LX0 + sw, LX1 - sw, LY1 - sw, LY1)),
        ("west1", (LX0 + sw, LOT_MX - DRIVEWAY, LY0, LY0 + sw)),
        ("west2", (LOT_MX + DRIVEWAY, LX1 - sw, LY0, LY0 + sw)),
    ):
        box(f"{tag}_sidewalk_{name}", ((x0 + x1) / 2, (y0 + y1) / 2, -KERB / 2), (x1 - x0, y1 - y0, KERB), "sidewalk")
    for n, x in enumerate((-7.5, 10.5)):  # parked in unnumbered stalls beside the RNDF's spots
        box(f"{tag}_car{n + 1}", (x, sum(SPOT_Y) / 2, ROAD_TOP - CAR[2] / 2), (CAR[1], CAR[0], CAR[2]), "car")

    # cars parked along the kerbs: (segment lane, block index along it, offset from the block middle)
    for n, (axis, street, side, block, off) in enumerate(PARKED):
        c = STREETS[street]
        lat = c + side * (HALF_ROAD - PARKING / 2)
        mid = (STREETS[block] + STREETS[block + 1]) / 2 + off
        if axis == "x":  # along an avenue
            center, size = (mid, lat, ROAD_TOP - CAR[2] / 2), (CAR[0], CAR[1], CAR[2])
        else:
            center, size = (lat, mid, ROAD_TOP - CAR[2] / 2), (CAR[1], CAR[0], CAR[2])
        box(f"parked_car{n + 1}", center, size, "car", comment="cars parked along the kerbs" if n == 0 else "")
    return out


# (axis of the street, street index, side of its centre line (+1: east/north), block index, offset m)
PARKED = (
    ("x", 1, +1, 0, -20.0),
    ("x", 1, +1, 0, -13.0),
    ("x", 0, -1, 2, 15.0),
    ("y", 1, -1, 0, 12.0),
    ("y", 2, +1, 1, -25.0),
    ("y", 3, -1, 2, 0.0),
    ("x", 2, -1, 2, 18.0),
)

# Start poses: (segment, lane, block index along the travel direction); each at the
# middle of a block, on the lane centre, facing along the lane.
STARTS = ((1, 1, 0), (2, 2, 1), (3, 1, 2), (4, 2, 0), (5, 1, 1), (6, 2, 2), (7, 1, 0), (8, 2, 1))


def start_poses(segs) -> list[tuple[str, tuple, tuple]]:
    out = []
    for n, (seg, lane_no, block) in enumerate(STARTS):
        lane = segs[seg][lane_no - 1]
        s = (STREETS[lane.nodes[block]] + STREETS[lane.nodes[block + 1]]) / 2
        x, y = lane.point(s)
        out.append((f"PlayerStart{n + 1}", (x, y, START_Z), (0.0, 0.0, lane.yaw)))
    return out


# --------------------------------------------------------------------------- checks


def footprint_distance(obj: dict, x: float, y: float) -> float:
    """Horizontal distance from (x, y) to an object's footprint (0 inside); objects here
    are axis-aligned."""
    cx, cy, _ = obj["center"]
    if obj["shape"] == "cylinder":
        return max(0.0, math.hypot(x - cx, y - cy) - obj["radius"])
    sx, sy, _ = obj["size"]
    dx = max(0.0, abs(x - cx) - sx / 2)
    dy = max(0.0, abs(y - cy) - sy / 2)
    return math.hypot(dx, dy)


def check(objs, poses) -> None:
    obstacles = [o for _, o in objs if o["material"] != "asphalt"]
    for name, (x, y, _), _ in poses:
        near = min(footprint_distance(o, x, y) for o in obstacles)
        assert near >= 3.5, f"{name}: an obstacle {near:.2f} m away"


# --------------------------------------------------------------------------- writers


def geo(x: float, y: float) -> tuple[float, float]:
    return world_to_geographic(x, y, GEO)


def write_rndf(segs, path: Path) -> dict:
    lines = [
        f"RNDF_name\t{NAME}",
        "num_segments\t8",
        "num_zones\t1",
        "format_version\t1.0",
        "creation_date\t2007-11-03",
        "/* A 3 x 3 block town of two-lane streets; every crossing is an all-way stop. */",
        "/* Generated by tools/make_road_world.py with the world DM-Road_UrbanChallenge.yaml. */",
    ]
    exits = intersection_exits(segs) + zone_exits(segs)
    by_exit: dict[str, list[str]] = {}
    for a, b in exits:
        by_exit.setdefault(a, []).append(b)
    checkpoint = 0
    checkpoints: dict[str, int] = {}
    for seg in sorted(segs):
        lanes = segs[seg]
        name = AVENUES[seg - 1] if seg <= 4 else STREET_NAMES[seg - 5]
        lines += [f"segment\t{seg}", f"num_lanes\t{len(lanes)}", f"segment_name\t{name}"]
        for lane in lanes:
            wps = lane.waypoints()
            lines += [
                f"lane\t{lane.id}",
                f"num_waypoints\t{len(wps)}",
                f"lane_width\t{LANE_FT}",
                "left_boundary\tdouble_yellow",
                "right_boundary\tsolid_white",
            ]
            checkpoint += 1
            cp_wp = f"{lane.id}.6"  # the middle of the second block along the lane
            checkpoints[cp_wp] = checkpoint
            lines.append(f"checkpoint\t{cp_wp}\t{checkpoint}")
            for wid, _, _ in wps:
                if wid.split(".")[2] in ("4", "8", "12"):
                    lines.append(f"stop\t{wid}")
            for wid, _, _ in wps:
                for entry in by_exit.get(wid, []):
                    lines.append(f"exit\t{wid}\t{entry}")
            for wid, x, y in wps:
                la, lo = geo(x, y)
                lines.append(f"{wid}\t{la:.6f}\t{lo:.6f}")
            lines.append("end_lane")
        lines.append("end_segment")
    lines += [
        f"zone\t{ZONE_ID}",
        f"num_spots\t{len(SPOT_X)}",
        "zone_name\tParking_Lot",
        f"perimeter\t{ZONE_ID}.0",
        f"num_perimeterpoints\t{len(PERIMETER)}",
    ]
    for n in range(1, len(PERIMETER) + 1):
        for entry in by_exit.get(f"{ZONE_ID}.0.{n}", []):
            lines.append(f"exit\t{ZONE_ID}.0.{n}\t{entry}")
    for n, (x, y) in enumerate(PERIMETER, 1):
        la, lo = geo(x, y)
        lines.append(f"{ZONE_ID}.0.{n}\t{la:.6f}\t{lo:.6f}")
    lines.append("end_perimeter")
    for n, x in enumerate(SPOT_X, 1):
        checkpoint += 1
        lines += [f"spot\t{ZONE_ID}.{n}", f"spot_width\t{SPOT_FT}", f"checkpoint\t{ZONE_ID}.{n}.2\t{checkpoint}"]
        checkpoints[f"{ZONE_ID}.{n}.2"] = checkpoint
        for p, y in enumerate(SPOT_Y, 1):
            la, lo = geo(x, y)
            lines.append(f"{ZONE_ID}.{n}.{p}\t{la:.6f}\t{lo:.6f}")
        lines.append("end_spot")
    lines += ["end_zone", "end_file"]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return checkpoints


# A mission: a tour of the town that parks twice in the lot (checkpoint ids of the RNDF:
# 1-16 one per lane, in segment and lane order; 17-20 the parking spots).
MISSION = (1, 9, 17, 6, 12, 3, 15, 19, 8, 14, 2, 11)


def write_mdf(path: Path) -> None:
    lines = [
        f"MDF_name\t{NAME}_tour",
        f"RNDF\t{NAME}",
        "format_version\t1.0",
        "creation_date\t2007-11-03",
        "checkpoints",
        f"num_checkpoints\t{len(MISSION)}",
        *[str(c) for c in MISSION],
        "end_checkpoints",
        "speed_limits",
        "num_speed_limits\t9",
        *[f"{s}\t{STREET_MPH[0]}\t{STREET_MPH[1]}" for s in range(1, 9)],
        f"{ZONE_ID}\t{LOT_MPH[0]}\t{LOT_MPH[1]}",
        "end_speed_limits",
        "end_file",
    ]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


HEADER = f"""\
# {NAME} -- a small town street network for road robots, with a DARPA Urban
# Challenge route network ({NAME}.rndf) and a mission ({NAME}.mdf).
# Generated by tools/make_road_world.py (edit that script, not this file).
#
# What it models
#   A 3 x 3 grid of town blocks between four north-south avenues (Avenue_A..D,
#   RNDF segments 1-4, west to east) and four east-west streets (First..Fourth
#   _Street, segments 5-8, south to north). Every street is a two-way road:
#   two 12 ft travel lanes and an 8 ft parking strip along each kerb. Every
#   crossing is an all-way stop. Eight blocks are raised sidewalk slabs with
#   low buildings set back from the kerb and street light poles at their
#   corners; the ninth (row 2, column 3) is a parking lot, RNDF zone 9, entered
#   from Avenue C through a driveway gap. A few cars are parked along the kerbs
#   and in the lot.
#
# Sources (facts only)
#   [1] DARPA, "Urban Challenge Route Network Definition File (RNDF) and
#       Mission Data File (MDF) Formats", March 14, 2007: segments, lanes,
#       waypoints, checkpoints, stops, exits, zones, perimeters, spots;
#       lane_width and spot_width in feet; speed limits in mph.
#   [2] AASHTO, "A Policy on Geometric Design of Highways and Streets" (the
#       Green Book): 12 ft is the standard travel lane width, 10-12 ft on
#       urban streets (12 ft used here, lane_width 12 in the RNDF: 3.6576 m).
#   [3] DARPA Urban Challenge 2007 final event: the former George Air Force
#       Base, Victorville, California, about 34.58 N, 117.37 W; its speed
#       limits were at most 30 mph. The geo_reference below puts this town
#       there; the street plan is invented, not a survey of the site.
#   [4] WGS84 ellipsoid (a = 6378137 m, f = 1/298.257223563): metres per degree
#       of latitude and of longitude at the geo_reference latitude
#       ({SCALE_LAT:g} and {SCALE_LON:g} m), the scales of the GPS sensor here.
#   [5] NOAA Global Monitoring Laboratory, "General Solar Position
#       Calculations" (https://gml.noaa.gov/grad/solcalc/solareqns.PDF): the
#       sun's zenith angle at solar noon is the latitude minus the solar
#       declination, and the declination is 0 at the equinoxes; at
#       {LAT0:g} N the noon sun of an equinox stands {SUN_ELEVATION_DEG:.1f} degrees above the
#       southern horizon: the direction of the sun light below.
#
# Estimates (no exact numbers from the sources)
#   * Blocks of {STREETS[1] - STREETS[0] - ROAD:.1f} m kerb to kerb (street centre lines every
#     {STREETS[1] - STREETS[0]:g} m); sidewalks {SIDEWALK:g} m; building fronts {SETBACK:g} m from the kerb;
#     buildings 4-9 m tall (one or two storeys, so that GPS still sees the
#     sky along the streets); light poles 6 m, 0.24 m thick.
#   * Parking strips 8 ft wide; kerbs 6 in (0.15 m) high.
#   * Parked cars as boxes of {CAR[0]:g} x {CAR[1]:g} x {CAR[2]:g} m (a mid-size sedan).
#   * Parking spots 10 ft wide; speed limits 25 mph on the streets, 10 mph
#     in the lot (the MDF); the mission is a tour of the town with two stops
#     in parking spots.
#
# Lighting: daylight over the whole town, a sun (a directional light, from [5])
# and the sky's light (the ambient light), so that cameras see every street lit
# wherever they are. The levels are estimates for the renderer: the sun {SUN_INTENSITY:g}
# of full white, the sky {SKY_AMBIENT:g} grey, enough to show the dark asphalt and the
# walls facing away from the sun. The sun casts no shadows: one shadow map over
# a town 300 m across would be too coarse to show them.
#
# Route network and world agree: every RNDF waypoint, mapped through the
# geo_reference (x = (lat - latitude_deg) * scale_latitude_m, y = (lon -
# longitude_deg) * scale_longitude_m, as the GPS sensor computes them the other
# way), lies on the centre line of its lane, half a lane right of the road's
# centre line (right-hand traffic), to within the 6 decimals of the RNDF
# (about 6 cm). Lane waypoints: after each crossing ({STOP_BACK:g} m from the
# crossing street's centre line), {MID:g} m either side of each block's middle,
# and at the stop line before the next crossing ({STOP_BACK:g} m).
#
# Start poses: on lanes, at the middle of a block, facing along the lane, each
# at least 3.5 m (4.2 m or more) from any kerb, car, pole or building, so that
# a 4.6 m x 2.2 m car fits anywhere around it.
#
# Conventions
#   USARSim frame: X north, Y east, Z down; metres, radians. The ground is
#   the plane z = 0; road and lot surfaces are {ROAD_THICK:g} m asphalt boxes whose top
#   is {-ROAD_TOP * 1000:g} mm above it; sidewalks stand {KERB:g} m high. Box size and
#   cylinder length are full extents. Yaw is clockwise seen from above: 0
#   faces north, 1.5708 east, 3.1416 south, 4.7124 west.
"""


def write_world(objs, poses, path: Path) -> None:
    lines = [
        HEADER.rstrip("\n"),
        "",
        f"name: {NAME}",
        "description: town streets - 3 x 3 blocks of two-lane roads, all-way stops, a parking lot; "
        "DARPA Urban Challenge RNDF and MDF beside it",
        "time_limit_min: 0",
        "floor:",
        "  center: [0.0, 0.0]",
        "  size: [300.0, 300.0]",
        "  material: ground",
        "geo_reference:",
        f"  latitude_deg: {LAT0}",
        f"  longitude_deg: {LON0}",
        f"  scale_latitude_m: {SCALE_LAT}",
        f"  scale_longitude_m: {SCALE_LON}",
        f"ambient_light: {vec((SKY_AMBIENT,) * 3)}",
        "lights:",
        f"  - {{name: sun, type: directional, direction: {vec(SUN_DIRECTION)}, color: [1.0, 1.0, 1.0], "
        f"intensity: {fmt(SUN_INTENSITY)}, cast_shadows: false}}",
        "materials:",
        "  ground: {rgba: [0.42, 0.48, 0.26, 1.0], friction: 0.8, texture: grass}      # dry grass around the town",
        "  asphalt: {rgba: [0.22, 0.22, 0.24, 1.0], friction: 1.0, texture: road}"
        "     # dry asphalt, lane markings and stop lines",
        "  sidewalk: {rgba: [0.68, 0.68, 0.66, 1.0], friction: 1.0, texture: concrete}    # concrete",
        "  building: {rgba: [0.80, 0.74, 0.62, 1.0], friction: 0.8, texture: concrete}    # stucco walls",
        "  metal: {rgba: [0.45, 0.47, 0.50, 1.0], friction: 0.6}       # light poles",
        "  car: {rgba: [0.60, 0.12, 0.12, 1.0], friction: 0.8}         # parked cars",
        "objects:",
    ]
    for comment, o in objs:
        if comment:
            lines.append(f"  # {comment}")
        parts = [f"name: {o['name']}", f"shape: {o['shape']}", f"center: {vec(o['center'])}"]
        if o["shape"] == "box":
            parts.append(f"size: {vec(o['size'])}")
        else:
            parts += [f"radius: {fmt(o['radius'])}", f"length: {fmt(o['length'])}"]
        if "rotation" in o:
            parts.append(f"rotation: {vec(o['rotation'])}")
        parts.append(f"material: {o['material']}")
        lines.append("  - {" + ", ".join(parts) + "}")
    lines.append("start_poses:")
    for (name, loc, rot), (seg, lane, block) in zip(poses, STARTS):
        lines.append(
            f"  - {{name: {name}, location: {vec(loc)}, rotation: {vec(rot)}}}"
            f"  # lane {seg}.{lane}, block {block + 1} along it"
        )
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "src" / "usarsim" / "data" / "worlds")
    args = ap.parse_args(argv)
    segs = build_lanes()
    objs = objects()
    poses = start_poses(segs)
    check(objs, poses)
    args.out.mkdir(parents=True, exist_ok=True)
    write_world(objs, poses, args.out / f"{NAME}.yaml")
    write_rndf(segs, args.out / f"{NAME}.rndf")
    write_mdf(args.out / f"{NAME}.mdf")
    print(f"wrote {NAME}.yaml ({len(objs)} objects, {len(poses)} start poses), {NAME}.rndf, {NAME}.mdf to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
