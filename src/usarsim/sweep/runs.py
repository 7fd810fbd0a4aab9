"""The runs of a sweep: the run parameters an experiment file may vary and the values each
may take, what a file is read into (a :class:`Run` per configuration and seed, its team's
:class:`Member` s, its :class:`Controller`, the whole :class:`Experiment`), and finding a
Python brain by its ``module:callable`` name.
"""

from __future__ import annotations

import hashlib
import importlib
import inspect
import json
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from usarsim.config.reader import did_you_mean

# The run parameters a grid or a runs entry may vary, and what each key is called in a row.
AXES = ("world", "variant", "team", "wireless", "duration", "clock", "controller")
CLOCKS = ("lockstep", "max")
# "world": the world's own radio model (its ``wireless:`` section, else WAF); "off": no
# wireless servers (ComServer, WSS); a model name: that model (serve --wireless-model).
WIRELESS = ("world", "off", "waf", "waf2009", "distance", "perfect")
DEFAULTS = {
    "world": "DM-USAR_yellow",
    "variant": None,  # the world as written (serve --variant)
    "team": "P2AT",
    "wireless": "world",
    "duration": 60.0,
    "clock": "lockstep",
    "controller": "usarsim.brains.wander:Wander",
}
DEFAULT_TIMEOUT_S = 600.0
DEFAULT_PERIOD_S = 0.1
# What a controller command may name between braces; each is also an environment variable
# USARSIM_<NAME> of the command.
PLACEHOLDERS = (
    "host",
    "port",
    "truth_port",
    "wcs_port",
    "seconds",
    "seed",
    "world",
    "lockstep",
    "robot",
    "name",
    "start",
    "team",
    "map",
)
# The parameters a brain is given by the sweep itself, never in ``params``.
SWEEP_GIVES = ("robot", "origin")
_BRAIN_TARGET = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_][\w.]*$")


@dataclass(frozen=True)
class Member:
    """One robot of a run's team: its class, its name (R1, R2...) and where it starts: a
    start pose by name, or a location (metres, USARSim frame) and a yaw (radians)."""

    robot: str
    name: str
    start: str | None = None
    location: tuple[float, float, float] | None = None
    yaw: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        return {
            "robot": self.robot,
            "name": self.name,
            "start": self.start,
            "location": None if self.location is None else list(self.location),
            "yaw": self.yaw,
        }


@dataclass(frozen=True)
class Controller:
    """What drives a run's robots: a Python brain (``kind`` "brain", ``target``
    ``module:callable``, called once per robot with ``params``, stepped every ``period``
    simulated seconds) or an external command (``kind`` "command", ``target`` the command
    line with placeholders; ``isolate``: one per robot, each in a network namespace of its own,
    :mod:`usarsim.sweep.isolation`)."""

    kind: str
    target: str
    params: str = "{}"  # JSON text (sorted keys): hashable, and the same in every row
    period: float = DEFAULT_PERIOD_S
    label: str = ""
    isolate: bool = False

    @property
    def param_dict(self) -> dict[str, Any]:
        return json.loads(self.params)

    def identity(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind, "target": self.target}
        if self.kind == "brain":
            out.update(params=self.param_dict, period=self.period)
        if self.isolate:
            out["isolate"] = True
        return out


