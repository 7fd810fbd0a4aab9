"""An occupancy grid built from laser sweeps, and planning on it.

The grid covers a rectangle of the world's floor in the USARSim frame (X forward/north, Y
right/east, metres) with square cells; each cell holds the log-odds that it is occupied,
0 for a cell never observed.  A sweep lowers the log-odds of the cells each beam passed
through and raises that of the cell it ended in (S. Thrun, W. Burgard, D. Fox,
"Probabilistic Robotics", MIT Press 2005, table 9.1 and the inverse sensor model of
section 9.2), clamped so that the map can change its mind.

Planning uses a cost per cell (free cells cost 1, cells within reach of an obstacle more,
obstacles, unknown cells and cells closer to an obstacle than the robot's half-width
cannot be entered) and Dijkstra's algorithm over the 8-connected cells from the robot's
cell; a frontier is a known free cell beside an unknown one (B. Yamauchi, "A
Frontier-Based Approach for Autonomous Exploration", IEEE CIRA 1997).  The searches are
compiled by numba (the simulator's own ray caster is too), cached on disk.
"""

from __future__ import annotations

import heapq
import io
import math
import zlib
from dataclasses import dataclass

import numpy as np
from numba import njit

L_FREE = -0.7  # log-odds added to a cell a beam passed through
L_OCC = 1.4  # ... and to the cell it ended in
L_MIN, L_MAX = -3.0, 3.5  # clamping: a few sweeps change a cell's state
FREE_BELOW = -0.5  # log-odds below this: free
OCC_ABOVE = 0.6  # above this: occupied; between: unknown
BLOCKED = np.inf


@dataclass(frozen=True)
class Bounds:
    """A rectangle of the floor, metres, USARSim frame."""

    xmin: float
    ymin: float
    xmax: float
    ymax: float

    @classmethod
    def around(cls, x: float, y: float, half_size: float) -> Bounds:
        return cls(x - half_size, y - half_size, x + half_size, y + half_size)

    @classmethod
    def parse(cls, text: str) -> Bounds:
        """``xmin,ymin,xmax,ymax``."""
        parts = [float(p) for p in text.replace(" ", ",").split(",") if p]
        if len(parts) != 4 or not (parts[0] < parts[2] and parts[1] < parts[3]):
            raise ValueError(f"bounds must be xmin,ymin,xmax,ymax with xmin < xmax and ymin < ymax, got {text!r}")
        return cls(*parts)


