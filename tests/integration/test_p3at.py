"""USARBot.P3AT (Pioneer 3-AT), the default robot of NIST's ROS bridge (hrnr/ros-usarsim
usarsimInf.cpp) and one of NIST's Iridium test UI's robots, over the wire as that bridge
uses it: GETSTARTPOSES and an INIT at a start pose, GETCONF / GETGEO of the robot, then
wheel speeds worked out from a linear velocity with the WheelRadius and MaxSpeed it was
given (``Drive {Left v/r} {Right v/r}``, clamped at MaxSpeed)."""

from __future__ import annotations

import math

import pytest

from helpers import ground_truth, segments, vec


def ros_bridge_drive(v: float, wheel_radius: float, max_speed: float) -> str:
    """The bridge's DRIVE for a forward velocity ``v`` (m/s): spin = v / WheelRadius, held to
    MaxSpeed; it writes "Drive" with %f."""
    spin = min(v / wheel_radius, max_speed)
    return f"Drive {{Left {spin:f}}} {{Right {spin:f}}}"


def forward_speed(c, seconds: float) -> tuple[float, float, float]:
    """(speed along the start heading, sideways drift, turn) over ``seconds`` of stepping,
    from the GroundTruth lines."""
    gts = ground_truth(c.step(seconds))
    (t0, p0, o0), (t1, p1, o1) = gts[0], gts[-1]
    along = (p1[0] - p0[0]) * math.cos(o0[2]) + (p1[1] - p0[1]) * math.sin(o0[2])
    across = -(p1[0] - p0[0]) * math.sin(o0[2]) + (p1[1] - p0[1]) * math.cos(o0[2])
    return along / (t1 - t0), across, math.remainder(o1[2] - o0[2], 2 * math.pi)


def test_the_ros_bridge_spawns_a_p3at_at_a_start_pose_reads_its_figures_and_drives_it(server_factory, test_world):
    srv = server_factory(world=test_world, seed=3)
    c = srv.connect()
    c.nfo()
    # the bridge's first two lines (its spelling: "Classname"); the name is ROS<seconds>
    c.send("GETSTARTPOSES")
    c.wait_line("NFO {StartPoses")
    c.send("INIT {Classname USARBot.P3AT} {Name ROS1700000000} {Start Open}")
    lines = c.step(1.0)
    assert any(ln.text.startswith("STA ") for ln in lines), "no robot after INIT"

    # it stands on its four wheels at the start pose: level, the chassis origin half the
    # robot's 0.277 m height above the floor (z = 0, Z down), facing the pose's heading
    _, where, (roll, pitch, yaw) = ground_truth(c.step(0.5))[-1]
    assert abs(roll) < 0.02 and abs(pitch) < 0.02 and abs(math.remainder(yaw, 2 * math.pi)) < 0.02
    assert where[0] == pytest.approx(-6.0, abs=0.02) and where[1] == pytest.approx(0.0, abs=0.02)
    assert where[2] == pytest.approx(-0.1385, abs=0.01)

    conf = segments(c.ask("GETCONF {Type Robot}", "CONF").text)
    assert conf["Type"] == "GroundVehicle" and conf["Name"] == "P3AT" and conf["SteeringType"] == "SkidSteered"
    assert float(conf["Mass"]) == pytest.approx(11.9)  # UDK CONF (protocol.md 6.7)
    assert float(conf["MaxTorque"]) == pytest.approx(50000.0)  # UDK CONF, engine units
    max_speed = float(conf["MaxSpeed"])
    assert max_speed == pytest.approx(0.7 / 0.098, rel=1e-3)  # the data sheet's 0.7 m/s
    assert float(conf["MaxFrontSteer"]) == 0.0 and float(conf["MaxRearSteer"]) == 0.0

    geo = segments(c.ask("GETGEO {Type Robot}", "GEO").text)
    assert geo["Type"] == "GroundVehicle" and geo["Name"] == "P3AT"
    assert vec(geo["Dimensions"]) == pytest.approx((0.508, 0.497, 0.277))
    assert vec(geo["COG"]) == pytest.approx((0.0, 0.0, 0.0))
    wheel_radius = float(geo["WheelRadius"])
    assert wheel_radius == pytest.approx(0.098)  # UDK GEO (protocol.md 6.8)
    assert float(geo["WheelSeparation"]) == pytest.approx(0.36)
    assert float(geo["WheelBase"]) == pytest.approx(0.248)

    # cmd_vel 0.4 m/s: the wheels spin at 0.4 / WheelRadius and the robot does 0.4 m/s
    c.send(ros_bridge_drive(0.4, wheel_radius, max_speed))
    c.step(1.5)  # time to reach the speed
    speed, drift, turn = forward_speed(c, 2.0)
    assert speed == pytest.approx(0.4, rel=0.15)
    assert abs(drift) < 0.05 and abs(turn) < 0.05

    # cmd_vel 1 m/s is more than it can do: held to MaxSpeed, the data sheet's top speed
    c.send(ros_bridge_drive(1.0, wheel_radius, max_speed))
    c.step(1.5)
    speed, drift, turn = forward_speed(c, 2.0)
    assert speed == pytest.approx(max_speed * wheel_radius, rel=0.15)
    assert speed == pytest.approx(0.7, rel=0.15)
    assert abs(drift) < 0.08 and abs(turn) < 0.05

    c.send("Drive {Left 0.000000} {Right 0.000000}")
    c.step(1.5)
    speed, _, _ = forward_speed(c, 1.0)
    assert abs(speed) < 0.02
