"""The plugin framework of a robot's mounted items (design.md 4): a common base
(:class:`Item`: typed config with USARSim ini aliases, seeded generator, CONF fields, the
lifecycle), the sensor base and registry (:class:`Sensor`, :data:`SENSORS`), and the
look-up of an item's type among sensors, effecters (:mod:`usarsim.effecters`) and cameras
(:mod:`usarsim.sensors.camera`), which have bases and registries of their own.

A sensor measures; it does not format text, open sockets, start threads or draw.
The framework decides when it measures (its ``scan_interval_s`` of simulated
time), gives it its own seeded random generator, and hands its reading, a frozen
dataclass from :mod:`usarsim.readings`, to whoever listens.  An item operated with SET
(protocol.md 5.4) gets typed parameters and answers with a typed result; the protocol
layer prints both.
"""

from __future__ import annotations

import dataclasses
import math
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Generic, Self, TypeVar, get_args

import numpy as np

from usarsim.config.reader import did_you_mean
from usarsim.errors import ConfigError, PluginNotFoundError
from usarsim.readings import EffecterState, FieldValue, ItemParams, OperationResult, ZoomResult
from usarsim.registry import Registry
from usarsim.sensors.noise import Noise
from usarsim.sim.outputs import ItemDescription

if TYPE_CHECKING:
    import mujoco

    from usarsim.config.robot import MountedItem, RobotConfig
    from usarsim.sim.view import RobotHandle, WorldView

T = TypeVar("T", bound=type)


@dataclass(frozen=True, kw_only=True)
class ItemConfig:
    """Settings every mounted item accepts (protocol.md 7.1): a robot file may give them to
    any item of its ``sensors:`` list."""

    scan_interval_s: float = 0.2
    with_time_stamp: bool = True
    noise: float = 0.0  # relative amplitude, uniform in [-noise, +noise]

    def __post_init__(self) -> None:
        if not (self.scan_interval_s > 0 and math.isfinite(self.scan_interval_s)):
            raise ValueError(f"scan_interval_s must be > 0, got {self.scan_interval_s}")
        if not (0.0 <= self.noise < 1.0):
            raise ValueError(f"noise must be within [0, 1), got {self.noise}")


@dataclass(frozen=True, kw_only=True)
class SensorConfig(ItemConfig):
    """Settings every sensor has (protocol.md 7.1)."""


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


C = TypeVar("C", bound="ItemConfig")  # an item's own settings


class Item(Generic[C]):
    """What every mounted item plugin has: sensors (:class:`Sensor`), effecters
    (:class:`usarsim.effecters.Effecter`) and cameras (:class:`usarsim.sensors.camera.CameraItem`).

    A plugin names its settings (a frozen dataclass derived from :class:`ItemConfig`) as the
    type argument of its base, ``class Sonar(RangeSensor[SonarConfig])``: ``self.config`` is
    typed by it and the loader (:func:`build_config`) builds it (``Config``, set from the
    argument; a class may still set ``Config`` itself).  It sets ``ALIASES`` (USARSim ini key
    -> field name) and optionally ``PRESETS`` (named sets of values, e.g. ``SICK``);
    registration gives ``TYPE``, the canonical USARSim type name.
    """

    TYPE: ClassVar[str] = ""
    KIND: ClassVar[str] = ""  # its registry's kind, set at registration: sensor, effecter or camera
    LIVE_CONF: ClassVar[bool] = False  # True when SET operations change what CONF reports
    PERIODIC: ClassVar[bool] = False  # True for items that send SEN lines at their ScanInterval
    Config: ClassVar[type[ItemConfig]] = ItemConfig
    ALIASES: ClassVar[dict[str, str]] = {}
    PRESETS: ClassVar[dict[str, dict[str, Any]]] = {}
    config: C
    handle: RobotHandle  # the robot's bodies and sites in the model, set at every build

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "Config" in cls.__dict__:
            return
        for base in cls.__dict__.get("__orig_bases__", ()):  # class Sonar(RangeSensor[SonarConfig])
            for arg in get_args(base):
                if isinstance(arg, type) and issubclass(arg, ItemConfig):
                    cls.Config = arg

    def __init__(self, item: MountedItem, config: C, robot: RobotConfig, seed: int) -> None:
        self.item = item
        self.name = item.name
        self.config = config
        self.robot = robot
        self.rng = np.random.default_rng(seed)

    # Lifecycle -------------------------------------------------------------------
    def build(self, spec: mujoco.MjSpec, chassis: mujoco.MjsBody, prefix: str) -> None:
        """Add what this item needs to its robot's part of the model (a camera, a touch probe,
        a grasp's weld) when the robot is added to the world: ``chassis`` is the robot's
        chassis body, ``prefix`` the robot's name in the model (its handle's prefix)."""

    def configure(self, view: WorldView) -> None:
        """Resolve MuJoCo ids by name; called after every model (re)build."""

    def reset(self, view: WorldView) -> None:
        """Start over, e.g. at spawn."""

    def operate(self, view: WorldView, opcode: str, params: ItemParams) -> OperationResult | ZoomResult | None:
        """Handle ``SET {Opcode op} {Params p}`` (protocol.md 5.4): ``params`` are typed by
        the protocol layer (the numbers of Params, and Params as sent).  Return what the
        operation did (an :class:`OperationResult`, or a camera's :class:`ZoomResult`);
        None if the opcode is not supported (RES Failed)."""
        return None

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        """The typed (key, value) pairs after ``{Name n}`` in this item's CONF reply
        (protocol.md 6.7); the protocol layer prints them."""
        return ()

    def geo_mount(self) -> str:
        """The mount GETGEO reports (protocol.md 6.8): ``HARD`` for the chassis, else the
        robot part the item rides on, its location and orientation relative to that part.
        The robot file's ``mount``; an item that rides on a part by nature (an encoder on
        its wheel) names that part."""
        return self.item.mount

    def describe(self) -> ItemDescription:
        """What GETGEO and GETCONF report of this item (protocol.md 6.7, 6.8)."""
        i = self.item
        return ItemDescription(self.TYPE, i.name, i.location, i.orientation, self.geo_mount(), self.conf_fields())

    def state(self) -> EffecterState | None:
        """What the EFF line after an operation reports (None: this item sends none; an
        effecter's, protocol.md 6.6)."""
        return None


