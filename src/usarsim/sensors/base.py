"""The sensor plugin framework: base class, typed configs with USARSim ini aliases,
registration by USARSim type name, seeded noise, scheduling on simulated time.

A sensor measures; it does not format text, open sockets, start threads or draw.
The framework decides when it measures (its ``scan_interval_s`` of simulated
time), gives it its own seeded random generator, and hands its reading, a frozen
dataclass from :mod:`usarsim.readings`, to whoever listens.
"""

from __future__ import annotations

import dataclasses
import math
import zlib
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from usarsim.config.reader import did_you_mean
from usarsim.errors import ConfigError
from usarsim.registry import Registry

if TYPE_CHECKING:
    from usarsim.config.robot import MountedItem, RobotConfig
    from usarsim.sim.view import WorldView


@dataclass(frozen=True, kw_only=True)
class SensorConfig:
    """Settings every sensor has (protocol.md 7.1)."""

    scan_interval_s: float = 0.2
    with_time_stamp: bool = True
    noise: float = 0.0  # relative amplitude, uniform in [-noise, +noise]

    def __post_init__(self) -> None:
        if not (self.scan_interval_s > 0 and math.isfinite(self.scan_interval_s)):
            raise ValueError(f"scan_interval_s must be > 0, got {self.scan_interval_s}")
        if not (0.0 <= self.noise < 1.0):
            raise ValueError(f"noise must be within [0, 1), got {self.noise}")


def check_range(min_range_m: float, max_range_m: float) -> None:
    """The MinRange/MaxRange pair of a range sensor: 0 <= min < max."""
    if not (0.0 <= min_range_m < max_range_m):
        raise ValueError(f"need 0 <= min_range_m < max_range_m, got {min_range_m}, {max_range_m}")


NOISE_BLOCK = 1024  # uniform draws a sensor takes from its generator at a time

COMMON_ALIASES = {
    "ScanInterval": "scan_interval_s",
    "bWithTimeStamp": "with_time_stamp",
    "Noise": "noise",
}


class Sensor:
    """Base class of every sensor plugin.

    Subclasses set ``TYPE`` (the canonical USARSim type name), ``Config`` (a frozen
    dataclass derived from :class:`SensorConfig`), ``ALIASES`` (USARSim ini key ->
    field name) and optionally ``PRESETS`` (named sets of values, e.g. ``SICK``).
    ``PACKED`` sensors of one type on one robot are measured together and reported
    in one line (Sonar, IR, Encoder, Touch).
    """

    TYPE: ClassVar[str] = ""
    PACKED: ClassVar[bool] = False
    LIVE_CONF: ClassVar[bool] = False  # True when SET operations change what CONF reports
    PERIODIC: ClassVar[bool] = True  # False for items that never send SEN (effecters such as RFIDReleaser)
    Config: ClassVar[type] = SensorConfig
    ALIASES: ClassVar[dict[str, str]] = {}
    PRESETS: ClassVar[dict[str, dict[str, Any]]] = {}

    def __init__(self, item: MountedItem, config: SensorConfig, robot: RobotConfig, seed: int):
        self.item = item
        self.name = item.name
        self.config = config
        self.robot = robot
        self.rng = np.random.default_rng(seed)
        self._ubuf: np.ndarray | None = None
        self._upos = 0

    # Lifecycle -------------------------------------------------------------------
    def configure(self, view: WorldView) -> None:
        """Resolve MuJoCo ids by name; called after every model (re)build."""

    def reset(self, view: WorldView) -> None:
        """Start over, e.g. at spawn."""

    def measure(self, view: WorldView) -> Any:
        """Return a reading (or, for packed sensors, this item's part of one)."""
        raise NotImplementedError

    @classmethod
    def measure_group(cls, sensors: list[Sensor], view: WorldView) -> list[Any]:
        """Packed sensors: every item's part, measured together (override to batch)."""
        return [s.measure(view) for s in sensors]

    @classmethod
    def combine(cls, parts: list[Any]) -> Any:
        """Packed sensors: build one reading from every item's part."""
        raise NotImplementedError

    def operate(self, view: WorldView, opcode: str, params: str | None) -> Any:
        """Handle ``SET {Opcode ...}``: return the RES status (``OK``, ``Failed``), or
        (status, extra key/value pairs), or a ready reading of the result; None if the
        opcode is not supported."""
        return None

    def conf_fields(self) -> tuple[tuple[str, Any], ...]:
        """The (key, value) pairs after ``{Name n}`` in this item's CONF reply."""
        return (("ScanInterval", self.config.scan_interval_s),)

    # Noise -----------------------------------------------------------------------
    def relative_noise(self, values: np.ndarray) -> np.ndarray:
        """``values`` with the relative noise of the config: each multiplied by
        1 + u, u uniform in [-noise, noise]."""
        n = self.config.noise
        if n <= 0:
            return values
        values = np.asarray(values, dtype=float)
        return values * (1.0 + n * self.uniform(values.size).reshape(values.shape))

    def relative_noise_scalar(self, value: float) -> float:
        n = self.config.noise
        if n <= 0:
            return value
        return value * (1.0 + n * float(self.uniform(1)[0]))

    def uniform(self, k: int) -> np.ndarray:
        """``k`` draws, uniform in [-1, 1), from this sensor's own seeded generator
        (drawn ahead in blocks: a call costs a slice, not a generator call)."""
        buf, i = self._ubuf, self._upos
        if buf is None or i + k > len(buf):
            buf = self.rng.uniform(-1.0, 1.0, size=max(NOISE_BLOCK, k))
            self._ubuf, i = buf, 0
        self._upos = i + k
        return buf[i:i + k]


