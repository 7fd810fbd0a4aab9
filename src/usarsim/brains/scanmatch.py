"""Scan matching against an occupancy grid (:mod:`usarsim.brains.grid`): a sweep's end points
fitted to the walls already in the map correct the pose odometry gives.  The search is
compiled by numba, cached on disk.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from usarsim.brains.planning import _distance_to

if TYPE_CHECKING:
    from usarsim.brains.grid import OccupancyGrid


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
