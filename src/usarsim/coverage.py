"""The floor an exploration has seen: a coarse grid of cells over the world's floor, marked
along each laser beam from the sensor to what it hit (or to the sensing radius).

The beams are walked by a compiled kernel (numba, cached on disk as the ray caster's is):
the same points, cells and arithmetic as the array expression it replaced, in a loop that
stops at each beam's end instead of building every beam's points to the longest one.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def _mark(seen, x0, y0, cell, nx, ny, ox, oy, headings, lengths, step, points):  # pragma: no cover - compiled
    """Mark the cells of the points ``k * step`` (k = 0 .. points - 1, up to each beam's
    length) along each beam; return the cells seen for the first time, in increasing order."""
    new = np.empty(headings.size * points, dtype=np.intp)
    count = 0
    for i in range(headings.size):
        dx = math.cos(headings[i])
        dy = math.sin(headings[i])
        length = lengths[i]
        for k in range(points):
            s = k * step
            if not s <= length:
                break
            ix = math.floor((ox + dx * s - x0) / cell)
            iy = math.floor((oy + dy * s - y0) / cell)
            if ix < 0 or ix >= nx or iy < 0 or iy >= ny:
                continue
            c = ix * ny + iy
            if not seen[c]:
                seen[c] = True
                new[count] = c
                count += 1
    return np.sort(new[:count])


class CoverageGrid:
    """Square cells of ``cell_m`` over ``bounds`` (x min, y min, x max, y max; the USARSim
    frame seen from above, X forward/north, Y right/east), each seen or not."""

    def __init__(self, bounds: tuple[float, float, float, float], cell_m: float):
        if not cell_m > 0:
            raise ValueError(f"the coverage cell size must be > 0 m, got {cell_m!r}")
        self.x0, self.y0, x1, y1 = (float(b) for b in bounds)
        self.cell_m = float(cell_m)
        self.nx = max(1, math.ceil((x1 - self.x0) / self.cell_m))
        self.ny = max(1, math.ceil((y1 - self.y0) / self.cell_m))
        self.seen = np.zeros(self.nx * self.ny, dtype=bool)

    @property
    def cell_area_m2(self) -> float:
        return self.cell_m * self.cell_m

    @property
    def seen_m2(self) -> float:
        """The area seen so far."""
        return float(np.count_nonzero(self.seen)) * self.cell_area_m2

    def clear(self) -> None:
        self.seen[:] = False

    def mark_beams(self, origin: tuple[float, float], headings: np.ndarray, lengths: np.ndarray) -> np.ndarray:
        """Mark the cells along beams from ``origin`` (x, y) in the world directions
        ``headings`` (radians, clockwise from X, the USARSim yaw) over ``lengths`` (metres);
        return the flat indices of the cells seen for the first time."""
        headings = np.asarray(headings, dtype=float)
        lengths = np.asarray(lengths, dtype=float)
        if headings.size == 0:
            return np.zeros(0, dtype=np.intp)
        step = self.cell_m / 2.0
        # as many points as np.arange(0, longest + step / 2, step) has
        points = max(0, math.ceil((float(lengths.max()) + step / 2) / step))
        return _mark(
            self.seen,
            self.x0,
            self.y0,
            self.cell_m,
            self.nx,
            self.ny,
            float(origin[0]),
            float(origin[1]),
            np.ascontiguousarray(headings.ravel()),
            np.ascontiguousarray(lengths.ravel()),
            step,
            points,
        )
