"""The experiment file: what to run, read strictly into the list of runs of a sweep.

An experiment file is YAML.  Its top-level keys give the value every run has unless a
``grid`` or a ``runs`` entry says otherwise::

    name: yellow-vs-red
    world: DM-USAR_yellow
    seeds: [1, 2, 3]
    team: P2AT
    duration: 60
    clock: lockstep
    controller: usarsim.brains.frontier:FrontierExplorer
    grid:
      world: [DM-USAR_yellow, DM-USAR_red]

The configurations are every combination of the ``grid``'s lists, then each entry of
``runs``; each configuration runs once per seed.  docs/experiments.md lists every key.

Errors name the file, the key and what is allowed, with "did you mean" for a misspelt key,
world, robot class, start pose, brain or brain parameter (:class:`usarsim.errors.ConfigError`).
"""

from __future__ import annotations

import itertools
import json
import math
import re
import shlex
import shutil
import string
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any, cast

from usarsim.config.reader import Section, did_you_mean, load_yaml
from usarsim.errors import ConfigError
from usarsim.sweep.runs import (
    _BRAIN_TARGET,
    AXES,
    CLOCKS,
    CONFIG_COLUMNS,
    DEFAULT_PERIOD_S,
    DEFAULT_TIMEOUT_S,
    DEFAULTS,
    PLACEHOLDERS,
    SWEEP_GIVES,
    WIRELESS,
    Controller,
    Experiment,
    Member,
    MemberSpec,
    Run,
    brain_parameters,
    resolve_brain,
    team_label,
    varying_axes,
)

__all__ = [
    "AXES",
    "CLOCKS",
    "CONFIG_COLUMNS",
    "DEFAULTS",
    "DEFAULT_PERIOD_S",
    "DEFAULT_TIMEOUT_S",
    "PLACEHOLDERS",
    "SWEEP_GIVES",
    "WIRELESS",
    "Controller",
    "Experiment",
    "Member",
    "Reader",
    "Run",
    "brain_parameters",
    "load_experiment",
    "resolve_brain",
    "team_label",
    "varying_axes",
]


# ---------------------------------------------------------------- reading the file


def load_experiment(path: str | Path) -> Experiment:
    """Read and check an experiment file; every run it describes, in order."""
    p = Path(path)
    data = load_yaml(p)
    return Reader(p).read(data)


