"""One robot on the ROS 2 graph: what its GETGEO and GETCONF say, its publishers, and the
conversion of each of its messages (readings, status, mission packages) to ROS 2 messages and of
ROS 2 commands (cmd_vel, joint commands, victim reports) to its protocol lines.  The bridge
(:mod:`usarsim.ros2.bridge`) owns the node, the sockets and the clock."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from usarsim.client.blocking import Robot
from usarsim.client.core import ClientError, ServerError, drive_line
from usarsim.protocol import messages as M
from usarsim.readings import (
    GpsReading,
    ImuReading,
    OdometryReading,
    PoseReading,
    RangeReading,
    RangeScan3DReading,
    RangeScanReading,
    RfidReading,
    TachometerReading,
    TouchReading,
    VictimReading,
)

from .convert import BadTwist, Kinematics, drive_of, quaternion, vector
from .publishing import WORLD_FRAME, Conf, SensorTopics, b_time

if TYPE_CHECKING:
    from .bridge import Bridge

log = logging.getLogger("usarsim.ros2")

# GETGEO types asked of every robot for /tf_static (an EmptyGeometry answer: the robot has none)
SENSOR_TYPES = (
    "RangeScanner",
    "RangeScanner3D",
    "Sonar",
    "IR",
    "Odometry",
    "INS",
    "IMU",
    "GroundTruth",
    "GPS",
    "Camera",
    "VictSensor",
    "Touch",
    "RFID",
    "Acoustic",
    "HumanMotion",
)
NODE_NAME = "usarsim_bridge"  # the bridge's node


@dataclass
class RobotSpec:
    """A robot to spawn: ``CLASS@START[:NAME]`` on the command line, START a start pose's name
    or ``x,y,z[,yaw]`` (metres and radians, USARSim's axes)."""

    class_name: str
    start: str | None = None
    name: str | None = None
    location: tuple[float, float, float] | None = None
    yaw: float = 0.0

    @classmethod
    def parse(cls, text: str) -> RobotSpec:
        whole = text
        name = None
        if ":" in text:
            text, name = text.rsplit(":", 1)
        cls_name, _, start = text.partition("@")
        if not cls_name:
            raise ValueError(f"a robot is CLASS[@START][:NAME], e.g. P2AT@PlayerStart1:robot1; got {whole!r}")
        if start and start[0] in "-+.0123456789":
            try:
                values = [float(v) for v in start.split(",")]
            except ValueError:
                values = []
            if len(values) not in (3, 4):
                raise ValueError(f"{whole!r}: a place is x,y,z or x,y,z,yaw (metres, radians)")
            return cls(
                cls_name, None, name or None, (values[0], values[1], values[2]), values[3] if len(values) == 4 else 0.0
            )
        return cls(cls_name, start or None, name or None)


class RobotBridge(SensorTopics):
    """One robot: its publishers, its subscriptions and what it last reported."""

    def __init__(self, bridge: Bridge, robot: Robot, frame_prefix: str):
        self.bridge = bridge
        self.robot = robot
        self.name = robot.name
        self.ns = f"/{robot.name}"
        self.prefix = frame_prefix
        self.geo = robot.geo("Robot")
        self.conf = robot.conf("Robot")
        self.kinematics = Kinematics.of(self.geo, self.conf)
        self.mounts: dict[str, M.ItemPose] = {}  # sensor name -> its GETGEO mount
        self.confs: dict[str, Conf] = {}  # sensor name -> its CONF fields
        self.types: dict[str, str] = {}  # sensor name -> its type
        for item_type in SENSOR_TYPES:
            try:
                geo = robot.geo(item_type)
                conf = robot.conf(item_type)
            except ServerError:
                continue
            for item in getattr(geo, "items", ()):
                self.mounts[item.name] = item
                self.types[item.name] = item_type
            for item in getattr(conf, "items", ()):
                self.confs[item.name] = Conf({k: str(v) for k, v in item.fields})
        self.packages: dict[str, list[int]] = {}  # mission package -> its links (MISPKG)
        try:
            mis = robot.geo("MisPkg")
            for pkg in getattr(mis, "packages", ()):
                self.packages[pkg.name] = [link.link for link in pkg.links]
        except ServerError:
            pass
        self.joints: dict[str, float] = {}  # STA joints (flippers...) and package links, by ROS joint name
        self.wheels: dict[str, tuple[float, float]] = {}  # tachometer: position, velocity
        self.cameras = [
            name
            for name, item in self.mounts.items()
            if self.confs.get(name, Conf()).fields.get("CameraFov") is not None
        ]
        self.next_picture = 0.0
        self.pubs: dict[str, Any] = {}
        self.kept: dict[str, Any] = {}  # topic -> its message, reused (rclpy serialises on publish)
        self.scan_topics: dict[str, str] = {}
        self.rows: dict[str, dict[int, tuple[float, Any]]] = {}  # a split 3D sweep's rows so far
        self.points_named = sum(1 for t in self.types.values() if t == "RangeScanner3D") > 1
        self.last_odom: tuple[float, float, float, float] | None = None  # t, x, y, yaw (ROS)
        self.last_truth: tuple[float, float, float, float, float] | None = None  # t, x, y, z, yaw (ROS)
        self.map_tf_sent = -1.0
        self.battery_full: int | None = None
        self.warned: set[str] = set()
        from visualization_msgs.msg import MarkerArray

        for item_type, topic in (("VictSensor", "victims"), ("RFID", "rfid")):
            if item_type in self.types.values():
                # published while something is in view: on the graph from the start all the same, so
                # a subscriber finds it at once (and no discovery comes in the middle of a run)
                self.publisher(topic, MarkerArray)

    def frame(self, name: str) -> str:
        return f"{self.prefix}{name}"

    # publishers made on first use: a robot without a sensor has no topic for it ----------------
    def publisher(self, topic: str, msg_type: Any) -> Any:
        pub = self.pubs.get(topic)
        if pub is None:
            pub = self.pubs[topic] = self.bridge.node.create_publisher(msg_type, f"{self.ns}/{topic}", self.bridge.qos)
        return pub

    def emit(self, topic: str, msg_type: Any, msg: Any, stamp: float) -> None:
        self.publisher(topic, msg_type).publish(msg)
        self.bridge._record(f"{self.ns}/{topic}", msg, stamp)

    def warn_once(self, key: str, text: str) -> None:
        if key not in self.warned:
            self.warned.add(key)
            log.warning("robot %s: %s", self.name, text)

    def static_transforms(self) -> list[Any]:
        """base_link to every sensor's frame, from the GETGEO mounts (items on a mission
        package's link at the package's rest pose)."""
        out = []
        for name, item in self.mounts.items():
            out.append(
                self.bridge.transform(0.0, self.frame("base_link"), self.frame(name), item.location, item.orientation)
            )
        for name in self.cameras:  # REP 103's optical frame: z forward, x right, y down
            ts = self.bridge.transform(
                0.0, self.frame(name), self.frame(f"{name}_optical"), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
            )
            r = ts.transform.rotation
            r.x, r.y, r.z, r.w = quaternion(-math.pi / 2, 0.0, -math.pi / 2)
            out.append(ts)
        return out

    def on_joints(self, names: list[str], positions: list[float]) -> None:
        """A JointState command: each name a mission package's link (``CameraPanTilt_link2``,
        to MISPKG) or a joint of the robot's STA (a flipper, to DRIVE {Name} {Value})."""
        by_package: dict[str, dict[int, float]] = {}
        for name, value in zip(names, positions):
            if not math.isfinite(value):
                log.warning("robot %s: ignored a joint command for %s with %g", self.name, name, value)
                continue
            pkg, _, link = name.rpartition("_link")
            if pkg in self.packages and link.isdigit() and int(link) in self.packages[pkg]:
                by_package.setdefault(pkg, {})[int(link)] = value
            elif name in self.joints and "_link" not in name:
                self.bridge.commands.put((self, drive_line_joint(name, value)))
            else:
                known = sorted(self.joints) + [f"{p}_link{k}" for p, ks in self.packages.items() for k in ks]
                log.warning(
                    "robot %s: a joint command names no joint of it: %r (its joints: %s)",
                    self.name,
                    name,
                    ", ".join(dict.fromkeys(known)) or "none",
                )
        for pkg, values in by_package.items():
            from usarsim.client.core import mispkg_line

            self.bridge.commands.put((self, mispkg_line(pkg, values)))

    def on_report(self, x: float, y: float, z: float, frame: str) -> None:
        """A victim report (a point in the ``map`` frame) to REPORT {Type Victim}."""
        if frame not in ("", WORLD_FRAME):
            self.warn_once("report-frame", f"a victim report in frame {frame!r} ignored: give it in {WORLD_FRAME!r}")
            return
        if not all(math.isfinite(v) for v in (x, y, z)):
            log.warning("robot %s: ignored a victim report at a point that is not finite", self.name)
            return
        from usarsim.client.core import report_line

        self.bridge.commands.put((self, report_line(vector((x, y, z)))))

    # commands from ROS ------------------------------------------------------------------------
    def on_twist(self, vx: float, vy: float, vz: float, wz: float) -> None:
        try:
            keys = drive_of(self.kinematics, vx, vy, vz, wz)
        except BadTwist as exc:
            log.warning("robot %s: ignored a %s", self.name, exc)
            return
        except ValueError as exc:
            self.warn_once("cmd_vel", f"ignored cmd_vel: {exc}")
            return
        limited = drive_of(self.kinematics, vx, vy, vz, wz, clip=False) != keys
        if limited:
            self.warn_once(
                "limit",
                f"cmd_vel ({vx:g}, {vy:g}, {vz:g} m/s, {wz:g} rad/s) is beyond what the robot "
                f"can do: limited to its MaxSpeed and MaxFrontSteer (said once)",
            )
        if "wheels" in keys:
            line = (
                "DRIVE "
                + " ".join(
                    f"{{WheelNumber {n}}} {{WheelSpeed {v:.4f}}} {{WheelSteer {a:.4f}}}" for n, v, a in keys["wheels"]
                )
                + "\r\n"
            )
        else:
            line = drive_line(**keys)
        self.bridge.commands.put((self, line))

    # messages from the simulator --------------------------------------------------------------
    def handle(self, msg: Any) -> None:
        b = self.bridge
        t = getattr(msg, "time", None)
        stamp = t if isinstance(t, float) and math.isfinite(t) else (self.robot.time or b.sim_time)
        if isinstance(msg, M.SensorMessage):
            r = msg.reading
            if isinstance(r, RangeScanReading):
                self.publish_scan(stamp, r)
            elif isinstance(r, RangeScan3DReading):
                self.publish_points(stamp, r)
            elif isinstance(r, OdometryReading):
                self.publish_odometry(stamp, r)
            elif isinstance(r, PoseReading) and r.sensor_type == "GroundTruth":
                self.publish_ground_truth(stamp, r)
            elif isinstance(r, PoseReading) and r.sensor_type == "INS":
                self.publish_imu(stamp, r.name, r.orientation, None, None)
            elif isinstance(r, ImuReading):
                self.publish_imu(stamp, r.name, r.orientation, r.angular_velocity, r.acceleration)
            elif isinstance(r, RangeReading):
                self.publish_ranges(stamp, r)
            elif isinstance(r, GpsReading):
                self.publish_gps(stamp, r)
            elif isinstance(r, VictimReading):
                self.publish_victims(stamp, r)
            elif isinstance(r, TouchReading):
                self.publish_touch(stamp, r)
            elif isinstance(r, RfidReading):
                self.publish_rfid(stamp, r)
            elif isinstance(r, TachometerReading):
                for i, (v, p) in enumerate(zip(r.velocities_rad_s, r.positions_rad)):
                    self.wheels[f"{r.name}_wheel{i}"] = (float(p), float(v))
        elif isinstance(msg, M.StatusMessage):
            self.publish_battery(stamp, msg.status.battery_s)
            for name, value in msg.status.joints:
                self.joints[name] = float(value)
            if self.joints or self.wheels:
                self.publish_joint_states(stamp)
        elif isinstance(msg, M.MisPkgMessage):
            for link in msg.state.links:
                self.joints[f"{msg.state.name}_link{link.link}"] = float(link.value)
            self.publish_joint_states(stamp)

    def publish_joint_states(self, stamp: float) -> None:
        from sensor_msgs.msg import JointState

        m = JointState()
        m.header.stamp = b_time(stamp)
        m.name = list(self.joints) + list(self.wheels)
        m.position = [*self.joints.values(), *(p for p, _ in self.wheels.values())]
        if self.wheels:
            m.velocity = [math.nan] * len(self.joints) + [v for _, v in self.wheels.values()]
        self.emit("joint_states", JointState, m, stamp)

    def publish_picture(self, stamp: float, camera: str, compressed: bool, raw: bool, info: bool) -> None:
        """One picture of ``camera`` from the image server: image_raw (rgb8), its JPEG and the
        camera's intrinsics (a pinhole of its horizontal field of view)."""
        from sensor_msgs.msg import CameraInfo, CompressedImage, Image

        try:
            rgb = self.robot.picture(camera)
        except ClientError as exc:
            self.warn_once(f"camera-{camera}", f"no picture of {camera}: {exc} (is the image server on?)")
            return
        h, w = int(rgb.shape[0]), int(rgb.shape[1])
        frame = self.frame(f"{camera}_optical")
        base = "camera" if camera == self.cameras[0] else f"camera/{camera}"
        if raw:
            m = Image()
            m.header.stamp, m.header.frame_id = b_time(stamp), frame
            m.height, m.width, m.encoding, m.step = h, w, "rgb8", 3 * w
            m.data = rgb.tobytes()
            self.emit(f"{base}/image_raw", Image, m, stamp)
        if compressed:
            import io

            from PIL import Image as PILImage

            buf = io.BytesIO()
            PILImage.fromarray(rgb).save(buf, format="JPEG", quality=85)
            c = CompressedImage()
            c.header.stamp, c.header.frame_id = b_time(stamp), frame
            c.format = "rgb8; jpeg compressed bgr8"  # image_transport's compressed format string
            c.data = buf.getvalue()
            self.emit(f"{base}/image_raw/compressed", CompressedImage, c, stamp)
        if info:
            fov = self.confs.get(camera, Conf()).number("CameraFov", math.radians(90.0))
            f = (w / 2.0) / math.tan(fov / 2.0)
            ci = CameraInfo()
            ci.header.stamp, ci.header.frame_id = b_time(stamp), frame
            ci.height, ci.width = h, w
            ci.distortion_model = "plumb_bob"
            ci.d = [0.0] * 5
            ci.k = [f, 0.0, w / 2.0, 0.0, f, h / 2.0, 0.0, 0.0, 1.0]
            ci.r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
            ci.p = [f, 0.0, w / 2.0, 0.0, 0.0, f, h / 2.0, 0.0, 0.0, 0.0, 1.0, 0.0]
            self.emit(f"{base}/camera_info", CameraInfo, ci, stamp)

    def camera_wanted(self) -> list[tuple[str, bool, bool, bool]]:
        """The cameras with a subscriber (or a recording): (camera, compressed, raw, info)."""
        out: list[tuple[str, bool, bool, bool]] = []
        recording = self.bridge.recorder is not None
        for cam in self.cameras:
            base = f"{self.ns}/{'camera' if cam == self.cameras[0] else f'camera/{cam}'}"
            compressed, raw, info = (
                recording or self.bridge.node.count_subscribers(f"{base}/{t}") > 0
                for t in ("image_raw/compressed", "image_raw", "camera_info")
            )
            if compressed or raw or info:
                out.append((cam, compressed, raw, info))
        return out

    def publish_battery(self, stamp: float, seconds: int) -> None:
        from sensor_msgs.msg import BatteryState

        if self.battery_full is None or seconds > self.battery_full:
            self.battery_full = max(1, int(seconds))
        m = BatteryState()
        m.header.stamp = b_time(stamp)
        m.header.frame_id = self.frame("base_link")
        m.voltage = m.temperature = m.current = m.charge = m.capacity = m.design_capacity = math.nan
        m.percentage = float(seconds) / self.battery_full  # of the life the robot had when the bridge met it
        m.power_supply_status = BatteryState.POWER_SUPPLY_STATUS_DISCHARGING
        m.present = True
        self.emit("battery", BatteryState, m, stamp)


def drive_line_joint(name: str, value: float) -> str:
    """``DRIVE {Name joint} {Value v} {Order 0}``: a joint of the robot to a position (protocol.md
    5.3f)."""
    return f"DRIVE {{Name {name}}} {{Value {value:.4f}}} {{Order 0}}\r\n"
