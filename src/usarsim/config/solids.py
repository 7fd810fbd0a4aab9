"""Point-inside tests for the solids of a world (WorldConfig.solid_at): a point in the frame of
a turned object, inside a box, and how deep inside the closed surface of a mesh file (OBJ or
binary STL) it lies.

Coordinates are in the USARSim frame (X forward/north, Y right/east, Z down), metres and
radians.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from functools import cache
from pathlib import Path

Vec3 = tuple[float, float, float]
Triangle = tuple[Vec3, Vec3, Vec3]


def rotation_matrix(rpy: Sequence[float]) -> tuple[Vec3, Vec3, Vec3]:
    """The rotation matrix of (roll, pitch, yaw) applied yaw, then pitch, then roll (the
    USARSim frame's convention, docs/world-files.md): object axes -> world axes."""
    cr, sr = math.cos(rpy[0]), math.sin(rpy[0])
    cp, sp = math.cos(rpy[1]), math.sin(rpy[1])
    cy, sy = math.cos(rpy[2]), math.sin(rpy[2])
    return (
        (cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
        (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
        (-sp, cp * sr, cp * cr),
    )


def to_local(point: Sequence[float], center: Sequence[float], rotation: Sequence[float]) -> Vec3:
    """``point`` (world) in the frame of an object at ``center`` turned by ``rotation``."""
    d = (point[0] - center[0], point[1] - center[1], point[2] - center[2])
    m = rotation_matrix(rotation)
    return (
        m[0][0] * d[0] + m[1][0] * d[1] + m[2][0] * d[2],
        m[0][1] * d[0] + m[1][1] * d[1] + m[2][1] * d[2],
        m[0][2] * d[0] + m[1][2] * d[1] + m[2][2] * d[2],
    )


def in_box(local: Sequence[float], size: Sequence[float], margin: float) -> bool:
    """Whether ``local`` (the box's frame) lies more than ``margin`` inside a box of full
    extents ``size`` centred on the origin."""
    return all(abs(c) < e / 2.0 - margin for c, e in zip(local, size))


def _sub(a: Sequence[float], b: Sequence[float]) -> Vec3:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _dot(a: Sequence[float], b: Sequence[float]) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a: Sequence[float], b: Sequence[float]) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@cache
def mesh_triangles(mesh_file: str, scale: tuple[float, ...], mtime: float) -> tuple[Triangle, ...]:
    """The triangles of an OBJ (its faces, fanned) or binary STL file, scaled, in the
    object's frame; empty when the file cannot be read.  (``mtime``: read again when the
    file changes.)"""
    p = Path(mesh_file)
    tris: list[Triangle] = []
    try:
        if p.suffix.lower() == ".obj":
            verts: list[Vec3] = []
            for line in p.read_text(errors="replace").splitlines():
                parts = line.split()
                if parts[:1] == ["v"] and len(parts) >= 4:
                    x, y, z = (float(v) * k for v, k in zip(parts[1:4], scale))
                    verts.append((x, y, z))
                elif parts[:1] == ["f"] and len(parts) >= 4:
                    idx = [int(t.split("/")[0]) for t in parts[1:]]
                    idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                    tris += [(verts[idx[0]], verts[idx[k]], verts[idx[k + 1]]) for k in range(1, len(idx) - 1)]
        else:
            data = p.read_bytes()
            (count,) = struct.unpack_from("<I", data, 80)
            for t in range(count):
                v = struct.unpack_from("<9f", data, 84 + 50 * t + 12)
                a, b, c = ((v[3 * i] * scale[0], v[3 * i + 1] * scale[1], v[3 * i + 2] * scale[2]) for i in range(3))
                tris.append((a, b, c))
    except (OSError, ValueError, IndexError, struct.error):
        return ()
    return tuple(tris)


def closest_on_triangle(p: Sequence[float], a: Vec3, b: Vec3, c: Vec3) -> Vec3:
    """The point of triangle abc closest to p (C. Ericson, Real-Time Collision Detection,
    2005, section 5.1.5)."""
    ab, ac, ap = _sub(b, a), _sub(c, a), _sub(p, a)
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    if d1 <= 0 and d2 <= 0:
        return a
    bp = _sub(p, b)
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    if d3 >= 0 and d4 <= d3:
        return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        v = d1 / (d1 - d3)
        return (a[0] + v * ab[0], a[1] + v * ab[1], a[2] + v * ab[2])
    cp = _sub(p, c)
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    if d6 >= 0 and d5 <= d6:
        return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        w = d2 / (d2 - d6)
        return (a[0] + w * ac[0], a[1] + w * ac[1], a[2] + w * ac[2])
    va = d3 * d6 - d5 * d4
    if va <= 0 and (d4 - d3) >= 0 and (d5 - d6) >= 0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return (b[0] + w * (c[0] - b[0]), b[1] + w * (c[1] - b[1]), b[2] + w * (c[2] - b[2]))
    denom = 1.0 / (va + vb + vc)
    v, w = vb * denom, vc * denom
    return (a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w)


# A direction no mesh edge or face of a hand-made file is likely to be parallel to, for the
# inside test's ray.
_RAY = (0.5773, 0.5781, 0.5766)


def mesh_depth(mesh_file: str, scale: Sequence[float], local: Sequence[float]) -> float:
    """How deep ``local`` (the object's frame) lies inside the closed surface of a mesh file:
    the distance to its nearest triangle when a ray from it crosses the surface an odd
    number of times (Moeller and Trumbore's ray-triangle test), else negative."""
    try:
        mtime = Path(mesh_file).stat().st_mtime
    except OSError:
        return -1.0
    tris = mesh_triangles(mesh_file, tuple(scale), mtime)
    if not tris:
        return -1.0
    crossings, nearest = 0, math.inf
    for a, b, c in tris:
        q = closest_on_triangle(local, a, b, c)
        nearest = min(nearest, math.dist(local, q))
        e1, e2 = _sub(b, a), _sub(c, a)
        h = _cross(_RAY, e2)
        det = _dot(e1, h)
        if abs(det) < 1e-12:
            continue
        sv = _sub(local, a)
        u = _dot(sv, h) / det
        qv = _cross(sv, e1)
        v = _dot(_RAY, qv) / det
        if u < 0 or v < 0 or u + v > 1:
            continue
        if _dot(e2, qv) / det > 0:
            crossings += 1
    return nearest if crossings % 2 else -nearest
