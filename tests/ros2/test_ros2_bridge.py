"""The ROS 2 bridge seen from a real rclpy node in another process: what it publishes equals what
the simulator sent it (the lines kept by a relay between them), its commands move the robots
the way ROS means them, and its clock is the simulator's."""

from __future__ import annotations

import math
import re

import pytest

pytest.importorskip("rclpy", reason="the ROS 2 extra is not installed (pip install -e '.[ros2]')")

from geometry_msgs.msg import Twist  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402
from sensor_msgs.msg import LaserScan, Range  # noqa: E402
from std_srvs.srv import Trigger  # noqa: E402

PERIOD = 0.1


def stamp(msg) -> float:
    s = msg.header.stamp if hasattr(msg, "header") else msg.clock
    return s.sec + s.nanosec * 1e-9


def sen_time(line: str) -> float:
    return float(re.search(r"\{Time ([-\d.]+)\}", line).group(1))


def yaw(q) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def test_sensors_clock_and_frames(ros_sim, probe):
    """/clock, scan, odom, sonar, /tf_static and /tf of a P2AT, against the SEN lines."""
    from tf2_msgs.msg import TFMessage

    clock = probe.subscribe("/clock", Clock)
    scans = probe.subscribe("/robot1/scan", LaserScan, qos_profile_sensor_data)  # best effort matches too
    odom = probe.subscribe("/robot1/odom", Odometry)
    sonar = probe.subscribe("/robot1/sonar/F4", Range)
    tf = probe.subscribe("/tf", TFMessage)
    bridge, tap = ros_sim("--robot", "P2AT@Skid:robot1", "--rtf", "4")
    probe.wait(lambda: len(scans) >= 5 and len(odom) >= 5 and len(clock) >= 10 and tf, what="5 scans and odometry")
    # a late subscriber of /tf_static still gets it (transient local)
    static = probe.subscribe(
        "/tf_static",
        TFMessage,
        QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL),
    )
    probe.wait(lambda: static, what="/tf_static")

    # /clock: simulated time, a step at a time, never backwards
    times = [stamp(m) for m in probe.messages("/clock")]
    assert all(b > a for a, b in zip(times, times[1:]))
    assert all(abs(t / PERIOD - round(t / PERIOD)) < 1e-6 for t in times)

    # scan: the ranges of the SEN line of the same time, in the same order (the first is the
    # rightmost beam, ROS's angle_min); angles from the line's resolution and field of view
    lines = {sen_time(line): line for line in tap.sen("RangeScanner")}
    checked = 0
    for m in probe.messages("/robot1/scan"):
        line = lines.get(round(stamp(m), 4))
        assert line is not None, f"no SEN RangeScanner at {stamp(m)}"
        ranges = [float(v) for v in re.search(r"\{Range ([^}]*)\}", line).group(1).split(",")]
        assert list(m.ranges) == pytest.approx(ranges, abs=1e-6)
        resolution = float(re.search(r"\{Resolution ([-\d.]+)\}", line).group(1))
        assert m.angle_increment == pytest.approx(resolution, abs=1e-6)
        assert m.angle_min == pytest.approx(-(len(ranges) - 1) * resolution / 2, abs=1e-5)
        assert m.range_max == pytest.approx(20.0) and m.range_min == pytest.approx(0.1)
        assert m.header.frame_id == "robot1/Scanner1"
        checked += 1
    assert checked >= 5
    # no scan is stamped ahead of the simulated clock: the /clock of its step comes (the two
    # topics reach the subscriber on readers of their own, in either order, and the lists
    # above were read while more came in)
    newest = stamp(probe.messages("/robot1/scan")[-1])
    probe.wait(
        lambda: max(stamp(m) for m in probe.messages("/clock")) >= newest - 1e-9,
        timeout=1.0,  # the next step's /clock, within a fraction of a second at 4 times real time
        what=f"/clock at the newest scan's time {newest}",
    )
    # straight ahead is the wall, 11 m away less the scanner's mount (0.144 m ahead of the centre)
    last = probe.messages("/robot1/scan")[-1]
    assert last.ranges[len(last.ranges) // 2] == pytest.approx(11.0 - 0.144, abs=0.05)

    # odom: the Odometry SEN of the same time, in ROS axes (y left, yaw counter-clockwise)
    lines = {sen_time(line): line for line in tap.sen("Odometry")}
    for m in probe.messages("/robot1/odom"):
        x, y, theta = (float(v) for v in re.search(r"\{Pose ([^}]*)\}", lines[round(stamp(m), 4)]).group(1).split(","))
        p = m.pose.pose.position
        assert (p.x, p.y) == pytest.approx((x, -y), abs=1e-6)
        assert yaw(m.pose.pose.orientation) == pytest.approx(-theta, abs=1e-6)
        assert (m.header.frame_id, m.child_frame_id) == ("robot1/odom", "robot1/base_link")

    # sonar F4 (10 degrees right of ahead): its SEN range
    line = {sen_time(x): x for x in tap.sen("Sonar")}[round(stamp(sonar[-1]), 4)]
    assert sonar[-1].range == pytest.approx(float(re.search(r"\{Name F4 Range ([-\d.]+)\}", line).group(1)), abs=1e-6)
    assert sonar[-1].radiation_type == Range.ULTRASOUND

    # /tf_static: base_link to every sensor GETGEO names, at its mount in ROS axes
    frames = {t.child_frame_id: t for t in static[-1].transforms}
    for name in [
        "Scanner1",
        "Odometry",
        "INS",
        "GroundTruth",
        "Camera",
        "VictSensor",
        "Touch",
        "RFID",
        *(f"F{i}" for i in range(1, 9)),
        *(f"R{i}" for i in range(1, 9)),
    ]:
        assert f"robot1/{name}" in frames, f"/tf_static lacks robot1/{name}"
        assert frames[f"robot1/{name}"].header.frame_id == "robot1/base_link"
    sc = frames["robot1/Scanner1"].transform.translation
    assert (sc.x, sc.y, sc.z) == pytest.approx((0.144, 0.0, 0.092), abs=1e-6)  # GETGEO 0.144,0,-0.092 (Z down)
    f1 = frames["robot1/F1"].transform  # GETGEO F1: 0.145,-0.13,0 yaw -90 deg (facing right in USARSim)
    assert (f1.translation.x, f1.translation.y) == pytest.approx((0.145, 0.13), abs=1e-6)
    assert yaw(f1.rotation) == pytest.approx(math.pi / 2, abs=1e-3)

    # /tf: odom -> base_link, as tf2_msgs/msg/TFMessage
    pairs = {(t.header.frame_id, t.child_frame_id) for m in tf for t in m.transforms}
    assert ("robot1/odom", "robot1/base_link") in pairs


def ground_truth_speed(gt: list, since: float, until: float) -> tuple[float, float]:
    """Mean speed (m/s) and yaw rate (rad/s, counter-clockwise) by ground truth between two
    simulated times."""
    w = [m for m in gt if since <= stamp(m) <= until]
    assert len(w) >= 5, f"{len(w)} ground-truth samples between {since} and {until}"
    a, b = w[0], w[-1]
    dt = stamp(b) - stamp(a)
    d = math.dist((a.pose.pose.position.x, a.pose.pose.position.y), (b.pose.pose.position.x, b.pose.pose.position.y))
    turn = math.remainder(yaw(b.pose.pose.orientation) - yaw(a.pose.pose.orientation), math.tau)
    return d / dt, turn / dt


def drive(
    probe,
    topic: str,
    gt: list,
    vx: float = 0.0,
    wz: float = 0.0,
    vz: float = 0.0,
    settle: float = 1.5,
    measure: float = 3.0,
) -> tuple[float, float]:
    """Publish one Twist; the ground-truth speed and turn rate over ``measure`` simulated seconds
    after ``settle``."""
    pub = probe.publisher(topic, Twist)
    t0 = stamp(gt[-1])
    msg = Twist()
    msg.linear.x, msg.linear.z, msg.angular.z = vx, vz, wz
    pub.publish(msg)
    probe.wait(lambda: stamp(gt[-1]) >= t0 + settle + measure + 0.2, timeout=60, what="the drive to finish")
    return ground_truth_speed(gt, t0 + settle, t0 + settle + measure)


def test_cmd_vel_moves_a_p2at(ros_sim, probe):
    from tf2_msgs.msg import TFMessage

    gt = probe.subscribe("/robot1/ground_truth", Odometry)
    probe.subscribe("/tf", TFMessage)
    ros_sim("--robot", "P2AT@Skid:robot1", "--rtf", "5", "--map-tf")
    probe.wait(lambda: len(gt) >= 3, what="ground truth")
    speed, turn = drive(probe, "/robot1/cmd_vel", gt, vx=0.3)
    assert speed == pytest.approx(0.3, rel=0.05)
    assert abs(turn) < 0.05
    _, turn = drive(probe, "/robot1/cmd_vel", gt, wz=0.5)
    assert turn > 0.25, f"told to turn left at 0.5 rad/s, it turned at {turn:.3f} rad/s"

    # --map-tf: map -> odom -> base_link, composed, is where ground truth puts the robot
    by_pair: dict[tuple[str, str], dict[float, object]] = {}
    for m in probe.messages("/tf"):
        for t in m.transforms:
            by_pair.setdefault((t.header.frame_id, t.child_frame_id), {})[round(stamp(t), 4)] = t.transform
    map_odom, odom_base = by_pair[("map", "robot1/odom")], by_pair[("robot1/odom", "robot1/base_link")]
    truth = {round(stamp(m), 4): m.pose.pose for m in gt}
    t = max(set(map_odom) & set(odom_base) & set(truth))
    a, b = map_odom[t], odom_base[t]
    ya, yb = yaw(a.rotation), yaw(b.rotation)
    x = a.translation.x + math.cos(ya) * b.translation.x - math.sin(ya) * b.translation.y
    y = a.translation.y + math.sin(ya) * b.translation.x + math.cos(ya) * b.translation.y
    assert (x, y) == pytest.approx((truth[t].position.x, truth[t].position.y), abs=1e-3)
    assert math.remainder(ya + yb - yaw(truth[t].orientation), math.tau) == pytest.approx(0.0, abs=1e-3)


def test_cmd_vel_moves_a_sedan_and_an_airrobot(ros_sim, probe):
    car = probe.subscribe("/car/ground_truth", Odometry)
    air = probe.subscribe("/drone/ground_truth", Odometry)
    ros_sim("--robot", "Sedan@Car:car", "--robot", "AirRobot@Air:drone", "--rtf", "5")
    probe.wait(lambda: len(car) >= 3 and len(air) >= 3, what="ground truth")
    speed, turn = drive(probe, "/car/cmd_vel", car, vx=2.0, wz=0.2, settle=3.0)
    assert speed == pytest.approx(2.0, rel=0.1)
    assert turn == pytest.approx(0.2, rel=0.25), "the car turns left at about v / R"
    z0 = air[-1].pose.pose.position.z
    speed, turn = drive(probe, "/drone/cmd_vel", air, vz=0.5, wz=-0.3, settle=1.0, measure=2.0)
    assert air[-1].pose.pose.position.z > z0 + 0.5, "told to climb, the AirRobot climbs (ROS z up)"
    assert turn < -0.15, f"told to turn right at 0.3 rad/s, it turned at {turn:.3f} rad/s"


def test_pause_stops_the_clock_and_step_advances_it(ros_sim, probe):
    clock = probe.subscribe("/clock", Clock)
    ros_sim("--robot", "P2AT@Skid:robot1", "--rtf", "4")
    probe.wait(lambda: len(clock) >= 3, what="/clock")
    assert probe.call("/usarsim/pause", Trigger).success
    probe.wait(lambda: True)
    import time

    time.sleep(0.3)
    before = stamp(probe.messages("/clock")[-1])
    time.sleep(0.5)
    assert stamp(probe.messages("/clock")[-1]) == before, "paused, the clock stands"
    reply = probe.call("/usarsim/step", Trigger)
    assert reply.success, reply.message
    probe.wait(lambda: stamp(probe.messages("/clock")[-1]) > before, what="the step's /clock")
    time.sleep(0.3)
    assert stamp(probe.messages("/clock")[-1]) == pytest.approx(before + PERIOD, abs=1e-9)
    assert probe.call("/usarsim/resume", Trigger).success
    probe.wait(lambda: stamp(probe.messages("/clock")[-1]) > before + 5 * PERIOD, what="the clock to run again")


def test_cmd_vel_moves_a_holonomic_lisa_sideways(ros_sim, probe):
    """Lisa's two steered wheels: forward, then to the left (ROS +y) without turning."""
    gt = probe.subscribe("/lisa/ground_truth", Odometry)
    ros_sim("--robot", "Lisa@Spare:lisa", "--rtf", "5")
    probe.wait(lambda: len(gt) >= 3, what="ground truth")
    p0 = gt[-1].pose.pose.position
    x0, y0 = p0.x, p0.y
    speed, turn = drive(probe, "/lisa/cmd_vel", gt, vx=0.3, settle=1.5, measure=2.0)
    assert speed == pytest.approx(0.3, rel=0.15) and abs(turn) < 0.1
    p1 = gt[-1].pose.pose.position
    assert p1.x - x0 > 0.5 and abs(p1.y - y0) < 0.15, "forward is ROS +x"
    pub = probe.publisher("/lisa/cmd_vel", Twist)
    side = Twist()
    side.linear.y = 0.2
    pub.publish(side)
    t0 = stamp(gt[-1])
    probe.wait(lambda: stamp(gt[-1]) >= t0 + 4.0, timeout=60, what="the sideways drive")
    p2 = gt[-1].pose.pose.position
    assert p2.y - p1.y > 0.3, f"told to move left (ROS +y) it moved {p2.y - p1.y:+.2f} m in y"
    assert abs(yaw(gt[-1].pose.pose.orientation)) < 0.2
