"""One robot on the ROS 2 graph: what its GETGEO and GETCONF say, its publishers, and the
conversion of each of its messages (readings, status, mission packages) to ROS 2 messages and of
ROS 2 commands (cmd_vel, joint commands, victim reports) to its protocol lines.  The bridge
(:mod:`usarsim.ros2.bridge`) owns the node, the sockets and the clock."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
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

from .convert import BadTwist, Kinematics, angles, drive_of, quaternion, ros_pose, scan_angles, vector, yaw_of

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
WORLD_FRAME = "map"  # the simulator's world, in REP 103 axes (ground truth, victims, map -> odom)
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


@dataclass
class _Conf:
    """One item's CONF fields, by key (the text the server sent)."""

    fields: dict[str, str] = field(default_factory=dict)

    def number(self, key: str, default: float) -> float:
        try:
            return float(self.fields[key])
        except (KeyError, ValueError):
            return default


class RobotBridge:
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
        self.confs: dict[str, _Conf] = {}  # sensor name -> its CONF fields
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
                self.confs[item.name] = _Conf({k: str(v) for k, v in item.fields})
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
            if self.confs.get(name, _Conf()).fields.get("CameraFov") is not None
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
        elif isinstance(msg, (M.GroundVehicleStatus, M.AerialVehicleStatus)):
            self.publish_battery(stamp, msg.battery_s)
            for name, value in getattr(msg, "joints", ()):
                self.joints[name] = float(value)
            if self.joints or self.wheels:
                self.publish_joint_states(stamp)
        elif isinstance(msg, M.MisPkgStatus):
            for link in msg.links:
                self.joints[f"{msg.name}_link{link.link}"] = float(link.value)
            self.publish_joint_states(stamp)

    def publish_scan(self, stamp: float, r: RangeScanReading) -> None:
        from sensor_msgs.msg import LaserScan

        topic = self.scan_topics.get(r.name)
        if topic is None:
            topic = self.scan_topics[r.name] = "scan" if not self.scan_topics else f"scan/{r.name}"
        conf = self.confs.get(r.name, _Conf())
        m = self.kept.get(topic)
        if m is None:
            m = self.kept[topic] = LaserScan()
            m.header.frame_id = self.frame(r.name)
            m.time_increment = 0.0  # every beam of a sweep is measured at once
            m.scan_time = conf.number("ScanInterval", 0.0)
            m.range_min = conf.number("MinRange", 0.0)
            m.range_max = conf.number("MaxRange", max(r.ranges_m, default=0.0))
        set_time(m.header.stamp, stamp)
        n = len(r.ranges_m)
        m.angle_min, m.angle_max = scan_angles(n, r.resolution_rad)
        m.angle_increment = float(r.resolution_rad)
        m.ranges = r.ranges_m
        self.emit(topic, LaserScan, m, stamp)

    def publish_points(self, stamp: float, r: RangeScan3DReading) -> None:
        """A 3D sweep (row-major, the top row first, each row from its rightmost beam) as a
        PointCloud2 of its returns (beams short of MaxRange) in the scanner's frame; a sweep sent
        one row a line is published once its last row is in."""
        import numpy as np
        from sensor_msgs.msg import PointCloud2, PointField

        vres, hres = r.resolution_rad
        vfov, hfov = r.fov_rad
        rows_total = r.frames or (int(round(vfov / vres)) + 1 if vres > 0 else 1)
        if r.frame is not None:  # one row of a split sweep
            parts = self.rows.setdefault(r.name, {})
            if parts and next(iter(parts.values()))[0] != stamp:
                parts.clear()
            parts[r.frame] = (stamp, r.ranges_m)
            if len(parts) < rows_total:
                return
            ranges = np.concatenate([np.asarray(parts[k][1], dtype=np.float64) for k in sorted(parts)])
            parts.clear()
        else:
            ranges = np.asarray(r.ranges_m, dtype=np.float64)
        if rows_total <= 0 or len(ranges) % rows_total:
            self.warn_once(
                f"points-{r.name}",
                f"a 3D sweep of {len(ranges)} beams does not split into {rows_total} rows: not published",
            )
            return
        cols = len(ranges) // rows_total
        elevation = vfov / 2.0 - np.arange(rows_total) * vres  # up positive
        azimuth = -((cols - 1) * hres) / 2.0 + np.arange(cols) * hres  # counter-clockwise, from the right
        el, az = np.meshgrid(elevation, azimuth, indexing="ij")
        rng = ranges.reshape(rows_total, cols)
        limit = self.confs.get(r.name, _Conf()).number("MaxRange", math.inf)
        keep = (rng > 0) & (rng < limit - 1e-3)
        xyz = np.stack([rng * np.cos(el) * np.cos(az), rng * np.cos(el) * np.sin(az), rng * np.sin(el)], axis=-1)
        pts = xyz[keep].astype(np.float32)
        m = PointCloud2()
        m.header.stamp = b_time(stamp)
        m.header.frame_id = self.frame(r.name)
        m.height, m.width = 1, len(pts)
        m.fields = [PointField(name=n, offset=4 * i, datatype=PointField.FLOAT32, count=1) for i, n in enumerate("xyz")]
        m.is_bigendian, m.point_step, m.row_step, m.is_dense = False, 12, 12 * len(pts), True
        m.data = pts.tobytes()
        self.emit("points" if not self.points_named else f"points/{r.name}", PointCloud2, m, stamp)

    def publish_odometry(self, stamp: float, r: OdometryReading) -> None:
        from nav_msgs.msg import Odometry

        x, y, yaw = float(r.x_m), -float(r.y_m), -float(r.theta_rad)
        m = Odometry()
        m.header.stamp = b_time(stamp)
        m.header.frame_id = self.frame("odom")
        m.child_frame_id = self.frame("base_link")
        m.pose.pose.position.x, m.pose.pose.position.y = x, y
        q = quaternion(0.0, 0.0, yaw)
        o = m.pose.pose.orientation
        o.x, o.y, o.z, o.w = q
        if self.last_odom is not None and stamp > self.last_odom[0]:
            t0, x0, y0, yaw0 = self.last_odom
            dt = stamp - t0
            dx, dy = (x - x0) / dt, (y - y0) / dt
            m.twist.twist.linear.x = math.cos(yaw) * dx + math.sin(yaw) * dy  # in base_link
            m.twist.twist.linear.y = -math.sin(yaw) * dx + math.cos(yaw) * dy
            m.twist.twist.angular.z = math.remainder(yaw - yaw0, math.tau) / dt
        self.last_odom = (stamp, x, y, yaw)
        self.send_map_tf()
        self.emit("odom", Odometry, m, stamp)
        self.bridge.send_tf(
            [
                self.bridge.transform(
                    stamp, self.frame("odom"), self.frame("base_link"), (r.x_m, r.y_m, 0.0), (0.0, 0.0, r.theta_rad)
                )
            ],
            stamp,
        )

    def publish_ground_truth(self, stamp: float, r: PoseReading) -> None:
        from nav_msgs.msg import Odometry

        m = Odometry()
        m.header.stamp = b_time(stamp)
        m.header.frame_id = WORLD_FRAME
        m.child_frame_id = self.frame("base_link")
        (px, py, pz), q = ros_pose(r.location, r.orientation)
        p = m.pose.pose.position
        p.x, p.y, p.z = px, py, pz
        o = m.pose.pose.orientation
        o.x, o.y, o.z, o.w = q
        self.emit("ground_truth", Odometry, m, stamp)
        self.last_truth = (stamp, px, py, pz, yaw_of(q))
        self.send_map_tf()

    def send_map_tf(self) -> None:
        """``map`` to ``NAME/odom`` (``--map-tf``): where odometry's origin is by ground truth,
        once both have a reading of the same time (in the plane: x, y, yaw; z of the truth)."""
        if not self.bridge.map_tf or self.last_truth is None or self.last_odom is None:
            return
        t, gx, gy, gz, gyaw = self.last_truth
        to, ox, oy, oyaw = self.last_odom
        if abs(t - to) > 1e-6 or t <= self.map_tf_sent:
            return
        self.map_tf_sent = t
        yaw = gyaw - oyaw
        c, s_ = math.cos(yaw), math.sin(yaw)
        x, y = gx - (c * ox - s_ * oy), gy - (s_ * ox + c * oy)
        # the transform in ROS axes; Bridge.transform takes USARSim's, so turn them back
        self.bridge.send_tf(
            [self.bridge.transform(t, WORLD_FRAME, self.frame("odom"), (x, -y, -gz), (0.0, 0.0, -yaw))], t
        )

    def publish_imu(self, stamp: float, name: str, orientation: Any, gyro: Any, accel: Any) -> None:
        from sensor_msgs.msg import Imu

        m = Imu()
        m.header.stamp = b_time(stamp)
        m.header.frame_id = self.frame(name)
        o = m.orientation
        o.x, o.y, o.z, o.w = quaternion(*angles(orientation))
        if gyro is None:
            m.angular_velocity_covariance[0] = -1.0  # REP 145: -1 marks a quantity the sensor does not give
        else:
            v = m.angular_velocity
            v.x, v.y, v.z = vector(gyro)
        if accel is None:
            m.linear_acceleration_covariance[0] = -1.0
        else:
            a = m.linear_acceleration
            a.x, a.y, a.z = vector(accel)
        self.emit("imu", Imu, m, stamp)

    def publish_ranges(self, stamp: float, r: RangeReading) -> None:
        from sensor_msgs.msg import Range

        kind = "sonar" if r.sensor_type.lower().startswith("sonar") else "ir"
        for item in r.items:
            topic = f"{kind}/{item.name}"
            m = self.kept.get(topic)
            if m is None:  # made once; each reading sets only its stamp and range
                conf = self.confs.get(item.name, _Conf())
                m = self.kept[topic] = Range()
                m.header.frame_id = self.frame(item.name)
                m.radiation_type = Range.ULTRASOUND if kind == "sonar" else Range.INFRARED
                m.field_of_view = conf.number("BeamAngle", 0.0)
                m.min_range = conf.number("MinRange", 0.0)
                m.max_range = conf.number("MaxRange", float(item.range_m))
            set_time(m.header.stamp, stamp)
            m.range = float(item.range_m)
            self.emit(topic, Range, m, stamp)

    def publish_gps(self, stamp: float, r: GpsReading) -> None:
        from sensor_msgs.msg import NavSatFix, NavSatStatus

        m = NavSatFix()
        m.header.stamp = b_time(stamp)
        m.header.frame_id = self.frame(r.name)
        m.status.status = NavSatStatus.STATUS_FIX if r.fix else NavSatStatus.STATUS_NO_FIX
        m.status.service = NavSatStatus.SERVICE_GPS
        m.latitude = _degrees(r.latitude, "S")
        m.longitude = _degrees(r.longitude, "W")
        m.altitude = math.nan  # the sensor reports none
        m.position_covariance_type = NavSatFix.COVARIANCE_TYPE_UNKNOWN
        self.emit("gps/fix", NavSatFix, m, stamp)

    def publish_victims(self, stamp: float, r: VictimReading) -> None:
        # one red sphere per part seen, its text the part's name (Head, Chest, ...)
        self.publish_markers(
            stamp,
            "victims",
            r.name,
            "SPHERE",
            0.1,
            (1.0, 0.2, 0.2),
            [(i, part.part_name, part.location) for i, part in enumerate(r.parts)],
        )

    def publish_markers(
        self,
        stamp: float,
        topic: str,
        sensor: str,
        shape: str,
        size: float,
        rgb: tuple[float, float, float],
        items: list[tuple[int, str, Any]],
    ) -> None:
        """A MarkerArray: a DELETEALL, then a marker per (id, text, USARSim location) in the
        sensor's frame (namespace ``topic``)."""
        from visualization_msgs.msg import Marker, MarkerArray

        out = MarkerArray()
        clear = Marker()
        clear.action = Marker.DELETEALL
        out.markers.append(clear)
        for ident, text, location in items:
            m = Marker()
            m.header.stamp = b_time(stamp)
            m.header.frame_id = self.frame(sensor)
            m.ns = topic
            m.id = ident
            m.type = getattr(Marker, shape)
            m.action = Marker.ADD
            m.text = text
            p = m.pose.position
            p.x, p.y, p.z = vector(location)
            m.pose.orientation.w = 1.0
            m.scale.x = m.scale.y = m.scale.z = size
            m.color.r, m.color.g, m.color.b = rgb
            m.color.a = 1.0
            out.markers.append(m)
        self.emit(topic, MarkerArray, out, stamp)

    def publish_touch(self, stamp: float, r: TouchReading) -> None:
        from std_msgs.msg import Bool

        for item in r.items:
            self.emit(f"touch/{item.name}", Bool, Bool(data=bool(item.touching)), stamp)

    def publish_rfid(self, stamp: float, r: RfidReading) -> None:
        # one green cube per tag in range, its id the tag's ID, its text the ID and the memory
        self.publish_markers(
            stamp,
            "rfid",
            r.name,
            "CUBE",
            0.05,
            (0.0, 1.0, 0.0),
            [
                (int(t.tag_id), str(t.tag_id) if t.memory is None else f"{t.tag_id} {t.memory}", t.location)
                for t in r.tags
            ],
        )

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
            fov = self.confs.get(camera, _Conf()).number("CameraFov", math.radians(90.0))
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
        out = []
        recording = self.bridge.recorder is not None
        for cam in self.cameras:
            base = f"{self.ns}/{'camera' if cam == self.cameras[0] else f'camera/{cam}'}"
            counts = [
                recording or self.bridge.node.count_subscribers(f"{base}/{t}") > 0
                for t in ("image_raw/compressed", "image_raw", "camera_info")
            ]
            if any(counts):
                out.append((cam, *counts))
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


def _degrees(value: Any, negative: str) -> float:
    """USARSim's (degrees, minutes, hemisphere) as signed decimal degrees."""
    if not value:
        return math.nan
    deg, minutes, hemi = value
    d = float(deg) + float(minutes) / 60.0
    return -d if str(hemi).upper() == negative else d


def _sec_nsec(t: float) -> tuple[int, int]:
    t = max(0.0, float(t))
    sec = int(math.floor(t))
    nsec = int(round((t - sec) * 1e9))
    if nsec >= 1_000_000_000:
        sec, nsec = sec + 1, nsec - 1_000_000_000
    return sec, nsec


def b_time(t: float) -> Any:
    """A ``builtin_interfaces/Time`` of simulated seconds."""
    from builtin_interfaces.msg import Time

    sec, nsec = _sec_nsec(t)
    return Time(sec=sec, nanosec=nsec)


def set_time(stamp: Any, t: float) -> None:
    """Set a ``builtin_interfaces/Time`` to simulated seconds."""
    stamp.sec, stamp.nanosec = _sec_nsec(t)
