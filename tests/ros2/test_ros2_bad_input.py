"""Bad input to the ROS 2 bridge: a one-line log or error each, never a traceback, and no other
robot affected."""

from __future__ import annotations

import math
import socket
import subprocess
import sys

import pytest

pytest.importorskip("rclpy", reason="the ROS 2 extra is not installed (pip install -e '.[ros2]')")

from geometry_msgs.msg import Twist  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from ros2_parts import Bridge  # noqa: E402


def one_line_error(stderr: str) -> str:
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert "Traceback" not in stderr, stderr
    assert len(lines) == 1, stderr
    return lines[0]


def test_no_simulator_is_one_line(domain):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # nothing listens there
    out = subprocess.run(
        [sys.executable, "-m", "usarsim", "ros2", "--port", str(port), "--domain", str(domain), "--robot", "P2AT"],
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    assert out.returncode == 1
    assert "cannot connect to the simulator at 127.0.0.1" in one_line_error(out.stderr)


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--robot", "P2AT", "--domain", "233"], "ROS domain 233 is out of range"),
        ([], "no robot to bridge"),
        (["--robot", "P2AT:a", "--robot", "P3AT:a"], "two robots named a"),
    ],
)
def test_bad_command_lines_are_one_line(args, says):
    out = subprocess.run(
        [sys.executable, "-m", "usarsim", "ros2", *args],
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    assert out.returncode == 1
    assert says in one_line_error(out.stderr)


def test_bad_twists_unknown_classes_and_a_second_bridge(ros_sim, probe, domain):
    gt = probe.subscribe("/robot1/ground_truth", Odometry)
    other = probe.subscribe("/robot2/ground_truth", Odometry)
    bridge, tap = ros_sim(
        "--robot", "P2AT@Skid:robot1", "--robot", "NoSuchBot@Spare:ghost", "--robot", "P2AT@Spare:robot2", "--rtf", "5"
    )
    probe.wait(lambda: len(gt) >= 3 and len(other) >= 3, what="both robots' ground truth")
    pub = probe.publisher("/robot1/cmd_vel", Twist)
    for bad in (math.nan, math.inf):
        m = Twist()
        m.linear.x = bad
        pub.publish(m)
    m = Twist()
    m.linear.x = 1e9  # absurd: limited to the P2AT's MaxSpeed
    pub.publish(m)
    n = len(other)
    probe.wait(lambda: len(other) >= n + 20, what="robot2 to go on")
    x0 = gt[-1].pose.pose.position.x
    probe.wait(lambda: gt[-1].pose.pose.position.x > x0 + 0.5, what="robot1 to drive at its top speed")

    # a second bridge on the same domain: refused in one line, the first goes on
    second = Bridge(tap.port, domain, "--lockstep", "--robot", "P2AT@Spare:robot3")
    ready, rc = second.ready, second.stop()  # stopped whatever happened
    assert not ready and rc == 1, second.stderr[-2000:]
    assert "publishes /clock on ROS_DOMAIN_ID" in one_line_error(second.stderr)
    n = len(other)
    probe.wait(lambda: len(other) >= n + 10, what="robot2 to go on after the second bridge")

    assert bridge.stop() == 0
    log = bridge.stderr
    assert "Traceback" not in log
    assert log.count("robot ghost not bridged: the server refused INIT: unknown robot class") == 1
    assert "ignored a cmd_vel with a value that is not a finite number (nan" in log
    assert "ignored a cmd_vel with a value that is not a finite number (inf" in log
    assert "limited to its MaxSpeed" in log


def test_the_simulator_going_away_is_one_line(ros_world, domain, tf2_ready):
    from usarsim.client.launch import launch

    server = launch(str(ros_world), lockstep=False, speed=1.0)
    try:
        bridge = Bridge(server.port, domain, "--robot", "P2AT@Skid:robot1")
        assert bridge.ready, bridge.ready_line
    finally:
        server.close()
    bridge.proc.wait(30)
    assert bridge.stop() == 1
    assert f"the simulator at 127.0.0.1:{server.port}" in one_line_error(bridge.stderr)
