"""Where a ground robot can drive: the ground each cell offers (the floor, or the top of a ramp,
a platform, a box it stands on) and the room above it, from a world's solids.

For each cell the vertical line through its centre meets each solid in an interval of heights
above the floor (a slab test of the line against the box, S. Kay and J. Kajiya, "Ray tracing
complex scenes", SIGGRAPH 1986; a quadratic for a cylinder).  The **ground** is the top of the
solids stacked from the floor up (the floor itself where none is), the **ceiling** the bottom of
the lowest solid above that ground (under a table: its top).  A robot stands on a cell whose
ground is no higher than MAX_GROUND_M with at least ``height`` below the ceiling, and moves to a
neighbouring cell whose ground differs by at most ``step`` (a slope, not a step: a P2AT climbs
the arenas' 10-degree ramps but not a 0.3 m platform's side).  A robot of radius r keeps r from
any cell it cannot stand on and from any edge where the ground jumps.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from usarsim.maps.grid import OccupancyMap, Solid

MAX_GROUND_M = 0.6  # ground higher than this is the top of a wall or a stack, not a place to drive
# the most the ground may rise from one cell to the next, as a slope: tan(30 degrees), steeper
# than the arenas' ramps (10 degrees) and humps (7.7 degrees), gentler than a box's side
MAX_SLOPE = math.tan(math.radians(30.0))
# the room a robot needs above the ground: a P2AT is 0.277 m tall (Pioneer 3-AT operations
# manual), its laser on top
ROBOT_HEIGHT_M = 0.35


def _intervals(grid: OccupancyMap, solid: Solid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(flat cell indices, lowest, highest height above the floor) where the vertical lines
    through the cells' centres meet ``solid`` (a cell counts when the solid overlaps it by half
    a cell each way, as usarsim.maps.grid.solid_cells counts it)."""
    res = grid.resolution
    cols = grid.shape[1]
    rot, box, rs, cs = solid.cell_window(grid)
    half = solid.half_extents()
    empty = (np.zeros(0, np.intp), np.zeros(0), np.zeros(0))
    if rs.start == rs.stop or cs.start == cs.stop or -box[2] < 0.0:  # none, or wholly below the floor
        return empty
    rr, cc = (a.ravel() for a in np.mgrid[rs, cs])
    wx = grid.origin[0] + (cc + 0.5) * res
    wy = -(grid.origin[1] + (rr + 0.5) * res)
    o = (np.column_stack((wx, wy, np.zeros_like(wx))) - np.asarray(solid.center)) @ rot  # local, at height 0
    d = -rot[2, :]  # the local direction of "up" (USARSim's z is down)
    pad = res / 2.0
    t0 = np.zeros(len(o))
    t1 = np.full(len(o), np.inf)
    if solid.shape == "cylinder":
        r = half[0] + pad
        a = d[0] ** 2 + d[1] ** 2
        b = 2.0 * (o[:, 0] * d[0] + o[:, 1] * d[1])
        c = o[:, 0] ** 2 + o[:, 1] ** 2 - r * r
        if a < 1e-12:
            t1 = np.where(c <= 0.0, t1, -1.0)
        else:
            disc = b * b - 4.0 * a * c
            ok = disc >= 0.0
            root = np.sqrt(np.where(ok, disc, 0.0))
            t0 = np.maximum(t0, np.where(ok, (-b - root) / (2 * a), np.inf))
            t1 = np.minimum(t1, np.where(ok, (-b + root) / (2 * a), -np.inf))
        axes: tuple[tuple[int, float], ...] = ((2, half[2]),)
    else:  # a box (a mesh by its bounding box)
        axes = ((0, half[0] + pad), (1, half[1] + pad), (2, half[2]))
    for i, h in axes:
        if abs(d[i]) < 1e-12:
            inside = np.abs(o[:, i]) <= h
            t1 = np.where(inside, t1, -1.0)
        else:
            a_, b_ = (-h - o[:, i]) / d[i], (h - o[:, i]) / d[i]
            t0 = np.maximum(t0, np.minimum(a_, b_))
            t1 = np.minimum(t1, np.maximum(a_, b_))
    hit = t1 > t0
    return (rr[hit] * cols + cc[hit]).astype(np.intp), t0[hit], t1[hit]


def ground_and_ceiling(
    grid: OccupancyMap, solids: Sequence[Solid], height: float = ROBOT_HEIGHT_M
) -> tuple[np.ndarray, np.ndarray]:
    """Each cell's ground and ceiling for a robot ``height`` tall: the ground is the top of the
    solids it cannot pass under (those reaching lower than ``height`` above the ground below
    them: a ramp's plate, a box, a platform; 0 for bare floor), the ceiling the bottom of the
    lowest solid above that (under a table: its top; inf for open sky)."""
    n = grid.shape[0] * grid.shape[1]
    spans = [s for s in (_intervals(grid, solid) for solid in solids) if len(s[0])]
    ground = np.zeros(n)
    eps = 1e-3
    for _ in range(len(spans) + 1):  # a stack of k solids settles in k passes
        changed = False
        for idx, t0, t1 in spans:
            g = ground[idx]
            up = (t0 < g + height) & (t1 > g + eps)
            if up.any():
                np.maximum.at(ground, idx[up], t1[up])
                changed = True
        if not changed:
            break
    ceiling = np.full(n, np.inf)
    for idx, t0, _ in spans:
        above = t0 > ground[idx] + eps
        np.minimum.at(ceiling, idx[above], t0[above])
    return ground.reshape(grid.shape), ceiling.reshape(grid.shape)


def clear_cells(
    grid: OccupancyMap,
    solids: Sequence[Solid],
    radius: float,
    *,
    height: float = ROBOT_HEIGHT_M,
    slope: float = MAX_SLOPE,
) -> np.ndarray:
    """The cells where a robot of ``radius`` and ``height`` can stand with its body clear of
    everything it cannot stand on or climb: their 4-connected regions are what it can drive
    between."""
    import cv2

    ground, ceiling = ground_and_ceiling(grid, solids, height)
    bad = (ground > MAX_GROUND_M) | (ceiling - ground < height)
    step = slope * grid.resolution
    edge = np.zeros(grid.shape, bool)
    jump_x = np.abs(np.diff(ground, axis=1)) > step
    jump_y = np.abs(np.diff(ground, axis=0)) > step
    edge[:, 1:] |= jump_x
    edge[:, :-1] |= jump_x
    edge[1:, :] |= jump_y
    edge[:-1, :] |= jump_y
    free = (~(bad | edge)).astype(np.uint8)
    return cv2.distanceTransform(free, cv2.DIST_L2, 5) * grid.resolution >= radius