SC = TypeVar("SC", bound=SensorConfig)


class Sensor(Item[SC]):
    """Base class of every sensor plugin: it measures at its ScanInterval of simulated
    time and sends SEN lines (protocol.md 6.3, 7).

    ``PACKED`` sensors of one type on one robot are measured together and reported
    in one line (Sonar, IR, Encoder, Touch).
    """

    PACKED: ClassVar[bool] = False
    PERIODIC: ClassVar[bool] = True
    RESETTABLE: ClassVar[bool] = False  # {Opcode RESET} starts it over (Odometry, Encoder, Tachometer)
    SCANNABLE: ClassVar[bool] = False  # {Opcode SCAN} makes it scan at once (the range scanners)
    # it measures only when asked ({Opcode SCAN}), unless its settings say ``continuous``
    # (the range imager, as USARSim's KinectDepth)
    ON_REQUEST: ClassVar[bool] = False
    Config: ClassVar[type[ItemConfig]] = SensorConfig
    NOISE: ClassVar[Noise | None] = None  # what corrupts what it senses (usarsim.sensors.noise)

    def __init__(self, item: MountedItem, config: SC, robot: RobotConfig, seed: int) -> None:
        super().__init__(item, config, robot, seed)
        self._ubuf: np.ndarray | None = None
        self._upos = 0

    def measure(self, view: WorldView) -> Any:
        """Return a reading (or, for packed sensors, this item's part of one): by default what
        :meth:`sense` gives, corrupted by the class's ``NOISE``, made a reading by :meth:`reading`
        (a sensor whose noise is its own model's overrides this instead)."""
        true = self.sense(view)
        return self.reading(true if self.NOISE is None else self.NOISE.apply(self, true))

    def sense(self, view: WorldView) -> Any:
        """The true values, before any noise."""
        raise NotImplementedError

    def reading(self, values: Any) -> Any:
        """The reading (or this item's part of one) of the values sensed and corrupted."""
        return values

    @classmethod
    def measure_group(cls, sensors: list[Self], view: WorldView) -> list[Any]:
        """Packed sensors: every item's part, measured together (override to batch)."""
        return [s.measure(view) for s in sensors]

    @classmethod
    def combine(cls, parts: list[Any]) -> Any:
        """Packed sensors: build one reading from every item's part."""
        raise NotImplementedError

    def operate(self, view: WorldView, opcode: str, params: ItemParams) -> OperationResult | None:
        """``{Opcode RESET}`` starts a RESETTABLE sensor over; ``{Opcode SCAN}`` makes a
        SCANNABLE one scan at once, its SEN line after the RES (protocol.md 5.4)."""
        op = opcode.upper()
        if op == "RESET" and self.RESETTABLE:
            self.reset(view)
            return OperationResult(ok=True)
        if op == "SCAN" and self.SCANNABLE:
            return OperationResult(ok=True)
        return None

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
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
        return buf[i : i + k]


