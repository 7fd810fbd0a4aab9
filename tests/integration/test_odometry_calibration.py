"""Odometry a controller can trust, and encoders that keep still (issues: robots that behave
like the real ones, item 11; odometry that a controller can trust).

A skid-steered robot's wheels slip sideways as it turns, so the turn its wheel angles count
is more than the turn it made (the P2AT's, about 1.18 times).  Its treads turn about
instantaneous centres of rotation further apart than its wheels, by a factor that holds at
every speed (Mandow et al., IROS 2007, for the Pioneer 3-AT): the Odometry sensor takes that
effective TrackWidth, from the robot file (the P2AT ships 0.552 m), or ``SET {Type
Odometry} {Name Odometry} {Opcode TrackWidth} {Params w}``, and CONF reports the one in
force.  Calibrated, the odometry counts the P2AT's turns within 3 % at every turn rate a
controller uses, in place and on arcs, and brings it round a 1.5 m square within 0.1 m and
0.1 rad."""

from __future__ import annotations

import dataclasses
import math

import pytest

from helpers import drive_skid, segments, sen_type, vec
from usarsim.config.catalog import resolve_robot
from usarsim.readings import EncoderReading, ItemParams, OdometryReading
from usarsim.sim.simulation import Simulation

P2AT_WHEEL_SEPARATION = 0.4712  # the P2AT's wheels, 0.2356 m either side (P2AT.yaml)
P2AT_WHEEL_RADIUS = 0.13  # m (P2AT.yaml)
SHIPPED_TRACK_WIDTH = 0.552  # the Odometry's TrackWidth in P2AT.yaml (m)


class Run:
    """A P2AT at the yellow arena's first start pose, its odometry's and the ground truth's
    headings summed up as it goes (radians, unwrapped, positive clockwise)."""

    def __init__(self, world, robot=None, track: float | None = None):
        self.sim = Simulation(world, seed=1)
        pose = world.start_pose("PlayerStart1")
        self.sim.spawn(1, robot or resolve_robot("P2AT"), "R", pose.location, pose.rotation, set_down=True)
        self.sim.advance(1.0)
        if track is not None:
            res = self.sim.operate(
                1, "Odometry", "Odometry", "TrackWidth", ItemParams(values=(track,), text=f"{track}")
            )
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
    """A user's calibration: one turn in place with the wheels' own separation, the
    odometry's turn against the truth's."""
    run = Run(world, track=P2AT_WHEEL_SEPARATION)
    run.turn(2 * math.pi)
    return P2AT_WHEEL_SEPARATION * run.odometry / run.truth


def square(run: Run) -> Run:
    for _ in range(4):
        run.straight(3.0)
        run.turn(math.pi / 2, rate=0.4)
    return run


def test_uncalibrated_skid_steer_odometry_overcounts_turns(yellow_world):
    run = square(Run(yellow_world, track=P2AT_WHEEL_SEPARATION))
    assert run.truth == pytest.approx(-2 * math.pi, abs=0.1)
    assert run.odometry / run.truth > 1.1  # the wheels slipped sideways in every turn


def test_calibrated_odometry_follows_the_heading_around_a_square(yellow_world):
    track = calibrated_track_width(yellow_world)
    assert track > 1.1 * P2AT_WHEEL_SEPARATION
    assert track == pytest.approx(SHIPPED_TRACK_WIDTH, rel=0.02)  # the robot file's calibration
    run = square(Run(yellow_world, track=track))
    assert run.odometry == pytest.approx(run.truth, rel=0.03)


def test_the_track_width_can_be_written_in_the_robot_file(yellow_world):
    p2at = resolve_robot("P2AT")
    items = tuple(
        dataclasses.replace(i, params={**i.params, "TrackWidth": 0.56}) if i.item_type == "Odometry" else i
        for i in p2at.items
    )
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
    assert res == [
        "RES {Time 0.40} {Type Odometry} {Name Odometry} {Status OK}",
        "RES {Time 0.40} {Type Odometry} {Name Odometry} {Status Failed}",
    ]


# Over the wire ----------------------------------------------------------------------------
class Wire:
    """A P2AT on a lock-step server driven as a controller drives it, over TCP: wheel speeds
    from a forward speed and a turn rate with the TrackWidth its odometry's CONF reports (the
    robot's effective track), and the poses of its SEN Odometry and GroundTruth lines, the
    headings summed up as they go (radians, unwrapped, positive clockwise as USARSim's)."""

    def __init__(self, srv):
        self.c = srv.connect()
        self.c.nfo()
        self.c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}")
        self.odo: tuple[float, float, float] | None = None
        self.truth_xy: tuple[float, float] | None = None
        self.odo_theta = self.truth_yaw = 0.0
        self._odo_raw = self._yaw_raw = None
        self.step(1.0)  # set down on the floor
        conf = segments(self.c.ask("GETCONF {Type Odometry}", "CONF").text)
        # a server that reports no TrackWidth works the heading out with the wheels' separation
        self.track = float(conf.get("TrackWidth", P2AT_WHEEL_SEPARATION))
        self.origin_xy, self.origin_yaw = self.truth_xy, self._yaw_raw

    def step(self, seconds: float) -> None:
        for ln in self.c.step(seconds):
            kind = sen_type(ln)
            if kind == "Odometry":
                x, y, theta = vec(segments(ln.text)["Pose"])
                if self._odo_raw is not None:
                    self.odo_theta += math.remainder(theta - self._odo_raw, 2 * math.pi)
                self._odo_raw, self.odo = theta, (x, y, theta)
            elif kind == "GroundTruth":
                seg = segments(ln.text)
                yaw = vec(seg["Orientation"])[2]
                if self._yaw_raw is not None:
                    self.truth_yaw += math.remainder(yaw - self._yaw_raw, 2 * math.pi)
                self._yaw_raw, self.truth_xy = yaw, vec(seg["Location"])[:2]

    def drive(self, v: float, w: float) -> None:
        """``v`` m/s forward, ``w`` rad/s of turn (clockwise, to the right, positive)."""
        left = (v + w * self.track / 2.0) / P2AT_WHEEL_RADIUS
        right = (v - w * self.track / 2.0) / P2AT_WHEEL_RADIUS
        self.c.send(f"DRIVE {{Left {left:.4f}}} {{Right {right:.4f}}}")

    def stop(self) -> None:
        self.drive(0.0, 0.0)
        self.step(0.6)

    def truth_pose(self) -> tuple[float, float, float]:
        """The true pose in the start pose's frame (x forward, y right, as Odometry's)."""
        dx, dy = self.truth_xy[0] - self.origin_xy[0], self.truth_xy[1] - self.origin_xy[1]
        c, s = math.cos(self.origin_yaw), math.sin(self.origin_yaw)
        return dx * c + dy * s, -dx * s + dy * c, self.truth_yaw


