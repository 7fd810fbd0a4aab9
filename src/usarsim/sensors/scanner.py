"""Scanning range finders (protocol.md 7.3): RangeScanner with SICK LMS200 and
Hokuyo URG-04LX presets.  All beams of one sweep are cast at one instant in one
batched ray cast; the first value is the rightmost beam."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from usarsim.readings import RangeScanReading
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig
from usarsim.sim.view import unit_dirs_yaw_pitch


def trunc4(x: float) -> float:
    """USARSim printed scanner Resolution and FOV truncated to 4 decimals (0.0174, 3.1415)."""
    return math.trunc(x * 10000.0) / 10000.0


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
        if not (0.0 <= self.min_range_m < self.max_range_m):
            raise ValueError(f"need 0 <= min_range_m < max_range_m, got {self.min_range_m}, {self.max_range_m}")
        if not (0.0 < self.resolution_rad <= self.fov_rad <= 2 * math.pi):
            raise ValueError(f"need 0 < resolution_rad <= fov_rad <= 2 pi, got {self.resolution_rad}, {self.fov_rad}")

    @property
    def beam_count(self) -> int:
        # floor(FOV / Resolution) + 1 (181 for 1 degree over 180 degrees); the small
        # tolerance keeps exact multiples from losing a beam to rounding.
        return int(math.floor(self.fov_rad / self.resolution_rad + 1e-6)) + 1


@SENSORS.register("RangeScanner")
class RangeScanner(Sensor):
    Config = RangeScannerConfig
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

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        cfg = self.config
        n = cfg.beam_count
        offsets = cfg.fov_rad / 2.0 - cfg.resolution_rad * np.arange(n)  # rightmost (+yaw) first
        if cfg.tilting and not cfg.panning:
            self._dirs = unit_dirs_yaw_pitch(np.zeros(n), offsets)
        else:
            self._dirs = unit_dirs_yaw_pitch(offsets, np.zeros(n))

    def measure(self, view) -> RangeScanReading:
        cfg = self.config
        pos, rot = self.handle.sensor_frame(view.data, self.item.location, self.item.orientation)
        dist, _, _ = view.caster.cast(pos, self._dirs @ rot.T, cfg.max_range_m, self.handle.body_id)
        hit = np.isfinite(dist)
        values = np.full(len(dist), cfg.max_range_m)
        if hit.any():
            values[hit] = self.relative_noise(dist[hit])
        np.clip(values, cfg.min_range_m, cfg.max_range_m, out=values)
        return RangeScanReading(self.TYPE, self.name, trunc4(cfg.resolution_rad), trunc4(cfg.fov_rad),
                                tuple(values.tolist()))

    def operate(self, view, opcode, params):
        if opcode.upper() == "SCAN":
            return "OK"
        return None

    def conf_fields(self):
        c = self.config
        return (("MaxRange", c.max_range_m), ("MinRange", c.min_range_m), ("Resolution", trunc4(c.resolution_rad)),
                ("Fov", trunc4(c.fov_rad)), ("Paning", c.panning), ("Tilting", c.tilting))
