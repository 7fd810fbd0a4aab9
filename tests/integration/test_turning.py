"""Skid-steered and tracked robots turn on the spot (issue: robots that behave like the real
ones, item 9).  NIST's ROS bridge turns a robot in place as a differential drive: for a
yaw rate w it sends DRIVE {Left -(w sep / 2) / r} {Right +(w sep / 2) / r} with the
WheelSeparation sep and WheelRadius r its GETGEO {Type Robot} reports.  On the arena floor
every shipped skid-steered robot turns within 30 % of that rate, about the centre of its
wheels (tracks) on the ground."""

from __future__ import annotations

import math

import pytest

from helpers import drive_skid
from usarsim.config.catalog import ROBOTS_DIR
from usarsim.config.robot import load_robot
from usarsim.robots import drive_class
from usarsim.robots.skid import ground_wheels
from usarsim.sim.simulation import Simulation

SKID_FILES = sorted(p for p in ROBOTS_DIR.glob("*.yaml") if load_robot(p).drive == "skid")
RATE = 0.5  # rad/s asked for, counter-clockwise seen from above (ROS: positive turns left)


def ros_turn_in_place(sim: Simulation, uid: int, robot, rate: float) -> None:
    """The ROS bridge's wheel speeds for a turn in place at ``rate`` (rad/s, positive left),
    from the robot's GEO figures."""
    geo = drive_class(robot).numbers(robot)
    rim = rate * geo.wheel_separation / 2.0 / geo.wheel_radius
    drive_skid(sim, uid, -rim, rim)


def tread_centre(sim: Simulation, uid: int, robot) -> tuple[float, float]:
    """Where the centre of the robot's wheels on the ground is (world X, Y): the point a skid
    turn pivots about (the Rugbot's tracks sit behind its chassis origin)."""
    placed = ground_wheels(robot)
    cx = sum(p[0] for _, p in placed) / len(placed)
    cy = sum(p[1] for _, p in placed) / len(placed)
    (x, y, _), (_, _, yaw) = sim.pose_of(uid)
    return x + cx * math.cos(yaw) - cy * math.sin(yaw), y + cx * math.sin(yaw) + cy * math.cos(yaw)


def turn(world, robot, rate: float, seconds: float = 3.0):
    """(yaw rate, rad/s, positive left; how far the centre of the treads moved, m) over
    ``seconds`` of a turn in place, after a second to settle and a second to spin up."""
    sim = Simulation(world, seed=1)
    start = world.start_pose("PlayerStart1")
    sim.spawn(1, robot, "R", start.location, start.rotation, set_down=True)
    sim.advance(1.0)
    c0 = tread_centre(sim, 1, robot)
    ros_turn_in_place(sim, 1, robot, rate)
    sim.advance(1.0)
    _, (_, _, a0) = sim.pose_of(1)
    sim.advance(seconds)
    _, (roll, pitch, a1) = sim.pose_of(1)
    c1 = tread_centre(sim, 1, robot)
    assert abs(math.remainder(roll, 2 * math.pi)) < 0.2 and abs(math.remainder(pitch, 2 * math.pi)) < 0.2
    # USARSim's yaw grows clockwise seen from above (Z down): a left turn makes it fall
    return -math.remainder(a1 - a0, 2 * math.pi) / seconds, math.dist(c0, c1)


def test_every_skid_steered_robot_is_tested():
    names = {p.stem for p in SKID_FILES}
    assert {
        "P2AT",
        "P3AT",
        "P2DX",
        "ATRVJr",
        "Kurt2D",
        "Kurt3D",
        "Zerg",
        "Tarantula",
        "Kenaf",
        "TeleMax",
        "Talon",
        "Soryu",
        "Rugbot",
    } <= names


@pytest.mark.parametrize("path", SKID_FILES, ids=lambda p: p.stem)
def test_a_ros_bridge_turn_in_place_turns_at_the_asked_rate_about_the_centre(path, yellow_world):
    rate, moved = turn(yellow_world, load_robot(path), RATE)
    assert 0.7 * RATE <= rate <= 1.3 * RATE, f"{path.stem} turns at {rate:.3f} rad/s for {RATE}"
    assert moved < 0.15, f"{path.stem}'s centre moved {moved:.3f} m"


@pytest.mark.parametrize("name", ["P2AT", "TeleMax"])
def test_a_turn_to_the_right_is_as_fast_as_one_to_the_left(name, yellow_world):
    robot = load_robot(ROBOTS_DIR / f"{name}.yaml")
    left, _ = turn(yellow_world, robot, RATE)
    right, _ = turn(yellow_world, robot, -RATE)
    assert right == pytest.approx(-left, rel=0.1)


def test_driving_straight_keeps_the_commanded_speed(yellow_world):
    """The treads' lower sideways friction costs nothing along them: 2 rad/s on 0.13 m wheels
    is 0.26 m/s, straight ahead."""
    sim = Simulation(yellow_world, seed=1)
    start = yellow_world.start_pose("PlayerStart1")
    sim.spawn(1, load_robot(ROBOTS_DIR / "P2AT.yaml"), "R", start.location, start.rotation, set_down=True)
    sim.advance(1.0)
    drive_skid(sim, 1, 2.0, 2.0)
    sim.advance(1.0)
    (x0, y0, _), (_, _, a0) = sim.pose_of(1)
    sim.advance(2.0)
    (x1, y1, _), (_, _, a1) = sim.pose_of(1)
    assert math.hypot(x1 - x0, y1 - y0) / 2.0 == pytest.approx(0.26, rel=0.05)
    assert abs(math.remainder(a1 - a0, 2 * math.pi)) < 0.02
