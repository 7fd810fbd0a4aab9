"""The shipped harbour DM-Harbour, where the Submarine (protocol.md 5.3e) sails: over real
sockets a client spawns it at a start pose under water, drives it with the nautical DRIVE,
and the ground truth shows it under way, submerged, turning and diving as commanded, and
rising towards the surface when stopped (it is slightly buoyant); a land robot starts dry
on a quay."""

from __future__ import annotations

import math

import pytest

from helpers import ground_truth, segments

SURFACE_Z = -3.5  # the basin's water surface (DM-Harbour.yaml: water z -3.5..0)
HULL_HALF_HEIGHT = 0.15  # the Submarine's hull is 0.3 m across (Submarine.yaml)


@pytest.fixture(scope="module")
def harbour():
    from usarsim.config.catalog import resolve_world

    return resolve_world("DM-Harbour")


def test_the_harbour_has_water_and_a_start_pose_in_it(harbour):
    (basin,) = harbour.water
    assert basin.density_kg_m3 == pytest.approx(999.7)
    assert basin.center[2] - basin.size[2] / 2 == pytest.approx(SURFACE_Z)
    wet = [p.name for p in harbour.start_poses if basin.depth_of(p.location) > HULL_HALF_HEIGHT]
    dry = [p.name for p in harbour.start_poses if basin.depth_of(p.location) == -math.inf]
    assert "Dive1" in wet and len(wet) >= 2 and len(dry) >= 4


def _motion(c, seconds):
    """Ground truth over ``seconds`` of stepping: the first and the last (time, location,
    orientation), and the least and the greatest Z on the way (Z is down: the highest and
    the deepest point)."""
    gts = ground_truth(c.step(seconds))
    assert len(gts) >= 2
    zs = [loc[2] for _, loc, _ in gts]
    return gts[0], gts[-1], min(zs), max(zs)


def test_the_submarine_sails_the_harbour_under_water(server_factory, harbour):
    srv = server_factory(world=harbour, seed=3)
    c = srv.connect()
    c.nfo()
    poses = c.ask("GETSTARTPOSES", "NFO {StartPoses").text
    assert "Dive1" in poses
    c.send("INIT {ClassName USARBot.Submarine} {Name Nemo} {Start Dive1}")
    lines = c.step(1.0)
    sta = [ln.text for ln in lines if ln.text.startswith("STA")]
    assert sta and sta[-1].startswith("STA {Type NauticalVehicle} {Time ")
    start = harbour.start_pose("Dive1").location
    (_, p0, o0), (_, p1, _), _, _ = _motion(c, 1.0)
    assert math.dist(p0, start) < 0.2  # it starts where the pose is, in the water
    assert abs(p1[2] - p0[2]) < 0.1  # and neither sinks nor shoots up (buoyant by under 1 %)

    # full ahead, rudder and planes amidships: 1.5 m/s (thrust 60 N / drag 40 N per m/s) up
    # the basin (north, +X), under water all the way
    c.send("DRIVE {Propeller 1} {Rudder 0} {SternPlane 0}")
    c.step(4.0)
    (t0, p0, o0), (t1, p1, o1), highest, _ = _motion(c, 2.0)
    speed = math.hypot(p1[0] - p0[0], p1[1] - p0[1]) / (t1 - t0)
    assert speed == pytest.approx(1.5, rel=0.1), speed
    assert p1[0] - p0[0] > 2.5 and abs(p1[1] - p0[1]) < 0.3  # north, straight
    assert highest > SURFACE_Z + 1.0  # it stays more than a metre under the surface
    assert srv.on_sim(lambda sim: sim.robots[1].in_water)

    # rudder to starboard: it turns right (yaw grows, clockwise seen from above)
    c.send("DRIVE {Rudder 0.3}")
    c.step(1.0)
    (t0, _, o0), (t1, _, o1), _, _ = _motion(c, 1.0)
    assert math.remainder(o1[2] - o0[2], 2 * math.pi) / (t1 - t0) > 0.2

    # stern planes down: it dives (Z grows towards the bottom)
    c.send("DRIVE {Rudder 0} {SternPlane -0.3}")
    c.step(0.5)
    (_, p0, _), (_, p1, _), _, deepest = _motion(c, 1.5)
    assert p1[2] - p0[2] > 0.4
    assert deepest < -HULL_HALF_HEIGHT  # not on the bottom

    # all stop: slightly buoyant, it drifts up, still afloat in the basin
    c.send("DRIVE {Propeller 0} {Rudder 0} {SternPlane 0}")
    c.step(3.0)
    (_, p0, _), (_, p1, _), _, _ = _motion(c, 3.0)
    assert p1[2] < p0[2]  # rising
    assert SURFACE_Z - HULL_HALF_HEIGHT < p1[2] < -HULL_HALF_HEIGHT
    sta = [segments(ln.text) for ln in c.step(0.4) if ln.text.startswith("STA")]
    assert sta[-1]["Battery"] != "0"  # a vessel keeps its battery in water


def test_a_land_robot_starts_dry_on_a_quay(server_factory, harbour):
    srv = server_factory(world=harbour, seed=3)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name Docker} {Start Quay1}")
    lines = c.step(1.5)
    (_, loc, _) = ground_truth(lines)[-1]
    assert loc[2] == pytest.approx(-4.5 - 0.1455, abs=0.02)  # on its wheels on the quay top
    assert not srv.on_sim(lambda sim: sim.robots[1].in_water)
    sta = [segments(ln.text) for ln in lines if ln.text.startswith("STA")]
    assert sta[-1]["Battery"] != "0"
