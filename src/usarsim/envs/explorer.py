"""One exploring robot: what it is told to do, what it observes and what it earns.

Every step, the messages its connection received are read in order: each laser sweep is
laid on the coverage grid from the robot's ground-truth pose at the sweep's own time, each
victim sensor sweep is matched against the world's victims, every Touch reading counts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from usarsim.client import Robot
from usarsim.coverage import CoverageGrid
from usarsim.readings import PoseReading, RangeReading, RangeScanReading, TouchReading, VictimReading

from .spec import MAX_VICTIM_PARTS, RobotSpec, side_speeds

POSE_HISTORY_S = 1.0  # ground-truth poses kept to place laser sweeps at their own time


@dataclass(frozen=True, kw_only=True)
class Rewards:
    """What an exploring robot earns: ``area`` per square metre of floor seen for the first
    time (cells of ``cell_m``, seen by laser beams up to ``sensing_range_m``), ``victim`` per
    victim detected for the first time (a victim sensor part within ``victim_match_m`` of a
    victim's ground-truth place), minus ``collision`` per step with a Touch sensor touching or
    a laser range under ``collision_range_m``.  The episode ends (terminated) when the battery
    is empty or the robot tilts more than ``flip_deg`` from upright."""

    area: float = 1.0
    victim: float = 10.0
    collision: float = 1.0
    cell_m: float = 0.5
    sensing_range_m: float = 5.0
    collision_range_m: float = 0.2
    victim_match_m: float = 1.5
    flip_deg: float = 60.0

    def __post_init__(self) -> None:
        if not (self.cell_m > 0 and self.sensing_range_m > 0 and self.victim_match_m > 0):
            raise ValueError("cell_m, sensing_range_m and victim_match_m must be > 0")
        if self.collision_range_m < 0 or not 0 < self.flip_deg <= 180:
            raise ValueError("collision_range_m must be >= 0 and flip_deg in (0, 180]")


@dataclass
class Outcome:
    """What one step brought a robot."""

    new_cells: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.intp))
    new_victims: list[str] = field(default_factory=list)
    collision: bool = False
    flipped: bool = False
    battery_empty: bool = False


def wrap_angle(a: float) -> float:
    """``a`` in [-pi, pi]."""
    return float(math.remainder(a, 2.0 * math.pi))


def tilt_rad(roll: float, pitch: float) -> float:
    """How far a body with this roll and pitch is tilted from upright (0: level, pi: upside
    down), whatever the Euler angles' branch."""
    return math.acos(max(-1.0, min(1.0, math.cos(roll) * math.cos(pitch))))


def downsample(ranges: np.ndarray, beams: int) -> np.ndarray:
    """``beams`` ranges from a sweep: the nearest of each of ``beams`` equal groups of
    neighbouring beams (an obstacle seen by any beam of a group is kept)."""
    n = len(ranges)
    if n == beams:
        return ranges.copy()
    starts = (np.arange(beams) * n) // beams
    return np.minimum.reduceat(ranges, starts)


class Explorer:
    """A robot of an environment: its connection (a :class:`usarsim.client.Robot`), its
    class's :class:`RobotSpec`, the observation keys and the reward settings; the coverage
    grid and the set of victims found may be shared with other robots (a team)."""

    def __init__(
        self,
        robot: Robot,
        spec: RobotSpec,
        keys: tuple[str, ...],
        laser_beams: int,
        rewards: Rewards,
        bounds: tuple[float, float, float, float],
        coverage: CoverageGrid,
        victims: dict[str, tuple[float, float]],
        found: set[str],
    ):
        self.robot = robot
        self.spec = spec
        self.keys = keys
        self.laser_beams = laser_beams
        self.rewards = rewards
        self.coverage = coverage
        self.victims = victims
        self.found = found
        self.bounds = bounds
        self.extent = math.hypot(bounds[2] - bounds[0], bounds[3] - bounds[1])
        self.poses: dict[float, tuple[float, ...]] = {}  # simulated time -> x, y, z, roll, pitch, yaw
        self.pose: tuple[float, ...] | None = None
        self.victims_found = 0  # by this robot
        self.speeds: tuple[float, float] | None = None  # of the last DRIVE sent
        self.sent = False  # a command sent since the last step

    def readings_used(self) -> tuple[str, ...]:
        """The types and names of the sensors whose readings the observation and the reward
        read (the rest go unread: an in-process simulator need not measure them)."""
        used = ["GroundTruth", "Touch"]  # the pose of every sweep, and collisions
        if self.spec.laser is not None:
            used.append(self.spec.laser.name)
        if self.spec.victim_sensor is not None:
            used.append(self.spec.victim_sensor)
        used += [{"sonar": "Sonar", "odometry": "Odometry"}[k] for k in self.keys if k in ("sonar", "odometry")]
        return tuple(used)

    # commands -----------------------------------------------------------------------------
    def drive(self, action, discrete: bool) -> None:
        """Send the action's side speeds as one DRIVE (percent of the top speed), unless
        they are those of the last DRIVE (which the robot keeps until told otherwise)."""
        left, right = side_speeds(action, discrete)
        speeds = (round(100.0 * left, 4), round(100.0 * right, 4))
        if speeds != self.speeds:
            self.robot.drive(left=speeds[0], right=speeds[1], normalized=True)
            self.speeds = speeds
            self.sent = True

    def take_sent(self) -> list[Robot]:
        """[the robot] if a command was sent to it since the last call, else []."""
        sent, self.sent = self.sent, False
        return [self.robot] if sent else []

    # what arrived -------------------------------------------------------------------------
    def update(self) -> Outcome:
        """Read the messages received since the last update (the robot's
        :meth:`~usarsim.client.Robot.take_messages`) into the coverage grid and the victims
        found; return what they brought."""
        out = Outcome()
        scans: list[tuple[float | None, RangeScanReading]] = []
        sweeps: list[tuple[float | None, VictimReading]] = []
        laser = self.spec.laser.name if self.spec.laser is not None else None
        for msg in self.robot.take_messages():
            r = getattr(msg, "reading", None)  # SEN lines
            if r is None:
                continue
            if isinstance(r, PoseReading) and r.sensor_type == "GroundTruth":
                self.pose = (*r.location, *r.orientation)
                if msg.time is not None:
                    self.poses[msg.time] = self.pose
            elif isinstance(r, RangeScanReading) and r.name == laser:
                scans.append((msg.time, r))
            elif isinstance(r, TouchReading):
                out.collision = out.collision or any(i.touching for i in r.items)
            elif isinstance(r, VictimReading) and r.name == self.spec.victim_sensor:
                sweeps.append((msg.time, r))
        if self.poses:
            latest = max(self.poses)
            self.poses = {t: p for t, p in self.poses.items() if t >= latest - POSE_HISTORY_S}
        new = [self._lay(t, r) for t, r in scans]
        if new:
            out.new_cells = np.unique(np.concatenate(new))
        for t, r in sweeps:
            out.new_victims += self._match(t, r)
        scan = self.robot.readings.get(laser) if laser else None
        if isinstance(scan, RangeScanReading) and scan.ranges_m and min(scan.ranges_m) < self.rewards.collision_range_m:
            out.collision = True
        if self.pose is not None:
            out.flipped = tilt_rad(self.pose[3], self.pose[4]) > math.radians(self.rewards.flip_deg)
        status = self.robot.status
        out.battery_empty = status is not None and status.battery_s <= 0
        return out

    def _pose_at(self, t: float | None) -> tuple[float, ...] | None:
        if t is not None and t in self.poses:
            return self.poses[t]
        if t is not None and self.poses:
            return self.poses[min(self.poses, key=lambda s: abs(s - t))]
        return self.pose

    def _lay(self, t: float | None, r: RangeScanReading) -> np.ndarray:
        """The cells a sweep sees for the first time, from the robot's pose at its time."""
        pose = self._pose_at(t)
        laser = self.spec.laser
        if pose is None or laser is None or not r.ranges_m:
            return np.zeros(0, dtype=np.intp)
        x, y, yaw = pose[0], pose[1], pose[5]
        mx, my, myaw = laser.mount
        c, s = math.cos(yaw), math.sin(yaw)
        origin = (x + mx * c - my * s, y + mx * s + my * c)
        ranges = np.asarray(r.ranges_m, dtype=float)
        n = len(ranges)
        half = (n - 1) * r.resolution_rad / 2.0
        angles = np.linspace(-half, half, n)  # counter-clockwise, the first beam rightmost
        headings = yaw + myaw - angles  # the USARSim yaw is clockwise
        return self.coverage.mark_beams(origin, headings, np.minimum(ranges, self.rewards.sensing_range_m))

    def _match(self, t: float | None, r: VictimReading) -> list[str]:
        """The victims a victim sensor sweep detects for the first time (for the team)."""
        pose = self._pose_at(t)
        if pose is None or not r.parts or not self.victims:
            return []
        x, y, yaw = pose[0], pose[1], pose[5]
        c, s = math.cos(yaw), math.sin(yaw)
        vx, vy = self.spec.victim_mount
        sx, sy = x + vx * c - vy * s, y + vx * s + vy * c
        names = list(self.victims)
        where = np.array([self.victims[n] for n in names])
        out = []
        for part in r.parts:
            px, py = part.location[0], part.location[1]
            wx, wy = sx + px * c - py * s, sy + px * s + py * c
            d = np.hypot(where[:, 0] - wx, where[:, 1] - wy)
            i = int(np.argmin(d))
            if d[i] <= self.rewards.victim_match_m and names[i] not in self.found:
                self.found.add(names[i])
                out.append(names[i])
        self.victims_found += len(out)
        return out

    def reward(self, out: Outcome) -> float:
        """The reward of one step's outcome."""
        rw = self.rewards
        return (
            rw.area * len(out.new_cells) * self.coverage.cell_area_m2
            + rw.victim * len(out.new_victims)
            - (rw.collision if out.collision else 0.0)
        )

    # what it observes -----------------------------------------------------------------------
    def observation(self) -> dict[str, np.ndarray]:
        """The observation (new arrays every call), within the space of
        :func:`usarsim.envs.spec.observation_space`."""
        spec, readings = self.spec, self.robot.readings
        obs: dict[str, np.ndarray] = {}
        for key in self.keys:
            if key == "laser":
                assert spec.laser is not None
                r = readings.get(spec.laser.name)
                if isinstance(r, RangeScanReading) and len(r.ranges_m) >= self.laser_beams:
                    v = downsample(np.asarray(r.ranges_m, dtype=float), self.laser_beams)
                else:
                    v = np.full(self.laser_beams, spec.laser.max_range_m)
                obs[key] = np.clip(v, 0.0, spec.laser.max_range_m).astype(np.float32)
            elif key == "sonar":
                r = readings.get("Sonar")
                got = {i.name: i.range_m for i in r.items} if isinstance(r, RangeReading) else {}
                v = np.array([got.get(n, spec.sonar_max_range_m) for n in spec.sonars], dtype=float)
                obs[key] = np.clip(v, 0.0, spec.sonar_max_range_m).astype(np.float32)
            elif key == "odometry":
                odo = self.robot.odometry() or (0.0, 0.0, 0.0)
                v = np.array([odo[0], odo[1], wrap_angle(odo[2])], dtype=float)
                obs[key] = np.clip(
                    v, [-self.extent, -self.extent, -math.pi], [self.extent, self.extent, math.pi]
                ).astype(np.float32)
            elif key == "battery":
                st = self.robot.status
                frac = 1.0 if st is None else st.battery_s / spec.battery_s
                obs[key] = np.array([min(1.0, max(0.0, frac))], dtype=np.float32)
            elif key == "victims":
                obs[key] = self._victim_summary(readings.get(spec.victim_sensor or ""))
        return obs

    def _victim_summary(self, r) -> np.ndarray:
        far = self.spec.victim_max_range_m
        if not isinstance(r, VictimReading) or not r.parts:
            return np.array([0.0, 0.0, far], dtype=np.float32)
        loc = np.array([p.location for p in r.parts], dtype=float)
        dist = np.linalg.norm(loc, axis=1)
        i = int(np.argmin(dist))
        bearing = -math.atan2(loc[i, 1], loc[i, 0])  # Y is to the right: positive to the left
        return np.array([min(len(r.parts), MAX_VICTIM_PARTS), bearing, min(float(dist[i]), far)], dtype=np.float32)
