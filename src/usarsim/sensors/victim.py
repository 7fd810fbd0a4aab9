"""The victim sensor (``VictSensor``, protocol.md 7.9) and the HumanMotion and Sound
sensors of the earlier USARSim versions (protocol.md 6.3).

VictSensor traces a grid of rays across its field of view.  The grid is traced in
four interleaved sub-grids, one per ScanInterval, each offset by half a step; the hits
accumulate and one SEN line goes out after the fourth (every 0.8 s at 0.2 s).  Every
ray that hits a victim's body part adds ``{PartName p} {Location x,y,z}`` with the hit
point in the sensor's frame plus Gaussian noise of sigma = distance x Sigma per axis.
A ray that hits a false-alarm object is reported as the object's part unless a
Gaussian test rejects it: rejected when |d (g - Mean)| <= Sigma x MaxRange / 3 for a
draw g.  The rays see through what cameras see through (glass).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from usarsim.readings import FieldValue, VictimPart, VictimReading
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig
from usarsim.sim import frames
from usarsim.sim.view import unit_dirs_yaw_pitch

if TYPE_CHECKING:
    from usarsim.config.robot import MountedItem, RobotConfig
    from usarsim.sim.view import WorldView

SUBGRIDS = 4  # interleaved sub-grids, one traced per ScanInterval (protocol.md 7.9)


@dataclass(frozen=True, kw_only=True)
class VictSensorConfig(SensorConfig):
    """A VictSensor's settings in a robot file (protocol.md 7.9): its range in metres, its field of view and the step
    between its rays (rad) both ways, the Sigma and Mean of its noise and false-alarm test, and its scan interval."""

    # protocol.md 7.9: Distance/MaxRange 4 m, HorizontalFOV and VerticalFOV 0.6981 rad (40 deg),
    # HorizontalStep/VerticalStep 0.0698 rad (4 deg), Sigma 0.05, ScanInterval 0.2.
    max_range_m: float = 4.0
    horizontal_fov_rad: float = 0.6981
    vertical_fov_rad: float = 0.6981
    horizontal_step_rad: float = 0.0698
    vertical_step_rad: float = 0.0698
    sigma: float = 0.05
    mean: float = 0.0
    scan_interval_s: float = 0.2

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.max_range_m <= 0 or self.sigma < 0:
            raise ValueError("max_range_m must be > 0 and sigma >= 0")
        for step, fov in (
            (self.horizontal_step_rad, self.horizontal_fov_rad),
            (self.vertical_step_rad, self.vertical_fov_rad),
        ):
            if not (0.0 < step <= fov < math.pi):
                raise ValueError(f"need 0 < step <= fov < pi, got step {step} and fov {fov}")


@SENSORS.register("VictSensor", "VictimSensor")
class VictSensor(Sensor[VictSensorConfig]):
    """The victim sensor (protocol.md 6.3, 7.9): the victims' parts its rays hit within its
    field of view and range, named and located in the robot's frame."""

    RAY_KIND = "camera"
    ALIASES = {
        "MaxRange": "max_range_m",
        "Distance": "max_range_m",
        "HorizontalFOV": "horizontal_fov_rad",
        "VerticalFOV": "vertical_fov_rad",
        "HorizontalStep": "horizontal_step_rad",
        "VerticalStep": "vertical_step_rad",
        "Sigma": "sigma",
        "Mean": "mean",
    }

    def __init__(self, item: MountedItem, config: VictSensorConfig, robot: RobotConfig, seed: int) -> None:
        super().__init__(item, config, robot, seed)
        c = self.config
        nh = int(math.floor(c.horizontal_fov_rad / c.horizontal_step_rad + 1e-6)) + 1
        nv = int(math.floor(c.vertical_fov_rad / c.vertical_step_rad + 1e-6)) + 1
        self._grids = []
        for k in range(SUBGRIDS):
            dy = (k % 2) * c.horizontal_step_rad / 2.0
            dp = (k // 2) * c.vertical_step_rad / 2.0
            yaws = -c.horizontal_fov_rad / 2.0 + dy + c.horizontal_step_rad * np.arange(nh)
            pitches = -c.vertical_fov_rad / 2.0 + dp + c.vertical_step_rad * np.arange(nv)
            keep_y = yaws <= c.horizontal_fov_rad / 2.0 + 1e-9
            keep_p = pitches <= c.vertical_fov_rad / 2.0 + 1e-9
            yy, pp = np.meshgrid(yaws[keep_y], pitches[keep_p], indexing="ij")
            self._grids.append(unit_dirs_yaw_pitch(yy.reshape(-1), pp.reshape(-1)))
        self._tick = 0
        self._found: list[VictimPart] = []

    def reset(self, view: WorldView) -> None:
        self._tick = 0
        self._found = []

    def measure(self, view: WorldView) -> VictimReading | None:
        c = self.config
        ents = view.entities
        pos, rot = self.handle.sensor_frame(view.data, self.item.location, self.item.orientation, self.item.mount)
        dirs_local = self._grids[self._tick % SUBGRIDS]
        # the grid's corners are the widest its rays go from the sensor's axis
        half = math.atan(math.hypot(math.tan(c.horizontal_fov_rad / 2.0), math.tan(c.vertical_fov_rad / 2.0)))
        if ents is not None and ents.parts and ents.parts_within(view.data, pos, c.max_range_m, rot[:, 0], half):
            dist, _, gid = view.caster.cast(
                pos, dirs_local @ rot.T, c.max_range_m, self.handle.body_id, kind=self.RAY_KIND
            )
        else:  # no victim or false alarm within reach: nothing to trace
            dist = np.empty(0)
        if ents is not None:
            for i in np.flatnonzero(np.isfinite(dist)).tolist():
                hit = ents.parts.get(int(gid[i]))
                if hit is None:
                    continue
                d = float(dist[i])
                if hit.false_alarm:
                    g = float(self.rng.normal())
                    if abs(d * (g - c.mean)) <= c.sigma * c.max_range_m / 3.0:
                        continue  # the Gaussian test saw through it
                # hit point in the sensor frame (USARSim axes), with per-axis noise
                local_mj = dirs_local[i] * d
                x, y, z = frames.from_mj_vec(local_mj)
                noise = self.rng.normal(0.0, c.sigma * d, 3) if c.sigma > 0 else np.zeros(3)
                self._found.append(
                    VictimPart(
                        hit.part,
                        (x + float(noise[0]), y + float(noise[1]), z + float(noise[2])),
                        None if hit.false_alarm else hit.owner,
                    )
                )
        self._tick += 1
        if self._tick % SUBGRIDS:
            return None
        found, self._found = self._found, []
        return VictimReading(self.name, tuple(found))

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        c = self.config
        return (
            ("MaxRange", c.max_range_m),
            ("HorizontalFOV", c.horizontal_fov_rad),
            ("VerticalFOV", c.vertical_fov_rad),
        )
