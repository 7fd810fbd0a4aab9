"""One robot's sensor topics: each reading of its protocol lines as the ROS 2 message of its
topic (scan, points, odom, ground_truth with the map -> odom transform, imu, sonar and ir
ranges, gps/fix, victims and rfid markers, touch).

:class:`SensorTopics` is a part of :class:`usarsim.ros2.robot.RobotBridge`: it uses the robot
bridge's ``emit``, ``frame``, ``bridge``, ``kept`` messages and settings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from usarsim.readings import (
    GpsReading,
    OdometryReading,
    PoseReading,
    RangeReading,
    RangeScan3DReading,
    RangeScanReading,
    RfidReading,
    TouchReading,
    VictimReading,
)

from .convert import angles, quaternion, ros_pose, scan_angles, vector, yaw_of

if TYPE_CHECKING:
    from .bridge import Bridge

WORLD_FRAME = "map"  # the simulator's world, in REP 103 axes (ground truth, victims, map -> odom)


@dataclass
class Conf:
    """One item's CONF fields, by key (the text the server sent)."""

    fields: dict[str, str] = field(default_factory=dict)

    def number(self, key: str, default: float) -> float:
        try:
            return float(self.fields[key])
        except (KeyError, ValueError):
            return default


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


class SensorTopics:
    """The robot bridge's publishers of readings (see the module's description)."""

    if TYPE_CHECKING:  # what the robot bridge gives
        bridge: Bridge
        confs: dict[str, Conf]
        kept: dict[str, Any]
        scan_topics: dict[str, str]
        rows: dict[str, dict[int, tuple[float, Any]]]
        points_named: bool
        last_odom: tuple[float, float, float, float] | None
        last_truth: tuple[float, float, float, float, float] | None
        map_tf_sent: float

        def frame(self, name: str) -> str: ...
        def emit(self, topic: str, msg_type: Any, msg: Any, stamp: float) -> None: ...
        def warn_once(self, key: str, text: str) -> None: ...

    def publish_scan(self, stamp: float, r: RangeScanReading) -> None:
        from sensor_msgs.msg import LaserScan

        topic = self.scan_topics.get(r.name)
        if topic is None:
            topic = self.scan_topics[r.name] = "scan" if not self.scan_topics else f"scan/{r.name}"
        conf = self.confs.get(r.name, Conf())
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
        limit = self.confs.get(r.name, Conf()).number("MaxRange", math.inf)
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
                conf = self.confs.get(item.name, Conf())
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
        clear.header.stamp = b_time(stamp)  # the array's time even with nothing in it
        clear.header.frame_id = self.frame(sensor)
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
