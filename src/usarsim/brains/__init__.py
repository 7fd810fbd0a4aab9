"""Brains: ready-made robot controllers, the successors of the Pyro brains of USARSim's
manual (sections 4.4.2 and 13.2).

Each brain drives one robot through :mod:`usarsim.client`: it reads the robot's latest
readings and sends its DRIVE once per control period, so the same brain runs in real time
or in lock-step, alone or beside other code::

    from usarsim.client import launch
    from usarsim.brains import Wander, run

    with launch(world="DM-USAR_yellow", seed=1) as server:      # a lock-step simulator
        world = server.connect()
        robot = world.spawn("P2AT", start="PlayerStart1")
        brain = Wander(robot)
        run(world, [brain], seconds=60)                         # or: world.step(0.1); brain.step(0.1)

* :class:`Wander` (``python -m usarsim.brains.wander``): obstacle-avoiding wander;
* :class:`WallFollower` (``wall_follower``): keeps a wall on one side at a set distance;
* :class:`FrontierExplorer` (``frontier``): maps with the laser and drives to the nearest
  frontier of its occupancy grid;
* :class:`VictimApproacher` (``victim``): explores until the victim sensor sees a victim,
  then drives to it and reports where it is;
* :class:`Team` (``team``): frontier explorers sharing their maps over the ComServer.

:mod:`usarsim.brains.coverage` scores an exploration against the world file. See
docs/brains.md.
"""

from __future__ import annotations

import importlib
from typing import Any

# Loaded on first use, so that ``python -m usarsim.brains.<brain>`` runs the module once.
_WHERE = {
    "P2AT": "base",
    "Body": "base",
    "Brain": "base",
    "Bounds": "grid",
    "OccupancyGrid": "grid",
    "FrontierExplorer": "frontier",
    "run": "runner",
    "Team": "team",
    "VictimApproacher": "victim",
    "WallFollower": "wall_follower",
    "Wander": "wander",
}

__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    if name not in _WHERE:
        raise AttributeError(f"module 'usarsim.brains' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
    globals()[name] = value
    return value
