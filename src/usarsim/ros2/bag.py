"""rosbag2 recordings of what the bridge publishes: a folder with ``metadata.yaml`` and an MCAP
file of ``ros2msg`` schemas and CDR messages, as ``ros2 bag record -s mcap`` writes it, so that
``ros2 bag play`` (Jazzy: bag version 9) plays it.

The messages are serialised by rclpy itself (the bytes the bridge sends on the wire); the
``rosbags`` package writes the container, with Jazzy's message definitions for the schemas.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

from usarsim.errors import UsarsimError

log = logging.getLogger("usarsim.ros2")


class BagError(UsarsimError):
    """The recording cannot be written (the folder exists, the disk is full, ...)."""


def type_name(msg: Any) -> str:
    """``sensor_msgs/msg/LaserScan`` of an rclpy message."""
    cls = type(msg)
    return f"{cls.__module__.split('.')[0]}/msg/{cls.__name__}"


class BagWriter:
    """Messages, each on its topic at its simulated time, into a rosbag2 folder."""

    def __init__(self, path: str | Path):
        from rosbags.rosbag2 import StoragePlugin, Writer
        from rosbags.typesys import Stores, get_typestore

        self.path = Path(path)
        if self.path.exists():
            raise BagError(f"{self.path} exists already: rosbag2 writes a new folder (give another name, or remove it)")
        self.typestore = get_typestore(Stores.ROS2_JAZZY)
        self.writer = Writer(self.path, version=9, storage_plugin=StoragePlugin.MCAP)
        self.writer.open()
        self.connections: dict[str, Any] = {}
        self.count = 0
        self._serialize: Any = None

    def write(self, topic: str, msg: Any, stamp: float) -> None:
        if self._serialize is None:
            from rclpy.serialization import serialize_message

            self._serialize = serialize_message
        conn = self.connections.get(topic)
        if conn is None:
            from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

            durability = QosDurability.TRANSIENT_LOCAL if topic == "/tf_static" else QosDurability.VOLATILE
            never = QosTime(sec=0x7FFFFFFF, nsec=0xFFFFFFFF)
            qos = Qos(
                history=QosHistory.KEEP_LAST,
                depth=1 if topic == "/tf_static" else 10,
                reliability=QosReliability.RELIABLE,
                durability=durability,
                deadline=never,
                lifespan=never,
                liveliness=QosLiveliness.AUTOMATIC,
                liveliness_lease_duration=never,
                avoid_ros_namespace_conventions=False,
            )
            conn = self.connections[topic] = self.writer.add_connection(
                topic, type_name(msg), typestore=self.typestore, serialization_format="cdr", offered_qos_profiles=[qos]
            )
        self.writer.write(conn, int(round(max(0.0, stamp) * 1e9)), self._serialize(msg))
        self.count += 1

    def close(self) -> None:
        self.writer.close()
        log.warning(
            "rosbag2 recording %s: %d messages on %d topics (ros2 bag play %s)",
            self.path,
            self.count,
            len(self.connections),
            self.path,
        )
