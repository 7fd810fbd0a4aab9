"""Sensors of the earlier USARSim versions that clients still parse (protocol.md 6.3):
``Sound`` (victims groaning) and ``HumanMotion`` (a moving person in view).

Sound: each victim whose world entry has a sound groans for ``duration_s`` once every
``period_s`` (each victim at its own phase).  Its level at the sensor falls with
spherical spreading from 1 m, L = L(1 m) - 20 log10(d), and loses ``WallLoss`` dB for
each wall in between; the loudest sound above ``Threshold`` is reported as
``{Loudness L} {Duration d}``, silence as 0, 0.

HumanMotion: a waving victim whose waving arm is inside the sensor's field of view,
within range and in line of sight is a moving human; the probability falls linearly
from 1 at the sensor to 0 at MaxRange (the larger the motion looks, the surer the
detector), with Gaussian noise, clipped to [0, 1].  The highest wins.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from usarsim.readings import HumanMotionReading, SoundReading
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig
from usarsim.sim import frames, victims

if TYPE_CHECKING:
    from usarsim.config.world import Victim
    from usarsim.sim.view import WorldView


def _walls_between(
    view: WorldView, pos_mj: np.ndarray, target_mj: np.ndarray, kind: str, stop_at_first: bool = False
) -> int:
    """Walls on the segment (``RayCaster.count_walls``); the target's own surface does not count."""
    return int(
        view.caster.count_walls(
            pos_mj[None, :], target_mj[None, :], kind=kind, end_margin=0.05, stop_at_first=stop_at_first
        )[0]
    )


def _victim_point(victim: Victim, local: tuple[float, float, float]) -> np.ndarray:
    """A point of a victim (its own frame, posture applied) in the world, MuJoCo frame."""
    c = victims.victim_part_pose(victim.posture, local, None, None)[0]
    world = np.array(victim.location, dtype=float) + frames.euler_to_mat(*victim.rotation) @ np.array(c)
    return frames.to_mj_vec(world)


@dataclass(frozen=True, kw_only=True)
class SoundConfig(SensorConfig):
    """A Sound sensor's settings in a robot file (protocol.md 6.3): its scan interval, the quietest level it reports
    and the loss through each wall (dB), and the Gaussian noise of a level (dB)."""

    # ScanInterval: the sensor base's 0.1 s (protocol.md 7.1).  Threshold and wall loss
    # are estimates (no USARSim figures survive): a groan is heard down to 20 dB, and a
    # partition wall takes 20 dB off.
    scan_interval_s: float = 0.1
    threshold_db: float = 20.0
    wall_loss_db: float = 20.0
    sigma_db: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.wall_loss_db < 0 or self.sigma_db < 0:
            raise ValueError("wall_loss_db and sigma_db must be >= 0")


@SENSORS.register("Sound", "SoundSensor")
class Sound(Sensor[SoundConfig]):
    """Victims groaning (protocol.md 6.3): the loudest sound above the threshold, spread
    spherically and muffled by walls (see the module's docstring)."""

    ALIASES = {"Threshold": "threshold_db", "WallLoss": "wall_loss_db", "Sigma": "sigma_db"}

    def measure(self, view: WorldView) -> SoundReading:
        c = self.config
        world, ents = view.world, view.entities
        best = (0.0, 0.0)
        if world is not None and ents is not None:
            pos, _ = self.handle.sensor_frame(view.data, self.item.location, self.item.orientation, self.item.mount)
            for v in world.victims:
                if v.sound_loudness_db <= 0:
                    continue
                phase = (zlib.crc32(v.name.encode()) % 1000) / 1000.0 * v.sound_period_s
                if (view.time + phase) % v.sound_period_s >= v.sound_duration_s:
                    continue  # quiet now
                head = _victim_point(v, (0.78, 0.0, 0.0))
                d = max(float(np.linalg.norm(head - pos)), 1.0)
                level = v.sound_loudness_db - 20.0 * math.log10(d)
                if c.wall_loss_db > 0:
                    level -= c.wall_loss_db * _walls_between(view, pos, head, "sonar")
                if c.sigma_db > 0:
                    level += float(self.rng.normal(0.0, c.sigma_db))
                if level >= c.threshold_db and level > best[0]:
                    best = (level, v.sound_duration_s)
        return SoundReading(self.name, best[0], best[1])


@dataclass(frozen=True, kw_only=True)
class HumanMotionConfig(SensorConfig):
    """A HumanMotion sensor's settings in a robot file (protocol.md 6.3): its scan interval, range in metres, field
    of view in radians, and the sigma of the Gaussian noise on the probability."""

    # Estimates (the v2-era sensor's settings are lost): a 60 degree cone, 10 m, noise 0.05.
    scan_interval_s: float = 0.1
    max_range_m: float = 10.0
    fov_rad: float = 1.0472
    sigma: float = 0.05

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.max_range_m <= 0 or not (0 < self.fov_rad <= 2 * math.pi) or self.sigma < 0:
            raise ValueError("need max_range_m > 0, 0 < fov_rad <= 2 pi and sigma >= 0")


@SENSORS.register("HumanMotion", "HumanMotionSensor")
class HumanMotion(Sensor[HumanMotionConfig]):
    """A moving person in view (protocol.md 6.3): the highest probability of a waving victim's
    arm in the field of view, within range and in line of sight (see the module's docstring)."""

    RAY_KIND = "camera"
    ALIASES = {"MaxRange": "max_range_m", "FOV": "fov_rad", "Sigma": "sigma"}

    def measure(self, view: WorldView) -> HumanMotionReading:
        c = self.config
        world = view.world
        best = 0.0
        seen = False
        if world is not None:
            pos, rot = self.handle.sensor_frame(view.data, self.item.location, self.item.orientation, self.item.mount)
            for v in world.victims:
                if not v.waving:
                    continue
                arm = _victim_point(v, victims.shoulder_of(v))
                delta = arm - pos
                d = float(np.linalg.norm(delta))
                if d > c.max_range_m or d < 1e-6:
                    continue
                forward = rot[:, 0]  # the sensor's X axis, world (MuJoCo) frame
                if math.acos(max(-1.0, min(1.0, float(forward @ delta) / d))) > c.fov_rad / 2.0:
                    continue
                if _walls_between(view, pos, arm, self.RAY_KIND, stop_at_first=True):
                    continue
                seen = True
                best = max(best, 1.0 - d / c.max_range_m)
        if seen and c.sigma > 0:
            best += float(self.rng.normal(0.0, c.sigma))
        return HumanMotionReading(self.name, min(max(best, 0.0), 1.0))