@pytest.mark.parametrize(
    ("rate", "speed"),
    [(0.3, 0.0), (-0.8, 0.0), (1.5, 0.0), (-0.3, 0.3), (1.0, 0.2), (-1.5, 0.2)],
    ids=["0.3-in-place", "0.8-left-in-place", "1.5-in-place", "0.3-left-arc", "1.0-arc", "1.5-left-arc"],
)
def test_the_shipped_calibration_counts_turns_at_every_rate(server_factory, rate, speed):
    """A quarter turn at the rate asked for (rad/s; negative: to the left), in place or on an
    arc at ``speed`` m/s, from rest to rest: the odometry's turn is the true turn within 3 %
    (with the wheels' own separation it is about 1.17 times the true turn)."""
    run = Wire(server_factory(seed=2))
    odo0, truth0 = run.odo_theta, run.truth_yaw
    run.drive(speed, rate)
    run.step(round(math.pi / 2 / abs(rate), 1))
    run.stop()
    turned = run.truth_yaw - truth0
    assert abs(turned) > 1.0 and math.copysign(1.0, turned) == math.copysign(1.0, rate)
    assert (run.odo_theta - odo0) / turned == pytest.approx(1.0, abs=0.03)


def test_conf_reports_the_track_width_in_force(server_factory):
    c = Wire(server_factory(seed=3)).c
    conf = "CONF {Type Odometry} {Name Odometry} {ScanInterval 0.2000} {EncoderResolution 0.0099} {TrackWidth %s}"
    assert c.ask("GETCONF {Type Odometry}", "CONF").text == conf % "0.5520"  # the robot file's
    widths = []
    for sent in ("0.56", "-1", "0"):  # a client's, one refused (kept), back to the file's
        c.send(f"SET {{Type Odometry}} {{Name Odometry}} {{Opcode TrackWidth}} {{Params {sent}}}")
        c.step(0.1)
        widths.append(c.ask("GETCONF {Type Odometry}", "CONF").text)
    assert widths == [conf % "0.5600", conf % "0.5600", conf % "0.5520"]


def test_a_controller_on_odometry_drives_a_square_and_knows_where_it_is(server_factory):
    """A controller that knows only its odometry (as a real one): four times, 1.5 m straight
    ahead at 0.4 m/s holding its heading, then a quarter turn to the right in place at up to
    0.8 rad/s, slowing to 0.3 rad/s near the goal.  Where its odometry says it is then, it
    is, within 0.1 m and 0.1 rad, back at its start (with the wheels' own separation each
    turn falls short by a sixth, and the odometry ends nearly a radian out)."""
    run = Wire(server_factory(seed=4))
    dt = 0.2  # the odometry's ScanInterval: one new reading each step
    for leg in range(4):
        heading = leg * math.pi / 2
        x0, y0, _ = run.odo
        while math.hypot(run.odo[0] - x0, run.odo[1] - y0) < 1.5 - 0.4 * dt / 2:
            run.drive(0.4, max(-0.3, min(0.3, 2.0 * (heading - run.odo_theta))))
            run.step(dt)
        run.stop()
        goal = heading + math.pi / 2
        while goal - run.odo_theta > 0.01:
            run.drive(0.0, max(0.3, min(0.8, 2.0 * (goal - run.odo_theta))))
            run.step(dt)
        run.stop()
    x, y, theta = run.truth_pose()
    ox, oy, _ = run.odo
    assert math.hypot(ox - x, oy - y) <= 0.10
    assert abs(run.odo_theta - theta) <= 0.10
    assert math.hypot(x, y) <= 0.10  # so it came back to where it started


def test_encoders_of_a_robot_at_rest_keep_their_count(yellow_world):
    """After driving (the wheels have turned many ticks) and stopping, 5 s of readings at
    rest all count the same."""
    run = Run(yellow_world)
    run.straight(2.0)
    run.advance(1.0)
    run.sim.take_outputs()
    run.sim.advance(5.0)
    ticks = [
        tuple(i.tick for i in o.value.items) for o in run.sim.take_outputs() if isinstance(o.value, EncoderReading)
    ]
    assert len(ticks) >= 45 and abs(ticks[0][0]) > 100  # 10 Hz; 2 s at 2 rad/s: 229 ticks of 1 degree
    assert set(ticks) == {ticks[0]}
