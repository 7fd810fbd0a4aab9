"""An occupancy grid built from laser sweeps.

The grid covers a rectangle of the world's floor in the USARSim frame (X forward/north, Y
right/east, metres) with square cells; each cell holds the log-odds that it is occupied,
0 for a cell never observed.  A sweep lowers the log-odds of the cells each beam passed
through and raises that of the cell it ended in (S. Thrun, W. Burgard, D. Fox,
"Probabilistic Robotics", MIT Press 2005, table 9.1 and the inverse sensor model of
section 9.2), clamped so that the map can change its mind.

Planning and frontiers on the grid are in :mod:`usarsim.brains.planning`, scan matching
against it in :mod:`usarsim.brains.scanmatch`; their names can be imported from here too.
"""

from __future__ import annotations

import io
import math
import zlib
from dataclasses import dataclass
from typing import Any, overload

import numpy as np

from usarsim.brains.planning import BLOCKED, SQRT2, Planner, frontier_cells, frontier_clusters, path_to
from usarsim.brains.scanmatch import PRIOR_A, PRIOR_XY, ScanMatcher

__all__ = [
    "BLOCKED",
    "FREE_BELOW",
    "L_FREE",
    "L_MAX",
    "L_MIN",
    "L_OCC",
    "OCC_ABOVE",
    "PRIOR_A",
    "PRIOR_XY",
    "SQRT2",
    "Bounds",
    "OccupancyGrid",
    "Planner",
    "ScanMatcher",
    "frontier_cells",
    "frontier_clusters",
    "path_to",
    "warm_up",
]

L_FREE = -0.7  # log-odds added to a cell a beam passed through
L_OCC = 1.4  # ... and to the cell it ended in
L_MIN, L_MAX = -3.0, 3.5  # clamping: a few sweeps change a cell's state
FREE_BELOW = -0.5  # log-odds below this: free
OCC_ABOVE = 0.6  # above this: occupied; between: unknown


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

    @overload
    def center(self, i: np.ndarray, j: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...
    @overload
    def center(self, i: float | np.integer, j: float | np.integer) -> tuple[float, float]: ...
    def center(self, i: Any, j: Any) -> Any:
        """The middle of cell (i, j) (of each, for arrays of indices), in metres."""
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


def warm_up() -> None:
    """Compile (or load from the disk cache) the searches now, not on the first plan."""
    g = OccupancyGrid(Bounds(0.0, 0.0, 1.0, 1.0), 0.25)
    g.logodds[:] = L_MIN
    g.logodds[0, 0] = L_MAX
    Planner().search(g, (0.6, 0.6))
    frontier_clusters(g)
