"""Single-beam range sensors: the generic RangeSensor, Sonar (cone model) and IR
(protocol.md 7.2).  All items of one type on a robot are reported together in one
packed SEN line."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Self, TypeVar

import mujoco
import numpy as np

from usarsim.readings import FieldValue, RangeItem, RangeReading
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig, check_range
from usarsim.sensors.noise import RANGES
from usarsim.sim import frames
from usarsim.sim.robotspec import add_housing
from usarsim.sim.view import unit_dirs_yaw_pitch

if TYPE_CHECKING:
    from usarsim.config.robot import MountedItem, RobotConfig
    from usarsim.sim.view import WorldView


@dataclass(frozen=True, kw_only=True)
class RangeSensorConfig(SensorConfig):
    """A single-beam range sensor's settings in a robot file (protocol.md 7.2): the range it reports within, in
    metres, its relative noise and its scan interval."""

    # UDK RangeSensor defaults (protocol.md 7.2): MaxRange 3 m; base noise 0.001 (7.1).
    max_range_m: float = 3.0
    min_range_m: float = 0.0
    noise: float = 0.001
    scan_interval_s: float = 0.2

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range(self.min_range_m, self.max_range_m)


RC = TypeVar("RC", bound=RangeSensorConfig)


@SENSORS.register("RangeSensor")
class RangeSensor(Sensor[RC]):
    """One ray along the sensor's X axis; MaxRange when nothing is hit; clamped."""

    PACKED = True
    RAY_KIND = "laser"  # which materials the rays pass through (world materials' see_through)
    Config = RangeSensorConfig
    NOISE = RANGES
    ALIASES = {"MaxRange": "max_range_m", "MinRange": "min_range_m"}

    def _directions(self) -> np.ndarray:
        return np.array([[1.0, 0.0, 0.0]])

    def _true_range(self, view: WorldView) -> float:
        pos, rot = self.handle.sensor_frame(view.data, self.item.location, self.item.orientation, self.item.mount)
        dirs = self._directions() @ rot.T
        dist, _, _ = view.caster.cast(pos, dirs, self.config.max_range_m, self.handle.body_id, kind=self.RAY_KIND)
        return float(dist.min())

    def sense(self, view: WorldView) -> float:
        return self._true_range(view)

    def reading(self, values: float) -> RangeItem:
        return RangeItem(self.name, values)

    @classmethod
    def combine(cls, parts: list[RangeItem]) -> RangeReading:
        return RangeReading(cls.TYPE, tuple(parts))

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        return (("MaxRange", self.config.max_range_m), ("MinRange", self.config.min_range_m))


@dataclass(frozen=True, kw_only=True)
class SonarConfig(RangeSensorConfig):
    """A Sonar's settings in a robot file (protocol.md 7.2): its range, the full angle of its cone and the largest
    angle of incidence an echo comes back from (rad), and how many rays trace the cone."""

    # SonarSensor defaults (protocol.md 7.2): MaxRange 5, MinRange 0.1, beam angle 0.349 rad
    # (20 degree full cone), maximum angle of incidence 0.1745 rad, ScanInterval 0.2.
    max_range_m: float = 5.0
    min_range_m: float = 0.1
    beam_angle_rad: float = 0.3491
    max_angle_of_incidence_rad: float = 0.1745
    # The UDK sonar traced 10 cones of 16 rays.  Two cones of 8 rays (17 rays with the
    # centre one) keep 64 robots with 16 sonars each faster than real time; raise them
    # in a robot file (numberOfCones, tracesPerCone) for a finer cone.
    number_of_cones: int = 2
    traces_per_cone: int = 8

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (0.0 < self.beam_angle_rad < math.pi):
            raise ValueError(f"beam_angle_rad must be within (0, pi), got {self.beam_angle_rad}")
        if self.number_of_cones < 0 or self.traces_per_cone < 1:
            raise ValueError("number_of_cones must be >= 0 and traces_per_cone >= 1")


