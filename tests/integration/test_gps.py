"""The GPS sensor (protocol.md 6.3 and 7.6): position mapping, satellites and fix under
open sky and under a roof, noise statistics with fixed seeds, and the SEN line.

Readings are taken from :class:`usarsim.sim.simulation.Simulation` directly (no sockets),
on a P2AT body carrying only a GPS, in small worlds written to ``tmp_path``.
"""

from __future__ import annotations

import math
import re
import types

import numpy as np
import pytest

from usarsim.config.catalog import ROBOTS_DIR
from usarsim.config.robot import load_robot
from usarsim.config.world import GeoReference
from usarsim.config.world_file import load_world
from usarsim.errors import ConfigError
from usarsim.protocol.messages import SensorMessage, format_message, parse_message
from usarsim.readings import GpsReading
from usarsim.sensors.gps import (  # importing the module registers the GPS plugin
    GPS,
    SKY,
    degrees_minutes,
    geographic_to_degrees,
    noise_sigma_m,
    world_to_geographic,
)
from usarsim.sim import frames
from usarsim.sim.simulation import Simulation, describe_items

GEO = GeoReference()  # the worlds below define no geo_reference: USARSim's ZeroZeroLocation
# GPS mount on the robot (USARSim frame, m): above the chassis top (z = -0.146), off-centre
# so that the mount offset and the robot's heading matter.
MOUNT = (-0.1, 0.05, -0.2)
# UDK GPSSensor defaults (protocol.md 7.6).
MAX_NOISE, MIN_NOISE = 2.5, 0.75

OPEN_WORLD = """\
name: GpsOpen
description: open sky over a 60 m x 60 m floor
floor: {center: [0.0, 0.0], size: [60.0, 60.0]}
start_poses:
  - {name: Origin, location: [0.0, 0.0, -0.2]}
"""

# A roof 3 m above the floor (its underside at z = -3.0), 200 m square: a ray 5 degrees
# above the horizon rises 3 m within 34 m, so every satellite in the sky is shaded.
ROOFED_WORLD = (
    OPEN_WORLD.replace("name: GpsOpen", "name: GpsRoofed")
    + """\
objects:
  - {name: roof, shape: box, center: [0.0, 0.0, -3.05], size: [200.0, 200.0, 0.1]}
"""
)

# A 30 m tall wall 1 m east of the origin, 200 m long: it hides the eastern sky.
WALLED_WORLD = (
    OPEN_WORLD.replace("name: GpsOpen", "name: GpsWalled")
    + """\
objects:
  - {name: wall, shape: box, center: [0.0, 1.5, -15.0], size: [200.0, 1.0, 30.0]}
"""
)


def write_world(tmp_path, text: str, name: str):
    path = tmp_path / f"{name}.yaml"
    path.write_text(text)
    return load_world(path)


def gps_robot(tmp_path, **params):
    """A copy of the shipped P2AT whose only sensor is a GPS named ``GPS`` at MOUNT."""
    p2at = (ROBOTS_DIR / "P2AT.yaml").read_text()
    head = p2at.split("\nsensors:")[0].replace("class_name: P2AT", "class_name: GpsProbe")
    extra = "".join(f", {k}: {v}" for k, v in params.items())
    text = head + f"\nsensors:\n  - {{type: GPS, name: GPS, location: [{MOUNT[0]}, {MOUNT[1]}, {MOUNT[2]}]{extra}}}\n"
    path = tmp_path / "GpsProbe.yaml"
    path.write_text(text)
    return load_robot(path)


def run(
    world, robot, *, seed: int = 0, spawns=((0.0, 0.0, 0.0),), settle: float = 1.0, seconds: float = 2.0
) -> tuple[Simulation, dict[int, list[tuple[float, GpsReading]]]]:
    """Spawn one robot per (x, y, yaw) in ``spawns``, let them settle, then collect the
    (time, reading) pairs of each robot's GPS over ``seconds``."""
    sim = Simulation(world, seed=seed)
    for uid, (x, y, yaw) in enumerate(spawns, start=1):
        sim.spawn(uid, robot, f"R{uid}", (x, y, -0.2), (0.0, 0.0, yaw))
    sim.advance(settle)
    sim.take_outputs()
    sim.advance(seconds)
    out: dict[int, list] = {uid: [] for uid in range(1, len(spawns) + 1)}
    for o in sim.take_outputs():
        if isinstance(o.value, GpsReading):
            out[o.uid].append((o.time, o.value))
    return sim, out


def true_sensor_xy(sim: Simulation, uid: int) -> tuple[float, float]:
    """World x (north) and y (east) of the GPS: the robot's pose plus the rotated mount."""
    loc, rpy = sim.pose_of(uid)
    offset = frames.euler_to_mat(*rpy) @ np.array(MOUNT)  # both in the USARSim frame
    return loc[0] + offset[0], loc[1] + offset[1]


