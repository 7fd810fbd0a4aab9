"""The exact ray tests of the compiled ray caster (:mod:`usarsim.sim.raycast`), one shape at a
time: the distance along a ray to a plane, sphere, capsule, ellipsoid, cylinder or box, and
the outward surface normal where it hits.  They follow MuJoCo's ray semantics (``mj_ray``):
the nearest non-negative intersection, so a ray starting inside a shape reports where it
leaves it; planes are seen from their front face only and within their size when it is set.
Compiled by numba, cached on disk.
"""

from __future__ import annotations

import math

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
        x0, x1 = _quad(vx * vx + vy * vy + vz * vz, vx * px + vy * py + vz * pz, px * px + py * py + pz * pz - s0 * s0)
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
        x0, x1 = _quad(
            i0 * vx * vx + i1 * vy * vy + i2 * vz * vz,
            i0 * vx * px + i1 * vy * py + i2 * vz * pz,
            i0 * px * px + i1 * py * py + i2 * pz * pz - 1.0,
        )
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
def _world_normal(gtype, s0, s1, s2, m, dx, dy, dz, out):
    """The outward normal (world frame) into ``out`` at the point (d) relative to a geom
    whose orientation is m (row-major), on its surface."""
    nx, ny, nz = _normal_local(
        gtype,
        s0,
        s1,
        s2,
        m[0] * dx + m[3] * dy + m[6] * dz,
        m[1] * dx + m[4] * dy + m[7] * dz,
        m[2] * dx + m[5] * dy + m[8] * dz,
    )
    out[0] = m[0] * nx + m[1] * ny + m[2] * nz
    out[1] = m[3] * nx + m[4] * ny + m[5] * nz
    out[2] = m[6] * nx + m[7] * ny + m[8] * nz


@njit(cache=True, nogil=True, inline="always")
def _ray_in_frame(gtype, s0, s1, s2, m, dx, dy, dz, vx, vy, vz):
    """:func:`_ray_local` for a ray from (d) along (v), both in the world frame relative to
    a geom whose orientation is m (row-major)."""
    return _ray_local(
        gtype,
        s0,
        s1,
        s2,
        m[0] * dx + m[3] * dy + m[6] * dz,
        m[1] * dx + m[4] * dy + m[7] * dz,
        m[2] * dx + m[5] * dy + m[8] * dz,
        m[0] * vx + m[3] * vy + m[6] * vz,
        m[1] * vx + m[4] * vy + m[7] * vz,
        m[2] * vx + m[5] * vy + m[8] * vz,
    )
