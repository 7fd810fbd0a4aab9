"""What an environment needs to know of a robot class: its sensors as GETGEO and GETCONF
report them, its drive and battery life from its robot file, and from them the
observation and action spaces."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from gymnasium import spaces

from usarsim.client import Robot
from usarsim.config.catalog import resolve_robot
from usarsim.config.robot import RobotConfig
from usarsim.config.world import WorldConfig

OBSERVATIONS = ("laser", "sonar", "odometry", "battery", "victims")
"""The observation keys an environment can have, in the order of its Dict space."""

DRIVES = ("skid", "legged")
"""Drives whose DRIVE takes a left and a right side speed (``{Left} {Right}``, percent with
``{Normalized True}``): skid-steered and tracked robots, and legged robots walking as one."""

DISCRETE_ACTIONS = (
    ("forward", (1.0, 1.0)),
    ("left", (-0.5, 0.5)),
    ("right", (0.5, -0.5)),
    ("back", (-1.0, -1.0)),
    ("stop", (0.0, 0.0)),
)
"""The discrete actions in order, as (left, right) side speeds, fractions of the top speed."""

MAX_VICTIM_PARTS = 1024.0
"""The bound of the victim summary's part count (a VictSensor sweep of the default 40 x 40
degree field in 4 degree steps reports at most 4 x 11 x 11 parts; wider sensors are clipped)."""


@dataclass(frozen=True)
class LaserSpec:
    """A robot's first RangeScanner: its name, range, beam count and where it sits on the
    robot (x forward, y right, yaw clockwise; metres, radians)."""

    name: str
    max_range_m: float
    resolution_rad: float
    fov_rad: float
    mount: tuple[float, float, float]

    @property
    def beams(self) -> int:
        """Beams per sweep: floor(FOV / Resolution) + 1 of the CONF values (181 on a SICK LMS200)."""
        return int(math.floor(self.fov_rad / self.resolution_rad + 1e-9)) + 1


@dataclass(frozen=True)
class RobotSpec:
    """A robot class as an environment sees it: what GETGEO and GETCONF report of its
    sensors (see :func:`describe_robot`), and its drive and battery life from its robot file."""

    class_name: str
    drive: str
    battery_s: float
    laser: LaserSpec | None
    sonars: tuple[str, ...]
    sonar_max_range_m: float
    victim_sensor: str | None
    victim_max_range_m: float
    victim_mount: tuple[float, float]
    touch: bool
    odometry: bool
    ground_truth: bool

    def available(self) -> tuple[str, ...]:
        """The observation keys this robot can fill."""
        have = {
            "laser": self.laser is not None,
            "sonar": bool(self.sonars),
            "odometry": self.odometry,
            "battery": True,
            "victims": self.victim_sensor is not None,
        }
        return tuple(k for k in OBSERVATIONS if have[k])


def robot_config(class_name: str, robot_dirs: tuple[str, ...] = ()) -> RobotConfig:
    """A robot class's file (shipped, or in one of ``robot_dirs``), refused with ValueError
    when an environment cannot drive it."""
    cfg = resolve_robot(class_name, extra_dirs=robot_dirs)
    if cfg.drive not in DRIVES:
        raise ValueError(
            f"robot class {cfg.class_name} has the {cfg.drive!r} drive; the environments drive "
            f"robots by a left and a right side speed ({', '.join(DRIVES)} drives)"
        )
    return cfg


def _mount_xy(cfg: RobotConfig, location, mount: str) -> tuple[float, float]:
    """An item's place on the robot seen from above (x forward, y right), following the
    links it is mounted on with their joints at zero."""
    x, y = float(location[0]), float(location[1])
    links = {ln.name: ln for ln in cfg.links}
    seen = set()
    while mount in links and mount not in seen:
        seen.add(mount)
        link = links[mount]
        x += link.location[0]
        y += link.location[1]
        mount = link.parent
    return (x, y)


def _items(robot: Robot, item_type: str) -> list[tuple[str, dict[str, float], Any]]:
    """(name, numeric CONF fields by lower-case key, GEO pose) of each of the robot's items
    of a type, in the order GETGEO lists them."""
    conf = {i.name: i.fields for i in getattr(robot.conf(item_type), "items", ())}
    out = []
    for pose in getattr(robot.geo(item_type), "items", ()):
        fields = {}
        for key, value in conf.get(pose.name, ()):
            try:
                fields[key.lower()] = float(value)
            except (TypeError, ValueError):
                continue
        out.append((pose.name, fields, pose))
    return out


def describe_robot(cfg: RobotConfig, robot: Robot) -> RobotSpec:
    """The spec of a robot class from one of its robots in a simulator: its sensors' GETGEO
    and GETCONF (the names, places and ranges the simulator reports)."""
    laser = None
    scanners = _items(robot, "RangeScanner")
    if scanners:
        name, f, pose = scanners[0]
        laser = LaserSpec(
            name,
            f.get("maxrange", 20.0),
            f.get("resolution", 0.0174),
            f.get("fov", math.pi),
            (*_mount_xy(cfg, pose.location, pose.mount), float(pose.orientation[2])),
        )
    sonars = _items(robot, "Sonar")
    victims = _items(robot, "VictSensor")
    return RobotSpec(
        class_name=cfg.class_name,
        drive=cfg.drive,
        battery_s=float(cfg.battery_s),
        laser=laser,
        sonars=tuple(name for name, _, _ in sonars),
        sonar_max_range_m=max((f.get("maxrange", 5.0) for _, f, _ in sonars), default=0.0),
        victim_sensor=victims[0][0] if victims else None,
        victim_max_range_m=victims[0][1].get("maxrange", 4.0) if victims else 0.0,
        victim_mount=_mount_xy(cfg, victims[0][2].location, victims[0][2].mount) if victims else (0.0, 0.0),
        touch=bool(_items(robot, "Touch")),
        odometry=bool(_items(robot, "Odometry")),
        ground_truth=bool(_items(robot, "GroundTruth")),
    )


def check_robot(spec: RobotSpec, observations: tuple[str, ...] | None) -> tuple[str, ...]:
    """The observation keys to use (``None``: every one the robot can fill); an unknown key,
    one the robot has no sensor for, or a robot without the GroundTruth sensor the reward
    needs raises ValueError."""
    if not spec.ground_truth:
        raise ValueError(
            f"robot class {spec.class_name} has no GroundTruth sensor, which the exploration reward "
            "and the termination need"
        )
    if observations is None:
        return spec.available()
    out = []
    for key in observations:
        if key not in OBSERVATIONS:
            raise ValueError(f"unknown observation {key!r}; known: {', '.join(OBSERVATIONS)}")
        if key not in spec.available():
            raise ValueError(
                f"robot class {spec.class_name} has no sensor for the observation {key!r}; it can "
                f"fill {', '.join(spec.available())}"
            )
        if key not in out:
            out.append(key)
    if not out:
        raise ValueError("an environment needs at least one observation")
    return tuple(k for k in OBSERVATIONS if k in out)


def world_bounds(world: WorldConfig, margin_m: float = 1.0) -> tuple[float, float, float, float]:
    """(x min, y min, x max, y max) of the world's floor, ``margin_m`` wider on each side."""
    (cx, cy), (sx, sy) = world.floor.center, world.floor.size
    return (cx - sx / 2 - margin_m, cy - sy / 2 - margin_m, cx + sx / 2 + margin_m, cy + sy / 2 + margin_m)