class Reader:
    """Reads one experiment file: the base values, the grid, the runs."""

    def __init__(self, path: Path):
        self.path = path
        self.file = str(path)
        self.folder = path.resolve().parent
        self.robot_dirs: tuple[str, ...] = ()

    def error(self, key: str, message: str) -> ConfigError:
        return ConfigError(message, path=self.file, key=key)

    def read(self, data: dict) -> Experiment:
        top = Section(data, path=self.file)
        name = top.str("name", self.path.stem)
        if not re.match(r"^[\w.\-]+$", name):
            raise top.error(
                "name", f"use letters, digits, '.', '-' and '_' only (it names the results' folder), got {name!r}"
            )
        description = top.raw("description", "")
        if not isinstance(description, str):
            raise top.error("description", f"expected a text, got {description!r}")
        self.robot_dirs = tuple(self._robot_dirs(top.list("robot_dirs", [])))
        timeout = top.float("timeout", DEFAULT_TIMEOUT_S, min=0.0, min_exclusive=True)
        seeds = self.seeds(top.raw("seeds", [0]), "seeds")
        base = {axis: self.value(axis, top.raw(axis, DEFAULTS[axis]), axis) for axis in AXES}
        grid_raw = top.raw("grid", None)
        runs_raw = top.raw("runs", None)
        top.finish()

        configs: list[tuple[dict[str, Any], tuple[int, ...], str]] = []  # (values, seeds, key for errors)
        if grid_raw is not None:
            if not isinstance(grid_raw, dict) or not grid_raw:
                raise self.error(
                    "grid",
                    f"expected a mapping of run parameters to lists of values ({', '.join(AXES)}), got {grid_raw!r}",
                )
            lists: list[tuple[str, list[Any]]] = []
            for k, values in grid_raw.items():
                key = f"grid.{k}"
                if k == "seeds":
                    raise self.error(
                        key,
                        "seeds are not a grid axis: every configuration runs with every seed "
                        "of the top-level 'seeds' (or of its 'runs' entry)",
                    )
                if k not in AXES:
                    raise self.error(key, f"unknown run parameter '{k}'{did_you_mean(str(k), AXES)}")
                if not isinstance(values, list) or not values:
                    raise self.error(key, f"expected a non-empty list of values, got {values!r}")
                lists.append((k, [self.value(k, v, f"{key}[{i}]") for i, v in enumerate(values)]))
            for combo in itertools.product(*(vals for _, vals in lists)):
                values = dict(base)
                values.update({k: v for (k, _), v in zip(lists, combo)})
                configs.append((values, seeds, "grid"))
        if runs_raw is not None:
            if not isinstance(runs_raw, list) or not runs_raw:
                raise self.error(
                    "runs", f"expected a non-empty list of runs (mappings of run parameters), got {runs_raw!r}"
                )
            for i, entry in enumerate(runs_raw):
                key = f"runs[{i}]"
                s = Section(entry, path=self.file, key=key)
                values = dict(base)
                for axis in AXES:
                    if s.has(axis):
                        values[axis] = self.value(axis, s.raw(axis), f"{key}.{axis}")
                    else:
                        s.raw(axis, None)  # known key: read, so that a misspelling of it is named
                run_seeds = self.seeds(s.raw("seeds"), f"{key}.seeds") if s.has("seeds") else seeds
                s.raw("seeds", None)
                s.finish()
                configs.append((values, run_seeds, key))
        if not configs:
            configs.append((base, seeds, ""))

        runs: list[Run] = []
        seen: set[str] = set()
        for values, run_seeds, key in configs:
            team = self.place_team(values["team"], values["world"], key)
            if values["controller"].isolate and values["clock"] == "lockstep":
                raise self.error(
                    key or "clock",
                    "isolated controllers need 'clock: max': in lock-step one process steps the world, "
                    "and isolated ones are one a robot",
                )
            for seed in run_seeds:
                run = Run(
                    experiment=name,
                    world=values["world"][0],
                    seed=seed,
                    team=team,
                    team_label=team_label(values["team"]),
                    wireless=values["wireless"],
                    duration_s=values["duration"],
                    clock=values["clock"],
                    controller=values["controller"],
                    timeout_s=timeout,
                    robot_dirs=self.robot_dirs,
                    cwd=str(self.folder),
                    variant=values["variant"],
                )
                if run.run_id not in seen:  # a configuration given twice runs once
                    seen.add(run.run_id)
                    runs.append(run)
        return Experiment(
            name=name,
            path=self.file,
            description=description,
            runs=tuple(runs),
            axes=varying_axes([r.columns() for r in runs]),
        )

    # -- one value of each run parameter

    def value(self, axis: str, v: Any, key: str) -> Any:
        return {
            "world": self.world,
            "variant": self.variant,
            "team": self.team,
            "wireless": self.wireless,
            "duration": self.duration,
            "clock": self.clock,
            "controller": self.controller,
        }[axis](v, key)

    def world(self, v: Any, key: str) -> tuple[str, Any]:
        """(the world as a run names it, its WorldConfig)."""
        from usarsim.config.catalog import resolve_world, world_files

        if not isinstance(v, str) or not v.strip():
            raise self.error(key, f"expected a world name or the path of a world file, got {v!r}")
        looks_like_path = v.endswith((".yaml", ".yml")) or "/" in v or "\\" in v
        if looks_like_path:
            p = Path(v) if Path(v).is_absolute() else self.folder / v
            if not p.exists():
                raise self.error(
                    key, f"no such world file {str(p)!r}; or give a shipped world: {', '.join(world_files())}"
                )
            try:
                cfg = _world_at(str(p.resolve()))
            except ConfigError as exc:
                raise self.error(key, f"the world file does not load: {exc}") from exc
            return str(p.resolve()), cfg
        try:
            cfg = resolve_world(v)
        except ConfigError as exc:
            raise self.error(key, exc.message) from None
        return cfg.name, cfg

    def variant(self, v: Any, key: str) -> int | None:
        """A world's variant (serve --variant): a whole number >= 0, or null for the world as written."""
        if v is None:
            return None
        if isinstance(v, bool) or not isinstance(v, int) or v < 0:
            raise self.error(key, f"a variant is a whole number >= 0 (or null: the world as written), got {v!r}")
        return v

    def team(self, v: Any, key: str) -> tuple[MemberSpec, ...]:
        entries = [v] if isinstance(v, (str, dict)) else v
        if not isinstance(entries, list) or not entries:
            raise self.error(
                key,
                f"expected a robot class (P2AT) or a list of team members "
                f"({{robot: P2AT, count: 2, start: PlayerStart1}}), got {v!r}",
            )
        out = []
        for i, entry in enumerate(entries):
            k = key if isinstance(v, (str, dict)) else f"{key}[{i}]"
            if isinstance(entry, str):
                out.append(MemberSpec(self.robot_class(entry, k), 1, (None,), None, 0.0, k))
                continue
            s = Section(entry, path=self.file, key=k)
            robot = self.robot_class(s.str("robot"), f"{k}.robot")
            count = s.int("count", 1, min=1)
            start = s.raw("start", "auto")
            # vec checks the length: three numbers (None when the file gives a null location)
            location = (
                cast("tuple[float, float, float] | None", s.vec("location", 3, None)) if s.has("location") else None
            )
            yaw = s.float("yaw", 0.0)
            s.finish()
            if location is not None:
                if s.has("start"):
                    raise self.error(f"{k}.start", "give either a start pose or a location, not both")
                if count != 1:
                    raise self.error(
                        f"{k}.count",
                        "robots placed at a location come one to an entry: "
                        f"give one entry per robot, got count {count}",
                    )
                out.append(MemberSpec(robot, 1, (None,), location, yaw, k))
                continue
            starts = [start] if isinstance(start, str) else start
            if not isinstance(starts, list) or not all(isinstance(x, str) and x.strip() for x in starts):
                raise self.error(
                    f"{k}.start", f"expected a start pose name, a list of them (one per robot) or 'auto', got {start!r}"
                )
            if starts == ["auto"]:
                starts = ["auto"] * count
            if len(starts) != count:
                raise self.error(
                    f"{k}.start", f"{len(starts)} start poses for {count} robots: give one per robot, or 'auto'"
                )
            out.append(MemberSpec(robot, count, tuple(None if x == "auto" else x for x in starts), None, yaw, k))
        return tuple(out)

    def robot_class(self, name: Any, key: str) -> str:
        from usarsim.config.catalog import resolve_robot

        if not isinstance(name, str) or not name.strip():
            raise self.error(key, f"expected a robot class name (see 'usarsim robots'), got {name!r}")
        try:
            return resolve_robot(name, extra_dirs=self.robot_dirs).class_name
        except ConfigError as exc:
            raise self.error(key, exc.message if exc.path is None else str(exc)) from None

    def wireless(self, v: Any, key: str) -> str:
        """``off``, ``world``, a radio model, or a wireless configuration file's absolute path."""
        if v is False or v is None:
            v = "off"
        if isinstance(v, str) and v.lower().endswith((".yaml", ".yml", ".ini")):  # serve --wireless-config
            from usarsim.sim.wireless_file import load_wireless_file

            p = Path(v) if Path(v).is_absolute() else self.folder / v
            try:
                load_wireless_file(p)
            except ConfigError as exc:
                raise self.error(key, str(exc)) from None
            return str(p.resolve())
        if not isinstance(v, str) or v.lower() not in WIRELESS:
            raise self.error(key, f"'{v}' is not a wireless setting or file{did_you_mean(str(v), WIRELESS)}")
        return v.lower()

    def duration(self, v: Any, key: str) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
            raise self.error(key, f"expected simulated seconds > 0, got {v!r}")
        return float(v)

    def clock(self, v: Any, key: str) -> str:
        if not isinstance(v, str) or v.lower() not in CLOCKS:
            raise self.error(
                key,
                f"'{v}' is not a clock: lockstep (the controller steps the world: reproducible) "
                f"or max (the simulator runs as fast as it can){did_you_mean(str(v), CLOCKS)}",
            )
        return v.lower()

    def seeds(self, v: Any, key: str) -> tuple[int, ...]:
        if isinstance(v, int) and not isinstance(v, bool):
            if v < 1:
                raise self.error(key, f"a number of seeds must be >= 1, got {v}")
            return tuple(range(v))
        if isinstance(v, list) and v and all(isinstance(x, int) and not isinstance(x, bool) and x >= 0 for x in v):
            if len(set(v)) != len(v):
                raise self.error(key, f"a seed is given twice: {v}")
            return tuple(v)
        raise self.error(key, f"expected a list of seeds (integers >= 0) or a number of seeds N (0 ... N-1), got {v!r}")

    def controller(self, v: Any, key: str) -> Controller:
        if isinstance(v, str):
            v = {"brain": v.strip()} if _BRAIN_TARGET.match(v.strip()) else {"command": v}
        s = Section(v, path=self.file, key=key)
        if s.has("brain") == s.has("command"):
            raise self.error(
                key,
                "give either 'brain: module:callable' (a Python brain) or 'command: ...' "
                "(any program, with {host} and {port} placeholders)",
            )
        label = s.str("label", "")
        if s.has("brain"):
            target = s.str("brain").strip()
            if s.has("isolate"):
                raise self.error(
                    f"{key}.isolate",
                    "isolation runs commands, one per robot: run the brain as one "
                    "(python -m usarsim.brains.wander --host {host} --port {port} --name {name} --start {start} ...)",
                )
            params = s.section("params", {}).data
            period = s.float("period", DEFAULT_PERIOD_S, min=0.0, min_exclusive=True)
            s.finish()
            factory = self.brain(target, f"{key}.brain")
            self.check_params(factory, target, params, f"{key}.params")
            try:
                text = json.dumps(params, sort_keys=True)
            except TypeError as exc:
                raise self.error(f"{key}.params", f"parameters must be plain values: {exc}") from None
            if not label:
                short = ", ".join(f"{k}={json.dumps(params[k])}" for k in sorted(params))
                label = target.rsplit(":", 1)[1] + (f"({short})" if short else "")
            return Controller("brain", target, text, period, label)
        command = s.str("command")
        isolate = s.bool("isolate", False)
        s.finish()
        self.check_command(command, f"{key}.command")
        return Controller("command", command, "{}", DEFAULT_PERIOD_S, label or command, isolate)

    def brain(self, target: str, key: str) -> Callable[..., Any]:
        if not _BRAIN_TARGET.match(target):
            raise self.error(
                key, f"a brain is 'module:callable' (usarsim.brains.frontier:FrontierExplorer), got {target!r}"
            )
        try:
            return resolve_brain(target)
        except (ImportError, AttributeError, TypeError) as exc:
            raise self.error(key, str(exc)) from None

    def check_params(self, factory: Callable[..., Any], target: str, params: dict, key: str) -> None:
        allowed = brain_parameters(factory)
        for name, value in params.items():
            if name in SWEEP_GIVES:
                raise self.error(f"{key}.{name}", f"'{name}' is given by the sweep (each robot and its start pose)")
            if allowed is not None and name not in allowed:
                raise self.error(
                    f"{key}.{name}",
                    f"{target} has no parameter '{name}'{did_you_mean(name, allowed - set(SWEEP_GIVES))}",
                )
            if name == "bounds" and value != "auto":
                ok = (
                    isinstance(value, list)
                    and len(value) == 4
                    and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in value)
                )
                if not ok or not (value[0] < value[2] and value[1] < value[3]):
                    raise self.error(
                        f"{key}.bounds",
                        f"expected [xmin, ymin, xmax, ymax] (metres, xmin < xmax, "
                        f"ymin < ymax) or 'auto' (the world's solids), got {value!r}",
                    )

    def check_command(self, command: str, key: str) -> None:
        try:
            names = [f for _, f, _, _ in string.Formatter().parse(command) if f is not None]
        except ValueError as exc:
            raise self.error(key, f"{exc} (write a literal brace as {{{{ or }}}})") from None
        for n in names:
            if n not in PLACEHOLDERS:
                raise self.error(key, f"unknown placeholder '{{{n}}}'{did_you_mean(n, PLACEHOLDERS)}")
        try:
            argv = shlex.split(command)
        except ValueError as exc:
            raise self.error(key, f"cannot split the command into words: {exc}") from None
        if not argv:
            raise self.error(key, "the command is empty")
        program = argv[0]
        if "{" not in program and shutil.which(program) is None and not (self.folder / program).exists():
            raise self.error(key, f"no program '{program}' on the PATH or in {self.folder}")

    def place_team(self, specs: tuple[MemberSpec, ...], world: tuple[str, Any], key: str) -> tuple[Member, ...]:
        """The team's robots with their names and start poses in ``world``: a start pose
        named in the file, or the world's next start pose no other robot of the team takes."""
        cfg = world[1]
        poses = [p.name for p in cfg.start_poses]
        taken: set[str] = set()
        for spec in specs:
            for s in spec.starts:
                if s is None:
                    continue
                pose = cfg.start_pose(s)
                if pose is None:
                    raise self.error(
                        f"{spec.key}.start",
                        f"world {cfg.name} has no start pose '{s}'"
                        f"{did_you_mean(s, poses)}" + (f" (in {key})" if key else ""),
                    )
                if pose.name in taken:
                    raise self.error(f"{spec.key}.start", f"start pose '{pose.name}' is taken twice")
                taken.add(pose.name)
        free = [p for p in poses if p not in taken]
        members: list[Member] = []
        for spec in specs:
            for s in spec.starts:
                n = f"R{len(members) + 1}"
                if spec.location is not None:
                    members.append(Member(spec.robot, n, None, spec.location, spec.yaw))
                    continue
                if s is None:
                    if not free:
                        raise self.error(
                            spec.key,
                            f"the team has more robots than world {cfg.name} has start poses "
                            f"({len(poses)}): place the others with 'location'",
                        )
                    start = free.pop(0)
                else:
                    start = cfg.start_pose(s).name
                members.append(Member(spec.robot, n, start))
        return tuple(members)

    def _robot_dirs(self, dirs: list) -> list[str]:
        out = []
        for i, d in enumerate(dirs):
            if not isinstance(d, str):
                raise self.error(f"robot_dirs[{i}]", f"expected a folder, got {d!r}")
            p = Path(d) if Path(d).is_absolute() else self.folder / d
            if not p.is_dir():
                raise self.error(f"robot_dirs[{i}]", f"no such folder {str(p)!r}")
            out.append(str(p.resolve()))
        return out


@cache
def _world_at(path: str) -> Any:
    from usarsim.config.catalog import resolve_world

    return resolve_world(path)
