"""Planning on an occupancy grid (:mod:`usarsim.brains.grid`): costs, shortest paths and
frontiers.

Planning uses a cost per cell (free cells cost 1, cells within reach of an obstacle more,
obstacles, unknown cells and cells closer to an obstacle than the robot's half-width
cannot be entered) and Dijkstra's algorithm over the 8-connected cells from the robot's
cell; a frontier is a known free cell beside an unknown one (B. Yamauchi, "A
Frontier-Based Approach for Autonomous Exploration", IEEE CIRA 1997).  The searches are
compiled by numba (the simulator's own ray caster is too), cached on disk.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

if TYPE_CHECKING:
    from usarsim.brains.grid import OccupancyGrid

BLOCKED = np.inf  # the cost of a cell that cannot be entered
SQRT2 = math.sqrt(2.0)


@njit(cache=True, nogil=True)
def _distance_to(sources, max_d):
    """Chamfer distance (cells; 1 and sqrt 2 steps) from every cell to the nearest source
    cell, up to ``max_d`` (beyond: max_d)."""
    nx, ny = sources.shape
    dist = np.full((nx, ny), max_d)
    h = [(0.0, 0)]
    h.pop()
    for i in range(nx):
        for j in range(ny):
            if sources[i, j]:
                dist[i, j] = 0.0
                h.append((0.0, i * ny + j))
    while len(h) > 0:
        d, f = heapq.heappop(h)
        i = f // ny
        j = f % ny
        if d > dist[i, j]:
            continue
        for di in range(-1, 2):
            for dj in range(-1, 2):
                if di == 0 and dj == 0:
                    continue
                a = i + di
                b = j + dj
                if a < 0 or a >= nx or b < 0 or b >= ny:
                    continue
                nd = d + (1.4142135623730951 if di != 0 and dj != 0 else 1.0)
                if nd < dist[a, b] and nd < max_d:
                    dist[a, b] = nd
                    heapq.heappush(h, (nd, a * ny + b))
    return dist


@njit(cache=True, nogil=True)
def _dijkstra(cost, si, sj):
    """Path lengths (cells, weighted by the mean cost of the two cells of each step) from
    (si, sj) to every cell, and each cell's predecessor (flat index, -1: none)."""
    nx, ny = cost.shape
    dist = np.full((nx, ny), np.inf)
    parent = np.full(nx * ny, -1, np.int64)
    dist[si, sj] = 0.0
    h = [(0.0, si * ny + sj)]
    while len(h) > 0:
        d, f = heapq.heappop(h)
        i = f // ny
        j = f % ny
        if d > dist[i, j]:
            continue
        ci = cost[i, j]
        for di in range(-1, 2):
            for dj in range(-1, 2):
                if di == 0 and dj == 0:
                    continue
                a = i + di
                b = j + dj
                if a < 0 or a >= nx or b < 0 or b >= ny:
                    continue
                cb = cost[a, b]
                if not np.isfinite(cb):
                    continue
                if di != 0 and dj != 0:
                    # no corner cutting between two blocked cells
                    if not (np.isfinite(cost[i + di, j]) and np.isfinite(cost[i, j + dj])):
                        continue
                    step = 1.4142135623730951
                else:
                    step = 1.0
                nd = d + step * 0.5 * (ci + cb)
                if nd < dist[a, b]:
                    dist[a, b] = nd
                    parent[a * ny + b] = f
                    heapq.heappush(h, (nd, a * ny + b))
    return dist, parent


@njit(cache=True, nogil=True)
def _label(mask):
    """8-connected components of ``mask``: labels (0: not in mask, 1..n) and n."""
    nx, ny = mask.shape
    labels = np.zeros((nx, ny), np.int64)
    n = 0
    stack = np.empty(nx * ny, np.int64)
    for i0 in range(nx):
        for j0 in range(ny):
            if not mask[i0, j0] or labels[i0, j0] != 0:
                continue
            n += 1
            labels[i0, j0] = n
            top = 0
            stack[top] = i0 * ny + j0
            top += 1
            while top > 0:
                top -= 1
                f = stack[top]
                i = f // ny
                j = f % ny
                for di in range(-1, 2):
                    for dj in range(-1, 2):
                        a = i + di
                        b = j + dj
                        if a < 0 or a >= nx or b < 0 or b >= ny:
                            continue
                        if mask[a, b] and labels[a, b] == 0:
                            labels[a, b] = n
                            stack[top] = a * ny + b
                            top += 1
    return labels, n


