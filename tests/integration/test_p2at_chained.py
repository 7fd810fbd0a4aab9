"""The wheels of a side of a P2AT turn together (issue: robots that behave like the real ones,
item 10): the Pioneer drives each side's wheels through one chain, so a P2AT pushing into a
wall stalls, its front and rear wheels alike, instead of spinning its front wheels up the
wall; its odometry then counts the distance it really drove; and its Touch sensor (item
12), at the front, feels the wall.

Test world (helpers.TEST_WORLD): the FacingWall pose puts the P2AT 2 m before a wall (face
at x = 5.0); its wheels (0.13 m) reach 0.274 m ahead of its origin."""

from __future__ import annotations

import dataclasses
import math

import pytest

from helpers import WALL_FACE_X, drive_skid
from usarsim.config.catalog import resolve_robot
from usarsim.readings import OdometryReading, TouchReading
from usarsim.sim.simulation import Simulation

SIDES = {"left": ("LeftFWheel", "LeftRWheel"), "right": ("RightFWheel", "RightRWheel")}


def push_into_the_wall(world, robot, seconds: float = 12.0):
    """Drive at 3 rad/s (0.39 m/s) for ``seconds``: about 4.5 s to the wall, then pushing.
    Returns (the path the chassis drove, m; the odometry's distance, m; the steepest pitch,
    rad; every sample of (front, rear) wheel speeds of each side, rad/s; the Touch readings
    as (time, touching))."""
    sim = Simulation(world, seed=1)
    pose = world.start_pose("FacingWall")
    sim.spawn(1, robot, "R", pose.location, pose.rotation)
    sim.advance(1.0)
    sim.take_outputs()
    r = sim.robots[1]
    (x, y, _), _ = sim.pose_of(1)
    path, steepest, speeds = 0.0, 0.0, []
    drive_skid(sim, 1, 3.0, 3.0)
    for _ in range(int(round(seconds / 0.1))):
        sim.advance(0.1)
        (x1, y1, _), (_, pitch, _) = sim.pose_of(1)
        path += math.hypot(x1 - x, y1 - y)
        x, y = x1, y1
        steepest = max(steepest, abs(math.remainder(pitch, 2 * math.pi)))
        qv = sim.data.qvel
        speeds.append(
            {side: tuple(float(qv[r.handle.joint_qvel[w]]) for w in wheels) for side, wheels in SIDES.items()}
        )
    assert x > WALL_FACE_X - 0.3  # it reached the wall
    outs = sim.take_outputs()
    odo = [o.value for o in outs if isinstance(o.value, OdometryReading)][-1]
    touch = [(o.time, o.value.items[0].touching) for o in outs if isinstance(o.value, TouchReading)]
    return path, math.hypot(odo.x_m, odo.y_m), steepest, speeds, touch


def test_a_p2at_pushing_into_a_wall_stalls_with_its_wheels_together(test_world):
    path, odometry, steepest, speeds, _ = push_into_the_wall(test_world, resolve_robot("P2AT"))
    for sample in speeds:
        for front, rear in sample.values():
            assert abs(front - rear) <= 0.05 * max(abs(front), abs(rear)) + 0.02, sample
    assert speeds[20]["left"][0] == pytest.approx(3.0, rel=0.05)  # driving at 2 s
    assert all(abs(v) < 0.1 for side in speeds[-1].values() for v in side)  # stalled at the wall
    assert steepest < math.radians(3.0)  # it does not climb the wall
    assert path == pytest.approx(WALL_FACE_X - 3.0 - 0.274, abs=0.05)
    assert odometry == pytest.approx(path, rel=0.2)


def test_unchained_front_wheels_would_spin_up_the_wall(test_world):
    """The option matters: with its sides unchained (robot file: chained: false) the front
    wheels spin against the wall while the rear ones stall, the nose rides up the wall and
    the odometry (on the front wheels) counts far more than the robot drove."""
    robot = dataclasses.replace(resolve_robot("P2AT"), chained=False)
    path, odometry, steepest, speeds, _ = push_into_the_wall(test_world, robot)
    front, rear = speeds[-1]["left"]
    assert front > 2.0 and abs(rear) < 0.5
    assert steepest > math.radians(5.0)
    assert odometry > 1.5 * path


def test_the_p2at_touch_sensor_feels_the_wall_it_drives_into(test_world):
    """Touch (protocol.md 7.2), 10 Hz: False on the way (it reaches the wall about 4.5 s after
    the start, at t = 5.5 s), True while the P2AT pushes against it."""
    _, _, _, _, touch = push_into_the_wall(test_world, resolve_robot("P2AT"))
    assert len(touch) == pytest.approx(120, abs=2)
    assert not any(t for when, t in touch if when < 5.0)
    assert all(t for when, t in touch if when > 6.5)
