"""Compiled ray casting against MuJoCo geoms, with a different origin per ray.

``mj_multiRay`` casts rays from a single point and tests every ray against every
geom of the model; a robot's 16 sonars need 16 calls, each paying for the whole
model, and a world of many robots would test every ray against every robot.  This
kernel takes one origin per ray and files the geoms in a grid of square cells over the
ground plane (by their bounding boxes, filed again when anything moved); it walks each
ray through the cells it crosses, nearest first, until a hit lies before the next
cell, and rejects each cell's geoms by bounding sphere before the exact test.  The exact
tests (:mod:`usarsim.sim.rayshapes`) follow MuJoCo's ray semantics (``mj_ray``): the nearest
non-negative intersection, so a ray starting inside a shape reports where it leaves it;
planes are seen from their front face only and within their size when it is set;
invisible geoms (alpha 0), excluded groups and the excluded body are skipped.

Shapes: plane, sphere, capsule, ellipsoid, cylinder, box.  A model that ray casts
would see with other shapes (meshes, height fields) is handled by ``mj_multiRay``
in :class:`usarsim.sim.raycaster.RayCaster`.  The kernel is compiled by numba on first
use and cached on disk.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from usarsim.sim.rayshapes import (
    BOX,
    CAPSULE,
    CYLINDER,
    ELLIPSOID,
    HFIELD,
    MINVAL,
    PLANE,
    SPHERE,
    SUPPORTED,
    _ray_in_frame,
    _world_normal,
)

__all__ = [
    "BOX",
    "CAPSULE",
    "CYLINDER",
    "ELLIPSOID",
    "GRID_CELL_M",
    "GRID_MAX_CELLS",
    "GRID_PAD_M",
    "HFIELD",
    "MINVAL",
    "PLANE",
    "SPHERE",
    "SUPPORTED",
    "build_grid",
    "cast_grid_kernel",
    "same_values",
    "warm_up",
]


# The grid's cells: this size (metres, about a P2AT's half length; 2-core machine, 256 P2ATs:
# a 181-beam scan took 545 us with 2 m cells, 296 with 1 m, 202 with 0.5 m, 178 with 0.25 m) unless the world is so
# large that the cells would pass GRID_MAX_CELLS, then larger.
GRID_CELL_M = 0.5
GRID_MAX_CELLS = 65536
# Bounding boxes are widened by this much (metres) against rounding in the walk.
GRID_PAD_M = 1e-6


@njit(cache=True, nogil=True, inline="always")
def _half_extents(gtype, s0, s1, s2):
    """Half sizes of a shape's box in its own frame."""
    if gtype == SPHERE:
        return s0, s0, s0
    if gtype == CAPSULE:
        return s0, s0, s1 + s0
    if gtype == CYLINDER:
        return s0, s0, s1
    return s0, s1, s2  # box, ellipsoid


@njit(cache=True, nogil=True, inline="always")
def _cell_span(lo, hi, g, x0, y0, cell, nx, ny):
    """The first and last cell along x and along y that geom g's box overlaps."""
    return (
        min(int((lo[g, 0] - x0) / cell), nx - 1),
        min(int((hi[g, 0] - x0) / cell), nx - 1),
        min(int((lo[g, 1] - y0) / cell), ny - 1),
        min(int((hi[g, 1] - y0) / cell), ny - 1),
    )


