"""The ground-truth map of a world: what a perfect map made at a robot's sensing height holds.

A cell is OCCUPIED when a solid of the world (walls, boxes, movable debris where the world
puts it, false alarms) stands in it at ``height`` metres above the floor, FREE when it is not
and a robot could get there (the floor joined to a start pose through free cells at that
height), and UNKNOWN otherwise (a closed-off pocket, the inside of a solid below the height).
Victims are not cells: they are listed with the RFID tags and start poses, to be drawn on the
map and scored.

:func:`ground_truth_map` is what ``usarsim map`` writes, what the ground-truth service hands
out (``{Map ...}``), what a recording holds on ``/map``, and what ``usarsim score-map`` scores
a team's map against.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from usarsim.config.world import WorldConfig
from usarsim.maps.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap, floor_grid, solid_cells, to_map_frame, world_solids

# The sensing height of the ground-truth map by default (metres above the floor): where a P2AT's
# laser sweeps.  Its SICK LMS200 is mounted 0.092 m above the body's centre (protocol.md 6.8)
# and the body's centre rests about 0.21 m above the floor (usarsim's P2AT: wheel radius
# 0.11 m, Pioneer 3-AT operations manual, plus the axle's offset), so about 0.3 m.
DEFAULT_HEIGHT_M = 0.3
# The ground-truth map's cell size by default (metres): 5 cm, the resolution the RoboCup Rescue
# virtual robot competitions' maps were handed in at (Balaguer et al., "Evaluating maps produced
# by urban search and rescue robots: lessons learned from RoboCup", Autonomous Robots 27(4), 2009).
DEFAULT_RESOLUTION_M = 0.05


@dataclass(frozen=True)
class Marker:
    """A thing drawn on a map: a victim, an RFID tag or a start pose, at map-frame (x, y)."""

    kind: str  # "victim", "tag", "start"
    name: str
    x: float
    y: float


@dataclass
class GroundTruthMap:
    """A world's ground-truth occupancy grid, with its victims, RFID tags and start poses."""

    world: str
    variant: int | None
    height: float
    grid: OccupancyMap
    markers: list[Marker] = field(default_factory=list)

    @property
    def reachable(self) -> np.ndarray:
        """The free cells (reachable from a start pose)."""
        return self.grid.free

    def victims(self) -> list[Marker]:
        return [m for m in self.markers if m.kind == "victim"]


def ground_truth_map(
    world: WorldConfig,
    *,
    resolution: float = DEFAULT_RESOLUTION_M,
    height: float = DEFAULT_HEIGHT_M,
    variant: int | None = None,
) -> GroundTruthMap:
    """The ground-truth map of ``world`` (a variant already applied: usarsim.maps.variation)."""
    if not height > 0:
        raise ValueError(f"the map's height must be > 0 m above the floor, got {height!r}")
    grid = floor_grid(world, resolution)
    solid = solid_cells(grid, world_solids(world), [height])
    starts = [to_map_frame(p.location[0], p.location[1]) for p in world.start_poses]
    reach = connected_to(~solid, starts, grid)
    grid.data[:] = UNKNOWN
    grid.data[solid] = OCCUPIED
    grid.data[reach] = FREE
    markers = [Marker("victim", v.name, *to_map_frame(v.location[0], v.location[1])) for v in world.victims]
    markers += [Marker("tag", str(t.tag_id), *to_map_frame(t.location[0], t.location[1])) for t in world.rfid_tags]
    markers += [Marker("start", p.name, *to_map_frame(p.location[0], p.location[1])) for p in world.start_poses]
    return GroundTruthMap(world.name, variant, float(height), grid, markers)


def connected_to(passable: np.ndarray, points, grid: OccupancyMap) -> np.ndarray:
    """The cells of ``passable`` joined (4-connected) to the cells holding any of ``points``
    (map-frame (x, y))."""
    import cv2

    pts = np.asarray(list(points), float).reshape(-1, 2)
    count, labels = cv2.connectedComponents(passable.astype(np.uint8), connectivity=4)
    rows, cols, inside = grid.cell_of(pts)
    keep = {int(labels[r, c]) for r, c, ok in zip(rows, cols, inside) if ok and passable[r, c]}
    if not keep:
        return np.zeros(passable.shape, bool)
    return np.isin(labels, sorted(keep))