@dataclass(frozen=True)
class Run:
    """One run of a sweep: everything that decides its outcome, and how it is labelled."""

    experiment: str
    world: str  # a shipped world's name, or the absolute path of a world file
    seed: int
    team: tuple[Member, ...]
    team_label: str
    wireless: str
    duration_s: float
    clock: str
    controller: Controller
    timeout_s: float = DEFAULT_TIMEOUT_S
    robot_dirs: tuple[str, ...] = ()
    cwd: str = "."  # the experiment file's folder: where a controller command runs
    variant: int | None = None  # the world's variant (serve --variant); None: as written
    # where the team's map and its picture are kept (a competition's maps folder); "": the
    # team hands no map in
    maps_dir: str = ""

    def identity(self) -> dict[str, Any]:
        """What makes two runs the same run (the label, timeout and folder do not)."""
        variant = {} if self.variant is None else {"variant": self.variant}
        return variant | {
            "world": self.world,
            "seed": self.seed,
            "team": [m.as_dict() for m in self.team],
            "wireless": self.wireless,
            "duration_s": self.duration_s,
            "clock": self.clock,
            "controller": self.controller.identity(),
            "robot_dirs": list(self.robot_dirs),
        }

    @property
    def run_id(self) -> str:
        """A hash of the run's configuration: the key of its row in the results."""
        text = json.dumps(self.identity(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def columns(self) -> dict[str, Any]:
        """The configuration columns of the run's row."""
        return {
            "run_id": self.run_id,
            "experiment": self.experiment,
            "world": self.world,
            "variant": self.variant,
            "seed": self.seed,
            "team": self.team_label,
            "robots_n": len(self.team),
            "wireless": self.wireless,
            "duration_s": self.duration_s,
            "clock": self.clock,
            "controller": self.controller.label,
            "config": json.dumps(self.identity(), sort_keys=True),
        }


@dataclass(frozen=True)
class Experiment:
    """An experiment file read (docs/experiments.md): its name and description, the file it came from, one
    :class:`Run` per configuration and seed (a configuration given twice runs once), and the configuration columns
    its runs differ in."""

    name: str
    path: str
    description: str
    runs: tuple[Run, ...]
    axes: tuple[str, ...] = field(default=())  # the row columns the configurations differ in


# The columns of a row that, with the seed, make a configuration.
CONFIG_COLUMNS = ("world", "variant", "team", "wireless", "duration_s", "clock", "controller")


def varying_axes(rows: list[dict[str, Any]]) -> tuple[str, ...]:
    """The configuration columns (besides the seed) that take more than one value."""
    return tuple(c for c in CONFIG_COLUMNS if len({r.get(c) for r in rows}) > 1)


# ---------------------------------------------------------------- brains


def resolve_brain(target: str) -> Callable[..., Any]:
    """The callable ``module:name`` names; ImportError or AttributeError with what is there."""
    module_name, attr = target.split(":", 1)
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        hint = ""
        if module_name.startswith("usarsim.brains.") or "." not in module_name:
            shipped = ["usarsim.brains." + n for n in ("frontier", "victim", "wall_follower", "wander")]
            hint = did_you_mean(module_name, shipped)
        raise ImportError(f"cannot import module '{module_name}' ({exc}){hint}") from None
    obj: Any = module
    for part in attr.split("."):
        if not hasattr(obj, part):
            names = [
                n
                for n in dir(obj)
                if not n.startswith("_")
                and callable(getattr(obj, n, None))
                and getattr(getattr(obj, n), "__module__", None) == module_name
            ]
            raise AttributeError(f"module '{module_name}' has no '{attr}'{did_you_mean(part, names)}")
        obj = getattr(obj, part)
    if not callable(obj):
        raise TypeError(f"'{target}' is not callable: a brain is a class or function called with the robot")
    return obj


def brain_parameters(factory: Callable[..., Any]) -> set[str] | None:
    """The keyword parameters a brain accepts (a class: its ``__init__`` and, while each
    passes ``**kw`` on, its bases'); None when it takes any keyword."""
    targets = (
        [vars(c)["__init__"] for c in factory.__mro__ if "__init__" in vars(c)]
        if inspect.isclass(factory)
        else [factory]
    )
    names: set[str] = set()
    for fn in targets:
        try:
            sig = inspect.signature(fn)
        except (TypeError, ValueError):
            return None
        params = list(sig.parameters.values())
        names |= {p.name for p in params if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}
        if not any(p.kind is p.VAR_KEYWORD for p in params):
            break
    else:
        if not inspect.isclass(factory):
            return None
    names -= {"self"}
    return names


@dataclass
class MemberSpec:
    """A member of a team as the experiment file gives it: ``count`` robots of a class, their
    start poses (None: the next free one), or a location and yaw; ``key`` where it was read."""

    robot: str
    count: int
    starts: tuple[str | None, ...]  # one per robot (None: the next free start pose)
    location: tuple[float, float, float] | None
    yaw: float
    key: str


def team_label(specs: tuple[MemberSpec, ...]) -> str:
    """``P2AT``, ``2xP2AT``, ``P2AT+P3AT``, ``P2AT@PlayerStart3``: the team as a row shows it."""
    parts = []
    for s in specs:
        text = s.robot if s.count == 1 else f"{s.count}x{s.robot}"
        named = [x for x in s.starts if x is not None]
        if s.location is not None:
            text += "@" + ",".join(f"{v:g}" for v in s.location)
        elif named:
            text += "@" + ",".join(x if x is not None else "auto" for x in s.starts)
        parts.append(text)
    return "+".join(parts)
