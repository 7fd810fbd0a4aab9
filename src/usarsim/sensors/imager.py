"""The range imager (``RangeImager``): a depth camera, the UDK's KinectDepth (protocol.md 6.3).

A picture is taken at one instant: one ray per pixel of a pinhole camera (pixels evenly
spaced on the picture plane, as a real depth camera's are), each pixel's value the depth of
what it sees along the optical axis, in metres (USARSim's KinectDepth also turned each range
into a depth).  On the wire the picture goes out as ``Frames`` SEN lines, ``Frame`` counting
from 0, each holding whole rows, the top row first, each row left to right::

    SEN {Time t} {Type RangeImager} {Name KinectDepth} {Frames n} {Frame k}
        {Resolution px,py} {FOV fx,fy} {Range d1,d2,...}

(one line on the wire), depths in millimetres (3 decimals).  ``Frames`` is chosen so that
every line fits the 4,096 bytes old clients read in one line (``frames`` in the robot file
picks it, as UDK's ``FrameCount`` did, when that fits).

As the UDK sensor did, it sends nothing until asked: ``SET {Type RangeImager} {Name n}
{Opcode SCAN}`` (MOAST adds ``{Value 0.0}``) answers ``RES ... {Status OK}`` and then the
picture's lines; ``continuous: true`` in the robot file sends a picture every ScanInterval.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from usarsim.errors import ConfigError
from usarsim.readings import FieldValue, ItemParams, OperationResult, RangeImageReading
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig, check_range
from usarsim.sensors.noise import Noise
from usarsim.sensors.scanner import LINE_LIMIT, trunc4
from usarsim.sim.robotspec import add_housing

if TYPE_CHECKING:
    from usarsim.config.robot import MountedItem, RobotConfig
    from usarsim.sim.view import WorldView

# SEN {Time t} with the widest time a run reaches (as the scanners reckon their lines)
_LONGEST_TIME = "999999999.9999"


@dataclass(frozen=True, kw_only=True)
class RangeImagerConfig(SensorConfig):
    """A range imager's settings in a robot file: its picture (pixels and field of view), the
    depths it reads, how its pictures are split into lines and whether it sends them unasked."""

    # USARSim's KinectDepth (UDK USARSensor KinectDepth.uc, defaultproperties): 320 x 240
    # returns over FovX 1.01226 rad (58 degrees) and FovY 0.7854 rad (45 degrees).  The
    # Kinect for Windows sensor itself gives 640 x 480 depth pixels over 57 x 43 degrees.
    pixels_x: int = 320
    pixels_y: int = 240
    fov_x_rad: float = 1.01226
    fov_y_rad: float = 0.7854
    # Kinect for Windows sensor, default range: depths from 0.8 m to 4.0 m (Microsoft, "Kinect
    # for Windows Sensor Components and Specifications", 2012).  A pixel that sees nothing
    # within reach reads MaxRange (as USARSim's KinectDepth read), one nearer than MinRange
    # reads MinRange.
    min_range_m: float = 0.8
    max_range_m: float = 4.0
    # lines a picture is split into (USARSim's FrameCount, 20 there, whose lines of 3,840
    # depths were ten times the 4,096 bytes old clients read); 0: as few as fit
    frames: int = 0
    scan_interval_s: float = 0.2
    continuous: bool = False  # a picture every ScanInterval, unasked (False: one per SCAN)
    axial_noise: bool = True  # the Kinect's depth noise (KinectNoise); False: exact depths

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range(self.min_range_m, self.max_range_m)
        if not (1 <= self.pixels_x <= 4096 and 1 <= self.pixels_y <= 4096):
            raise ValueError(f"need 1..4096 pixels each way, got {self.pixels_x} x {self.pixels_y}")
        for fov, what in ((self.fov_x_rad, "fov_x_rad"), (self.fov_y_rad, "fov_y_rad")):
            if not (0.0 < fov < math.pi):
                raise ValueError(f"{what} must be within (0, pi) for a pinhole camera, got {fov}")
        if self.frames < 0:
            raise ValueError(f"frames must be >= 0 (0: as few as fit), got {self.frames}")
        if self.frames and self.pixels_y % self.frames:
            raise ValueError(f"frames must divide the {self.pixels_y} rows, got {self.frames}")

    @property
    def focal_px(self) -> tuple[float, float]:
        """Focal lengths in pixels (fx, fy): half the picture over the tangent of half its FOV."""
        return (
            self.pixels_x / 2.0 / math.tan(self.fov_x_rad / 2.0),
            self.pixels_y / 2.0 / math.tan(self.fov_y_rad / 2.0),
        )

    def line_bytes(self, name: str, rows: int) -> int:
        """The bytes, CR LF included, of the longest SEN line holding ``rows`` rows."""
        frames = self.pixels_y // rows
        head = (
            "SEN {Time %s} {Type RangeImager} {Name %s} {Frames %d} {Frame %d} {Resolution %d,%d} "
            "{FOV %s,%s} {Range }\r\n"
            % (
                _LONGEST_TIME,
                name,
                frames,
                frames - 1,
                self.pixels_x,
                self.pixels_y,
                trunc4(self.fov_x_rad),
                trunc4(self.fov_y_rad),
            )
        )
        value = len("%.3f" % self.max_range_m) + 1  # a depth and its comma
        return len(head) + rows * self.pixels_x * value - 1

    def frame_count(self, name: str) -> int:
        """The lines a picture of the sensor ``name`` goes out in (ConfigError-worthy
        ValueError when not even one row fits a line, or ``frames`` makes too long lines)."""
        if self.frames:
            rows = self.pixels_y // self.frames
            if self.line_bytes(name, rows) >= LINE_LIMIT:
                raise ValueError(
                    f"{self.frames} frames of {rows} rows of {self.pixels_x} depths make lines of "
                    f"{self.line_bytes(name, rows)} bytes, more than the {LINE_LIMIT - 1} old clients read: "
                    f"choose more frames, or frames: 0 to have as few as fit"
                )
            return self.frames
        for rows in sorted((d for d in range(1, self.pixels_y + 1) if self.pixels_y % d == 0), reverse=True):
            if self.line_bytes(name, rows) < LINE_LIMIT:
                return self.pixels_y // rows
        raise ValueError(
            f"one row of {self.pixels_x} depths up to {self.max_range_m:g} m makes a line of "
            f"{self.line_bytes(name, 1)} bytes, more than the {LINE_LIMIT - 1} old clients read: choose fewer "
            f"pixels_x or a shorter max_range_m"
        )


class KinectNoise(Noise):
    """The Kinect's axial (depth) noise: Gaussian, of standard deviation
    ``0.0012 + 0.0019 (z - 0.4)^2`` m at depth z (Nguyen, Izadi and Lovell, "Modeling Kinect
    Sensor Noise for Improved 3D Reconstruction and Tracking", 3DIMPVT 2012, eq. 6: surfaces
    turned less than 60 degrees from the sensor); one draw per pixel within reach, from the
    sensor's generator, row by row.  A pixel that sees nothing within MaxRange reads MaxRange;
    every value is held to [MinRange, MaxRange].  ``true``: the depths, NaN where nothing is
    seen."""

    def apply(self, sensor: Sensor[Any], true: np.ndarray) -> np.ndarray:
        c: RangeImagerConfig = sensor.config
        seen = np.isfinite(true) & (true <= c.max_range_m)
        values = np.full(true.shape, c.max_range_m)
        z = true[seen]
        if c.axial_noise and z.size:
            z = z + sensor.rng.standard_normal(z.size) * (0.0012 + 0.0019 * (z - 0.4) ** 2)
        values[seen] = z
        np.clip(values, c.min_range_m, c.max_range_m, out=values)
        return values


KINECT = KinectNoise()


@SENSORS.register("RangeImager", "KinectDepth")
class RangeImager(Sensor[RangeImagerConfig]):
    """A depth camera (see the module's description): every pixel's depth at one instant."""

    NOISE = KINECT
    SCANNABLE = True
    ON_REQUEST = True
    RAY_KIND = "ir"  # a structured-light depth camera sees in the near infrared
    ALIASES = {
        "MaxRange": "max_range_m",
        "MinRange": "min_range_m",
        "PixelsX": "pixels_x",
        "PixelsY": "pixels_y",
        "FovX": "fov_x_rad",
        "FovY": "fov_y_rad",
        "FrameCount": "frames",
    }

    def __init__(self, item: MountedItem, config: RangeImagerConfig, robot: RobotConfig, seed: int) -> None:
        super().__init__(item, config, robot, seed)
        c = self.config
        try:
            self.frames = c.frame_count(self.name)
        except ValueError as exc:
            raise ConfigError(f"invalid {self.TYPE} settings: {exc}", path=robot.path, key=item.key_path) from None
        fx, fy = c.focal_px
        u = (np.arange(c.pixels_x) + 0.5 - c.pixels_x / 2.0) / fx  # right of the axis, per unit ahead
        v = (np.arange(c.pixels_y) + 0.5 - c.pixels_y / 2.0) / fy  # below it
        vv, uu = np.meshgrid(v, u, indexing="ij")  # row by row, the top row first, left to right
        # in the sensor's MuJoCo-frame coordinates (forward, left, up): USARSim's (x, y, z) is (x, -y, -z)
        rays = np.stack([np.ones(uu.size), -uu.reshape(-1), -vv.reshape(-1)], axis=-1)
        norm = np.linalg.norm(rays, axis=1)
        self._dirs = rays / norm[:, None]
        self._cos = 1.0 / norm  # depth per unit of range along each ray
        self._reach = c.max_range_m * float(norm.max())  # a corner ray's range at MaxRange depth
        self._scan = False  # a SCAN asked for a picture

    def build(self, spec: mujoco.MjSpec, chassis: mujoco.MjsBody, prefix: str) -> None:
        """What cameras see of it: a Kinect's bar, 279 x 63 x 38 mm, black (Kinect for Windows),
        its lenses on the front face."""
        add_housing(
            spec, chassis, self.item, prefix, box=(0.063, 0.279, 0.038), rgb=(0.05, 0.05, 0.05), offset=(-0.033, 0, 0)
        )

    def operate(self, view: WorldView, opcode: str, params: ItemParams) -> OperationResult | None:
        result = super().operate(view, opcode, params)
        if result is not None and result.ok and opcode.upper() == "SCAN":
            self._scan = True  # the simulation measures the sensor at once (its picture follows the RES)
        return result

    def measure(self, view: WorldView) -> Any:
        """A picture when one was asked for (or always, ``continuous``); None otherwise."""
        if not (self._scan or self.config.continuous):
            return None
        self._scan = False
        return super().measure(view)

    def sense(self, view: WorldView) -> np.ndarray:
        pos, rot = self.handle.sensor_frame(view.data, self.item.location, self.item.orientation, self.item.mount)
        dist, _, _ = view.caster.cast(pos, self._dirs @ rot.T, self._reach, self.handle.body_id, kind=self.RAY_KIND)
        depth: np.ndarray = dist * self._cos  # inf where nothing is hit stays inf
        return depth

    def reading(self, values: np.ndarray) -> RangeImageReading:
        c = self.config
        return RangeImageReading(
            self.name,
            (c.pixels_x, c.pixels_y),
            (trunc4(c.fov_x_rad), trunc4(c.fov_y_rad)),
            tuple(values.tolist()),
            frames=self.frames,
        )

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        """UDK's KinectDepth CONF (its RangeSensor keys, then ``{Resolution px,py} {Fov fx,fy}``),
        then what a vision client needs besides: the lines of a picture, and the pinhole's focal
        lengths and principal point in pixels (extensions after the documented keys)."""
        c = self.config
        fx, fy = c.focal_px
        return (
            ("ScanInterval", c.scan_interval_s),
            ("MaxRange", c.max_range_m),
            ("MinRange", c.min_range_m),
            ("Resolution", "%d,%d" % (c.pixels_x, c.pixels_y)),
            ("Fov", (trunc4(c.fov_x_rad), trunc4(c.fov_y_rad))),
            ("Frames", self.frames),
            ("FocalLength", (fx, fy)),
            ("PrincipalPoint", (c.pixels_x / 2.0, c.pixels_y / 2.0)),
        )