def reading_xy(r: GpsReading, geo: GeoReference = GEO) -> tuple[float, float]:
    """The reported position converted back to world metres."""
    lat = geographic_to_degrees(r.latitude)
    lon = geographic_to_degrees(r.longitude)
    return (lat - geo.latitude_deg) * geo.scale_latitude_m, (lon - geo.longitude_deg) * geo.scale_longitude_m


def sigma_of(r: GpsReading) -> float:
    return noise_sigma_m(r.satellites, MAX_NOISE, MIN_NOISE)


@pytest.fixture(scope="module")
def worlds(tmp_path_factory):
    d = tmp_path_factory.mktemp("gps_worlds")
    return {
        "open": write_world(d, OPEN_WORLD, "GpsOpen"),
        "roofed": write_world(d, ROOFED_WORLD, "GpsRoofed"),
        "walled": write_world(d, WALLED_WORLD, "GpsWalled"),
    }


# --------------------------------------------------------------------------- pure helpers


def test_noise_sigma_follows_the_udk_line():
    # protocol.md 7.6: maxNoise/3 with 4 satellites, minNoise/3 with 12, linear between
    assert noise_sigma_m(4, 2.5, 0.75) == pytest.approx(2.5 / 3)
    assert noise_sigma_m(12, 2.5, 0.75) == pytest.approx(0.75 / 3)
    assert noise_sigma_m(8, 2.5, 0.75) == pytest.approx((2.5 + 0.75) / 2 / 3)
    assert noise_sigma_m(20, 2.5, 0.75) == pytest.approx(0.75 / 3)  # held at 12 satellites


def test_degrees_minutes_hemispheres_and_carry():
    assert degrees_minutes(GEO.latitude_deg, "N", "S") == (39, pytest.approx(8.0273), "N")
    assert degrees_minutes(GEO.longitude_deg, "E", "W") == (77, pytest.approx(12.998), "W")
    assert degrees_minutes(-33.5, "N", "S") == (33, pytest.approx(30.0), "S")
    assert degrees_minutes(151.25, "E", "W") == (151, pytest.approx(15.0), "E")
    # 9.99999999 deg would print as 9,60.0000: it carries to 10,0.0000
    assert degrees_minutes(9.99999999, "N", "S") == (10, 0.0, "N")
    for v in (GEO.latitude_deg, GEO.longitude_deg, -0.001, 12.3456789):
        assert geographic_to_degrees(degrees_minutes(v, "E", "W")) == pytest.approx(v, abs=1e-12)


def test_world_axes_map_north_and_east():
    lat0, lon0 = world_to_geographic(0.0, 0.0, GEO)
    lat1, lon1 = world_to_geographic(111.2, 71.67, GEO)
    assert (lat0, lon0) == (GEO.latitude_deg, GEO.longitude_deg)
    assert (lat1 - lat0) * 60 == pytest.approx(0.06)  # 111.2 m north: 0.06 minutes more latitude
    assert (lon1 - lon0) * 60 == pytest.approx(0.06)  # 71.67 m east: 0.06 minutes less west longitude
    assert degrees_minutes(lon1, "E", "W")[1] == pytest.approx(12.998 - 0.06)


def test_constellation_shows_about_ten_satellites_and_moves_slowly():
    mask = math.sin(math.radians(5.0))
    counts = [int((SKY.directions_enu(t, GEO.latitude_deg)[:, 2] > mask).sum()) for t in range(0, 43200, 600)]
    assert 8 <= min(counts) and max(counts) <= 13
    a, b = SKY.directions_enu(0.0, GEO.latitude_deg), SKY.directions_enu(10.0, GEO.latitude_deg)
    assert np.allclose(np.linalg.norm(a, axis=1), 1.0)
    moved = np.degrees(np.arccos(np.clip((a * b).sum(axis=1), -1, 1)))
    assert moved.max() < 0.2  # well under a degree in 10 s: a steady sky over a test
    assert not np.allclose(a, SKY.directions_enu(3600.0, GEO.latitude_deg))  # but it does move


# --------------------------------------------------------------------------- configuration


def test_config_defaults_aliases_and_conf(worlds, tmp_path):
    robot = gps_robot(tmp_path)
    (desc,) = describe_items(robot)
    assert desc.item_type == "GPS"
    assert desc.conf == (("ScanInterval", 0.2),)  # CONF {ScanInterval 0.2000} (UDK GPSSensor)
    robot = gps_robot(tmp_path, maxNoise=4.0, MINNOISE=1.0, ScanInterval=0.5)
    (desc,) = describe_items(robot)
    assert desc.conf == (("ScanInterval", 0.5),)
    sim = Simulation(worlds["open"], seed=0)
    r = sim.spawn(1, robot, "R1", (0.0, 0.0, -0.2), (0.0, 0.0, 0.0))
    (gps,) = r.sensors
    assert isinstance(gps, GPS)
    assert (gps.config.max_noise_m, gps.config.min_noise_m, gps.config.scan_interval_s) == (4.0, 1.0, 0.5)
    with pytest.raises(ConfigError):
        describe_items(gps_robot(tmp_path, maxNoise=0.5, minNoise=1.0))  # min above max
    with pytest.raises(ConfigError):
        describe_items(gps_robot(tmp_path, maxnoise=-1.0))


