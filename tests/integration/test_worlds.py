"""The shipped worlds as a robot meets them (issue: worlds): a P2AT climbs the orange arena's
ramp to its upper level, a P2AT driving into the yellow arena pushes the brick in its way,
and the ground-truth service follows the brick."""

from __future__ import annotations

import math

import pytest

from helpers import drive_skid
from usarsim.config.catalog import resolve_robot, resolve_world
from usarsim.sim.simulation import Simulation


def test_a_p2at_climbs_the_orange_ramp_to_the_upper_level():
    """The orange arena's ramp (14 degrees, x -1.8 .. 2.6 at y -10.8 .. -9.2) leads from the
    floor to the deck 1.1 m up: a P2AT driven straight up it at 3 rad/s (0.39 m/s) ends
    on the deck, level, its wheels 1.1 m above the floor."""
    world = resolve_world("DM-USAR_orange")
    sim = Simulation(world, seed=0)
    sim.spawn(1, resolve_robot("P2AT"), "R1", (-3.2, -10.0, -0.25), (0.0, 0.0, 0.0))
    sim.advance(1.0)
    (_, _, z_floor), _ = sim.pose_of(1)
    drive_skid(sim, 1, 3.0, 3.0)
    steepest = 0.0
    for _ in range(20):
        sim.advance(1.0)
        _, (_, pitch, _) = sim.pose_of(1)
        steepest = max(steepest, pitch)
    (x, _, z), (roll, pitch, _) = sim.pose_of(1)
    assert steepest == pytest.approx(math.radians(14.0), abs=0.03)  # nose up on the slope
    assert x > 2.8 and z - z_floor == pytest.approx(-1.1, abs=0.02)  # on the deck
    assert abs(roll) < 0.05 and abs(pitch) < 0.05 and sim.resets == 0


def test_a_robot_pushes_the_brick_in_its_way():
    """From PlayerStart1 a P2AT drives north through the yellow arena's entrance into the
    brick standing on its edge in the foyer: the brick (a movable object of 2.3 kg) is
    shoved ahead and tumbles, the robot gets past it, and the ground-truth service reports
    where the brick went."""
    world = resolve_world("DM-USAR_yellow")
    sim = Simulation(world, seed=0)
    pose = world.start_pose("PlayerStart1")
    sim.spawn(1, resolve_robot("P2AT"), "R1", pose.location, pose.rotation, set_down=True)
    sim.advance(1.0)
    (before,) = sim.truth("MovableObject", "brick_foyer")
    drive_skid(sim, 1, 3.0, 3.0)
    sim.advance(22.0)
    (after,) = sim.truth("MovableObject", "brick_foyer")
    (x, y, _), _ = sim.pose_of(1)
    assert after[3][0] > before[3][0] + 0.1 and abs(after[3][1] - before[3][1]) < 0.1  # shoved north
    assert after[4] != pytest.approx(before[4], abs=0.1)  # it tumbled
    assert x > after[3][0] + 1.0 and sim.resets == 0  # the robot went on over it


def test_paper_on_the_orange_floor_is_slippery(tmp_path):
    """A sheet of paper (the orange arena's material, friction 0.3) decides the grip of the
    wheels on it: a P2AT pushing into a wall from the bare floor stalls (its wheels hold),
    from a sheet of paper its wheels spin on the paper."""
    from helpers import TEST_WORLD, WALL_FACE_X
    from usarsim.config.world_file import load_world

    paper = resolve_world("DM-USAR_orange").materials["paper"]
    assert paper.friction == pytest.approx(0.3)
    spin = {}
    for label in ("paper", "floor"):
        text = TEST_WORLD.replace(
            "materials:\n", "materials:\n  paper: {rgba: [0.9, 0.9, 0.9, 1.0], friction: %g}\n" % paper.friction
        )
        if label == "paper":  # a sheet under the robot where it meets the wall
            text = text.replace(
                "objects:\n",
                "objects:\n  - {name: sheet, shape: box, center: [4.4, 0.0, -0.0025], "
                "size: [1.2, 0.8, 0.005], material: paper}\n",
            )
        (tmp_path / "TestArena.yaml").write_text(text)
        world = load_world(tmp_path / "TestArena.yaml")
        sim = Simulation(world, seed=0)
        sim.spawn(1, resolve_robot("P2AT"), "R", (WALL_FACE_X - 0.55, 0.0, -0.3), (0.0, 0.0, 0.0))
        sim.advance(1.0)
        drive_skid(sim, 1, 4.0, 4.0)
        sim.advance(3.0)  # at the wall, pushing
        h = sim.robots[1].handle
        spin[label] = sum(abs(float(sim.data.qvel[h.joint_qvel[w]])) for w in ("LeftFWheel", "RightFWheel")) / 2
        (x, _, _), _ = sim.pose_of(1)
        assert x > WALL_FACE_X - 0.35, label  # it reached the wall
    assert spin["floor"] < 0.3  # stalled
    assert spin["paper"] > 1.0, spin  # spinning on the paper