class ItemRegistry(Registry):
    """The plugins of one kind of mounted item (``sensor``, ``effecter``, ``camera``).  The
    kinds share one name space (:class:`ItemKinds`): a robot file lists every item under
    ``sensors:``, so a type name registered by two kinds is an error, as one registered twice
    by one kind is."""

    def __init__(self, kind: str, family: ItemKinds) -> None:
        super().__init__(kind)
        self.family = family

    def register(self, name: str, *aliases: str) -> Callable[[T], T]:
        deco = super().register(name, *aliases)

        def checked(cls: T) -> T:
            for n in (name, *aliases):
                other = self.family.kind_of(n)
                if other is not None and other is not self:
                    raise ValueError(
                        f"item type name '{n}' is registered already as a {other.kind}; choose another "
                        f"name for the {self.kind} {cls.__qualname__}"
                    )
            registered = deco(cls)
            setattr(registered, "KIND", self.kind)  # noqa: B010  (every item class has KIND)
            return registered

        return checked


class ItemKinds:
    """The registries of every kind of mounted item, and the look-up of a robot file's item
    type among them (any case; an unknown name fails with the closest match and the list of
    valid ones)."""

    def __init__(self) -> None:
        self.registries: list[ItemRegistry] = []

    def new(self, kind: str) -> ItemRegistry:
        """A registry for one more kind of item."""
        registry = ItemRegistry(kind, self)
        self.registries.append(registry)
        return registry

    def kind_of(self, name: str) -> ItemRegistry | None:
        """The registry that has ``name`` (None: none has it); an error if several have it."""
        found = [r for r in self.registries if name in r]
        if len(found) > 1:
            raise PluginNotFoundError(
                f"item type '{name}' is registered as a {' and a '.join(r.kind for r in found)}: rename one of them"
            )
        return found[0] if found else None

    def names(self) -> list[str]:
        return sorted({n for r in self.registries for n in r.names()})

    def canonical(self, name: str) -> str | None:
        registry = self.kind_of(name)
        return registry.canonical(name) if registry is not None else None

    def get(self, name: str) -> type[Item[Any]]:
        registry = self.kind_of(name)
        if registry is None:
            # "sensor": a robot file lists every item under ``sensors:``
            raise PluginNotFoundError(f"unknown sensor type '{name}'{did_you_mean(name, self.names())}")
        return registry.get(name)

    def __contains__(self, name: str) -> bool:
        return self.kind_of(name) is not None


ITEMS = ItemKinds()
SENSORS = ITEMS.new("sensor")


def build_config(cls: type[Item[Any]], item: MountedItem, robot_path: str) -> ItemConfig:
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
            raise ConfigError(
                f"unknown preset {preset!r}{did_you_mean(str(preset), cls.PRESETS)}",
                path=robot_path,
                key=f"{key_base}.preset",
            )
        values.update(presets[preset.lower()][1])
    fields = {f.name: f for f in dataclasses.fields(cls.Config)}
    aliases = {**COMMON_ALIASES, **cls.ALIASES}
    lookup = {n.lower(): n for n in fields}
    lookup.update({a.lower(): f for a, f in aliases.items()})
    for raw_key, raw_value in params.items():
        field_name = lookup.get(str(raw_key).lower())
        if field_name is None:
            allowed = sorted(set(fields) | set(aliases))
            raise ConfigError(
                f"unknown {cls.TYPE} setting '{raw_key}'{did_you_mean(str(raw_key), allowed)}",
                path=robot_path,
                key=f"{key_base}.{raw_key}",
            )
        values[field_name] = _coerce(fields[field_name], raw_value, robot_path, f"{key_base}.{raw_key}")
    try:
        return cls.Config(**values)
    except (ValueError, TypeError) as exc:
        raise ConfigError(f"invalid {cls.TYPE} settings: {exc}", path=robot_path, key=key_base) from exc


def _coerce(field: dataclasses.Field[Any], value: Any, path: str, key: str) -> Any:
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


def make_item(item: MountedItem, robot: RobotConfig, world_seed: int, robot_key: str) -> Item[Any]:
    """The plugin of a robot file's item: its type looked up among sensors, effecters and
    cameras, its config built and checked, its generator seeded for this robot and item."""
    cls = ITEMS.get(item.item_type)
    config = build_config(cls, item, robot.path)
    return cls(item, config, robot, component_seed(world_seed, robot_key, cls.TYPE, item.name))
