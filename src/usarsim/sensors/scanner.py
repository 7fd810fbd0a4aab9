"""Scanning range finders (protocol.md 7.3): RangeScanner with SICK LMS200 and
Hokuyo URG-04LX presets, IRScanner, RangeScanner3D.  All beams of one sweep are cast at one instant in one
batched ray cast; the first value is the rightmost beam."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from usarsim.readings import FieldValue, RangeScan3DReading, RangeScanReading
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig, check_range
from usarsim.sim.view import unit_dirs_yaw_pitch

if TYPE_CHECKING:
    from usarsim.config.robot import MountedItem, RobotConfig
    from usarsim.sim.view import WorldView


def trunc4(x: float) -> float:
    """USARSim printed scanner Resolution and FOV truncated to 4 decimals (0.0174, 3.1415);
    a value already written with 4 decimals (0.087) keeps them despite binary rounding."""
    scaled = x * 10000.0
    nearest = round(scaled)
    return (nearest if abs(scaled - nearest) < 1e-6 else math.trunc(scaled)) / 10000.0


@dataclass(frozen=True, kw_only=True)
class RangeScannerConfig(SensorConfig):
    # UDK RangeScanner base (protocol.md 7.3): MaxRange 4, MinRange 0.1, ScanInterval 0.2,
    # Resolution 0.157 rad, ScanFov 3.14, pan scan.
    max_range_m: float = 4.0
    min_range_m: float = 0.1
    resolution_rad: float = 0.157
    fov_rad: float = 3.14
    panning: bool = True
    tilting: bool = False
    noise: float = 0.001

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range(self.min_range_m, self.max_range_m)
        if not (0.0 < self.resolution_rad <= self.fov_rad <= 2 * math.pi):
            raise ValueError(f"need 0 < resolution_rad <= fov_rad <= 2 pi, got {self.resolution_rad}, {self.fov_rad}")

    @property
    def beam_count(self) -> int:
        # floor(FOV / Resolution) + 1 (181 for 1 degree over 180 degrees); the small
        # tolerance keeps exact multiples from losing a beam to rounding.
        return int(math.floor(self.fov_rad / self.resolution_rad + 1e-6)) + 1


@SENSORS.register("RangeScanner")
class RangeScanner(Sensor):
    SCANNABLE = True
    Config = RangeScannerConfig
    RAY_KIND = "laser"  # which materials the beams pass through (world materials' see_through)
    ALIASES = {"MaxRange": "max_range_m", "MinRange": "min_range_m", "Resolution": "resolution_rad",
               "ScanFov": "fov_rad", "Fov": "fov_rad", "bYaw": "panning", "bPitch": "tilting",
               "Paning": "panning", "Panning": "panning", "Tilting": "tilting"}
    PRESETS = {
        # SICK LMS200 as USARSim configured it (protocol.md 7.3): 180 degrees, 1 degree,
        # 20 m.  The data sheet (SICK LMS200 Technical Description, 2003) gives 0.25/0.5/1
        # degree angular resolution over 180 degrees and a 10 mm range resolution.
        "SICK": {"max_range_m": 20.0, "min_range_m": 0.1, "resolution_rad": math.pi / 180.0,
                 "fov_rad": math.pi, "scan_interval_s": 0.2},
        # Hokuyo URG-04LX (protocol.md 7.3; Hokuyo URG-04LX specification: 240 degrees,
        # 0.36 degree steps, 4 m, 100 ms scan).  USARSim used 0.0184 rad steps and 0.3 s.
        "HokuyoURG04LX": {"max_range_m": 4.0, "min_range_m": 0.02, "resolution_rad": 0.0184,
                          "fov_rad": 4.189, "scan_interval_s": 0.3},
    }

    def __init__(self, item: MountedItem, config: SensorConfig, robot: RobotConfig, seed: int) -> None:
        super().__init__(item, config, robot, seed)
        cfg = self.config
        n = cfg.beam_count
        offsets = cfg.fov_rad / 2.0 - cfg.resolution_rad * np.arange(n)  # rightmost (+yaw) first
        if cfg.tilting and not cfg.panning:
            self._dirs = unit_dirs_yaw_pitch(np.zeros(n), offsets)
        else:
            self._dirs = unit_dirs_yaw_pitch(offsets, np.zeros(n))

    def measure(self, view: WorldView) -> RangeScanReading:
        cfg = self.config
        pos, rot = self.handle.sensor_frame(view.data, self.item.location, self.item.orientation, self.item.mount)
        dist, _, _ = view.caster.cast(pos, self._dirs @ rot.T, cfg.max_range_m, self.handle.body_id,
                                      kind=self.RAY_KIND)
        hit = np.isfinite(dist)
        values = np.full(len(dist), cfg.max_range_m)
        if hit.any():
            values[hit] = self.relative_noise(dist[hit])
        np.clip(values, cfg.min_range_m, cfg.max_range_m, out=values)
        return RangeScanReading(self.TYPE, self.name, trunc4(cfg.resolution_rad), trunc4(cfg.fov_rad),
                                tuple(values.tolist()))

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        c = self.config
        return (("MaxRange", c.max_range_m), ("MinRange", c.min_range_m), ("Resolution", trunc4(c.resolution_rad)),
                ("Fov", trunc4(c.fov_rad)), ("Paning", c.panning), ("Tilting", c.tilting))


@dataclass(frozen=True, kw_only=True)
class IRScannerConfig(RangeScannerConfig):
    # IRScanner (protocol.md 7.3): MaxRange 10, Resolution 0.087, ScanFov 3.14.
    max_range_m: float = 10.0
    resolution_rad: float = 0.087
    fov_rad: float = 3.14


@SENSORS.register("IRScanner")
class IRScanner(RangeScanner):
    """A scanning infrared range finder: its beams pass through what IR sees through (glass)."""

    Config = IRScannerConfig
    RAY_KIND = "ir"
    PRESETS = {}


# Bytes of range values one SEN line of a 3D scanner may carry: old clients read a line into
# a 4096-byte buffer (protocol.md 1, "keep single lines below 4096 bytes"); the rest of the
# line (Time, Type, Name, Frames, Frame, Resolution, FOV, braces, CR LF) stays well under
# the 512 bytes left.
ROW_BYTES = 4096 - 512


@dataclass(frozen=True, kw_only=True)
class RangeScanner3DConfig(SensorConfig):
    # RangeScanner3D (protocol.md 7.3, UT Tarantula/Ardabot configs): MaxRange 1000
    # (effectively unlimited), ScanInterval 0.4, HorizontalFOV 1.0472, HorizontalResolution
    # 0.0209, VerticalFOV 0.4363, VerticalResolution 0.0145 -> 51 x 31 points.
    max_range_m: float = 1000.0
    min_range_m: float = 0.1
    scan_interval_s: float = 0.4
    horizontal_fov_rad: float = 1.0472
    horizontal_resolution_rad: float = 0.0209
    vertical_fov_rad: float = 0.4363
    vertical_resolution_rad: float = 0.0145
    panning: bool = False
    tilting: bool = True
    noise: float = 0.001

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range(self.min_range_m, self.max_range_m)
        for res, fov, what in ((self.horizontal_resolution_rad, self.horizontal_fov_rad, "horizontal"),
                               (self.vertical_resolution_rad, self.vertical_fov_rad, "vertical")):
            if not (0.0 < res <= fov <= 2 * math.pi):
                raise ValueError(f"need 0 < {what} resolution <= {what} fov <= 2 pi, got {res}, {fov}")
        rows, cols = self.counts
        if rows * cols > 100_000:
            raise ValueError(f"{rows} x {cols} beams is more than 100000 per scan")
        # one row must fit in one SEN line (see RangeScanner3D): its values, each at most
        # len("%.4f" % max_range_m) characters and a comma, within ROW_BYTES
        width = len("%.4f" % self.max_range_m) + 1
        if cols * width > ROW_BYTES:
            raise ValueError(f"a row of {cols} beams up to {self.max_range_m:g} m is {cols * width} bytes, too long "
                             f"for one SEN line (at most {ROW_BYTES // width} beams a row at this MaxRange): "
                             f"choose a coarser horizontal_resolution_rad or a narrower horizontal_fov_rad")

    @property
    def counts(self) -> tuple[int, int]:
        """(rows, columns): vertical steps, horizontal steps."""
        return (int(math.floor(self.vertical_fov_rad / self.vertical_resolution_rad + 1e-6)) + 1,
                int(math.floor(self.horizontal_fov_rad / self.horizontal_resolution_rad + 1e-6)) + 1)


@SENSORS.register("RangeScanner3D", "3DRangeScanner")
class RangeScanner3D(Sensor):
    """A 3D laser (a tilting or panning 2D scanner, as on Kurt3D): all beams of a sweep
    at one instant, every ScanInterval of simulated time, row-major -- one horizontal line
    per vertical step, the top row first, each row from its rightmost beam to its leftmost,
    as the 2D scanner.

    On the wire (protocol.md 6.3) a sweep is one SEN line when that line stays under the
    4096 bytes old clients can read (protocol.md 1)::

        SEN {Time t} {Type RangeScanner3D} {Name n} {Resolution vres,hres} {FOV vfov,hfov} {Range r1,r2,...}

    A longer sweep (the 51 x 31 beams of USARSim's configuration make about 11 kB) is sent
    as one line per row instead, all with the sweep's Time, the top row first, each naming
    its row the way the RangeImager names its frames (protocol.md 6.3)::

        SEN {Time t} {Type RangeScanner3D} {Name n} {Frames rows} {Frame k}
            {Resolution vres,hres} {FOV vfov,hfov} {Range r1,...,r_cols}

    (one line on the wire, broken here for reading).

    ``Frames`` is the number of rows (= lines) of the sweep and ``Frame`` the row this line
    holds, 0 for the top row up to rows - 1; Resolution and FOV are the whole sweep's, so
    row k looks ``vfov / 2 - k * vres`` up.  A row never needs more than one line: the
    configuration refuses rows too long for one.
    """

    SCANNABLE = True
    Config = RangeScanner3DConfig
    RAY_KIND = "laser"
    ALIASES = {"MaxRange": "max_range_m", "MinRange": "min_range_m",
               "HorizontalFOV": "horizontal_fov_rad", "HorizontalResolution": "horizontal_resolution_rad",
               "VerticalFOV": "vertical_fov_rad", "VerticalResolution": "vertical_resolution_rad",
               "bYaw": "panning", "bPitch": "tilting", "Paning": "panning", "Panning": "panning",
               "Tilting": "tilting"}

    def __init__(self, item: MountedItem, config: SensorConfig, robot: RobotConfig, seed: int) -> None:
        super().__init__(item, config, robot, seed)
        c = self.config
        rows, cols = c.counts
        pitches = c.vertical_fov_rad / 2.0 - c.vertical_resolution_rad * np.arange(rows)  # top row first
        yaws = c.horizontal_fov_rad / 2.0 - c.horizontal_resolution_rad * np.arange(cols)  # rightmost first
        pp, yy = np.meshgrid(pitches, yaws, indexing="ij")
        self._dirs = unit_dirs_yaw_pitch(yy.reshape(-1), pp.reshape(-1))

    def measure(self, view: WorldView) -> RangeScan3DReading:
        c = self.config
        pos, rot = self.handle.sensor_frame(view.data, self.item.location, self.item.orientation, self.item.mount)
        dist, _, _ = view.caster.cast(pos, self._dirs @ rot.T, c.max_range_m, self.handle.body_id, kind=self.RAY_KIND)
        values = np.full(len(dist), c.max_range_m)
        hit = np.isfinite(dist)
        if hit.any():
            values[hit] = self.relative_noise(dist[hit])
        np.clip(values, c.min_range_m, c.max_range_m, out=values)
        return RangeScan3DReading(self.name, (trunc4(c.vertical_resolution_rad), trunc4(c.horizontal_resolution_rad)),
                                  (trunc4(c.vertical_fov_rad), trunc4(c.horizontal_fov_rad)), tuple(values.tolist()),
                                  sensor_type=self.TYPE, frames=c.counts[0])

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        c = self.config
        return (("MaxRange", c.max_range_m), ("MinRange", c.min_range_m),
                ("Resolution", (trunc4(c.vertical_resolution_rad), trunc4(c.horizontal_resolution_rad))),
                ("Fov", (trunc4(c.vertical_fov_rad), trunc4(c.horizontal_fov_rad))),
                ("Paning", c.panning), ("Tilting", c.tilting))