def frontier_cells(grid: OccupancyGrid) -> np.ndarray:
    """Free cells with an unknown 4-neighbour (bool array)."""
    unknown = grid.unknown
    near = np.zeros_like(unknown)
    near[1:, :] |= unknown[:-1, :]
    near[:-1, :] |= unknown[1:, :]
    near[:, 1:] |= unknown[:, :-1]
    near[:, :-1] |= unknown[:, 1:]
    return grid.free & near


def frontier_clusters(grid: OccupancyGrid, min_cells: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Frontier cells grouped 8-connected; groups under ``min_cells`` dropped.  Returns the
    label array (0: none) and the sizes by label."""
    labels, n = _label(frontier_cells(grid))
    sizes = np.bincount(labels.reshape(-1), minlength=n + 1)
    small = sizes < min_cells
    small[0] = True
    labels[small[labels]] = 0
    sizes[small] = 0
    return labels, sizes


@dataclass
class Planner:
    """Costs and paths on an :class:`OccupancyGrid` for a robot of ``radius`` metres (the
    half-width it needs beside an obstacle), keeping ``clearance`` metres more where it can."""

    radius: float = 0.3
    clearance: float = 0.35
    near_wall_cost: float = 6.0
    escape_radius: float = 0.45

    def costs(self, grid: OccupancyGrid, robot_xy: tuple[float, float]) -> np.ndarray:
        res = grid.resolution
        occupied = grid.occupied
        reach = self.radius + self.clearance
        d = _distance_to(occupied, reach / res + 1.0) * res  # metres to the nearest obstacle
        cost = np.ones(grid.shape, np.float64)
        band = d < reach
        cost[band] += self.near_wall_cost * (reach - d[band]) / self.clearance
        blocked = (d < self.radius) | grid.unknown
        # where the robot stands, and just around it, it may move even if the map says no
        # (it is there): only real obstacles stop it
        ci, cj = grid.cell(*robot_xy)
        k = int(math.ceil(self.escape_radius / res))
        i0, i1 = max(0, ci - k), min(grid.shape[0], ci + k + 1)
        j0, j1 = max(0, cj - k), min(grid.shape[1], cj + k + 1)
        if i0 < i1 and j0 < j1:
            ii, jj = np.mgrid[i0:i1, j0:j1]
            near = (ii - ci) ** 2 + (jj - cj) ** 2 <= k * k
            sub = blocked[i0:i1, j0:j1]
            sub[near & ~occupied[i0:i1, j0:j1]] = False
            cost[i0:i1, j0:j1][near] += 2.0
        cost[blocked] = BLOCKED
        return cost

    def search(self, grid: OccupancyGrid, robot_xy: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
        """Path costs (metres, weighted) from the robot to every cell, and predecessors."""
        cost = self.costs(grid, robot_xy)
        ci, cj = grid.cell(*robot_xy)
        ci = min(max(ci, 0), grid.shape[0] - 1)
        cj = min(max(cj, 0), grid.shape[1] - 1)
        cost[ci, cj] = 1.0
        dist, parent = _dijkstra(cost, ci, cj)
        return dist * grid.resolution, parent


def path_to(grid: OccupancyGrid, parent: np.ndarray, goal: tuple[int, int]) -> list[tuple[float, float]]:
    """The cells from the search's start to ``goal`` as world points (start first)."""
    ny = grid.shape[1]
    f = goal[0] * ny + goal[1]
    cells: list[int] = []
    while f >= 0 and len(cells) <= parent.size:
        cells.append(f)
        f = int(parent[f])
    cells.reverse()
    return [grid.center(c // ny, c % ny) for c in cells]
