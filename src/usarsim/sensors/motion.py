"""Wheel-based and pose sensors: Odometry (protocol.md 7.4), Encoder (7.5),
GroundTruth (7.8) and INS (7.7).

Their noise (:mod:`usarsim.sensors.noise`): the Encoder's is :class:`EncoderCountNoise`, the
relative error of its counting, and the INS's is :class:`InsDrift`, the drift of its pose
integrated from noisy increments; both are declared as the sensor's ``NOISE`` and applied by the
framework to what the sensor senses, drawn from the sensor's own seeded generator.  Odometry has
no noise (its wheel angles are quantised by its EncoderResolution, exactly), nor has
GroundTruth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from usarsim.readings import (
    EncoderItem,
    EncoderReading,
    FieldValue,
    ItemParams,
    OdometryReading,
    OperationResult,
    PoseReading,
)
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig
from usarsim.sensors.noise import Noise
from usarsim.sim.frames import wrap_2pi, wrap_pi

if TYPE_CHECKING:
    from usarsim.config.robot import MountedItem, RobotConfig
    from usarsim.sim.view import WorldView


@dataclass(frozen=True, kw_only=True)
class OdometryConfig(SensorConfig):
    """An Odometry sensor's settings in a robot file (protocol.md 6.7, 7.4): its scan interval, the encoder
    resolution (rad) the wheel angles are quantised by, the wheels it follows (empty: the first of each side) and its
    effective track width in metres."""

    # UT CONF example (protocol.md 6.7): ScanInterval 0.2, EncoderResolution 0.0099 rad.
    scan_interval_s: float = 0.2
    encoder_resolution_rad: float = 0.0099
    left_wheel: str = ""
    right_wheel: str = ""
    # The effective track width (m) the heading is worked out with; 0: the wheels' own
    # separation (protocol.md 7.4).  A skid-steered robot's wheels slip sideways as it
    # turns, so its wheel angles overstate its turns; the Pioneer's controller corrects
    # that with a calibrated RevCount (encoder ticks per half turn of the robot, Pioneer 3
    # Operations Manual, ARCOS FLASH parameters), this with a wider track (the kinematics
    # in the Odometry class's docstring).
    track_width_m: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.encoder_resolution_rad < 0:
            raise ValueError(f"encoder_resolution_rad must be >= 0, got {self.encoder_resolution_rad}")
        if not (self.track_width_m >= 0 and math.isfinite(self.track_width_m)):
            raise ValueError(f"track_width_m must be >= 0, got {self.track_width_m}")


def _quantise(angle: float, resolution: float) -> float:
    if resolution <= 0:
        return angle
    return math.floor(angle / resolution + 0.5) * resolution


@SENSORS.register("Odometry")
class Odometry(Sensor[OdometryConfig]):
    """Differential dead reckoning from the left and right wheel angles, quantised by
    EncoderResolution; pose relative to the spawn pose (or the last RESET); positive
    theta is a clockwise (right) turn, as in the Z-down frame.

    The heading changes by r (dl - dr) / TrackWidth.  That is the kinematics of a
    skid-steered vehicle whose treads turn about instantaneous centres of rotation (ICRs)
    that stay put relative to the body: Martinez et al., "Approximating kinematics for
    tracked mobile robots", IJRR 24(10), 2005, for tracked robots, and Mandow et al.,
    "Experimental kinematics for wheeled skid-steer mobile robots", IROS 2007, for the
    Pioneer 3-AT, whose turn rate is r (wr - wl) / (y_ICRl - y_ICRr): the distance
    between the treads' ICRs, the wheels' separation B times an ICR expansion factor
    (chi >= 1, the sideways slip of the wheels as they turn), is an effective track width
    that one calibration fixes for a robot on a floor.  The simulated P2AT keeps its ICRs
    so (the tread contact of usarsim.robots.skid): over the rates a controller asks for
    (0.3 to 1.5 rad/s, in place and on arcs at up to 0.4 m/s) its wheel angles count 1.16 to
    1.20 times its turn (98 % of turns; the median 1.176), and less in the moments it starts
    and stops turning; so its robot file carries TrackWidth 0.552 m (1.172 x its
    WheelSeparation, 0.4712 m), with which it counts quarter turns from rest to rest within
    2 %, and 98 % of long turns within 2.5 % (tests/integration/test_odometry_calibration.py).

    TrackWidth is the wheels' separation (protocol.md 7.4) unless the robot file gives
    ``TrackWidth`` or a client sets it (``SET {Type Odometry} {Name n} {Opcode TrackWidth}
    {Params w}``, w in metres; 0 goes back to the file's value); CONF reports the one in
    force as ``TrackWidth``."""

    RESETTABLE = True
    LIVE_CONF = True  # CONF's TrackWidth follows a SET
    ALIASES = {
        "EncoderResolution": "encoder_resolution_rad",
        "LeftWheel": "left_wheel",
        "RightWheel": "right_wheel",
        "TrackWidth": "track_width_m",
    }

    def __init__(self, item: MountedItem, config: OdometryConfig, robot: RobotConfig, seed: int) -> None:
        super().__init__(item, config, robot, seed)
        self._set_track = 0.0  # a client's TrackWidth (m; 0: none), kept across model rebuilds
        wheels = {w.name: w for w in robot.wheels}
        self._left = self.config.left_wheel or next((w.name for w in robot.wheels if w.side == "left"), "")
        self._right = self.config.right_wheel or next((w.name for w in robot.wheels if w.side == "right"), "")
        left, right = wheels.get(self._left), wheels.get(self._right)
        self._radius = left.radius_m if left else 0.0
        # sep = 2 x the lateral offset of the right wheel (protocol.md 7.4)
        self._wheel_sep = 2.0 * abs(right.position[1]) if right else 0.0

    def configure(self, view: WorldView) -> None:
        names = {w.name for w in self.robot.wheels}
        if self._left not in names or self._right not in names:
            raise ValueError(
                f"odometry {self.name}: needs a left and a right wheel (LeftWheel, RightWheel), "
                f"got {self._left!r} and {self._right!r}"
            )

    @property
    def _sep(self) -> float:
        return self._set_track or self.config.track_width_m or self._wheel_sep

    @property
    def track_width_m(self) -> float:
        """The track width the heading is worked out with now (m)."""
        return self._sep

    def _angles(self, view: WorldView) -> tuple[float, float]:
        q = view.data.qpos
        res = self.config.encoder_resolution_rad
        return (
            _quantise(float(q[self.handle.joint_qpos[self._left]]), res),
            _quantise(float(q[self.handle.joint_qpos[self._right]]), res),
        )

    def reset(self, view: WorldView) -> None:
        self.x = self.y = self.theta = 0.0
        self._last = self._angles(view)

    def measure(self, view: WorldView) -> OdometryReading:
        left, right = self._angles(view)
        dl, dr = left - self._last[0], right - self._last[1]
        self._last = (left, right)
        ds = self._radius * (dl + dr) / 2.0
        dtheta = self._radius * (dl - dr) / self._sep
        mid = self.theta + dtheta / 2.0
        self.x += ds * math.cos(mid)
        self.y += ds * math.sin(mid)
        self.theta = wrap_pi(self.theta + dtheta)
        # reported in [0, 2 pi) as UT2004 did (protocol.md 6.3 example: 6.2432)
        return OdometryReading(self.name, self.x, self.y, wrap_2pi(self.theta))

    def operate(self, view: WorldView, opcode: str, params: ItemParams) -> OperationResult | None:
        """``{Opcode RESET}`` (protocol.md 5.4) and ``{Opcode TrackWidth} {Params w}``: the
        effective track width from now on (m; 0: the robot file's)."""
        if opcode.upper() != "TRACKWIDTH":
            return super().operate(view, opcode, params)
        vals = params.values
        if vals is None or len(vals) != 1 or not vals[0] >= 0:
            return OperationResult(ok=False)
        self._set_track = float(vals[0])
        return OperationResult(ok=True)

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        c = self.config
        return (
            ("ScanInterval", c.scan_interval_s),
            ("EncoderResolution", c.encoder_resolution_rad),
            ("TrackWidth", self.track_width_m),
        )


@dataclass(frozen=True, kw_only=True)
class EncoderConfig(SensorConfig):
    """An Encoder's settings in a robot file (protocol.md 7.5): its scan interval, its resolution in radians per
    tick, its relative noise and the wheel it counts (empty: the robot's first)."""

    # Encoder (protocol.md 7.5): Resolution 0.01745 rad per tick, Noise 0.005; the
    # sensor base ScanInterval is 0.1 s (7.1).
    scan_interval_s: float = 0.1
    resolution_rad: float = 0.01745
    noise: float = 0.005
    wheel: str = ""

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.resolution_rad <= 0:
            raise ValueError(f"resolution_rad must be > 0, got {self.resolution_rad}")


class EncoderCountNoise(Noise):
    """The relative error of an encoder's counting: each reading's true change of wheel angle
    (rad) is scaled by (1 + U(-Noise, Noise)) before it is added to the count (protocol.md 7.5
    scales the whole angle), so that a wheel at rest keeps its count, as a real encoder does,
    however far it has turned: a change of 0 is no draw and stays 0.  ``true``: the change
    (a float)."""

    def apply(self, sensor: Sensor[Any], true: Any) -> Any:
        if true == 0.0:
            return true
        return sensor.relative_noise_scalar(true)


@SENSORS.register("Encoder")
class Encoder(Sensor[EncoderConfig]):
    """Tick = round(accumulated wheel angle / Resolution), forward rotation counting up;
    the noise is the counting's (:class:`EncoderCountNoise`): it senses the change of its
    wheel's angle since the last reading, and counts it as corrupted."""

    PACKED = True
    RESETTABLE = True
    NOISE = EncoderCountNoise()
    ALIASES = {"Resolution": "resolution_rad", "Wheel": "wheel", "Joint": "wheel"}

    def configure(self, view: WorldView) -> None:
        self._wheel = self.config.wheel or self.robot.wheels[0].name
        if self._wheel not in {w.name for w in self.robot.wheels}:
            raise ValueError(f"encoder {self.name}: unknown wheel {self._wheel}")

    def reset(self, view: WorldView) -> None:
        self._last = float(view.data.qpos[self.handle.joint_qpos[self._wheel]])
        self._counted = 0.0  # the angle counted so far, with its noise (rad)

    def sense(self, view: WorldView) -> float:
        """The wheel's true change of angle since the last reading (rad)."""
        angle = float(view.data.qpos[self.handle.joint_qpos[self._wheel]])
        step, self._last = angle - self._last, angle
        return step

    def reading(self, values: float) -> EncoderItem:
        """The change counted (``values``, with its noise) added to the count; the ticks."""
        if values != 0.0:  # a wheel at rest: the count stays as it is
            self._counted += values
        return EncoderItem(self.name, int(round(self._counted / self.config.resolution_rad)))

    @classmethod
    def combine(cls, parts: list[EncoderItem]) -> EncoderReading:
        return EncoderReading(tuple(parts))

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        # printed truncated, as USARSim did (0.01745 -> 0.0174, protocol.md 6.7)
        return (("Resolution", math.trunc(self.config.resolution_rad * 1e4) / 1e4),)

    def geo_mount(self) -> str:
        """An encoder rides on the wheel it counts: GEO names that wheel as its mount
        (protocol.md 6.8, a robot part such as RightFWheel), its pose relative to the wheel;
        a mount written in the robot file wins."""
        if self.item.mount != "HARD" or not self.robot.wheels:
            return self.item.mount
        return self.config.wheel or self.robot.wheels[0].name


@dataclass(frozen=True, kw_only=True)
class GroundTruthConfig(SensorConfig):
    """A GroundTruth sensor's settings in a robot file (protocol.md 7.8): its scan interval."""

    # GroundTruth ScanInterval 0.1 (protocol.md 7.8).
    scan_interval_s: float = 0.1


@SENSORS.register("GroundTruth")
class GroundTruth(Sensor[GroundTruthConfig]):
    """The exact pose of the robot's origin in the world frame, no noise."""

    def measure(self, view: WorldView) -> PoseReading:
        d = view.data
        r, p, y = self.handle.orientation(d)
        return PoseReading("GroundTruth", self.name, self.handle.location(d), (wrap_2pi(r), wrap_2pi(p), wrap_2pi(y)))


@dataclass(frozen=True, kw_only=True)
class InsConfig(SensorConfig):
    """An INS's settings in a robot file (protocol.md 7.7): its scan interval, the Sigma and Mean of its noisy
    increments, and the Precision and Drifting that set its per-axis biases."""

    # INS (protocol.md 7.7): ScanInterval 0.2, Sigma 0.05, Precision 1000, Drifting.
    scan_interval_s: float = 0.2
    sigma: float = 0.05
    mean: float = 0.0
    precision: float = 1000.0
    drifting: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.sigma < 0 or self.precision <= 0:
            raise ValueError("sigma must be >= 0 and precision > 0")


class InsMotion(NamedTuple):
    """What an INS senses in one tick: the true pose of its robot (location, Euler angles),
    its change since the last tick (that of the angles wrapped to [-pi, pi)), the distance
    moved and whether the estimate integrates yet (False until the robot has settled)."""

    loc: np.ndarray
    ori: np.ndarray
    dloc: np.ndarray
    dori: np.ndarray
    moved: float
    integrating: bool


class InsDrift(Noise):
    """The drift of an INS (protocol.md 7.7: Sigma, Mean, Precision, Drifting): its estimated
    pose integrates noisy increments of the true pose.  Each tick the true change of every
    Euler angle is scaled by (1 + N(meanRot, Sigma)), and the true displacement d is added
    with |d| x N(meanPos, Sigma) on each axis.  The means are the configured Mean or, with
    Drifting, per-axis biases drawn once (:meth:`draw_means`: U(-0.5, 0.5) / Precision^2 for
    the angles, U(-0.5, 0.5) / Precision for the location), at reset and when a client sets the
    pose.  Until the robot has settled the estimate is the true pose.  ``true``: an
    :class:`InsMotion`; the result: the estimated location and Euler angles (arrays), kept on
    the sensor (``est_loc``, ``est_ori``) with the drawn means (``_mean_rot``, ``_mean_pos``)."""

    def draw_means(self, ins: INS) -> None:
        """The means of the sensor's increments' noise, from its settings (drawn with Drifting)."""
        c = ins.config
        if c.drifting:
            ins._mean_rot = ins.rng.uniform(-0.5, 0.5, 3) / c.precision**2
            ins._mean_pos = ins.rng.uniform(-0.5, 0.5, 3) / c.precision
        else:
            ins._mean_rot = np.full(3, c.mean)
            ins._mean_pos = np.full(3, c.mean)

    def apply(self, sensor: Sensor[Any], true: Any) -> Any:
        if not isinstance(sensor, INS):
            raise TypeError(f"InsDrift is an INS's noise, not a {type(sensor).__name__}'s")
        c = sensor.config
        m: InsMotion = true
        if not m.integrating:
            sensor.est_loc, sensor.est_ori = m.loc.copy(), m.ori.copy()
        else:
            sensor.est_ori = sensor.est_ori + m.dori * (1.0 + sensor.rng.normal(sensor._mean_rot, c.sigma))
            sensor.est_loc = sensor.est_loc + m.dloc + m.moved * sensor.rng.normal(sensor._mean_pos, c.sigma)
        return sensor.est_loc, sensor.est_ori


INS_DRIFT = InsDrift()


@SENSORS.register("INS")
class INS(Sensor[InsConfig]):
    """Integrates noisy increments of the true pose (its noise, :class:`InsDrift`): it
    senses the true pose and its change each tick.  Integration starts after the robot has
    been at rest for one tick."""

    ALIASES = {"Sigma": "sigma", "Mean": "mean", "Precision": "precision", "Drifting": "drifting"}
    NOISE = INS_DRIFT
    est_loc: np.ndarray  # the estimated pose (InsDrift's)
    est_ori: np.ndarray
    _mean_rot: np.ndarray  # the means of its increments' noise (InsDrift.draw_means)
    _mean_pos: np.ndarray

    def _true(self, view: WorldView) -> tuple[np.ndarray, np.ndarray]:
        d = view.data
        return np.array(self.handle.location(d)), np.array(self.handle.orientation(d))

    def reset(self, view: WorldView) -> None:
        loc, ori = self._true(view)
        self.est_loc = loc.copy()
        self.est_ori = ori.copy()
        self._last_loc, self._last_ori = loc, ori
        self._started = False
        self._reset_time = view.time
        INS_DRIFT.draw_means(self)

    def sense(self, view: WorldView) -> InsMotion:
        """The true pose, its change since the last tick, and whether the estimate integrates
        yet."""
        loc, ori = self._true(view)
        dloc = loc - self._last_loc
        dori = (ori - self._last_ori + math.pi) % (2 * math.pi) - math.pi
        self._last_loc, self._last_ori = loc, ori
        moved = float(np.linalg.norm(dloc))
        integrating = self._started
        if not self._started:
            # wait until the robot has settled (e.g. after dropping onto the floor):
            # a tick after spawn with the chassis at rest
            qv = view.data.qvel[self.handle.root_qvel : self.handle.root_qvel + 6]
            if view.time > self._reset_time and float(np.abs(qv).max()) < 0.02:
                self._started = True
        return InsMotion(loc, ori, dloc, dori, moved, integrating)

    def reading(self, values: tuple[np.ndarray, np.ndarray]) -> PoseReading:
        """The estimated pose (location, Euler angles) as a reading."""
        est_loc, est_ori = values
        o = tuple(wrap_2pi(float(a)) for a in est_ori)
        x, y, z = (float(v) for v in est_loc)
        roll, pitch, yaw = o
        return PoseReading("INS", self.name, (x, y, z), (roll, pitch, yaw))

    def operate(self, view: WorldView, opcode: str, params: ItemParams) -> OperationResult | None:
        """``{Opcode POSE} {Params x,y,z,roll,pitch,yaw}`` (UDK, protocol.md 5.4): the
        estimate starts over from that pose."""
        if opcode.upper() != "POSE" or not params.text:
            return None
        vals = params.values
        if vals is None or len(vals) != 6:
            return OperationResult(ok=False)
        self.est_loc = np.array(vals[:3])
        self.est_ori = np.array(vals[3:])
        INS_DRIFT.draw_means(self)
        return OperationResult(ok=True)