@njit(cache=True, nogil=True)
def build_grid(gtype, gsize, use, xpos, xmat, cell_m, max_cells):
    """File the geoms of ``use`` (planes apart) in a grid over x and y.

    Returns (x0, y0, cell, nx, ny, start, items, planes, z0, z1): the geoms of cell
    (cx, cy) are items[start[c]:start[c + 1]] with c = cy * nx + cx; planes are
    tested by every ray; z0..z1 is the height every filed geom lies within (a ray is
    done with the grid where it leaves that layer: one that climbs to a satellite
    crosses no cell above the walls).
    """
    ng = gtype.shape[0]
    lo = np.empty((ng, 2))
    hi = np.empty((ng, 2))
    inside = np.zeros(ng, np.bool_)
    nplanes = 0
    x0 = y0 = z0 = math.inf
    x1 = y1 = z1 = -math.inf
    for g in range(ng):
        if not use[g]:
            continue
        if gtype[g] == PLANE:
            nplanes += 1
            continue
        h0, h1, h2 = _half_extents(gtype[g], gsize[g, 0], gsize[g, 1], gsize[g, 2])
        m = xmat[g]
        ex = abs(m[0]) * h0 + abs(m[1]) * h1 + abs(m[2]) * h2 + GRID_PAD_M
        ey = abs(m[3]) * h0 + abs(m[4]) * h1 + abs(m[5]) * h2 + GRID_PAD_M
        ez = abs(m[6]) * h0 + abs(m[7]) * h1 + abs(m[8]) * h2 + GRID_PAD_M
        z0 = min(z0, xpos[g, 2] - ez)
        z1 = max(z1, xpos[g, 2] + ez)
        lo[g, 0] = xpos[g, 0] - ex
        lo[g, 1] = xpos[g, 1] - ey
        hi[g, 0] = xpos[g, 0] + ex
        hi[g, 1] = xpos[g, 1] + ey
        inside[g] = True
        x0 = min(x0, lo[g, 0])
        y0 = min(y0, lo[g, 1])
        x1 = max(x1, hi[g, 0])
        y1 = max(y1, hi[g, 1])
    planes = np.empty(nplanes, np.int64)
    k = 0
    for g in range(ng):
        if use[g] and gtype[g] == PLANE:
            planes[k] = g
            k += 1
    if x0 > x1:  # nothing but planes
        return 0.0, 0.0, 1.0, 0, 0, np.zeros(1, np.int64), np.empty(0, np.int64), planes, 0.0, 0.0
    cell = cell_m
    while math.ceil((x1 - x0) / cell) * math.ceil((y1 - y0) / cell) > max_cells:
        cell *= 2.0
    nx = max(1, int(math.ceil((x1 - x0) / cell)))
    ny = max(1, int(math.ceil((y1 - y0) / cell)))
    count = np.zeros(nx * ny + 1, np.int64)
    for g in range(ng):
        if not inside[g]:
            continue
        ax, bx, ay, by = _cell_span(lo, hi, g, x0, y0, cell, nx, ny)
        for cy in range(ay, by + 1):
            for cx in range(ax, bx + 1):
                count[cy * nx + cx + 1] += 1
    for c in range(nx * ny):
        count[c + 1] += count[c]
    items = np.empty(count[nx * ny], np.int64)
    fill = count[:-1].copy()
    for g in range(ng):  # ascending ids within each cell
        if not inside[g]:
            continue
        ax, bx, ay, by = _cell_span(lo, hi, g, x0, y0, cell, nx, ny)
        for cy in range(ay, by + 1):
            for cx in range(ax, bx + 1):
                c = cy * nx + cx
                items[fill[c]] = g
                fill[c] += 1
    return x0, y0, cell, nx, ny, count, items, planes, z0, z1


@njit(cache=True, nogil=True)
def same_values(a, b):
    """Whether two arrays of the same length hold the same values (stops at the first difference)."""
    if a.shape[0] != b.shape[0]:
        return False
    for i in range(a.shape[0]):
        if a[i] != b[i]:
            return False
    return True


@njit(cache=True, nogil=True, inline="always")
def _slab(o, v, lo, hi, ta, tb):
    """The stretch [ta, tb] of a ray cut to where its coordinate (o + t v) lies in [lo, hi]
    (tb < ta: nowhere)."""
    if abs(v) < MINVAL:
        if o < lo or o > hi:
            return ta, -1.0
        return ta, tb
    e0, e1 = (lo - o) / v, (hi - o) / v
    return max(ta, min(e0, e1)), min(tb, max(e0, e1))


@njit(cache=True, nogil=True, inline="always")
def _stepping(o, v, lo, c, cell):
    """Walking a ray through the cells along one axis from cell c: the step (+1, -1 or 0),
    where the ray leaves cell c, and how far it goes through each cell."""
    if abs(v) < MINVAL:
        return 0, math.inf, math.inf
    if v > 0.0:
        return 1, (lo + (c + 1) * cell - o) / v, cell / v
    return -1, (lo + c * cell - o) / v, -cell / v


