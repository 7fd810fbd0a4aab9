"""MuJoCo's thread pool gives the very same physics as one thread, and gets the cores but
one from 32 robots on (none on a 2-core machine), every core from 160 robots on."""

from __future__ import annotations

import numpy as np
import pytest

from usarsim.config.catalog import resolve_robot
from usarsim.controls import DriveCommand, WheelSpeeds
from usarsim.sim import simulation
from usarsim.sim.settings import SimSettings
from usarsim.sim.simulation import Simulation


def driven_world(world, threads: int) -> tuple[np.ndarray, int, float]:
    """Three P2ATs driven for 2 s: the state, the pool's threads, how far the first went."""
    sim = Simulation(world, seed=1, settings=SimSettings(physics_threads=threads))
    p2at = resolve_robot("P2AT")
    for uid, pose in enumerate(world.start_poses[:3], start=1):
        sim.spawn(uid, p2at, f"R{uid}", pose.location, pose.rotation, set_down=True)
        sim.drive(uid, DriveCommand(parts=(WheelSpeeds(1.0 + uid / 4, 1.5 - uid / 4),)))
    start = sim.robots[1].handle.position_mj(sim.data).copy()
    sim.advance(2.0)
    moved = float(np.linalg.norm(sim.robots[1].handle.position_mj(sim.data) - start))
    return sim.data.qpos.copy(), sim.threads, moved


def test_the_pool_gives_the_same_physics_bit_for_bit(yellow_world):
    one, no_pool, moved = driven_world(yellow_world, 0)
    pooled, threads, _ = driven_world(yellow_world, 2)
    assert no_pool == 0 and threads == 2
    assert moved > 0.3  # the robots drove, with contacts all the way
    np.testing.assert_array_equal(pooled, one)


@pytest.mark.parametrize(
    ("cores", "robots", "want"),
    [(2, 64, 0), (2, 159, 0), (2, 160, 0), (2, 256, 0), (4, 64, 3), (4, 256, 3), (4, 16, 0), (16, 64, 8), (1, 256, 0)],
)
def test_auto_leaves_a_core_to_the_measuring_thread(monkeypatch, cores, robots, want):
    monkeypatch.setattr(simulation.os, "sched_getaffinity", lambda pid: set(range(cores)))
    assert simulation.physics_threads(robots) == want


def test_a_number_of_threads_overrides_and_out_of_range_is_refused(monkeypatch):
    monkeypatch.setattr(simulation.os, "sched_getaffinity", lambda pid: set(range(4)))
    assert simulation.physics_threads(1, 5) == 5
    assert simulation.physics_threads(256, 1) == 0
    assert simulation.physics_threads(64, None) == 3  # None: the automatic rule
    with pytest.raises(ValueError, match="physics_threads must be within 0..256"):
        SimSettings(physics_threads=100000)  # what serve --physics-threads takes at most