@SENSORS.register("Sonar")
class Sonar(RangeSensor[SonarConfig]):
    """Cone model: a centre ray plus rays on concentric cones inside the beam angle;
    the range is the nearest hit among rays whose angle of incidence on the surface
    they hit is below the maximum (specular surfaces at grazing angles are not seen)."""

    RAY_KIND = "sonar"
    ALIASES = {
        **RangeSensor.ALIASES,
        "BeamAngle": "beam_angle_rad",
        "beamAngle": "beam_angle_rad",
        "maxAngleOfIncidence": "max_angle_of_incidence_rad",
        "numberOfCones": "number_of_cones",
        "tracesPerCone": "traces_per_cone",
    }

    def build(self, spec: mujoco.MjSpec, chassis: mujoco.MjsBody, prefix: str) -> None:
        """What cameras see of it: a Polaroid 600 series transducer's gold foil, 38.5 mm across
        (Polaroid 600 Series Instrument Grade Electrostatic Transducer data sheet), its face at
        the sensor."""
        add_housing(
            spec, chassis, self.item, prefix, disc=(0.019, 0.006), rgb=(0.72, 0.62, 0.35), offset=(-0.004, 0, 0)
        )

    def __init__(self, item: MountedItem, config: SonarConfig, robot: RobotConfig, seed: int) -> None:
        super().__init__(item, config, robot, seed)
        cfg = self.config
        yaws, pitches = [0.0], [0.0]
        half = cfg.beam_angle_rad / 2.0
        for c in range(1, cfg.number_of_cones + 1):
            cone = half * c / cfg.number_of_cones
            for k in range(cfg.traces_per_cone):
                a = 2.0 * math.pi * k / cfg.traces_per_cone
                yaws.append(cone * math.cos(a))
                pitches.append(cone * math.sin(a))
        self._dirs = unit_dirs_yaw_pitch(np.array(yaws), np.array(pitches))
        # the robot's stacked sonar mounts, built on the first group measurement
        self._stack: tuple[Any, ...] | None = None

    def _directions(self) -> np.ndarray:
        return self._dirs

    def _true_range(self, view: WorldView) -> float:
        pos, rot = self.handle.sensor_frame(view.data, self.item.location, self.item.orientation, self.item.mount)
        dirs = self._dirs @ rot.T
        dist, nrm, _ = view.caster.cast(
            pos, dirs, self.config.max_range_m, self.handle.body_id, normals=True, kind=self.RAY_KIND
        )
        hit = np.isfinite(dist)
        assert nrm is not None  # asked for
        if not hit.any():
            return math.inf
        cos_inc = np.abs(np.einsum("ij,ij->i", dirs, nrm))
        ok = hit & (cos_inc >= math.cos(self.config.max_angle_of_incidence_rad))
        if not ok.any():
            return math.inf
        return float(dist[ok].min())

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        return (
            ("MaxRange", self.config.max_range_m),
            ("MinRange", self.config.min_range_m),
            ("BeamAngle", self.config.beam_angle_rad),
        )

    @classmethod
    def measure_group(cls, sensors: list[Self], view: WorldView) -> list[RangeItem]:
        """All sonars of a robot in one batched cast: every cone ray from its own
        sonar's position, with the mount transforms stacked once per robot."""
        first = sensors[0]
        h, d = first.handle, view.data
        if any(s.item.mount != "HARD" for s in sensors):  # on moving parts: each from its own frame
            return [s.measure(view) for s in sensors]
        key = tuple(id(s) for s in sensors)
        stack = first._stack
        if stack is None or stack[0] != key:
            locs = np.concatenate(
                [np.repeat(frames.to_mj_vec(s.item.location)[None, :], len(s._dirs), axis=0) for s in sensors]
            )
            dirs = np.concatenate([s._dirs @ frames.usar_euler_to_mj_mat(s.item.orientation).T for s in sensors])
            counts = np.array([len(s._dirs) for s in sensors])
            stack = (
                key,
                locs,
                dirs,
                np.repeat(np.arange(len(sensors)), counts),
                np.cumsum(counts) - counts,
                np.array([math.cos(s.config.max_angle_of_incidence_rad) for s in sensors]),
                max(s.config.max_range_m for s in sensors),
            )
            first._stack = stack
        _, locs, local_dirs, owner, starts, cos_max, reach = stack
        rot = h.rotation_mj(d)
        origins = locs @ rot.T + h.position_mj(d)
        u = local_dirs @ rot.T
        dist, nrm, _ = view.caster.cast_from(origins, u, reach, h.body_id, normals=True, kind=first.RAY_KIND)
        assert nrm is not None  # asked for
        seen = np.isfinite(dist) & (np.abs(np.einsum("ij,ij->i", u, nrm)) >= cos_max[owner])
        nearest = np.minimum.reduceat(np.where(seen, dist, np.inf), starts)
        noise = cls.NOISE.apply  # each sonar's own noise, in order, from its own generator
        return [RangeItem(s.name, noise(s, r)) for s, r in zip(sensors, nearest.tolist())]


@dataclass(frozen=True, kw_only=True)
class IRConfig(RangeSensorConfig):
    """An IR sensor's settings in a robot file (protocol.md 7.2): a shorter range than a sonar's, in metres."""

    # IRSensor defaults (protocol.md 7.2): MaxRange 1.5, MinRange 0.2.
    max_range_m: float = 1.5
    min_range_m: float = 0.2


@SENSORS.register("IR")
class IR(RangeSensor[IRConfig]):
    """A single ray that passes through the materials IR sees through (glass), protocol.md 7.2."""

    RAY_KIND = "ir"
