"""``usarsim ros2 --bag DIR``: a rosbag2 folder an independent reader (rosbags) reads back, each
message of which rclpy's own message classes deserialise."""

from __future__ import annotations

import importlib

import pytest

pytest.importorskip("rclpy", reason="the ROS 2 extra is not installed (pip install -e '.[ros2]')")

from rclpy.serialization import deserialize_message  # noqa: E402


def message_class(name: str):
    package, _, cls = name.split("/")
    return getattr(importlib.import_module(f"{package}.msg"), cls)


def test_the_bag_reads_back_and_every_message_deserialises(ros_sim, tmp_path):
    import yaml
    from rosbags.rosbag2 import Reader

    bag = tmp_path / "run"
    bridge, _ = ros_sim(
        "--robot",
        "P2AT@Skid:robot1",
        "--robot",
        "AirRobot@Air:drone",
        "--rtf",
        "0",
        "--duration",
        "3",
        "--bag",
        str(bag),
    )
    bridge.proc.wait(60)
    assert bridge.stop() == 0, bridge.stderr
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["storage_identifier"] == "mcap" and meta["version"] == 9
    counts: dict[str, int] = {}
    types: dict[str, str] = {}
    last: dict[str, object] = {}
    with Reader(bag) as reader:
        for conn, timestamp, raw in reader.messages():
            msg = deserialize_message(raw, message_class(conn.msgtype))
            counts[conn.topic] = counts.get(conn.topic, 0) + 1
            types[conn.topic] = conn.msgtype
            last[conn.topic] = msg
            assert 0 <= timestamp <= 3.05e9
    for topic, msgtype in [
        ("/clock", "rosgraph_msgs/msg/Clock"),
        ("/tf", "tf2_msgs/msg/TFMessage"),
        ("/tf_static", "tf2_msgs/msg/TFMessage"),
        ("/robot1/scan", "sensor_msgs/msg/LaserScan"),
        ("/robot1/odom", "nav_msgs/msg/Odometry"),
        ("/robot1/sonar/F1", "sensor_msgs/msg/Range"),
        ("/robot1/imu", "sensor_msgs/msg/Imu"),
        ("/robot1/gps/fix", "sensor_msgs/msg/NavSatFix"),
        ("/robot1/battery", "sensor_msgs/msg/BatteryState"),
        ("/drone/ground_truth", "nav_msgs/msg/Odometry"),
    ]:
        assert types.get(topic) == msgtype, f"{topic}: {types.get(topic)}"
    assert counts["/clock"] == 30  # 3 s of 0.1 s steps
    assert counts["/robot1/scan"] in (15, 16)  # the P2AT's laser: 5 Hz (and one as it stood in the world)
    assert counts["/tf_static"] == 1
    assert last["/clock"].clock.sec == 3
    # the MCAP inside, as ros2 bag play's storage plugin reads it: ros2msg schemas, CDR messages
    from mcap.reader import make_reader

    with open(bag / "run.mcap", "rb") as f:
        summary = make_reader(f).get_summary()
    assert {s.encoding for s in summary.schemas.values()} == {"ros2msg"}
    assert {c.message_encoding for c in summary.channels.values()} == {"cdr"}
    assert {c.topic for c in summary.channels.values()} == set(counts)
