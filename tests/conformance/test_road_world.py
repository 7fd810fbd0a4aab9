"""The road world DM-Road_UrbanChallenge and its DARPA route network agree.

* the world loads and compiles; its RNDF and MDF parse and match each other;
* every RNDF lane waypoint, mapped into the world through the world's geo_reference, lies
  on a road surface box, half a lane to the right of the road's centre line (right-hand
  traffic), with the whole lane on the road and clear of every kerb, building, pole and
  parked car; zone perimeter points and parking spots lie on the lot, clear of obstacles;
* exits join nearby points (turns at a crossing, a driveway), stops are just before a
  crossing road;
* every start pose is on a lane centre line, faces along the lane, and has 3.5 m of clear
  ground around it;
* tools/make_road_world.py writes exactly the shipped files.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import pytest

from usarsim.config.catalog import WORLDS_DIR
from usarsim.config.rndf import load_mdf, load_rndf, waypoint_to_world
from usarsim.config.world_file import check_world_file
from usarsim.sim.simulation import Simulation

NAME = "DM-Road_UrbanChallenge"
WORLD_PATH = WORLDS_DIR / f"{NAME}.yaml"
RNDF_PATH = WORLDS_DIR / f"{NAME}.rndf"
MDF_PATH = WORLDS_DIR / f"{NAME}.mdf"
TOOL = Path(__file__).resolve().parents[2] / "tools" / "make_road_world.py"
ROAD_MATERIAL = "asphalt"
# RNDF coordinates have 6 decimals: 1e-6 degree is at most 0.11 m, so a waypoint is within
# about 6 cm of where it was put; 0.1 m leaves room for that.
TOL = 0.1
CLEARANCE_M = 3.5  # around a start pose: a 4.6 m x 2.2 m car fits whichever way it turns


@pytest.fixture(scope="module")
def world():
    return check_world_file(WORLD_PATH)


@pytest.fixture(scope="module")
def rndf():
    return load_rndf(RNDF_PATH)


def _frame(obj):
    """Centre (x, y), unit long axis, unit cross axis, half length, half width of a box's
    footprint (it turns about Z only)."""
    assert abs(obj.rotation[0]) < 1e-9 and abs(obj.rotation[1]) < 1e-9, obj.name
    yaw = obj.rotation[2]
    ax, ay = math.cos(yaw), math.sin(yaw)
    sx, sy = obj.size[0] / 2, obj.size[1] / 2
    if sx >= sy:
        return obj.center[:2], (ax, ay), (-ay, ax), sx, sy
    return obj.center[:2], (-ay, ax), (ax, ay), sy, sx


def footprint_distance(obj, x: float, y: float) -> float:
    """Horizontal distance from (x, y) to an object's footprint, 0 inside it."""
    if obj.shape == "cylinder":  # standing cylinders only here
        assert abs(obj.rotation[0]) < 1e-9 and abs(obj.rotation[1]) < 1e-9, obj.name
        return max(0.0, math.hypot(x - obj.center[0], y - obj.center[1]) - obj.radius_m)
    (cx, cy), u, n, hl, hw = _frame(obj)
    a = (x - cx) * u[0] + (y - cy) * u[1]
    b = (x - cx) * n[0] + (y - cy) * n[1]
    return math.hypot(max(0.0, abs(a) - hl), max(0.0, abs(b) - hw))


def roads(world):
    return [o for o in world.objects if o.material == ROAD_MATERIAL and o.name.startswith("road_")]


def obstacles(world):
    """Everything standing on the ground: kerbs (sidewalks), buildings, poles, cars."""
    return [o for o in world.objects if o.material != ROAD_MATERIAL]


def lane_geometry(world, lane):
    """World (x, y) of each waypoint and the unit direction of travel there."""
    pts = [waypoint_to_world(w, world.geo) for w in lane.waypoints]
    dirs = []
    for k in range(len(pts)):
        (x0, y0), (x1, y1) = (pts[k], pts[k + 1]) if k + 1 < len(pts) else (pts[k - 1], pts[k])
        d = math.hypot(x1 - x0, y1 - y0)
        dirs.append(((x1 - x0) / d, (y1 - y0) / d))
    return pts, dirs


def test_the_world_loads_and_compiles(world):
    sim = Simulation(world, seed=0)
    assert sim.model.ngeom >= 1 + len(world.objects)
    assert len(world.objects) <= 300  # ray casts test every geom
    assert len(world.start_poses) >= 6
    for o in roads(world):  # thin, flat and (nearly) flush with the ground: robots rest as on the floor
        top = o.center[2] - o.size[2] / 2
        assert -0.02 <= top <= 0.0 and o.size[2] <= 0.1 and o.rotation == (0.0, 0.0, 0.0), o.name


def test_the_rndf_and_mdf_belong_to_the_world(world, rndf):
    assert rndf.name == world.name
    mdf = load_mdf(MDF_PATH, rndf)  # checked against the RNDF: every checkpoint exists
    assert mdf.checkpoints and len(rndf.segments) == 8


