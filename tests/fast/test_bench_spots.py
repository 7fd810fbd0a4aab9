"""Where the bench starts its robots: on free floor, spread as far apart as the world allows."""

from __future__ import annotations

import numpy as np
import pytest

from usarsim.bench import free_spots, spread_spots
from usarsim.config.catalog import resolve_world


def _min_distance(spots) -> float:
    p = np.array([s[:2] for s in spots])
    d = np.linalg.norm(p[:, None, :] - p[None, :, :], axis=2) + np.eye(len(p)) * 1e9
    return float(d.min())


def _clear_of_objects(world, spots, clearance: float) -> bool:
    """No spot within ``clearance`` of a standing object's footprint (axis-aligned boxes
    only: enough for the arena's walls)."""
    for o in world.objects:
        if o.shape != "box" or any(abs(a) > 1e-9 for a in o.rotation):
            continue
        half = np.array(o.size[:2]) / 2.0
        if o.center[2] - o.size[2] / 2.0 >= -0.02:  # plates and ramps' feet do not block
            continue
        for s in spots[len(world.start_poses) :]:
            if np.all(np.abs(np.array(s[:2]) - np.array(o.center[:2])) <= half + clearance - 1e-9):
                return False
    return True


@pytest.mark.parametrize("n", [16, 64, 256])
def test_spread_spots_are_farther_apart_than_the_tight_grid_and_clear_of_walls(n):
    world = resolve_world("DM-USAR_yellow")
    tight, spread = free_spots(world, n), spread_spots(world, n)
    assert len(spread) == n and len(set(spread)) == n
    grid = spread[len(world.start_poses) :]
    assert _min_distance(grid) >= 0.7 * 0.99  # never closer than the tight grid's spacing
    assert _min_distance(grid) > _min_distance(tight[len(world.start_poses) :]) + 0.3
    assert _clear_of_objects(world, spread, 0.4)
    # the start poses come first, as in the tight grid
    assert spread[: len(world.start_poses)] == tight[: len(world.start_poses)]


def test_the_bench_says_when_the_world_has_no_room():
    world = resolve_world("DM-USAR_yellow")
    with pytest.raises(SystemExit, match="room for"):
        spread_spots(world, 100000)
    with pytest.raises(SystemExit, match="room for"):
        free_spots(world, 100000)
