"""A team's map, handed in at the end of a run: the occupancy grids of its brains merged into one
map in ROS's map frame (usarsim.maps.grid), written as map_server files for the scorer
(``usarsim serve --team-map``, docs/scoring.md "Map quality").

A brain takes part when it has an occupancy grid (``own``, a usarsim.brains.grid.OccupancyGrid
in the world frame its ``origin`` puts it in, as FrontierExplorer's) and may list the victims
it found (``victims_found``: (name, x, y) in the USARSim frame).  Merging adds the log-odds of
every brain's grid cell by cell (independent evidence, as occupancy grid mapping adds a sweep:
S. Thrun, W. Burgard, D. Fox, "Probabilistic Robotics", MIT Press 2005, section 9.2).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from usarsim.brains.grid import FREE_BELOW, OCC_ABOVE, OccupancyGrid
from usarsim.maps.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap


def grids_of(brains: Sequence[Any]) -> list[OccupancyGrid]:
    return [b.own for b in brains if isinstance(getattr(b, "own", None), OccupancyGrid)]


def merged_map(grids: Sequence[OccupancyGrid]) -> OccupancyMap | None:
    """The grids' log-odds added up on the first one's cell size, over all of them, as a map in
    ROS's map frame (None without grids)."""
    if not grids:
        return None
    res = grids[0].resolution
    xmin = min(g.bounds.xmin for g in grids)
    ymin = min(g.bounds.ymin for g in grids)
    xmax = max(g.bounds.xmax for g in grids)
    ymax = max(g.bounds.ymax for g in grids)
    total = OccupancyGrid(type(grids[0].bounds)(xmin, ymin, xmax, ymax), res)
    ii, jj = np.mgrid[0 : total.shape[0], 0 : total.shape[1]]
    cx, cy = total.center(ii, jj)
    for g in grids:
        gi = np.floor((cx - g.bounds.xmin) / g.resolution).astype(np.intp)
        gj = np.floor((cy - g.bounds.ymin) / g.resolution).astype(np.intp)
        inside = (gi >= 0) & (gi < g.shape[0]) & (gj >= 0) & (gj < g.shape[1])
        total.logodds[inside] += g.logodds[gi[inside], gj[inside]]
    states = np.full(total.shape, UNKNOWN, np.int8)
    states[total.logodds < FREE_BELOW] = FREE
    states[total.logodds > OCC_ABOVE] = OCCUPIED
    # logodds[i, j]: i along USARSim x (the map's x, columns), j along USARSim y (the map's -y):
    # the map's row 0 is the largest USARSim y
    data = np.flipud(states.T).copy()
    return OccupancyMap(res, (xmin, -(ymin + total.shape[1] * res)), data)


def write_team_map(brains: Sequence[Any], path: str | Path) -> Path | None:
    """Hand the team's map in at ``path`` (map_server YAML and PGM); None when no brain has a
    grid (nothing is written: the score says no map was handed in)."""
    from usarsim.maps.mapfile import write_map

    grid = merged_map(grids_of(brains))
    if grid is None:
        return None
    victims = []
    for b in brains:
        for name, x, y in getattr(b, "victims_found", None) or ():
            victims.append((str(name), float(x), -float(y)))
    return write_map(path, grid, victims=victims)