SENSORS = Registry("sensor")


def build_config(cls: type[Sensor], item: MountedItem, robot_path: str) -> SensorConfig:
    """Turn an item's raw keys into its plugin's frozen Config.

    Accepts our field names and USARSim's ini names (any case); a ``preset`` key
    picks a named set of values first.  Unknown keys fail with the closest match.
    """
    key_base = item.key_path or item.name
    params = dict(item.params)
    values: dict[str, Any] = {}
    preset = params.pop("preset", None)
    if preset is not None:
        presets = {k.lower(): (k, v) for k, v in cls.PRESETS.items()}
        if not isinstance(preset, str) or preset.lower() not in presets:
            raise ConfigError(f"unknown preset {preset!r}{did_you_mean(str(preset), cls.PRESETS)}",
                              path=robot_path, key=f"{key_base}.preset")
        values.update(presets[preset.lower()][1])
    fields = {f.name: f for f in dataclasses.fields(cls.Config)}
    aliases = {**COMMON_ALIASES, **cls.ALIASES}
    lookup = {n.lower(): n for n in fields}
    lookup.update({a.lower(): f for a, f in aliases.items()})
    for raw_key, raw_value in params.items():
        field_name = lookup.get(str(raw_key).lower())
        if field_name is None:
            allowed = sorted(set(fields) | set(aliases))
            raise ConfigError(f"unknown {cls.TYPE} setting '{raw_key}'{did_you_mean(str(raw_key), allowed)}",
                              path=robot_path, key=f"{key_base}.{raw_key}")
        values[field_name] = _coerce(fields[field_name], raw_value, robot_path, f"{key_base}.{raw_key}")
    try:
        return cls.Config(**values)
    except (ValueError, TypeError) as exc:
        raise ConfigError(f"invalid {cls.TYPE} settings: {exc}", path=robot_path, key=key_base) from exc


def _coerce(field: dataclasses.Field, value: Any, path: str, key: str) -> Any:
    t = field.type if isinstance(field.type, str) else getattr(field.type, "__name__", str(field.type))
    if t == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(float(value)):
            raise ConfigError(f"expected a finite number, got {value!r}", path=path, key=key)
        return float(value)
    if t == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"expected an integer, got {value!r}", path=path, key=key)
        return value
    if t == "bool":
        if isinstance(value, str) and value.lower() in ("true", "false"):
            return value.lower() == "true"
        if not isinstance(value, bool):
            raise ConfigError(f"expected true or false, got {value!r}", path=path, key=key)
        return value
    if t == "str":
        if not isinstance(value, str):
            raise ConfigError(f"expected a text, got {value!r}", path=path, key=key)
        return value
    return value


def component_seed(world_seed: int, *parts: str) -> int:
    """A stable per-component seed (independent of Python's hash randomisation)."""
    words = [world_seed & 0xFFFFFFFF] + [zlib.crc32(p.encode()) for p in parts]
    return int(np.random.SeedSequence(words).generate_state(1)[0])


def make_sensor(item: MountedItem, robot: RobotConfig, world_seed: int, robot_key: str) -> Sensor:
    cls = SENSORS.get(item.item_type)
    config = build_config(cls, item, robot.path)
    return cls(item, config, robot, component_seed(world_seed, robot_key, cls.TYPE, item.name))
