"""Every robot file of the catalogue (issue: robot catalogue): it lands at every start pose
of every shipped world on its wheels, tracks or legs without jitter; its drive command moves it the right way at
the speed its file promises (within 15 %); its CONF and GEO lines say what its file says."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from helpers import drive_ackermann, drive_skid, drive_velocities, drive_wheels
from usarsim.config.catalog import ROBOTS_DIR, WORLDS_DIR
from usarsim.config.robot import load_robot
from usarsim.config.world_file import load_world
from usarsim.protocol import messages as M
from usarsim.robots.base import drive_class
from usarsim.sim.simulation import Simulation

ROBOT_FILES = sorted(ROBOTS_DIR.glob("*.yaml"))
WORLD_FILES = sorted(WORLDS_DIR.glob("*.yaml"))
OPEN_WORLD = """\
name: OpenField
description: an empty 2 x 2 km floor, room for a car at speed (tests only)
floor: {center: [0.0, 0.0], size: [2000.0, 2000.0]}
start_poses:
  - {name: Centre, location: [-30.0, 0.0, -1.0], rotation: [0.0, 0.0, 0.0]}
"""


def rest_z(robot, spawn_z: float, ground_z: float = 0.0) -> float:
    """Where the chassis origin rests: its lowest wheel, ball or box touches the surface at
    ``ground_z`` (Z down); an aerial robot hovers where it was put."""
    if robot.drive == "aerial":  # set down at a start pose, it hovers there
        return ground_z - drive_class(robot).lowest_point_m(robot) - robot.spawn_clearance_m
    if robot.drive == "legged":
        return ground_z - drive_class(robot).lowest_point_m(robot)
    low = [w.position[2] + w.radius_m for w in robot.wheels if w.parent == "chassis"]
    low += [p.center[2] + p.radius_m for p in robot.chassis if p.shape == "sphere"]
    if robot.drive == "static" or not low:
        low += [p.center[2] + p.size[2] / 2.0 for p in robot.chassis if p.shape == "box"]
    return ground_z - max(low)


@pytest.fixture(scope="module")
def open_world(tmp_path_factory):
    p = tmp_path_factory.mktemp("open") / "OpenField.yaml"
    p.write_text(OPEN_WORLD)
    return load_world(p)


def clearance(world, x: float, y: float, ground_z: float = 0.0) -> float:
    """Horizontal distance from (x, y) to the nearest static object of the world that stands
    on the level of ``ground_z`` (Z down): more than 5 cm above it and starting less than
    2.5 m above it (a deck above a room does not block the room, nor the room's walls the
    deck)."""
    import numpy as np

    from usarsim.sim.frames import euler_to_mat

    best = math.inf
    for o in world.objects:
        if o.mass_kg > 0:
            continue  # movable obstacles are pushed aside
        if o.shape == "box":
            half = np.abs(euler_to_mat(*o.rotation)) @ (np.array(o.size) / 2.0)
        elif o.shape in ("cylinder", "capsule", "sphere"):
            half = np.abs(euler_to_mat(*o.rotation)) @ np.array(
                [o.radius_m, o.radius_m, o.length_m / 2.0 + (o.radius_m if o.shape != "cylinder" else 0.0)]
            )
        else:
            continue
        top, bottom = o.center[2] - half[2], o.center[2] + half[2]
        if top > ground_z - 0.05 or bottom < ground_z - 2.5:
            continue
        dx = max(abs(x - o.center[0]) - half[0], 0.0)
        dy = max(abs(y - o.center[1]) - half[1], 0.0)
        best = min(best, math.hypot(dx, dy))
    return best


def footprint_radius(robot) -> float:
    length, width, _ = robot.geometry.dimensions
    return math.hypot(length, width) / 2.0


def in_water(world, location) -> bool:
    return any(wv.depth_of(location) > 0.0 for wv in world.water)


def assert_lands(world, robot, poses, settle_s: float) -> None:
    """Dropped at each of ``poses`` (one robot at each, all at once: start poses leave
    room between them), after ``settle_s`` every robot is level, resting at its height on
    the surface below its pose, and still (no jitter, no creep), with no physics reset.
    At a pose under water a vessel floats level where it was put (slightly buoyant, it
    may drift up a little); a walking robot, not built for water, loses its battery
    there and folds, so it is not checked."""
    sim = Simulation(world, seed=0)
    grounds = [sim._ground_below(p.location) for p in poses]
    for uid, pose in enumerate(poses, start=1):
        sim.spawn(uid, robot, f"R{uid}", pose.location, pose.rotation, set_down=True)
    sim.advance(settle_s)
    before = {uid: sim.pose_of(uid) for uid in range(1, len(poses) + 1)}
    sim.advance(0.5)
    for uid, (pose, ground) in enumerate(zip(poses, grounds), start=1):
        (x0, y0, z0), (roll, pitch, _) = before[uid]
        (x1, y1, z1), _ = sim.pose_of(uid)
        where = f"{robot.class_name} at {pose.name}"
        if in_water(world, pose.location) and robot.drive in ("nautical", "legged"):
            if robot.drive == "nautical":
                assert abs(math.remainder(roll, 2 * math.pi)) < 0.1, where
                assert abs(math.remainder(pitch, 2 * math.pi)) < 0.1, where
                assert math.dist((x1, y1, z1), pose.location) < 0.2, where
            continue
        assert abs(math.remainder(roll, 2 * math.pi)) < 0.1 and abs(math.remainder(pitch, 2 * math.pi)) < 0.1, where
        assert z0 == pytest.approx(rest_z(robot, pose.location[2], ground), abs=0.03), where
        assert math.dist((x0, y0, z0), (x1, y1, z1)) < 0.005, where
    assert sim.resets == 0


@pytest.mark.parametrize("world_path", WORLD_FILES, ids=lambda p: p.stem)
def test_every_start_pose_has_room_for_every_robot(world_path: Path):
    """Start poses are set in the open: the largest robot of the catalogue fits at each."""
    world = load_world(world_path)
    sim = Simulation(world, seed=0)
    largest = max((load_robot(p) for p in ROBOT_FILES), key=footprint_radius)
    assert len(world.start_poses) >= 6
    for pose in world.start_poses:
        room = clearance(world, pose.location[0], pose.location[1], sim._ground_below(pose.location))
        assert room >= footprint_radius(largest), (
            f"{pose.name}: {room:.2f} m to the nearest obstacle, {largest.class_name} needs {footprint_radius(largest):.2f}"
        )


@pytest.mark.parametrize("world_path", WORLD_FILES, ids=lambda p: p.stem)
@pytest.mark.parametrize("path", ROBOT_FILES, ids=lambda p: p.stem)
def test_robot_lands_on_its_wheels_at_every_start_pose(path: Path, world_path: Path):
    world = load_world(world_path)
    assert_lands(world, load_robot(path), world.start_poses, settle_s=2.0)


@pytest.mark.parametrize("path", ROBOT_FILES, ids=lambda p: p.stem)
def test_robot_lands_on_its_wheels_in_the_open(path: Path, open_world):
    assert_lands(open_world, load_robot(path), open_world.start_poses[:1], settle_s=3.0)


@pytest.mark.parametrize("path", ROBOT_FILES, ids=lambda p: p.stem)
def test_robot_drives_the_right_way_at_its_promised_speed(path: Path, open_world):
    robot = load_robot(path)
    sim = Simulation(open_world, seed=0)
    pose = open_world.start_poses[0]
    sim.spawn(1, robot, "R1", pose.location, pose.rotation)
    sim.advance(2.0)
    if robot.drive == "static":
        pytest.skip(f"{robot.class_name} has no drive")
    if robot.drive == "nautical":
        pytest.skip(f"{robot.class_name} moves in water only (tests/integration/test_drives.py)")
    spin = 0.5 * robot.max_speed_rad_s
    radius = robot.geometry.wheel_radius_m
    settings = drive_class(robot).settings_of(robot)  # an aerial robot's limits, a walking robot's gait
    if robot.drive == "aerial":  # m/s: "spin" x "radius" is the linear speed
        spin, radius = 0.5 * settings.max_linear_m_s, 1.0
        drive_velocities(sim, 1, None, spin, None, None)
    elif robot.drive == "legged":
        spin, radius = 0.5 * settings.max_linear_m_s, 1.0
        drive_velocities(sim, 1, None, spin, None, None)
    elif robot.drive == "skid":
        drive_skid(sim, 1, spin, spin)
    elif robot.drive == "ackermann":
        drive_ackermann(sim, 1, spin, 0.0, 0.0)
    else:
        drive = [(w.number, spin, 0.0) for w in robot.wheels if w.number >= 0]
        drive_wheels(sim, 1, drive)
    # time to reach the speed: at least 3 s, more for a fast car accelerating at 0.3 g
    sim.advance(max(3.0, spin * radius / (0.3 * 9.81) + 1.0))
    (x0, y0, _), _ = sim.pose_of(1)
    sim.advance(1.0)
    (x1, y1, _), (_, _, yaw) = sim.pose_of(1)
    assert x1 - x0 == pytest.approx(spin * radius, rel=0.15), "forward speed"
    assert abs(y1 - y0) < 0.1 * spin * radius + 0.01 and abs(math.remainder(yaw, 2 * math.pi)) < 0.15
    # turning left: yaw decreases (protocol.md 3)
    if robot.drive == "skid":
        drive_skid(sim, 1, -0.3 * robot.max_speed_rad_s, 0.3 * robot.max_speed_rad_s)
    elif robot.drive == "aerial":
        drive_velocities(sim, 1, None, None, None, -0.5 * settings.max_yaw_rate_rad_s)
    elif robot.drive == "legged":
        drive_velocities(sim, 1, None, 0.0, None, -0.5 * settings.max_yaw_rate_rad_s)
    elif robot.drive == "ackermann":
        drive_ackermann(sim, 1, None, -0.5 * robot.max_front_steer_rad, None)
    else:
        drive_wheels(
            sim, 1, [(w.number, (-spin if w.side == "left" else spin), 0.0) for w in robot.wheels if w.number >= 0]
        )
    sim.advance(1.0)
    _, (_, _, y_a) = sim.pose_of(1)
    sim.advance(1.0)
    _, (_, _, y_b) = sim.pose_of(1)
    assert math.remainder(y_b - y_a, 2 * math.pi) < -0.05, "a left turn decreases yaw"
    assert sim.resets == 0


@pytest.mark.parametrize("path", ROBOT_FILES, ids=lambda p: p.stem)
def test_robot_conf_and_geo_lines_match_its_file(path: Path, server_factory):
    robot = load_robot(path)
    robots_dir = path.parent
    srv = server_factory(robot_dirs=(str(robots_dir),))
    c = srv.connect()
    c.nfo()
    c.send(f"INIT {{ClassName USARBot.{robot.class_name}}} {{Name R1}} {{Start PlayerStart1}}")
    c.step(0.2)
    g = robot.geometry
    geo = M.format_message(
        M.RobotGeometry(
            vehicle_type=robot.vehicle_type,
            class_name=robot.class_name,
            dimensions=g.dimensions,
            cog=g.cog,
            wheel_radius=g.wheel_radius_m,
            wheel_separation=g.wheel_separation_m,
            wheel_base=g.wheel_base_m,
        )
    )
    conf = M.format_message(
        M.RobotConfiguration(
            vehicle_type=robot.vehicle_type,
            class_name=robot.class_name,
            steering_type=robot.steering_type,
            mass_kg=robot.mass_kg,
            max_speed=robot.max_speed_rad_s,
            max_torque=robot.max_torque_nm,
            max_front_steer=robot.max_front_steer_rad,
            max_rear_steer=robot.max_rear_steer_rad,
        )
    )
    assert c.ask("GETGEO {Type Robot}", "GEO").raw.decode() == geo
    assert c.ask("GETCONF {Type Robot}", "CONF").raw.decode() == conf
    assert f"{{SteeringType {robot.steering_type}}}" in conf and f"{{Name {robot.class_name}}}" in conf


SCANNER_ROBOTS = [
    p for p in ROBOT_FILES if any(i.item_type in ("RangeScanner", "IRScanner") for i in load_robot(p).items)
]


@pytest.mark.parametrize("path", SCANNER_ROBOTS, ids=lambda p: p.stem)
def test_every_robots_laser_sees_past_its_own_body(path: Path):
    """At a start pose with open floor around it, a robot's laser reads the room, not its own
    arm, camera or chassis: no beam stops within 0.3 m (a scanner mounted inside a part of the
    robot reads its MinRange on every beam)."""
    from usarsim.readings import RangeScanReading

    robot = load_robot(path)
    world = load_world(WORLDS_DIR / "DM-USAR_yellow.yaml")
    pose = world.start_pose("PlayerStart1")
    sim = Simulation(world, seed=0)
    sim.spawn(1, robot, "R", pose.location, pose.rotation, set_down=True)
    sim.advance(1.0)
    scans = [o.value for o in sim.take_outputs() if isinstance(o.value, RangeScanReading)]
    assert scans, "no scan in 1 s"
    for s in scans[-len({x.name for x in scans}) :]:
        near = [r for r in s.ranges_m if r < 0.3]
        assert not near, f"{s.name}: {len(near)} of {len(s.ranges_m)} beams stop within 0.3 m"