# --------------------------------------------------------------------------- open sky and roofs


def test_open_sky_fix_and_position_maps_north_and_east(worlds, tmp_path):
    robot = gps_robot(tmp_path, ScanInterval=0.02)
    spawns = ((0.0, 0.0, 0.0), (20.0, 0.0, 0.0), (0.0, -15.0, math.pi / 2))
    sim, out = run(worlds["open"], robot, seed=3, spawns=spawns, seconds=1.0)
    means = {}
    for uid in out:
        readings = [r for _, r in out[uid]]
        assert len(readings) == 50
        tx, ty = true_sensor_xy(sim, uid)
        xs, ys = [], []
        for r in readings:
            assert r.fix and r.satellites >= 4 and r.name == "GPS"
            assert r.latitude[2] == "N" and r.longitude[2] == "W"
            x, y = reading_xy(r)
            assert abs(x - tx) < 4 * sigma_of(r) and abs(y - ty) < 4 * sigma_of(r)
            xs.append(x - tx)
            ys.append(y - ty)
        assert np.std(xs) > 0.05 and np.std(ys) > 0.05  # both axes really are noisy
        sigma = float(np.mean([sigma_of(r) for r in readings]))
        lat = np.mean([geographic_to_degrees(r.latitude) for r in readings])
        lon = np.mean([geographic_to_degrees(r.longitude) for r in readings])
        means[uid] = (lat, lon, (tx, ty), sigma)
    # moving the robot north by dx adds dx / 111200 degrees of latitude; east by dy adds
    # dy / 71670 degrees of (east) longitude: the printed west longitude decreases
    (lat1, lon1, (x1, y1), s1), (lat2, lon2, (x2, y2), s2), (lat3, lon3, (x3, y3), s3) = means.values()
    tol_m = 3 * math.hypot(s1, s2) / math.sqrt(50)  # 3 sigma of a difference of two means
    assert (lat2 - lat1) * GEO.scale_latitude_m == pytest.approx(x2 - x1, abs=tol_m)
    assert (lon2 - lon1) * GEO.scale_longitude_m == pytest.approx(y2 - y1, abs=tol_m)
    assert x2 - x1 == pytest.approx(20.0, abs=0.1)
    tol_m = 3 * math.hypot(s1, s3) / math.sqrt(50)
    assert (lon3 - lon1) * GEO.scale_longitude_m == pytest.approx(y3 - y1, abs=tol_m)
    assert y3 - y1 == pytest.approx(-15.0 + MOUNT[0] - MOUNT[1], abs=0.1)  # yawed: the mount turned too
    # west of the origin (y < 0) the printed west longitude is larger
    assert means[3][1] < means[1][1]


def test_roof_hides_every_satellite_no_fix_no_coordinates(worlds, tmp_path):
    _, out = run(worlds["roofed"], gps_robot(tmp_path), seconds=1.0)
    readings = [r for _, r in out[1]]
    assert len(readings) == 5  # ScanInterval 0.2 s (UDK GPSSensor)
    for r in readings:
        assert not r.fix and r.satellites < 4
        assert r.latitude is None and r.longitude is None
    line = format_message(SensorMessage(time=1.0, reading=readings[0]))
    assert line == "SEN {Time 1.0000} {Type GPS} {Name GPS} {Fix 0} {Satellites %d}\r\n" % readings[0].satellites


def test_a_tall_wall_hides_part_of_the_sky(worlds, tmp_path):
    robot = gps_robot(tmp_path)
    _, open_out = run(worlds["open"], robot, seconds=0.2)
    _, walled_out = run(worlds["walled"], robot, seconds=0.2)
    n_open = open_out[1][-1][1].satellites
    n_walled = walled_out[1][-1][1].satellites
    assert 8 <= n_open <= 13
    assert n_walled < n_open


