"""Odometry a user can calibrate, and encoders that keep still (issue: robots that behave
like the real ones, item 11).

A skid-steered robot's wheels slip sideways as it turns, so the turn its wheel angles count
is more than the turn it made (the P2AT's, about a fifth more).  The Pioneer's controller
is calibrated for that (its RevCount); the Odometry sensor takes an effective TrackWidth,
from the robot file or ``SET {Type Odometry} {Name Odometry} {Opcode TrackWidth} {Params
w}``: calibrated on one turn in place, it follows the robot's heading around a square."""

from __future__ import annotations

import dataclasses
import math

import pytest

from helpers import drive_skid
from usarsim.config.catalog import resolve_robot
from usarsim.readings import EncoderReading, ItemParams, OdometryReading
from usarsim.sim.simulation import Simulation

P2AT_WHEEL_SEPARATION = 0.4712  # the P2AT's wheels, 0.2356 m either side (P2AT.yaml)


class Run:
    """A P2AT at the yellow arena's first start pose, its odometry's and the ground truth's
    headings summed up as it goes (radians, unwrapped, positive clockwise)."""

    def __init__(self, world, robot=None, track: float | None = None):
        self.sim = Simulation(world, seed=1)
        pose = world.start_pose("PlayerStart1")
        self.sim.spawn(1, robot or resolve_robot("P2AT"), "R", pose.location, pose.rotation, set_down=True)
        self.sim.advance(1.0)
        if track is not None:
            res = self.sim.operate(1, "Odometry", "Odometry", "TrackWidth", ItemParams(values=(track,), text=f"{track}"))
            assert res.ok
        self.sim.take_outputs()
        self.odometry = self.truth = 0.0
        self._odo = 0.0
        self._yaw = self.yaw()

    def yaw(self) -> float:
        return self.sim.pose_of(1)[1][2]

    def advance(self, seconds: float) -> None:
        self.sim.advance(seconds)
        for o in self.sim.take_outputs():
            if isinstance(o.value, OdometryReading):
                self.odometry += math.remainder(o.value.theta_rad - self._odo, 2 * math.pi)
                self._odo = o.value.theta_rad
        yaw = self.yaw()
        self.truth += math.remainder(yaw - self._yaw, 2 * math.pi)
        self._yaw = yaw

    def turn(self, angle: float, rate: float = 0.5) -> None:
        """Turn in place by ``angle`` (rad, positive left) as the ROS bridge does, until the
        ground truth has turned that far; then stop and let the odometry catch up."""
        rim = rate * P2AT_WHEEL_SEPARATION / 2.0 / 0.13
        sign = 1.0 if angle > 0 else -1.0
        drive_skid(self.sim, 1, -sign * rim, sign * rim)
        goal = self.truth - angle  # a left turn makes the Z-down yaw fall
        while sign * (self.truth - goal) > 0:
            self.advance(0.02)
        self.stop()

    def straight(self, seconds: float, speed: float = 2.0) -> None:
        drive_skid(self.sim, 1, speed, speed)
        self.advance(seconds)
        self.stop()

    def stop(self) -> None:
        drive_skid(self.sim, 1, 0.0, 0.0)
        self.advance(0.6)


def calibrated_track_width(world) -> float:
    """A user's calibration: one turn in place, the odometry's turn against the truth's."""
    run = Run(world)
    run.turn(2 * math.pi)
    return P2AT_WHEEL_SEPARATION * run.odometry / run.truth


def square(run: Run) -> Run:
    for _ in range(4):
        run.straight(3.0)
        run.turn(math.pi / 2, rate=0.4)
    return run


def test_uncalibrated_skid_steer_odometry_overcounts_turns(yellow_world):
    run = square(Run(yellow_world))
    assert run.truth == pytest.approx(-2 * math.pi, abs=0.1)
    assert run.odometry / run.truth > 1.1  # the wheels slipped sideways in every turn


def test_calibrated_odometry_follows_the_heading_around_a_square(yellow_world):
    track = calibrated_track_width(yellow_world)
    assert track > 1.1 * P2AT_WHEEL_SEPARATION
    run = square(Run(yellow_world, track=track))
    assert run.odometry == pytest.approx(run.truth, rel=0.1)


def test_the_track_width_can_be_written_in_the_robot_file(yellow_world):
    p2at = resolve_robot("P2AT")
    items = tuple(dataclasses.replace(i, params={**i.params, "TrackWidth": 0.56}) if i.item_type == "Odometry" else i
                  for i in p2at.items)
    from_file = Run(yellow_world, robot=dataclasses.replace(p2at, items=items))
    from_set = Run(yellow_world, track=0.56)
    for run in (from_file, from_set):
        run.turn(math.pi)
    assert from_file.odometry == pytest.approx(from_set.odometry, rel=1e-6)
    assert from_file.odometry == pytest.approx(from_file.truth, rel=0.1)


def test_set_track_width_over_the_wire(server_factory):
    srv = server_factory(seed=3)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}")
    c.step(0.4)
    c.send("SET {Type Odometry} {Name Odometry} {Opcode TrackWidth} {Params 0.56}")
    c.send("SET {Type Odometry} {Name Odometry} {Opcode TrackWidth} {Params -1}")
    res = [ln.text for ln in c.step(0.1) if ln.text.startswith("RES ")]
    assert res == ["RES {Time 0.40} {Type Odometry} {Name Odometry} {Status OK}",
                   "RES {Time 0.40} {Type Odometry} {Name Odometry} {Status Failed}"]


def test_encoders_of_a_robot_at_rest_keep_their_count(yellow_world):
    """After driving (the wheels have turned many ticks) and stopping, 5 s of readings at
    rest all count the same."""
    run = Run(yellow_world)
    run.straight(2.0)
    run.advance(1.0)
    run.sim.take_outputs()
    run.sim.advance(5.0)
    ticks = [tuple(i.tick for i in o.value.items) for o in run.sim.take_outputs()
             if isinstance(o.value, EncoderReading)]
    assert len(ticks) >= 45 and abs(ticks[0][0]) > 100  # 10 Hz; 2 s at 2 rad/s: 229 ticks of 1 degree
    assert set(ticks) == {ticks[0]}
