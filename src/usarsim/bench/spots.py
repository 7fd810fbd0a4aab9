"""Where the bench's robots start: the world's start poses, then free points of a grid over
its floor, away from every object."""

from __future__ import annotations

import numpy as np

Spot = tuple[float, float, float, float]  # x, y, z, yaw


def free_spots(world, n: int, clearance: float = 0.4, spacing: float = 0.7) -> list[Spot]:
    """Start poses first, then points of a grid ``spacing`` apart at least ``clearance`` from
    every static object and ``spacing`` from every start pose."""
    spots = _spots(world, clearance, spacing, limit=None)
    if len(spots) < n:
        raise SystemExit(f"usarsim bench: the world has room for {len(spots)} robots, {n} asked")
    return spots[:n]


def spread_spots(world, n: int, clearance: float = 0.4, spacing: float = 0.7) -> list[Spot]:
    """``n`` spots as far apart as the world's free floor allows: the start poses, then a grid
    of the widest spacing (at least ``spacing``, to the centimetre) that still has room for
    ``n``.  Robots started on a tight grid in one corner of an arena jam into each other as they
    turn; the bench measures robots that meet now and then, not one pile-up."""
    if len(_spots(world, clearance, spacing, limit=n)) < n:
        raise SystemExit(
            f"usarsim bench: the world has room for {len(_spots(world, clearance, spacing))} robots, {n} asked"
        )
    lo, hi = spacing, spacing * 2
    while len(_spots(world, clearance, hi, limit=n)) >= n and hi < 1e3:
        lo, hi = hi, hi * 2
    while hi - lo > 0.01:  # the room for n shrinks (roughly) as the spacing grows: bisect
        mid = (lo + hi) / 2
        if len(_spots(world, clearance, mid, limit=n)) >= n:
            lo = mid
        else:
            hi = mid
    return _spots(world, clearance, lo, limit=n)


def _spots(world, clearance: float, spacing: float, limit: int | None = None) -> list[Spot]:
    """Free spots (x, y, z, yaw): the start poses, then grid points; at most ``limit``."""
    from usarsim.sim.frames import euler_to_mat

    spots = [tuple(p.location) + (p.rotation[2],) for p in world.start_poses]
    centers, halves = [], []
    for o in world.objects:
        if o.shape == "box":
            half = np.abs(euler_to_mat(*o.rotation)) @ (np.array(o.size) / 2.0)
        else:
            half = np.abs(euler_to_mat(*o.rotation)) @ np.array([o.radius_m, o.radius_m, o.length_m / 2.0])
        center = np.array(o.center)
        if center[2] - half[2] < -0.02:  # objects lower than 2 cm (plates, ramps' feet) do not block
            centers.append(center[:2])
            halves.append(half[:2])
    fl = world.floor
    xs = np.arange(fl.center[0] - fl.size[0] / 2 + 1.0, fl.center[0] + fl.size[0] / 2 - 1.0, spacing)
    ys = np.arange(fl.center[1] - fl.size[1] / 2 + 1.0, fl.center[1] + fl.size[1] / 2 - 1.0, spacing)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    grid = np.stack([gx.ravel(), gy.ravel()], axis=1)
    free = np.ones(len(grid), dtype=bool)
    if centers:  # outside every object's footprint grown by the clearance, along x or along y
        c, h = np.array(centers), np.array(halves) + clearance
        free = ~np.any(np.all(np.abs(grid[:, None, :] - c[None, :, :]) <= h[None, :, :], axis=2), axis=1)
    if spots:  # grid points lie ``spacing`` apart already; keep them as far from the start poses
        starts = np.array([sp[:2] for sp in spots])
        free &= np.all(np.linalg.norm(grid[:, None, :] - starts[None, :, :], axis=2) >= spacing * 0.99, axis=1)
    for x, y in grid[free]:
        if limit is not None and len(spots) >= limit:
            break
        spots.append((float(x), float(y), -0.25, 0.0))
    return spots if limit is None else spots[:limit]
