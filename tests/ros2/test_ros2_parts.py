"""The rest of a robot on ROS 2: its camera (pictures rendered by the image server), its joints
(read and commanded), its bumper and its victim reports."""

from __future__ import annotations

import math
import time

import pytest

pytest.importorskip("rclpy", reason="the ROS 2 extra is not installed (pip install -e '.[ros2]')")

from geometry_msgs.msg import PointStamped  # noqa: E402
from sensor_msgs.msg import CameraInfo, CompressedImage, Image, JointState, PointCloud2  # noqa: E402
from std_msgs.msg import Bool  # noqa: E402


def test_camera_topics_carry_the_rendered_picture(ros_sim, probe):
    from helpers import gl_problem

    if gl_problem():
        pytest.skip(gl_problem())
    raw = probe.subscribe("/robot1/camera/image_raw", Image)
    jpeg = probe.subscribe("/robot1/camera/image_raw/compressed", CompressedImage)
    info = probe.subscribe("/robot1/camera/camera_info", CameraInfo)
    ros_sim("--robot", "P2AT@Skid:robot1", "--rtf", "2", image=True)
    probe.wait(lambda: raw and jpeg and info, timeout=60, what="a picture, its JPEG and the camera's intrinsics")
    img, ci = raw[-1], info[-1]
    assert (img.width, img.height, img.encoding) == (ci.width, ci.height, "rgb8")
    assert len(img.data) == img.width * img.height * 3
    pixels = bytes(img.data)
    assert len(set(pixels[i] for i in range(0, len(pixels), 997))) > 10, "a picture of the world, not one colour"
    assert img.header.frame_id == "robot1/Camera_optical"
    assert bytes(jpeg[-1].data[:2]) == b"\xff\xd8"  # a JPEG
    # a pinhole of the P2AT camera's CONF field of view, 0.8727 rad across
    f = ci.k[0]
    assert f == pytest.approx((ci.width / 2) / math.tan(0.8727 / 2), rel=1e-3)
    assert (ci.k[2], ci.k[5]) == (ci.width / 2, ci.height / 2)


def test_joints_touch_and_victim_reports(ros_sim, probe):
    joints = probe.subscribe("/robot1/joint_states", JointState)
    touch = probe.subscribe("/robot1/touch/Touch", Bool)
    bridge, tap = ros_sim("--robot", "P2AT@Skid:robot1", "--rtf", "5")
    probe.wait(lambda: touch and joints, what="the bumper and the joint states")
    assert touch[-1].data is False  # nothing ahead for metres
    # the camera's pan-tilt, commanded by name to 0.3 rad of pan, reports it back
    cmd = probe.publisher("/robot1/joint_commands", JointState)
    m = JointState()
    m.name, m.position = ["CameraPanTilt_link1", "NoSuchJoint"], [0.3, 1.0]
    cmd.publish(m)

    def pan() -> float | None:
        last = probe.messages("/robot1/joint_states")[-1]
        return dict(zip(last.name, last.position)).get("CameraPanTilt_link1")

    probe.wait(lambda: pan() is not None and abs(pan() - 0.3) < 0.02, timeout=60, what="the pan to reach 0.3 rad")
    report = probe.publisher("/robot1/report_victim", PointStamped)
    p = PointStamped()
    p.header.frame_id = "map"
    p.point.x, p.point.y, p.point.z = 1.0, 2.0, 0.0
    report.publish(p)
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline and not any(line.startswith("RES") and "Victim" in line for line in tap.lines):
        time.sleep(0.05)
    reports = [line for line in tap.lines if line.startswith("RES") and "Victim" in line]
    assert reports, "the report reached the simulator and it answered"
    assert bridge.stop() == 0
    assert "a joint command names no joint of it: 'NoSuchJoint'" in bridge.stderr
    assert "Traceback" not in bridge.stderr


def test_a_3d_scanner_is_a_point_cloud(ros_sim, probe):
    """Kurt3D's RangeScanner3D: its returns as points, the wall 11 m ahead where it is."""
    import numpy as np

    points = probe.subscribe("/robot1/points", PointCloud2)
    ros_sim("--robot", "Kurt3D@Skid:robot1", "--rtf", "5")
    probe.wait(lambda: points, what="a point cloud")
    m = points[-1]
    assert m.header.frame_id == "robot1/" + m.header.frame_id.split("/", 1)[1]
    xyz = np.frombuffer(bytes(m.data), dtype=np.float32).reshape(-1, 3)
    assert len(xyz) == m.width > 0
    ahead = xyz[(np.abs(xyz[:, 1]) < 0.3) & (np.abs(xyz[:, 2]) < 0.3)]
    assert len(ahead) > 0, "beams straight ahead hit the wall"
    assert np.median(ahead[:, 0]) == pytest.approx(11.0, abs=0.4)  # the wall face, 11 m from the start pose


def test_flippers_and_an_arm_follow_joint_commands(ros_sim, probe):
    """TeleMax: a flipper (a joint of its STA, to DRIVE {Name}) and an arm link (its mission
    package, to MISPKG), commanded by name in one JointState, reach their positions."""
    probe.subscribe("/telemax/joint_states", JointState)
    ros_sim("--robot", "TeleMax@Spare:telemax", "--rtf", "5")

    def position(name: str) -> float | None:
        msgs = probe.messages("/telemax/joint_states")
        return dict(zip(msgs[-1].name, msgs[-1].position)).get(name) if msgs else None

    probe.wait(lambda: position("FRFlipper") is not None, what="the flippers in joint_states")
    cmd = probe.publisher("/telemax/joint_commands", JointState)
    m = JointState()
    m.name, m.position = ["FRFlipper", "TeleMaxArm_link2"], [0.5, 0.3]
    cmd.publish(m)
    probe.wait(lambda: abs(position("FRFlipper") - 0.5) < 0.02, timeout=60, what="the flipper at 0.5 rad")
    probe.wait(
        lambda: position("TeleMaxArm_link2") is not None and abs(position("TeleMaxArm_link2") - 0.3) < 0.03,
        timeout=60,
        what="the arm's link 2 at 0.3 rad",
    )
    assert abs(position("FLFlipper")) < 0.05, "the other flippers stay"
