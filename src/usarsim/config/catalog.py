"""Where robot and world files live, and lookup by name.

Robots and worlds shipped with usarsim are package data (``usarsim/data``);
a path to a file of one's own works wherever a name does.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

from usarsim.config.reader import did_you_mean, load_yaml
from usarsim.config.rndf import route_file_kind
from usarsim.config.robot import RobotConfig, class_name_problem, load_robot
from usarsim.config.world import WorldConfig
from usarsim.config.world_file import load_world
from usarsim.errors import ConfigError

DATA_DIR = Path(__file__).resolve().parent.parent / "data"
ROBOTS_DIR = DATA_DIR / "robots"
WORLDS_DIR = DATA_DIR / "worlds"
DEFAULT_WORLD = "DM-USAR_yellow"


def world_files() -> dict[str, Path]:
    return {p.stem: p for p in sorted(WORLDS_DIR.glob("*.yaml"))}


def robot_files(extra_dirs=()) -> dict[str, Path]:
    """Robot files by class name: the shipped ones, then those of ``extra_dirs``
    (``usarsim serve --robot-dir``), which may add classes or replace shipped ones."""
    files = {p.stem: p for p in sorted(ROBOTS_DIR.glob("*.yaml"))}
    for d in extra_dirs:
        files.update({p.stem: p for p in sorted(Path(d).glob("*.yaml"))})
    return files


def resolve_world(name_or_path: str) -> WorldConfig:
    p = Path(name_or_path)
    if p.suffix in (".yaml", ".yml") or p.exists():
        if not p.exists():
            raise ConfigError("no such world file", path=str(p))
        return load_world(p)
    files = world_files()
    for stem, path in files.items():
        if stem.lower() == name_or_path.lower():
            return load_world(path)
    raise ConfigError(
        f"unknown world '{name_or_path}'{did_you_mean(name_or_path, files)}; or give the path of a world file",
        key="--world",
    )


@cache
def _robot_cached(path: str, mtime: float) -> RobotConfig:
    return load_robot(path)


def robot_class_names() -> list[str]:
    return list(robot_files())


def resolve_robot(class_name: str, *, allow_path: bool = False, extra_dirs=()) -> RobotConfig:
    """A robot class by name (``P2AT``, ``USARBot.P2AT``, any case), or by file path
    when ``allow_path`` (never for names that come from the network)."""
    p = Path(class_name)
    if allow_path and p.suffix in (".yaml", ".yml"):
        if not p.exists():
            raise ConfigError("no such robot file", path=str(p))
        return _robot_cached(str(p), p.stat().st_mtime)
    bare = class_name.split(".", 1)[1] if class_name.lower().startswith("usarbot.") else class_name
    files = robot_files(extra_dirs)
    for stem, path in reversed(list(files.items())):
        if stem.lower() == bare.lower():
            robot = _robot_cached(str(path), path.stat().st_mtime)
            problem = class_name_problem(robot)  # the class asked for must be the class served
            if problem is not None:
                raise ConfigError(problem, path=str(path), key="class_name")
            return robot
    raise ConfigError(f"unknown robot class '{class_name}'{did_you_mean(bare, files)}")


def file_kind(path: str | Path) -> str:
    """'robot' or 'world', decided by the keys the file holds; 'rndf' or 'mdf' for a DARPA
    route network or mission file (config/rndf.py)."""
    route = route_file_kind(path)
    if route is not None:
        return route
    data = load_yaml(path)
    if "class_name" in data:
        return "robot"
    if "start_poses" in data or "floor" in data:
        return "world"
    raise ConfigError(
        "cannot tell whether this is a robot file (it would have 'class_name') "
        "or a world file (it would have 'floor' and 'start_poses')",
        path=str(path),
    )
