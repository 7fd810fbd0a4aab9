"""Compiled ray casting against MuJoCo geoms, with a different origin per ray.

``mj_multiRay`` casts rays from a single point and tests every ray against every
geom of the model; a robot's 16 sonars need 16 calls, each paying for the whole
model.  This kernel takes one origin per ray, keeps only the geoms whose bounding
sphere can be reached within the cutoff from the batch's origins, and rejects the
rest of each ray's candidates by bounding sphere before the exact test.  The exact
tests follow MuJoCo's ray semantics (``mj_ray``): the nearest non-negative
intersection, so a ray starting inside a shape reports where it leaves it; planes
are seen from their front face only and within their size when it is set;
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

PLANE, HFIELD, SPHERE, CAPSULE, ELLIPSOID, CYLINDER, BOX = 0, 1, 2, 3, 4, 5, 6
SUPPORTED = (PLANE, SPHERE, CAPSULE, ELLIPSOID, CYLINDER, BOX)
MINVAL = 1e-15  # MuJoCo's mjMINVAL: below this a denominator counts as zero


@njit(cache=True, nogil=True, inline="always")
def _quad(a, b, c):
    """Smallest non-negative root of a x^2 + 2 b x + c = 0, else -1; and the other root."""
    det = b * b - a * c
    if det < MINVAL:
        return -1.0, -1.0
    det = math.sqrt(det)
    x0 = (-b - det) / a
    x1 = (-b + det) / a
    return x0, x1


@njit(cache=True, nogil=True, inline="always")
def _first(x0, x1):
    if x0 >= 0.0:
        return x0
    if x1 >= 0.0:
        return x1
    return -1.0


@njit(cache=True, nogil=True)
def _ray_local(gtype, s0, s1, s2, px, py, pz, vx, vy, vz):
    """Distance along (v) from (p) to a shape at the origin of its own frame, or -1."""
    if gtype == BOX:
        x = -1.0
        for axis in range(3):
            if axis == 0:
                pa, va, sa, pb, vb, sb, pc, vc, sc = px, vx, s0, py, vy, s1, pz, vz, s2
            elif axis == 1:
                pa, va, sa, pb, vb, sb, pc, vc, sc = py, vy, s1, px, vx, s0, pz, vz, s2
            else:
                pa, va, sa, pb, vb, sb, pc, vc, sc = pz, vz, s2, px, vx, s0, py, vy, s1
            if abs(va) > MINVAL:
                for side in (-1.0, 1.0):
                    t = (side * sa - pa) / va
                    if t >= 0.0 and (x < 0.0 or t < x):
                        if abs(pb + t * vb) <= sb and abs(pc + t * vc) <= sc:
                            x = t
        return x
    if gtype == CYLINDER:
        x = -1.0
        if abs(vz) > MINVAL:
            for side in (-1.0, 1.0):
                t = (side * s1 - pz) / vz
                if t >= 0.0 and (x < 0.0 or t < x):
                    qx = px + t * vx
                    qy = py + t * vy
                    if qx * qx + qy * qy <= s0 * s0:
                        x = t
        a = vx * vx + vy * vy
        if a > MINVAL:
            x0, x1 = _quad(a, vx * px + vy * py, px * px + py * py - s0 * s0)
            t = _first(x0, x1)
            if t >= 0.0 and abs(pz + t * vz) <= s1 and (x < 0.0 or t < x):
                x = t
        return x
    if gtype == SPHERE:
        x0, x1 = _quad(vx * vx + vy * vy + vz * vz, vx * px + vy * py + vz * pz,
                       px * px + py * py + pz * pz - s0 * s0)
        return _first(x0, x1)
    if gtype == CAPSULE:
        x = -1.0
        a = vx * vx + vy * vy
        if a > MINVAL:
            x0, x1 = _quad(a, vx * px + vy * py, px * px + py * py - s0 * s0)
            t = _first(x0, x1)
            if t >= 0.0 and abs(pz + t * vz) <= s1:
                x = t
        aa = vx * vx + vy * vy + vz * vz
        for side in (-1.0, 1.0):
            dz = pz - side * s1
            x0, x1 = _quad(aa, vx * px + vy * py + vz * dz, px * px + py * py + dz * dz - s0 * s0)
            for t in (x0, x1):
                if t >= 0.0 and side * (pz + t * vz) >= s1 and (x < 0.0 or t < x):
                    x = t
        return x
    if gtype == ELLIPSOID:
        i0, i1, i2 = 1.0 / (s0 * s0), 1.0 / (s1 * s1), 1.0 / (s2 * s2)
        x0, x1 = _quad(i0 * vx * vx + i1 * vy * vy + i2 * vz * vz, i0 * vx * px + i1 * vy * py + i2 * vz * pz,
                       i0 * px * px + i1 * py * py + i2 * pz * pz - 1.0)
        return _first(x0, x1)
    if gtype == PLANE:
        if vz > -MINVAL:
            return -1.0
        t = -pz / vz
        if t < 0.0:
            return -1.0
        if (s0 <= 0.0 or abs(px + t * vx) <= s0) and (s1 <= 0.0 or abs(py + t * vy) <= s1):
            return t
        return -1.0
    return -1.0


@njit(cache=True, nogil=True)
def _normal_local(gtype, s0, s1, s2, qx, qy, qz):
    """Outward surface normal, in the shape's frame, at a point (q) on its surface."""
    if gtype == BOX:
        ax, ay, az = abs(qx) / s0, abs(qy) / s1, abs(qz) / s2
        if ax >= ay and ax >= az:
            return (1.0 if qx >= 0 else -1.0), 0.0, 0.0
        if ay >= az:
            return 0.0, (1.0 if qy >= 0 else -1.0), 0.0
        return 0.0, 0.0, (1.0 if qz >= 0 else -1.0)
    if gtype == CYLINDER:
        rho = math.sqrt(qx * qx + qy * qy)
        if abs(abs(qz) - s1) < abs(rho - s0) or rho < MINVAL:
            return 0.0, 0.0, (1.0 if qz >= 0 else -1.0)
        return qx / rho, qy / rho, 0.0
    if gtype == CAPSULE:
        cz = min(max(qz, -s1), s1)
        nx, ny, nz = qx, qy, qz - cz
    elif gtype == ELLIPSOID:
        nx, ny, nz = qx / (s0 * s0), qy / (s1 * s1), qz / (s2 * s2)
    elif gtype == SPHERE:
        nx, ny, nz = qx, qy, qz
    else:  # plane
        return 0.0, 0.0, 1.0
    n = math.sqrt(nx * nx + ny * ny + nz * nz)
    if n < MINVAL:
        return 0.0, 0.0, 1.0
    return nx / n, ny / n, nz / n


