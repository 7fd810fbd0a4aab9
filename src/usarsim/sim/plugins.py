"""The plugins a simulation builds its robots from, as the simulation sees them.

The simulation's core (:mod:`usarsim.sim.simulation`, :mod:`usarsim.sim.robotspec`, the
facade) never imports a plugin package: drive models (:mod:`usarsim.robots`) and mounted
items (:mod:`usarsim.sensors`, :mod:`usarsim.effecters`) sit above it and use its leaf
modules (the world view, the output records, frames).  What the core needs of them is one
:class:`PluginSet`, handed to it by the composition root (:mod:`usarsim.plugins` builds the
built-in one; the server's :class:`~usarsim.server.app.Application` passes it on).  A
simulation built without one (a test, a benchmark) finds the built-in set by its module
name, the way plugins are found at run time.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the plugins' base classes, for the types only
    from usarsim.config.robot import MountedItem, RobotConfig
    from usarsim.robots.base import DriveModel
    from usarsim.sensors.base import Item

# the module whose BUILTIN is the set of every built-in plugin (it imports each plugin package)
BUILTIN_MODULE = "usarsim.plugins"


@dataclass(frozen=True)
class PluginSet:
    """What the simulation asks of its plugins: a drive model for a robot file, its class
    (what it accepts, the numbers GETGEO reports), a mounted item for a robot file's entry,
    and an item type's canonical spelling."""

    drive_class: Callable[[RobotConfig], type[DriveModel[Any, Any]]]
    make_drive: Callable[[RobotConfig], DriveModel[Any, Any]]
    make_item: Callable[[MountedItem, RobotConfig, int, str], Item[Any]]
    canonical_item_type: Callable[[str], str | None]


def builtin_plugins() -> PluginSet:
    """The built-in plugins (every drive, sensor, effecter and camera shipped), found by module name."""
    plugins: PluginSet = importlib.import_module(BUILTIN_MODULE).BUILTIN
    return plugins