def test_every_lane_waypoint_is_on_its_lane_of_a_road(world, rndf):
    road_boxes = roads(world)
    blockers = obstacles(world)
    checked = 0
    for lane in rndf.lanes():
        width = lane.width_m
        assert width == pytest.approx(3.6576)  # 12 ft
        pts, dirs = lane_geometry(world, lane)
        for w, (x, y), (dx, dy) in zip(lane.waypoints, pts, dirs):
            right = (-dy, dx)  # X north, Y east: the right of a northbound lane is east
            fits = []
            for o in road_boxes:
                (cx, cy), u, n, hl, hw = _frame(o)
                if abs(u[0] * dy - u[1] * dx) > 1e-3:  # the road must run along the lane
                    continue
                along = (x - cx) * u[0] + (y - cy) * u[1]
                offset = (x - cx) * right[0] + (y - cy) * right[1]  # right of the road's centre line
                if abs(along) <= hl and abs(offset - width / 2) <= TOL and abs(offset) + width / 2 <= hw + TOL:
                    fits.append(o.name)
            assert fits, f"waypoint {w.id} at ({x:.2f}, {y:.2f}) is not on the right half of a road along its lane"
            near = min(blockers, key=lambda o: footprint_distance(o, x, y))
            gap = footprint_distance(near, x, y)
            assert gap >= width / 2, f"waypoint {w.id}: the lane runs into {near.name} ({gap:.2f} m away)"
            checked += 1
    assert checked == 192


def test_zone_points_and_spots_are_on_the_lot(world, rndf):
    (zone,) = rndf.zones
    lot = [o for o in world.objects if o.material == ROAD_MATERIAL and not o.name.startswith("road_")]
    assert len(lot) == 1
    blockers = obstacles(world)
    for w in zone.perimeter.points + tuple(p for s in zone.spots for p in s.waypoints):
        x, y = waypoint_to_world(w, world.geo)
        assert footprint_distance(lot[0], x, y) == 0.0, f"{w.id} is off the lot"
        gap = min(footprint_distance(o, x, y) for o in blockers)
        assert gap >= 0.3, f"{w.id} is {gap:.2f} m from an obstacle"
    for s in zone.spots:  # a car parked in a spot stands clear of the parked ones
        (x1, y1), (x2, y2) = (waypoint_to_world(p, world.geo) for p in s.waypoints)
        half = s.width_m / 2
        for o in blockers:
            for t in (0.0, 0.5, 1.0):
                gap = footprint_distance(o, x1 + t * (x2 - x1), y1 + t * (y2 - y1))
                assert gap >= half - TOL, f"spot {s.id} overlaps {o.name}"


def test_exits_join_nearby_points_and_stops_are_before_a_crossing(world, rndf):
    points = rndf.points()
    for e in rndf.exits():
        (x0, y0), (x1, y1) = (waypoint_to_world(points[i], world.geo) for i in (e.exit, e.entry))
        assert 2.0 < math.hypot(x1 - x0, y1 - y0) < 25.0, f"exit {e.exit} -> {e.entry}"
    road_boxes = roads(world)
    lanes = {lane.id: lane for lane in rndf.lanes()}
    for stop in rndf.stops():
        lane = lanes[stop.rsplit(".", 1)[0]]
        k = [w.id for w in lane.waypoints].index(stop)
        pts, dirs = lane_geometry(world, lane)
        (x, y), (dx, dy) = pts[k], dirs[k]
        ahead = (x + 3.0 * dx, y + 3.0 * dy)  # 3 m on lies in the crossing road
        crossing = [
            o
            for o in road_boxes
            if abs(_frame(o)[1][0] * dx + _frame(o)[1][1] * dy) < 1e-3 and footprint_distance(o, *ahead) == 0.0
        ]
        assert crossing, f"stop {stop} is not just before a crossing road"


def test_start_poses_are_on_lanes_facing_along_them_with_room_around(world, rndf):
    lanes = [lane_geometry(world, lane) for lane in rndf.lanes()]
    blockers = obstacles(world)
    for p in world.start_poses:
        x, y, _ = p.location
        heading = (math.cos(p.rotation[2]), math.sin(p.rotation[2]))  # yaw clockwise from north: X north, Y east
        on_lane = False
        for pts, dirs in lanes:
            for (x0, y0), (x1, y1), d in zip(pts, pts[1:], dirs):
                seg = math.hypot(x1 - x0, y1 - y0)
                t = ((x - x0) * d[0] + (y - y0) * d[1]) / seg
                off = abs((x - x0) * -d[1] + (y - y0) * d[0])
                if 0.0 <= t <= 1.0 and off <= TOL and heading[0] * d[0] + heading[1] * d[1] > 0.999:
                    on_lane = True
        assert on_lane, f"{p.name} is not on a lane facing along it"
        near = min(blockers, key=lambda o: footprint_distance(o, x, y))
        gap = footprint_distance(near, x, y)
        assert gap >= CLEARANCE_M, f"{p.name}: {near.name} is {gap:.2f} m away"


def test_the_generator_writes_the_shipped_files(tmp_path):
    out = subprocess.run(
        [sys.executable, str(TOOL), "--out", str(tmp_path)], capture_output=True, text=True, timeout=60, check=False
    )
    assert out.returncode == 0, out.stderr
    for suffix in (".yaml", ".rndf", ".mdf"):
        made = (tmp_path / f"{NAME}{suffix}").read_bytes()
        assert made == (WORLDS_DIR / f"{NAME}{suffix}").read_bytes(), f"{NAME}{suffix} differs: run {TOOL.name}"
