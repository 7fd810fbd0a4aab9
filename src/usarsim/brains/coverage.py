"""Scoring exploration against the world file: which floor a robot can reach, and how much
of it its laser has swept.

This is the referee's side, not the robot's: it reads the world file (floor and static
solids) and the robots' true poses (ground truth), which an exploring brain never uses.

* :meth:`FloorMap.from_world` rasterises the floor: a cell is floor unless a static solid
  of the world (movable objects are left out: they get pushed about) stands in it below
  ``height`` metres;
* :meth:`FloorMap.reachable` floods the floor from a point (4-connected cells);
* :meth:`FloorMap.region` is the bounding box of the world's static solids (for an arena,
  its outer walls): the reachable floor inside it is what an explorer of the arena has to
  cover, the open ground around it left out;
* :class:`Sweeps` marks the cells the laser beams crossed, given each sweep and the pose
  it was taken from.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from usarsim.config.world import WorldConfig
from usarsim.maps.grid import rotation

SAMPLE_HEIGHTS = (0.03, 0.1, 0.2, 0.35)  # m above the floor where solids are looked for
MAX_TILT = math.radians(2.0)  # a sweep taken tilted more than this is not counted
NEAR_M = 3.0  # m: "seen from near" (Referee.near)


@dataclass
class FloorMap:
    """Floor cells of a world: ``floor[i, j]`` is the cell whose corner is
    (x0 + i res, y0 + j res)."""

    x0: float
    y0: float
    resolution: float
    floor: np.ndarray
    solids_box: tuple[float, float, float, float]  # xmin, ymin, xmax, ymax of the static solids

    @classmethod
    def from_world(cls, world: WorldConfig, resolution: float = 0.1, height: float = 0.4) -> FloorMap:
        (cx, cy), (sx, sy) = world.floor.center, world.floor.size
        x0, y0 = cx - sx / 2.0, cy - sy / 2.0
        nx, ny = int(round(sx / resolution)), int(round(sy / resolution))
        ii, jj = np.mgrid[0:nx, 0:ny]
        px = x0 + (ii + 0.5) * resolution
        py = y0 + (jj + 0.5) * resolution
        floor = np.ones((nx, ny), bool)
        box = [math.inf, math.inf, -math.inf, -math.inf]
        heights = [h for h in SAMPLE_HEIGHTS if h < height]
        pad = np.array([resolution / 2.0, resolution / 2.0, 0.0])
        for obj in world.objects:
            if obj.mass_kg > 0 or obj.shape not in ("box", "cylinder"):
                continue
            rot = rotation(obj.rotation)
            if obj.shape == "box":
                half = np.asarray(obj.size, float) / 2.0
            else:
                half = np.array([obj.radius_m, obj.radius_m, obj.length_m / 2.0])
            # the footprint's bounding box, to look at those cells only
            corners = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)]) * half
            world_corners = corners @ rot.T + np.asarray(obj.center)
            lo, hi = world_corners.min(axis=0), world_corners.max(axis=0)
            box = [min(box[0], lo[0]), min(box[1], lo[1]), max(box[2], hi[0]), max(box[3], hi[1])]
            sel = (
                (px >= lo[0] - resolution)
                & (px <= hi[0] + resolution)
                & (py >= lo[1] - resolution)
                & (py <= hi[1] + resolution)
            )
            if not sel.any():
                continue
            qx, qy = px[sel], py[sel]
            hit = np.zeros(qx.shape, bool)
            for h in heights:
                d = np.column_stack((qx, qy, np.full(qx.shape, -h))) - np.asarray(obj.center)
                local = d @ rot  # into the object's frame
                # a cell counts as solid when the solid overlaps it (half a cell each way): a
                # wall thinner than a cell still splits the floor
                if obj.shape == "box":
                    hit |= np.all(np.abs(local) <= half + pad, axis=1)
                else:
                    hit |= (np.hypot(local[:, 0], local[:, 1]) <= obj.radius_m + pad[0]) & (
                        np.abs(local[:, 2]) <= half[2] + pad[2]
                    )
            floor[sel] &= ~hit
        if not math.isfinite(box[0]):
            box = [x0, y0, x0 + sx, y0 + sy]
        return cls(x0, y0, resolution, floor, (box[0], box[1], box[2], box[3]))

    @property
    def shape(self) -> tuple[int, int]:
        return self.floor.shape

    def cell(self, x: float, y: float) -> tuple[int, int]:
        return (int(math.floor((x - self.x0) / self.resolution)), int(math.floor((y - self.y0) / self.resolution)))

    def reachable(self, x: float, y: float) -> np.ndarray:
        """The floor cells joined to (x, y) through floor cells (4-connected)."""
        i, j = self.cell(x, y)
        if not (0 <= i < self.shape[0] and 0 <= j < self.shape[1]) or not self.floor[i, j]:
            raise ValueError(f"({x:.2f}, {y:.2f}) is not on the floor")
        reach = np.zeros_like(self.floor)
        reach[i, j] = True
        while True:
            grown = reach.copy()
            grown[1:, :] |= reach[:-1, :]
            grown[:-1, :] |= reach[1:, :]
            grown[:, 1:] |= reach[:, :-1]
            grown[:, :-1] |= reach[:, 1:]
            grown &= self.floor
            if np.array_equal(grown, reach):
                return reach
            reach = grown

    def region(self, box: tuple[float, float, float, float] | None = None) -> np.ndarray:
        """Cells whose centres lie inside ``box`` (xmin, ymin, xmax, ymax; default: the
        bounding box of the static solids)."""
        xmin, ymin, xmax, ymax = box or self.solids_box
        ii, jj = np.mgrid[0 : self.shape[0], 0 : self.shape[1]]
        px = self.x0 + (ii + 0.5) * self.resolution
        py = self.y0 + (jj + 0.5) * self.resolution
        return (px > xmin) & (px < xmax) & (py > ymin) & (py < ymax)


class Sweeps:
    """The cells of a :class:`FloorMap`'s grid that laser beams have crossed (within
    ``within`` metres of the scanner, when given: what it has seen from near enough to make
    out, say, a victim)."""

    def __init__(self, floor: FloorMap, within: float | None = None):
        self.floor = floor
        self.within = within
        self.seen = np.zeros(floor.shape, bool)
        self.sweeps = 0

    def add(
        self,
        location: tuple[float, float],
        orientation: tuple[float, float, float],
        ranges: np.ndarray,
        angles: np.ndarray,
        max_range: float | None = None,
        scanner_offset: tuple[float, float] = (0.144, 0.0),
    ) -> bool:
        """One sweep taken with the robot at ``location`` (x, y) and ``orientation`` (roll,
        pitch, yaw; world frame, yaw clockwise), beams at ``angles`` (the client's:
        counter-clockwise, 0 ahead) of ``ranges`` metres, from a scanner at
        ``scanner_offset`` on the robot.  A sweep taken with the robot tilted more than
        ``MAX_TILT`` (on a ramp, over a box) is left out, as its beams may pass over the
        walls rather than along the floor; returns whether it was counted."""
        roll, pitch, yaw = orientation
        if max(abs(math.remainder(roll, math.tau)), abs(math.remainder(pitch, math.tau))) > MAX_TILT:
            return False
        ranges = np.asarray(ranges, float)
        if max_range is not None:
            ranges = np.minimum(ranges, max_range)
        if self.within is not None:
            ranges = np.minimum(ranges, self.within)
        c, s = math.cos(yaw), math.sin(yaw)
        ox = location[0] + scanner_offset[0] * c - scanner_offset[1] * s
        oy = location[1] + scanner_offset[0] * s + scanner_offset[1] * c
        direction = yaw - np.asarray(angles, float)
        res = self.floor.resolution
        step = res * 0.5
        n = int(math.ceil(float(ranges.max(initial=0.0)) / step))
        t = np.arange(n) * step
        mask = t[None, :] < ranges[:, None]
        px = (ox + t[None, :] * np.cos(direction)[:, None])[mask]
        py = (oy + t[None, :] * np.sin(direction)[:, None])[mask]
        i = np.floor((px - self.floor.x0) / res).astype(np.int64)
        j = np.floor((py - self.floor.y0) / res).astype(np.int64)
        keep = (i >= 0) & (i < self.floor.shape[0]) & (j >= 0) & (j < self.floor.shape[1])
        self.seen[i[keep], j[keep]] = True
        self.sweeps += 1
        return True

    def share(self, of: np.ndarray) -> float:
        """The share of the cells of ``of`` (a mask: the reachable floor) swept."""
        total = int(np.count_nonzero(of))
        return float(np.count_nonzero(self.seen & of)) / total if total else 0.0

    def to_png(
        self, path: str, of: np.ndarray | None = None, marks: list[tuple[float, float]] | None = None, scale: int = 3
    ) -> None:
        """A picture (north up): solids black, floor grey, swept floor white, ``of`` outlined
        by leaving the rest darker, ``marks`` red."""
        from PIL import Image

        fl = self.floor
        img = np.zeros(fl.shape + (3,), np.uint8)
        img[fl.floor] = (90, 90, 90)
        if of is not None:
            img[of] = (150, 150, 150)
        img[self.seen & fl.floor] = (235, 235, 235)
        for x, y in marks or []:
            i, j = fl.cell(x, y)
            if 0 <= i < fl.shape[0] and 0 <= j < fl.shape[1]:
                img[max(0, i - 1) : i + 2, max(0, j - 1) : j + 2] = (220, 30, 30)
        Image.fromarray(img[::-1]).resize((fl.shape[1] * scale, fl.shape[0] * scale), Image.Resampling.NEAREST).save(
            path
        )


class Referee:
    """Keeps the score of an exploration: after each step, :meth:`observe` adds every
    robot's new laser sweep at its true pose (its GroundTruth sensor).  ``arena`` is the
    reachable floor inside the static solids' bounding box (the arena), ``reachable`` all
    the floor reachable from ``start`` (x, y).  ``sweeps`` counts the whole length of the
    beams; ``near`` only their first ``near_m`` metres."""

    def __init__(self, world: WorldConfig, start: tuple[float, float], resolution: float = 0.1, near_m: float = NEAR_M):
        self.floor = FloorMap.from_world(world, resolution)
        self.reachable = self.floor.reachable(*start)
        self.arena = self.reachable & self.floor.region()
        self.sweeps = Sweeps(self.floor)
        self.near = Sweeps(self.floor, near_m)
        self._last: dict[str, float | None] = {}
        self.tilted = 0  # sweeps left out because the robot leant

    def observe(self, robots) -> None:
        for robot in robots:
            scan, truth = robot.scan(), robot.ground_truth()
            if scan is None or truth is None or self._last.get(robot.name) == scan.time:
                continue
            self._last[robot.name] = scan.time
            if not self.sweeps.add(truth[0][:2], truth[1], scan.ranges, scan.angles, scan.max_range):
                self.tilted += 1
            self.near.add(truth[0][:2], truth[1], scan.ranges, scan.angles, scan.max_range)

    def arena_share(self, near: bool = False) -> float:
        """The share of the arena's reachable floor swept so far (``near``: within
        ``near_m`` of the laser)."""
        return (self.near if near else self.sweeps).share(self.arena)

    def reachable_share(self) -> float:
        return self.sweeps.share(self.reachable)
