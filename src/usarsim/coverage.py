"""The floor an exploration has seen: a coarse grid of cells over the world's floor, marked
along each laser beam from the sensor to what it hit (or to the sensing radius)."""

from __future__ import annotations

import math

import numpy as np


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
        ks = np.arange(0.0, float(lengths.max()) + step / 2, step)
        dx, dy = np.cos(headings), np.sin(headings)
        keep = ks[None, :] <= lengths[:, None]
        xs = (origin[0] + dx[:, None] * ks[None, :])[keep]
        ys = (origin[1] + dy[:, None] * ks[None, :])[keep]
        ix = np.floor((xs - self.x0) / self.cell_m).astype(np.intp)
        iy = np.floor((ys - self.y0) / self.cell_m).astype(np.intp)
        inside = (ix >= 0) & (ix < self.nx) & (iy >= 0) & (iy < self.ny)
        cells = np.unique(ix[inside] * self.ny + iy[inside])
        new = cells[~self.seen[cells]]
        self.seen[new] = True
        return new
