"""USARSim's axes and drives to ROS 2's (usarsim.ros2.convert: plain numbers, no rclpy), and the
bridge's robot specifications."""

from __future__ import annotations

import math

import pytest

from usarsim.protocol import messages as M
from usarsim.ros2.convert import (
    BadTwist,
    Kinematics,
    angles,
    drive_of,
    quaternion,
    ros_pose,
    scan_angles,
    vector,
    yaw_of,
)
from usarsim.ros2.robot import RobotSpec

P2AT_GEO = M.RobotGeometry(
    class_name="P2AT",
    dimensions=(0.5238, 0.4968, 0.2913),
    wheel_radius=0.13,
    wheel_separation=0.4712,
    wheel_base=0.2884,
)
P2AT_CONF = M.RobotConfiguration(
    class_name="P2AT", steering_type="SkidSteered", mass_kg=14.0, max_speed=5.385, max_torque=60.0
)
SEDAN_GEO = M.RobotGeometry(
    class_name="Sedan", dimensions=(4.785, 1.78, 1.415), wheel_radius=0.3143, wheel_separation=1.545, wheel_base=2.67
)
SEDAN_CONF = M.RobotConfiguration(
    class_name="Sedan",
    steering_type="AckermanSteered",
    mass_kg=1445.0,
    max_speed=159.0,
    max_torque=800.0,
    max_front_steer=0.557,
)
AIR_GEO = M.RobotGeometry(vehicle_type="AerialVehicle", class_name="AirRobot", dimensions=(1.0, 1.0, 0.2))
AIR_CONF = M.RobotConfiguration(
    vehicle_type="AerialVehicle",
    class_name="AirRobot",
    steering_type="None",
    mass_kg=1.3,
    max_speed=1.0,
    max_torque=0.0001,
)


def test_axes_turn_half_a_turn_about_x():
    assert vector((1.0, 2.0, 3.0)) == (1.0, -2.0, -3.0)  # right -> left, down -> up
    assert angles((0.1, 0.2, 0.3)) == (0.1, -0.2, -0.3)  # clockwise yaw -> counter-clockwise
    # a robot facing USARSim's +Y (yaw 90 degrees clockwise, to the right) faces ROS's -Y
    (x, y, z), q = ros_pose((1.0, 2.0, -0.5), (0.0, 0.0, math.pi / 2))
    assert (x, y, z) == (1.0, -2.0, 0.5)
    assert yaw_of(q) == pytest.approx(-math.pi / 2)


def test_quaternion_of_a_yaw():
    assert quaternion(0.0, 0.0, math.pi / 2) == pytest.approx((0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5)))
    for yaw in (-3.0, -1.0, 0.0, 0.5, 2.5):
        assert yaw_of(quaternion(0.0, 0.0, yaw)) == pytest.approx(yaw)
    x, y, z, w = quaternion(0.3, -0.2, 1.1)
    assert x * x + y * y + z * z + w * w == pytest.approx(1.0)


def test_a_scan_keeps_its_order_from_the_right():
    assert scan_angles(181, math.radians(1.0)) == pytest.approx((-math.pi / 2, math.pi / 2))
    assert scan_angles(1, 0.1) == (0.0, 0.0)


def test_skid_steering_from_geometry():
    k = Kinematics.of(P2AT_GEO, P2AT_CONF)
    assert k.kind == "skid"
    d = drive_of(k, 0.3, 0.0, 0.0, 0.0)
    assert d["left"] == d["right"] == pytest.approx(0.3 / 0.13)
    d = drive_of(k, 0.0, 0.0, 0.0, 0.5)  # counter-clockwise: the right side forward
    assert d["right"] == pytest.approx(0.5 * 0.4712 / 2 / 0.13) and d["left"] == pytest.approx(-d["right"])
    d = drive_of(k, 100.0, 0.0, 0.0, 0.0)  # beyond MaxSpeed: limited
    assert d["left"] == d["right"] == 5.385
    assert drive_of(k, 100.0, 0.0, 0.0, 0.0, clip=False)["left"] == pytest.approx(100 / 0.13)
    for bad in (math.nan, math.inf, -math.inf):
        with pytest.raises(BadTwist):
            drive_of(k, bad, 0.0, 0.0, 0.0)