def observation_space(spec: RobotSpec, keys: tuple[str, ...], laser_beams: int, world: WorldConfig) -> spaces.Dict:
    """The Dict of float32 Boxes for ``keys``: ``laser`` (``laser_beams`` ranges, metres,
    right to left), ``sonar`` (one range per sonar, metres, in the robot file's order),
    ``odometry`` (x, y metres from the start, yaw radians in [-pi, pi], clockwise),
    ``battery`` (the fraction left), ``victims`` (victim parts seen, bearing of the nearest
    in radians, 0 ahead and positive to the left, and its distance in metres)."""
    xmin, ymin, xmax, ymax = world_bounds(world)
    extent = float(math.hypot(xmax - xmin, ymax - ymin))
    out: dict[str, spaces.Space[Any]] = {}
    for key in keys:
        if key == "laser":
            assert spec.laser is not None
            out[key] = spaces.Box(0.0, spec.laser.max_range_m, (laser_beams,), np.float32)
        elif key == "sonar":
            out[key] = spaces.Box(0.0, spec.sonar_max_range_m, (len(spec.sonars),), np.float32)
        elif key == "odometry":
            out[key] = spaces.Box(
                np.array([-extent, -extent, -math.pi], np.float32),
                np.array([extent, extent, math.pi], np.float32),
                (3,),
                np.float32,
            )
        elif key == "battery":
            out[key] = spaces.Box(0.0, 1.0, (1,), np.float32)
        elif key == "victims":
            out[key] = spaces.Box(
                np.array([0.0, -math.pi, 0.0], np.float32),
                np.array([MAX_VICTIM_PARTS, math.pi, spec.victim_max_range_m], np.float32),
                (3,),
                np.float32,
            )
    return spaces.Dict(out)


def action_space(discrete: bool) -> spaces.Space:
    """Two side speeds in [-1, 1] (fractions of the top speed; left, right), or
    :data:`DISCRETE_ACTIONS` by number."""
    if discrete:
        return spaces.Discrete(len(DISCRETE_ACTIONS))
    return spaces.Box(-1.0, 1.0, (2,), np.float32)


def side_speeds(action, discrete: bool) -> tuple[float, float]:
    """(left, right) in [-1, 1] for an action of :func:`action_space`."""
    if discrete:
        a = int(np.asarray(action).item())
        if not 0 <= a < len(DISCRETE_ACTIONS):
            raise ValueError(
                f"a discrete action is 0..{len(DISCRETE_ACTIONS) - 1} "
                f"({', '.join(n for n, _ in DISCRETE_ACTIONS)}), got {action!r}"
            )
        return DISCRETE_ACTIONS[a][1]
    v = np.asarray(action, dtype=float).reshape(-1)
    if v.shape != (2,) or not np.all(np.isfinite(v)):
        raise ValueError(f"a continuous action is two finite side speeds in [-1, 1], got {action!r}")
    v = np.clip(v, -1.0, 1.0)
    return (float(v[0]), float(v[1]))
