"""Reading a world file: :func:`load_world` (the sections read by
:mod:`usarsim.config.world_sections` into the classes of :mod:`usarsim.config.world`) and
:func:`check_world_file`, what ``usarsim validate`` checks of a world before it is served."""

from __future__ import annotations

from pathlib import Path

from usarsim.config.reader import load_yaml, name_entries
from usarsim.config.world import SOLID_MARGIN_M, WorldConfig
from usarsim.config.world_sections import read_world
from usarsim.errors import ConfigError


def load_world(path: str | Path) -> WorldConfig:
    """A world file read and checked (ConfigError naming the file and the key when it is wrong)."""
    path = str(path)
    data = load_yaml(path)
    try:
        return read_world(data, path)
    except ConfigError as exc:
        name_entries(exc, data)
        raise


def check_world_file(path: str | Path) -> WorldConfig:
    """Load a world file and check what a world must have to be served (``usarsim
    validate``): at least one start pose, none inside a solid (WorldConfig.solid_at)."""
    cfg = load_world(path)
    if not cfg.start_poses:
        raise ConfigError("a world needs at least one start pose", path=str(path), key="start_poses")
    for i, pose in enumerate(cfg.start_poses):
        solid = cfg.solid_at(pose.location)
        if solid is not None:
            where = ", ".join(f"{c:g}" for c in pose.location)
            err = ConfigError(
                f"start pose '{pose.name}' at [{where}] lies inside {solid} (more than "
                f"{SOLID_MARGIN_M * 100:g} cm deep): move it into free space or onto a surface (z is "
                f"down; the floor is z = 0)",
                path=str(path),
                key=f"start_poses[{i}].location",
            )
            raise name_entries(err, load_yaml(path))
    return cfg
