"""Occupancy grids in ROS's map convention, and rasterising a world's solids into one.

A map is laid out as ``nav_msgs/OccupancyGrid`` and ROS's map_server lay it out: square cells
of ``resolution`` metres, row-major from the cell at ``origin`` (the lower-left corner of the
grid), each cell FREE (0), OCCUPIED (100) or UNKNOWN (-1).  Its frame is ROS's ``map`` frame
(REP 103: X forward/north, Y left/west), which the ROS 2 bridge also uses for the world: a
world point (x, y, z) in USARSim's frame (X north, Y east, Z down) lies at (x, -y) on a map.

:func:`solid_cells` marks the cells a world's solids stand in at given heights above the
floor; :mod:`usarsim.maps.truth` builds the ground-truth map from it.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from usarsim.config.solids import mesh_depth, rotation_matrix
from usarsim.config.world import StaticObject, WorldConfig

FREE = 0
OCCUPIED = 100
UNKNOWN = -1


@dataclass
class OccupancyMap:
    """A grid of cells in the map frame: ``data[row, col]`` is the cell whose lower-left corner
    is (origin x + col resolution, origin y + row resolution); row 0 is the lowest (south-most
    along the map's Y), as in nav_msgs/OccupancyGrid."""

    resolution: float
    origin: tuple[float, float]
    data: np.ndarray  # int8, (rows, cols): FREE, OCCUPIED or UNKNOWN

    @property
    def shape(self) -> tuple[int, int]:
        rows, cols = self.data.shape
        return int(rows), int(cols)

    @property
    def occupied(self) -> np.ndarray:
        return self.data == OCCUPIED

    @property
    def free(self) -> np.ndarray:
        return self.data == FREE

    @property
    def known(self) -> np.ndarray:
        return self.data != UNKNOWN

    def centres(self, mask: np.ndarray | None = None) -> np.ndarray:
        """The map-frame (x, y) centres of the cells of ``mask`` (all cells by default), an
        (N, 2) array in row-major order."""
        rows, cols = np.nonzero(np.ones(self.shape, bool) if mask is None else mask)
        return np.column_stack(
            (
                self.origin[0] + (cols + 0.5) * self.resolution,
                self.origin[1] + (rows + 0.5) * self.resolution,
            )
        )

    def cell_of(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(rows, cols, inside) of the cells holding the map-frame points ``points`` (N, 2)."""
        pts = np.asarray(points, float).reshape(-1, 2)
        cols = np.floor((pts[:, 0] - self.origin[0]) / self.resolution).astype(np.intp)
        rows = np.floor((pts[:, 1] - self.origin[1]) / self.resolution).astype(np.intp)
        inside = (rows >= 0) & (rows < self.shape[0]) & (cols >= 0) & (cols < self.shape[1])
        return rows, cols, inside

    def copy(self) -> OccupancyMap:
        return OccupancyMap(self.resolution, self.origin, self.data.copy())


def to_map_frame(x: float, y: float) -> tuple[float, float]:
    """A USARSim world point's (x, y) on a map (the ROS map frame)."""
    return (float(x), -float(y))


def from_map_frame(x: float, y: float) -> tuple[float, float]:
    """A map point's (x, y) in the USARSim world frame."""
    return (float(x), -float(y))


def floor_grid(world: WorldConfig, resolution: float) -> OccupancyMap:
    """An all-free map over the world's floor rectangle."""
    if not resolution > 0:
        raise ValueError(f"the map resolution must be > 0 m, got {resolution!r}")
    (cx, cy), (sx, sy) = world.floor.center, world.floor.size
    cols, rows = int(math.ceil(sx / resolution - 1e-9)), int(math.ceil(sy / resolution - 1e-9))
    # the floor's south-west corner on the map: USARSim y at its east edge is the map's lowest y
    origin = (round(cx - sx / 2.0, 9), round(-(cy + sy / 2.0), 9))
    return OccupancyMap(resolution, origin, np.zeros((rows, cols), np.int8))


def rotation(rpy: Sequence[float]) -> np.ndarray:
    """The object-to-world rotation of a world file's (roll, pitch, yaw) as an array
    (usarsim.config.solids.rotation_matrix)."""
    return np.array(rotation_matrix(rpy))


@dataclass(frozen=True)
class Solid:
    """A solid to rasterise: a box (full extents ``size``), a cylinder (``size`` = radius,
    radius, length) or a mesh, at ``center`` turned by ``rotation`` (USARSim frame)."""

    shape: str
    center: tuple[float, float, float]
    size: tuple[float, float, float]
    rotation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    mesh_file: str = ""
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)

    @classmethod
    def of(cls, obj: StaticObject) -> Solid:
        if obj.shape == "cylinder":
            size = (obj.radius_m, obj.radius_m, obj.length_m)
        else:
            size = obj.size
        return cls(obj.shape, obj.center, size, obj.rotation, obj.mesh_file, obj.scale)

    def half_extents(self) -> np.ndarray:
        if self.shape == "box":
            return np.asarray(self.size, float) / 2.0
        if self.shape == "cylinder":
            return np.array([self.size[0], self.size[1], self.size[2] / 2.0])
        return np.full(3, _mesh_radius(self.mesh_file, self.scale))

    def world_box(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(rotation, lowest corner, highest corner) of the solid's bounding box in the world
        (USARSim frame)."""
        rot = rotation(self.rotation)
        corners = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)]) * self.half_extents()
        pts = corners @ rot.T + np.asarray(self.center)
        return rot, pts.min(axis=0), pts.max(axis=0)

    def cell_window(self, grid: OccupancyMap) -> tuple[np.ndarray, np.ndarray, slice, slice]:
        """(rotation, world box's lowest corner, rows, columns) of the cells of ``grid`` its
        footprint may touch, a cell's width around it (empty slices when none)."""
        rot, lo, hi = self.world_box()
        res = grid.resolution
        rows, cols = grid.shape
        c0 = max(0, int(math.floor((lo[0] - res - grid.origin[0]) / res)))
        c1 = min(cols, int(math.ceil((hi[0] + res - grid.origin[0]) / res)))
        r0 = max(0, int(math.floor((-hi[1] - res - grid.origin[1]) / res)))
        r1 = min(rows, int(math.ceil((-lo[1] + res - grid.origin[1]) / res)))
        return rot, np.concatenate((lo, hi)), slice(r0, max(r0, r1)), slice(c0, max(c0, c1))


def _mesh_radius(mesh_file: str, scale: Sequence[float]) -> float:
    from pathlib import Path

    from usarsim.config.solids import mesh_triangles

    tris = np.asarray(mesh_triangles(mesh_file, tuple(scale), Path(mesh_file).stat().st_mtime), float).reshape(-1, 3)
    return float(np.abs(tris).max()) if tris.size else 0.0


def world_solids(world: WorldConfig, *, movable: bool = True) -> list[Solid]:
    """The world's objects (movable ones too unless ``movable`` is False) and false alarms."""
    out = [Solid.of(o) for o in world.objects if movable or o.mass_kg <= 0]
    out += [Solid("box", a.center, a.size, a.rotation) for a in world.false_alarms]
    return out


def solid_cells(grid: OccupancyMap, solids: Iterable[Solid], heights: Sequence[float]) -> np.ndarray:
    """The cells of ``grid`` a solid stands in at any of ``heights`` (metres above the floor).
    A cell counts when the solid overlaps it (half a cell each way), so that a wall thinner
    than a cell still splits the floor."""
    res = grid.resolution
    out = np.zeros(grid.shape, bool)
    pad = np.array([res / 2.0, res / 2.0, 0.0])
    for solid in solids:
        rot, box, rs, cs = solid.cell_window(grid)
        half = solid.half_extents()
        if not any(-box[5] - 1e-9 <= h <= -box[2] + 1e-9 for h in heights):
            continue  # wholly above or below the heights looked at
        if rs.start == rs.stop or cs.start == cs.stop:
            continue
        r0, r1, c0, c1 = rs.start, rs.stop, cs.start, cs.stop
        rr, cc = np.mgrid[r0:r1, c0:c1]
        wx = grid.origin[0] + (cc.ravel() + 0.5) * res
        wy = -(grid.origin[1] + (rr.ravel() + 0.5) * res)
        hit = np.zeros(wx.shape, bool)
        for h in heights:
            local = (np.column_stack((wx, wy, np.full(wx.shape, -h))) - np.asarray(solid.center)) @ rot
            if solid.shape == "box":
                hit |= np.all(np.abs(local) <= half + pad, axis=1)
            elif solid.shape == "cylinder":
                hit |= (np.hypot(local[:, 0], local[:, 1]) <= half[0] + pad[0]) & (np.abs(local[:, 2]) <= half[2])
            else:
                for k in np.nonzero(~hit)[0]:
                    hit[k] = mesh_depth(solid.mesh_file, solid.scale, tuple(local[k])) > 0.0
        out[r0:r1, c0:c1] |= hit.reshape(rr.shape)
    return out