def test_ackermann_steering_from_geometry():
    k = Kinematics.of(SEDAN_GEO, SEDAN_CONF)
    assert k.kind == "ackermann"
    d = drive_of(k, 2.0, 0.0, 0.0, 0.2)  # a left turn: USARSim's steer is positive to the right
    assert d["speed"] == pytest.approx(2.0 / 0.3143)
    assert d["front_steer"] == pytest.approx(-math.atan(2.67 * 0.2 / 2.0))
    assert d["rear_steer"] == 0.0
    assert drive_of(k, 0.0, 0.0, 0.0, 0.5)["front_steer"] == 0.0  # no turning on the spot
    assert drive_of(k, 1.0, 0.0, 0.0, 50.0)["front_steer"] == -0.557  # MaxFrontSteer


def test_aerial_velocities_and_robots_without_cmd_vel():
    k = Kinematics.of(AIR_GEO, AIR_CONF)
    assert drive_of(k, 0.5, 0.2, 0.3, 0.4) == {
        "linear_velocity": 0.5,
        "lateral_velocity": -0.2,
        "altitude_velocity": 0.3,
        "rotational_velocity": -0.4,
    }
    static = Kinematics.of(
        M.RobotGeometry(vehicle_type="StaticPlatform", class_name="ComStation", dimensions=(1.0, 1.0, 1.0)),
        M.RobotConfiguration(
            vehicle_type="StaticPlatform",
            class_name="ComStation",
            steering_type="None",
            mass_kg=1.0,
            max_speed=0.0,
            max_torque=0.0,
        ),
    )
    assert static.kind == "none"
    with pytest.raises(ValueError, match="takes no cmd_vel"):
        drive_of(static, 1.0, 0.0, 0.0, 0.0)


@pytest.mark.parametrize(
    ("text", "spec"),
    [
        ("P2AT", RobotSpec("P2AT")),
        ("P2AT:robot1", RobotSpec("P2AT", None, "robot1")),
        ("P2AT@PlayerStart2:r2", RobotSpec("P2AT", "PlayerStart2", "r2")),
        ("Sedan@1,-2.5,-0.3:car", RobotSpec("Sedan", None, "car", (1.0, -2.5, -0.3), 0.0)),
        ("Kenaf@1,2,3,1.57", RobotSpec("Kenaf", None, None, (1.0, 2.0, 3.0), 1.57)),
    ],
)
def test_robot_specifications(text, spec):
    assert RobotSpec.parse(text) == spec


@pytest.mark.parametrize("text", ["@PlayerStart1", "P2AT@1,2", "P2AT@1,2,x"])
def test_bad_robot_specifications(text):
    with pytest.raises(ValueError):
        RobotSpec.parse(text)


def test_holonomic_wheels_turn_along_their_velocity():
    geo = M.RobotGeometry(class_name="Lisa", dimensions=(0.5, 0.5, 0.6), wheel_radius=0.08, wheel_separation=0.38)
    conf = M.RobotConfiguration(
        class_name="Lisa", steering_type="HolonomSteered", mass_kg=20.0, max_speed=20.0, max_torque=8.0
    )
    k = Kinematics.of(geo, conf)
    assert k.kind == "holonomic"
    assert drive_of(k, 0.4, 0.0, 0.0, 0.0)["wheels"] == [(0, pytest.approx(5.0), 0.0), (1, pytest.approx(5.0), 0.0)]
    # to the left (ROS +y): both wheels a quarter turn to the left, negative in USARSim's sense
    for _, speed, steer in drive_of(k, 0.0, 0.16, 0.0, 0.0)["wheels"]:
        assert (speed, steer) == (pytest.approx(2.0), pytest.approx(-math.pi / 2))
    # backwards: straight wheels spun backwards, not turned round
    for _, speed, steer in drive_of(k, -0.4, 0.0, 0.0, 0.0)["wheels"]:
        assert (speed, steer) == (pytest.approx(-5.0), pytest.approx(0.0))
    # in place, counter-clockwise: the left wheel back, the right forward
    (n0, left, _), (n1, right, _) = drive_of(k, 0.0, 0.0, 0.0, 1.0)["wheels"]
    assert (n0, n1) == (0, 1) and left == pytest.approx(-0.19 / 0.08) and right == pytest.approx(0.19 / 0.08)