@njit(cache=True, nogil=True)
def cast_grid_kernel(
    orig,
    dirs,
    cutoff,
    gtype,
    gsize,
    grbound,
    gbody,
    gok,
    xpos,
    xmat,
    exclude_body,
    want_normals,
    out_dist,
    out_geom,
    out_normal,
    x0,
    y0,
    cell,
    nx,
    ny,
    start,
    items,
    planes,
    z0,
    z1,
):
    """Cast ray i from orig[i] along dirs[i] (n x 3 each, MuJoCo world frame) through the
    grid of :func:`build_grid` (filed from the same positions).

    out_dist[i] is the distance to the nearest geom of ``gok`` not on ``exclude_body`` (in
    units of |dirs[i]|) or inf when none lies within ``cutoff``; out_geom[i] its id or -1
    (of geoms hit at the very same distance, the lowest id); out_normal[i] the outward
    surface normal there (when ``want_normals``).  Returns the number of geoms tested.
    """
    ng = gtype.shape[0]
    seen = np.full(ng, -1, np.int64)
    tested = 0
    x1 = x0 + nx * cell
    y1 = y0 + ny * cell
    for i in range(orig.shape[0]):
        ox, oy, oz = orig[i, 0], orig[i, 1], orig[i, 2]
        vx, vy, vz = dirs[i, 0], dirs[i, 1], dirs[i, 2]
        aa = vx * vx + vy * vy + vz * vz
        best = math.inf
        bg = -1
        for j in range(planes.shape[0]):
            g = planes[j]
            if not gok[g] or gbody[g] == exclude_body:
                continue
            tested += 1
            t = _ray_in_frame(
                PLANE,
                gsize[g, 0],
                gsize[g, 1],
                gsize[g, 2],
                xmat[g],
                ox - xpos[g, 0],
                oy - xpos[g, 1],
                oz - xpos[g, 2],
                vx,
                vy,
                vz,
            )
            if t >= 0.0 and (t < best or (t == best and g < bg)):
                best = t
                bg = g
        # the stretch of the ray over the grid, up to the cutoff
        ta, tb = 0.0, cutoff
        if nx > 0:
            ta, tb = _slab(ox, vx, x0, x1, ta, tb)
            ta, tb = _slab(oy, vy, y0, y1, ta, tb)
            ta, tb = _slab(oz, vz, z0, z1, ta, tb)
        else:
            tb = -1.0
        if ta <= tb and ta <= best:
            cx = min(max(int(math.floor((ox + ta * vx - x0) / cell)), 0), nx - 1)
            cy = min(max(int(math.floor((oy + ta * vy - y0) / cell)), 0), ny - 1)
            sx, nextx, dtx = _stepping(ox, vx, x0, cx, cell)
            sy, nexty, dty = _stepping(oy, vy, y0, cy, cell)
            while True:
                c = cy * nx + cx
                for k in range(start[c], start[c + 1]):
                    g = items[k]
                    if seen[g] == i:
                        continue
                    seen[g] = i
                    if not gok[g] or gbody[g] == exclude_body:
                        continue
                    tested += 1
                    dx, dy, dz = ox - xpos[g, 0], oy - xpos[g, 1], oz - xpos[g, 2]
                    # bounding sphere: skip geoms the ray misses or reaches only beyond the best hit
                    r = grbound[g]
                    b = vx * dx + vy * dy + vz * dz
                    c2 = dx * dx + dy * dy + dz * dz - r * r
                    if c2 > 0.0:
                        if b >= 0.0:
                            continue
                        det = b * b - aa * c2
                        if det < 0.0 or (-b - math.sqrt(det)) / aa > best:
                            continue
                    t = _ray_in_frame(gtype[g], gsize[g, 0], gsize[g, 1], gsize[g, 2], xmat[g], dx, dy, dz, vx, vy, vz)
                    if t >= 0.0 and (t < best or (t == best and g < bg)):
                        best = t
                        bg = g
                leave = min(nextx, nexty)
                if best < leave or leave > tb:
                    break
                if nextx < nexty:
                    cx += sx
                    nextx += dtx
                    if cx < 0 or cx >= nx:
                        break
                else:
                    cy += sy
                    nexty += dty
                    if cy < 0 or cy >= ny:
                        break
        if bg < 0 or best > cutoff:
            out_dist[i] = math.inf
            out_geom[i] = -1
            if want_normals:
                out_normal[i, 0] = out_normal[i, 1] = out_normal[i, 2] = 0.0
            continue
        out_dist[i] = best
        out_geom[i] = bg
        if want_normals:
            _world_normal(
                gtype[bg],
                gsize[bg, 0],
                gsize[bg, 1],
                gsize[bg, 2],
                xmat[bg],
                ox + best * vx - xpos[bg, 0],
                oy + best * vy - xpos[bg, 1],
                oz + best * vz - xpos[bg, 2],
                out_normal[i],
            )
    return tested


def warm_up() -> None:
    """Compile (or load from the disk cache) the kernel now, not on a robot's first scan."""
    one = np.zeros((1, 3))
    one[0, 0] = 1.0
    gtype, gsize, use = np.array([BOX], np.int64), np.ones((1, 3)), np.ones(1, np.bool_)
    xpos, xmat = np.full((1, 3), 5.0), np.eye(3).reshape(1, 9)
    grid = build_grid(gtype, gsize, use, xpos, xmat, GRID_CELL_M, GRID_MAX_CELLS)
    cast_grid_kernel(
        np.zeros((1, 3)),
        one,
        1.0,
        gtype,
        gsize,
        np.ones(1),
        np.zeros(1, np.int64),
        use,
        xpos,
        xmat,
        -1,
        True,
        np.empty(1),
        np.empty(1, np.int32),
        np.empty((1, 3)),
        *grid,
    )
    same_values(np.zeros(1), np.zeros(1))