def test_geo_reference_of_the_view_is_used(worlds, tmp_path):
    """A world view carrying ``geo`` (a GeoReference) moves the origin and the scales."""
    sim, _ = run(worlds["open"], gps_robot(tmp_path), seconds=0.0)
    gps = sim.robots[1].sensors[0]
    v = sim.view()
    geo = GeoReference(
        latitude_deg=-33.8568, longitude_deg=151.2153, scale_latitude_m=110900.0, scale_longitude_m=92390.0
    )  # Sydney: south and east hemispheres
    view = types.SimpleNamespace(model=v.model, data=v.data, time=v.time, caster=v.caster, geo=geo)
    r = gps.measure(view)
    assert r.fix and r.latitude[2] == "S" and r.longitude[2] == "E"
    assert (r.latitude[0], r.longitude[0]) == (33, 151)
    x, y = reading_xy(r, geo)
    tx, ty = true_sensor_xy(sim, 1)
    assert abs(x - tx) < 4 * sigma_of(r) and abs(y - ty) < 4 * sigma_of(r)


def test_geo_reference_of_the_world_file_is_used(tmp_path):
    """End to end: a world's ``geo_reference`` reaches the sensor through the world view."""
    text = (
        OPEN_WORLD
        + """\
geo_reference: {latitude_deg: -33.8568, longitude_deg: 151.2153, scale_latitude_m: 110900.0,
                scale_longitude_m: 92390.0}
"""
    )
    world = write_world(tmp_path, text, "GpsSydney")
    sim, out = run(world, gps_robot(tmp_path), seconds=0.4)
    tx, ty = true_sensor_xy(sim, 1)
    for _, r in out[1]:
        assert r.fix
        assert (r.latitude[0], r.latitude[2], r.longitude[0], r.longitude[2]) == (33, "S", 151, "E")
        x, y = reading_xy(r, world.geo)
        assert abs(x - tx) < 4 * sigma_of(r) and abs(y - ty) < 4 * sigma_of(r)


# --------------------------------------------------------------------------- noise


def test_noise_statistics_match_the_satellite_count(worlds, tmp_path):
    sim, out = run(worlds["open"], gps_robot(tmp_path, ScanInterval=0.01), seed=11, seconds=10.0)
    readings = [r for _, r in out[1]]
    assert len(readings) == 1000
    tx, ty = true_sensor_xy(sim, 1)
    err = np.array([reading_xy(r) for r in readings]) - (tx, ty)
    sigma = np.array([sigma_of(r) for r in readings])
    z = err / sigma[:, None]  # normalised by the sigma of each reading's satellite count
    n = len(z)
    # unbiased: the mean error is within 4 standard errors of zero, on both axes
    assert np.all(np.abs(z.mean(axis=0)) < 4 / math.sqrt(n))
    assert np.all(np.abs(err.mean(axis=0)) < 4 * sigma.max() / math.sqrt(n))
    # spread: sigma = (slope n + b) / 3 (protocol.md 7.6), within 15 %
    assert np.all(np.abs(z.std(axis=0) - 1.0) < 0.15)
    # Gaussian: about 68 % within one sigma, none beyond 5
    assert 0.6 < float(np.mean(np.abs(z) < 1.0)) < 0.76
    assert np.abs(z).max() < 5.0
    # independent errors on the two axes
    assert abs(np.corrcoef(err[:, 0], err[:, 1])[0, 1]) < 0.15


def test_same_seed_same_readings_other_seed_other_noise(worlds, tmp_path):
    robot = gps_robot(tmp_path)
    a = run(worlds["open"], robot, seed=4)[1][1]
    b = run(worlds["open"], robot, seed=4)[1][1]
    c = run(worlds["open"], robot, seed=5)[1][1]
    assert len(a) == 10
    assert a == b
    assert [r.latitude for _, r in a] != [r.latitude for _, r in c]
    assert [r.longitude for _, r in a] != [r.longitude for _, r in c]
    # the sky is the world's: the same satellites whatever the seed
    assert [r.satellites for _, r in a] == [r.satellites for _, r in c]


# --------------------------------------------------------------------------- the SEN line

SEN_FIX = re.compile(
    r"SEN \{Time \d+\.\d{4}\} \{Type GPS\} \{Name GPS\} \{Latitude 39,8\.\d{4},N\} "
    r"\{Longitude 77,1[23]\.\d{4},W\} \{Fix 1\} \{Satellites \d+\}\r\n"
)


def test_sen_line_matches_the_spec_and_parses_back(worlds, tmp_path):
    _, out = run(worlds["open"], gps_robot(tmp_path), seed=7, seconds=0.4)
    for t, r in out[1]:
        line = format_message(SensorMessage(time=t, reading=r))
        assert SEN_FIX.fullmatch(line), line
        msg = parse_message(line)
        assert isinstance(msg, SensorMessage)
        back = msg.reading
        assert isinstance(back, GpsReading)
        assert (back.name, back.fix, back.satellites) == ("GPS", True, r.satellites)
        for got, sent in ((back.latitude, r.latitude), (back.longitude, r.longitude)):
            assert got[0] == sent[0] and got[2] == sent[2]
            assert got[1] == pytest.approx(sent[1], abs=5e-5)  # minutes with 4 decimals