@njit(cache=True, nogil=True)
def cast_kernel(orig, dirs, cutoff, gtype, gsize, grbound, gbody, gok, xpos, xmat, exclude_body,
                want_normals, out_dist, out_geom, out_normal):
    """Cast ray i from orig[i] along dirs[i] (n x 3 each, MuJoCo world frame).

    out_dist[i] is the distance to the nearest visible geom (in units of |dirs[i]|)
    or inf when none lies within ``cutoff``; out_geom[i] its id or -1; out_normal[i]
    the outward surface normal there (when ``want_normals``).  Returns the number
    of candidate geoms that survived culling.
    """
    n = orig.shape[0]
    ng = gtype.shape[0]
    cx = cy = cz = 0.0
    for i in range(n):
        cx += orig[i, 0]
        cy += orig[i, 1]
        cz += orig[i, 2]
    if n > 0:
        cx /= n
        cy /= n
        cz /= n
    spread = 0.0
    for i in range(n):
        dx, dy, dz = orig[i, 0] - cx, orig[i, 1] - cy, orig[i, 2] - cz
        spread = max(spread, math.sqrt(dx * dx + dy * dy + dz * dz))
    reach = cutoff + spread
    cand = np.empty(ng, np.int64)
    k = 0
    for g in range(ng):
        if not gok[g] or gbody[g] == exclude_body:
            continue
        if gtype[g] != PLANE:
            dx, dy, dz = xpos[g, 0] - cx, xpos[g, 1] - cy, xpos[g, 2] - cz
            if math.sqrt(dx * dx + dy * dy + dz * dz) - grbound[g] > reach:
                continue
        cand[k] = g
        k += 1
    for i in range(n):
        ox, oy, oz = orig[i, 0], orig[i, 1], orig[i, 2]
        vx, vy, vz = dirs[i, 0], dirs[i, 1], dirs[i, 2]
        aa = vx * vx + vy * vy + vz * vz
        best = math.inf
        bg = -1
        for j in range(k):
            g = cand[j]
            t0 = gtype[g]
            dx, dy, dz = ox - xpos[g, 0], oy - xpos[g, 1], oz - xpos[g, 2]
            if t0 != PLANE:
                # bounding sphere: skip geoms the ray misses or reaches only beyond the best hit
                r = grbound[g]
                b = vx * dx + vy * dy + vz * dz
                c = dx * dx + dy * dy + dz * dz - r * r
                if c > 0.0:
                    if b >= 0.0:
                        continue
                    det = b * b - aa * c
                    if det < 0.0:
                        continue
                    if (-b - math.sqrt(det)) / aa > best:
                        continue
            m = xmat[g]
            px = m[0] * dx + m[3] * dy + m[6] * dz
            py = m[1] * dx + m[4] * dy + m[7] * dz
            pz = m[2] * dx + m[5] * dy + m[8] * dz
            lx = m[0] * vx + m[3] * vy + m[6] * vz
            ly = m[1] * vx + m[4] * vy + m[7] * vz
            lz = m[2] * vx + m[5] * vy + m[8] * vz
            t = _ray_local(t0, gsize[g, 0], gsize[g, 1], gsize[g, 2], px, py, pz, lx, ly, lz)
            if t >= 0.0 and t < best:
                best = t
                bg = g
        if bg < 0 or best > cutoff:
            out_dist[i] = math.inf
            out_geom[i] = -1
            if want_normals:
                out_normal[i, 0] = out_normal[i, 1] = out_normal[i, 2] = 0.0
            continue
        out_dist[i] = best
        out_geom[i] = bg
        if want_normals:
            m = xmat[bg]
            dx = ox + best * vx - xpos[bg, 0]
            dy = oy + best * vy - xpos[bg, 1]
            dz = oz + best * vz - xpos[bg, 2]
            qx = m[0] * dx + m[3] * dy + m[6] * dz
            qy = m[1] * dx + m[4] * dy + m[7] * dz
            qz = m[2] * dx + m[5] * dy + m[8] * dz
            nx, ny, nz = _normal_local(gtype[bg], gsize[bg, 0], gsize[bg, 1], gsize[bg, 2], qx, qy, qz)
            out_normal[i, 0] = m[0] * nx + m[1] * ny + m[2] * nz
            out_normal[i, 1] = m[3] * nx + m[4] * ny + m[5] * nz
            out_normal[i, 2] = m[6] * nx + m[7] * ny + m[8] * nz
    return k


def warm_up() -> None:
    """Compile (or load from the disk cache) the kernel now, not on a robot's first scan."""
    one = np.zeros((1, 3))
    one[0, 0] = 1.0
    cast_kernel(np.zeros((1, 3)), one, 1.0, np.array([BOX], np.int64), np.ones((1, 3)), np.ones(1),
                np.zeros(1, np.int64), np.ones(1, np.bool_), np.full((1, 3), 5.0), np.eye(3).reshape(1, 9), -1,
                True, np.empty(1), np.empty(1, np.int32), np.empty((1, 3)))