class OccupancyGrid:
    """Log-odds occupancy over ``bounds`` at ``resolution`` metres a cell.  ``logodds[i, j]``
    is the cell whose corner is (xmin + i res, ymin + j res)."""

    def __init__(self, bounds: Bounds, resolution: float = 0.1):
        if resolution <= 0:
            raise ValueError(f"resolution must be > 0, got {resolution}")
        self.bounds = bounds
        self.resolution = float(resolution)
        self.shape = (
            max(1, math.ceil((bounds.xmax - bounds.xmin) / resolution)),
            max(1, math.ceil((bounds.ymax - bounds.ymin) / resolution)),
        )
        self.logodds = np.zeros(self.shape, np.float32)

    # cells and coordinates -------------------------------------------------------------
    def cell(self, x: float, y: float) -> tuple[int, int]:
        """The cell holding (x, y) (it may lie outside the grid: check :meth:`inside`)."""
        return (
            int(math.floor((x - self.bounds.xmin) / self.resolution)),
            int(math.floor((y - self.bounds.ymin) / self.resolution)),
        )

    def inside(self, i: int, j: int) -> bool:
        return 0 <= i < self.shape[0] and 0 <= j < self.shape[1]

    def center(self, i: float, j: float) -> tuple[float, float]:
        return (self.bounds.xmin + (i + 0.5) * self.resolution, self.bounds.ymin + (j + 0.5) * self.resolution)

    # states ----------------------------------------------------------------------------
    @property
    def free(self) -> np.ndarray:
        return self.logodds < FREE_BELOW

    @property
    def occupied(self) -> np.ndarray:
        return self.logodds > OCC_ABOVE

    @property
    def unknown(self) -> np.ndarray:
        return (self.logodds >= FREE_BELOW) & (self.logodds <= OCC_ABOVE)

    def known_share(self) -> float:
        return float(np.count_nonzero(~self.unknown)) / self.logodds.size

    # updates ---------------------------------------------------------------------------
    def integrate(
        self,
        origin: tuple[float, float],
        directions: np.ndarray,
        ranges: np.ndarray,
        max_range: float,
        free_limit: float,
    ) -> None:
        """One sweep: beams from ``origin`` (world x, y) in ``directions`` (radians from +X
        towards +Y, i.e. clockwise seen from above), ``ranges`` metres.  A beam shorter than
        ``max_range`` (a little less: what the scanner reports when nothing was hit) ends in
        an obstacle; free space is marked up to ``free_limit`` at most (long beams fan out
        and small heading errors smear them)."""
        ranges = np.asarray(ranges, dtype=np.float64)
        directions = np.asarray(directions, dtype=np.float64)
        ok = np.isfinite(ranges) & (ranges > 0)
        ranges, directions = ranges[ok], directions[ok]
        if ranges.size == 0:
            return
        hit = ranges < max_range * 0.995
        reach = np.minimum(ranges, free_limit)
        hit &= ranges <= free_limit
        step = self.resolution * 0.5
        n = int(math.ceil(float(reach.max()) / step))
        t = np.arange(n, dtype=np.float64) * step  # along every beam
        c, s = np.cos(directions), np.sin(directions)
        # free: the samples before the end (half a cell short of a hit)
        limit = np.where(hit, reach - self.resolution * 0.5, reach)
        mask = t[None, :] < limit[:, None]
        px = origin[0] + t[None, :] * c[:, None]
        py = origin[1] + t[None, :] * s[:, None]
        free_idx = self._flat(px[mask], py[mask])
        hx = origin[0] + ranges[hit] * c[hit]
        hy = origin[1] + ranges[hit] * s[hit]
        occ_idx = self._flat(hx, hy)
        flat = self.logodds.reshape(-1)
        free_idx = np.setdiff1d(free_idx, occ_idx)  # np.unique inside: one update per cell and sweep
        flat[free_idx] = np.clip(flat[free_idx] + L_FREE, L_MIN, L_MAX)
        flat[occ_idx] = np.clip(flat[occ_idx] + L_OCC, L_MIN, L_MAX)

    def clear_disk(self, x: float, y: float, radius: float) -> None:
        """Mark the cells within ``radius`` of (x, y) free: where the robot stands is floor."""
        self._disk_set(x, y, radius, L_MIN * 0.5, lower_only=True)

    def mark_occupied(self, x: float, y: float, radius: float) -> None:
        """Mark the cells within ``radius`` of (x, y) occupied (an obstacle the laser does
        not see, found by running into it)."""
        self._disk_set(x, y, radius, L_MAX, lower_only=False)

    def _disk_set(self, x: float, y: float, radius: float, value: float, lower_only: bool) -> None:
        ci, cj = self.cell(x, y)
        k = int(math.ceil(radius / self.resolution))
        i0, i1 = max(0, ci - k), min(self.shape[0], ci + k + 1)
        j0, j1 = max(0, cj - k), min(self.shape[1], cj + k + 1)
        if i0 >= i1 or j0 >= j1:
            return
        ii, jj = np.mgrid[i0:i1, j0:j1]
        cx, cy = self.center(ii, jj)
        inside = (cx - x) ** 2 + (cy - y) ** 2 <= radius * radius
        block = self.logodds[i0:i1, j0:j1]
        if lower_only:
            block[inside] = np.minimum(block[inside], value)
        else:
            block[inside] = value

    def _flat(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        i = np.floor((x - self.bounds.xmin) / self.resolution).astype(np.int64)
        j = np.floor((y - self.bounds.ymin) / self.resolution).astype(np.int64)
        keep = (i >= 0) & (i < self.shape[0]) & (j >= 0) & (j < self.shape[1])
        return np.unique(i[keep] * self.shape[1] + j[keep])

    # sharing ---------------------------------------------------------------------------
    def to_bytes(self) -> bytes:
        """The log-odds quantised to signed bytes (tenths), compressed: a few kB for an arena."""
        q = np.clip(np.round(self.logodds * 10.0), -127, 127).astype(np.int8)
        return zlib.compress(q.tobytes(), 6)

    def from_bytes(self, data: bytes) -> np.ndarray:
        """The log-odds of a grid of this shape sent with :meth:`to_bytes`."""
        raw = zlib.decompress(data, bufsize=self.logodds.size + 16)
        if len(raw) != self.logodds.size:
            raise ValueError(f"a map of {len(raw)} cells does not fit this grid of {self.logodds.size}")
        return np.frombuffer(raw, np.int8).astype(np.float32).reshape(self.shape) / 10.0

    # pictures --------------------------------------------------------------------------
    def to_png(
        self,
        path: str,
        *,
        path_xy: list[tuple[float, float]] | None = None,
        marks: list[tuple[float, float]] | None = None,
        scale: int = 4,
    ) -> None:
        """Save the map as a picture (north up, east right): white free, black occupied,
        grey unknown; ``path_xy`` in blue, ``marks`` (robots, victims) in red."""
        from PIL import Image  # the image server's dependency

        img = np.full(self.shape + (3,), 128, np.uint8)
        img[self.free] = 255
        img[self.occupied] = 0
        for pts, colour in ((path_xy or [], (40, 90, 230)), (marks or [], (220, 30, 30))):
            for x, y in pts:
                i, j = self.cell(x, y)
                if self.inside(i, j):
                    img[max(0, i - 1) : i + 2, max(0, j - 1) : j + 2] = colour
        # rows: x decreasing downwards (north up); columns: y increasing (east right)
        pic = Image.fromarray(img[::-1, :, :]).resize(
            (self.shape[1] * scale, self.shape[0] * scale), Image.Resampling.NEAREST
        )
        buf = io.BytesIO()
        pic.save(buf, format="PNG")
        with open(path, "wb") as f:
            f.write(buf.getvalue())


# ------------------------------------------------------------------------------ planning

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
    cells = []
    while f >= 0 and len(cells) <= parent.size:
        cells.append(f)
        f = int(parent[f])
    cells.reverse()
    return [grid.center(c // ny, c % ny) for c in cells]


def warm_up() -> None:
    """Compile (or load from the disk cache) the searches now, not on the first plan."""
    g = OccupancyGrid(Bounds(0.0, 0.0, 1.0, 1.0), 0.25)
    g.logodds[:] = L_MIN
    g.logodds[0, 0] = L_MAX
    Planner().search(g, (0.6, 0.6))
    frontier_clusters(g)


# ------------------------------------------------------------------------------ scan matching


@njit(cache=True, nogil=True)
def _match(field, x0, y0, res, px, py, gx, gy, ga, dxs, dys, das, prior_xy, prior_a):
    """The pose (of the candidates around (gx, gy, ga)) whose beam end points (px, py in the
    robot's frame) fall best on the likelihood ``field``, less ``prior_xy`` and ``prior_a``
    times the squared offsets from the guess; returns (score, x, y, a)."""
    nx, ny = field.shape
    best = -1e300
    bx, by, ba = gx, gy, ga
    for a_off in das:
        a = ga + a_off
        c = math.cos(a)
        s = math.sin(a)
        for dx in dxs:
            for dy in dys:
                x = gx + dx
                y = gy + dy
                total = 0.0
                for k in range(px.size):
                    wx = x + px[k] * c - py[k] * s
                    wy = y + px[k] * s + py[k] * c
                    i = int(math.floor((wx - x0) / res))
                    j = int(math.floor((wy - y0) / res))
                    if i >= 0 and i < nx and j >= 0 and j < ny:
                        total += field[i, j]
                total -= prior_xy * (dx * dx + dy * dy) + prior_a * a_off * a_off
                if total > best:
                    best = total
                    bx, by, ba = x, y, a
    return best, bx, by, ba


PRIOR_XY = 0.05  # m
PRIOR_A = 0.02  # rad


class ScanMatcher:
    """Corrects a pose guess (from odometry) by fitting a sweep's end points to the walls
    already in the map: a brute-force search over small offsets of heading, then of
    position, scoring each candidate by how near its end points fall to occupied cells
    (a likelihood field, E. Olson, "Real-Time Correlative Scan Matching", ICRA 2009,
    without the multi-resolution tables)."""

    def __init__(self, sigma: float = 0.08, reach: float = 0.4, min_points: int = 40):
        self.sigma, self.reach, self.min_points = sigma, reach, min_points
        self.field: np.ndarray | None = None

    def refresh(self, grid: OccupancyGrid) -> None:
        """Recompute the likelihood field from the map's occupied cells."""
        occ = grid.occupied
        if np.count_nonzero(occ) < self.min_points:
            self.field = None
            return
        d = _distance_to(occ, self.reach / grid.resolution) * grid.resolution
        self.field = np.exp(-0.5 * (d / self.sigma) ** 2)

    def match(
        self, grid: OccupancyGrid, guess: tuple[float, float, float], points: np.ndarray, wide: bool = False
    ) -> tuple[float, float, float] | None:
        """The corrected pose for end points ``points`` ((n, 2), robot frame), or None when
        the sweep or the map has too little to go by.  ``wide`` searches further (0.4 rad,
        0.4 m: after the robot has lurched over a box, when the odometry may be far off)
        and asks for a better fit."""
        if self.field is None or len(points) < self.min_points:
            return None
        px = np.ascontiguousarray(points[:, 0], dtype=np.float64)
        py = np.ascontiguousarray(points[:, 1], dtype=np.float64)
        b = grid.bounds
        zero = np.zeros(1)
        # the guess is good over one sweep: moving it by PRIOR_XY (PRIOR_A) must gain a
        # twentieth of the points' score, so that a corridor, where nothing fixes the
        # position along it, leaves the guess alone
        n = len(points)
        prior_xy, prior_a = 0.05 * n / PRIOR_XY**2, 0.05 * n / PRIOR_A**2
        # heading first (a heading error moves the far points most), then position, twice
        stages = [
            (np.linspace(-0.08, 0.08, 17), 0.0, 3),
            (np.linspace(-0.02, 0.02, 5), 0.05, 3),
            (np.linspace(-0.006, 0.006, 3), 0.02, 3),
        ]
        if wide:
            stages.insert(0, (np.linspace(-0.4, 0.4, 41), 0.1, 4))
        gx, gy, ga = guess
        for das, step, k in stages:
            offs = np.arange(-k, k + 1) * step if step else zero
            score, gx, gy, ga = _match(
                self.field,
                b.xmin,
                b.ymin,
                grid.resolution,
                px,
                py,
                gx,
                gy,
                ga,
                offs,
                offs,
                das,
                0.0 if wide else prior_xy,
                0.0 if wide else prior_a,
            )
        if score < (0.5 if wide else 0.35) * len(points):  # most points should lie on known walls
            return None
        return gx, gy, ga
