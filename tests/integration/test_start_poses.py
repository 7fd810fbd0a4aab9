"""No shipped start pose puts a robot in front of something its laser cannot see: within 2 m
straight ahead of every start pose of every shipped world, whatever rays cast low across a
P2AT's width (below its laser) meet, the laser's plane meets too.  A controller that steers
by its laser (examples/drive_p2at.py) would otherwise drive into it from the start."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from usarsim.config.catalog import resolve_robot, resolve_world, world_files
from usarsim.config.world_file import load_world
from usarsim.sensors.scanner import RangeScanner
from usarsim.sim import frames
from usarsim.sim.simulation import Simulation

REACH_M = 2.0  # how far ahead of the robot's front nothing may hide below the laser
LOW_HEIGHTS_M = (0.05, 0.10, 0.15)  # above the ground: below a P2AT's laser (0.24 m)
SWATH_RAYS = 9  # low rays side by side across the robot's width
STANDING_M = 1.0  # a pose less than this above the ground stands on it; a higher one floats (water)

P2AT = resolve_robot("P2AT")
SCANNER = next(i for i in P2AT.items if i.item_type == "RangeScanner")
# The laser's height above the ground the P2AT stands on, and its beams (SICK LMS200 preset)
LASER_HEIGHT_M = P2AT.body_lowest_point_m - SCANNER.location[2]  # a skid-steered robot stands on its body
LASER_AHEAD_M = SCANNER.location[0]
PRESET = RangeScanner.PRESETS[SCANNER.params["preset"]]
BEAMS = int(round(PRESET["fov_rad"] / PRESET["resolution_rad"])) + 1
HALF_LENGTH_M, HALF_WIDTH_M = P2AT.geometry.dimensions[0] / 2.0, P2AT.geometry.dimensions[1] / 2.0


def hidden_ahead(world) -> list[str]:
    """What lies within REACH_M ahead of a start pose of ``world``, low, where a P2AT's laser
    does not see it (one line per pose and thing); a pose above the ground (under water)
    must have nothing at all within REACH_M ahead at its own height."""
    sim = Simulation(world, seed=0)
    mujoco.mj_forward(sim.model, sim.data)
    caster, model = sim.caster, sim.model
    problems = []
    for pose in world.start_poses:
        yaw = pose.rotation[2]
        origin = frames.to_mj_vec(pose.location)
        forward = frames.to_mj_vec((math.cos(yaw), math.sin(yaw), 0.0))
        right = frames.to_mj_vec((-math.sin(yaw), math.cos(yaw), 0.0))
        up = np.array([0.0, 0.0, 1.0])
        down, _, _ = caster.cast(origin, -up[None, :], 50.0, -1)
        ground = origin - up * down[0]
        standing = down[0] < STANDING_M
        across = np.linspace(-HALF_WIDTH_M, HALF_WIDTH_M, SWATH_RAYS)
        heights = LOW_HEIGHTS_M if standing else (0.0,)
        base = ground if standing else origin
        starts = np.array([base + up * h + right * s for h in heights for s in across])
        dist, _, gid = caster.cast_from(starts, np.tile(forward, (len(starts), 1)), HALF_LENGTH_M + REACH_M, -1)
        low = {int(g): d for d, g in sorted(zip(dist, gid), reverse=True) if np.isfinite(d)}  # nearest per geom
        if not low:
            continue
        if not standing:
            problems += [
                f"{world.name} {pose.name}: {model.geom(g).name} {d:.2f} m ahead of the pose, at its height "
                f"({down[0]:.1f} m above the ground)"
                for g, d in low.items()
            ]
            continue
        # the laser's beams, from where it sits on a P2AT standing at the pose
        laser = ground + up * LASER_HEIGHT_M + forward * LASER_AHEAD_M
        angles = PRESET["fov_rad"] / 2.0 - PRESET["resolution_rad"] * np.arange(BEAMS)  # + to the right
        beams = np.array([math.cos(a) * forward + math.sin(a) * right for a in angles])
        ldist, _, lgid = caster.cast(laser, beams, HALF_LENGTH_M + REACH_M + 1.0, -1, kind="laser")
        seen = set()
        for d, g, a in zip(ldist, lgid, angles):
            if np.isfinite(d) and abs(d * math.sin(a)) <= HALF_WIDTH_M + 0.1:  # in the robot's way
                seen.add(int(g))
        for g, d in low.items():
            if g not in seen:
                problems.append(
                    f"{world.name} {pose.name}: {model.geom(g).name} {d - HALF_LENGTH_M:.2f} m ahead "
                    f"of the robot, below its laser ({LASER_HEIGHT_M:.2f} m up), which does not see it"
                )
    return problems


def test_the_laser_height_is_the_p2ats():
    assert LASER_HEIGHT_M == pytest.approx(0.2377, abs=1e-3)  # 0.14565 m axle-to-ground + 0.092 m mount
    assert BEAMS == 181


@pytest.mark.parametrize("name", sorted(world_files()))
def test_no_start_pose_faces_something_below_the_laser(name):
    world = resolve_world(name)
    assert world.start_poses
    assert hidden_ahead(world) == []


ARENA = """\
name: LowThings
floor: {{center: [0.0, 0.0], size: [30.0, 30.0]}}
objects:
  - {{name: wall, shape: box, center: [1.5, 0.0, -0.6], size: [0.1, 3.0, 1.2]}}
  - {{name: kerb, shape: box, center: [10.0, {kerb_y}, -0.06], size: [0.2, 3.0, 0.12]}}
  - {{name: pillar, shape: box, center: [1.5, {pillar_y}, -2.5], size: [0.1, 1.0, 5.0]}}
false_alarms:
  - {{name: doll_head, center: [-8.8, 0.1, -0.1], size: [0.2, 0.2, 0.2], part: Head}}
start_poses:
  - {{name: FacingAWall, location: [0.0, 0.0, -0.25], rotation: [0.0, 0.0, 0.0]}}
  - {{name: FacingAKerb, location: [8.5, 0.0, -0.25], rotation: [0.0, 0.0, 0.0]}}
  - {{name: FacingADoll, location: [-8.0, 0.0, -0.25], rotation: [0.0, 0.0, 3.1416]}}
  - {{name: Floating, location: [0.0, 6.0, -3.0], rotation: [0.0, 0.0, 0.0]}}
"""


def test_the_check_finds_what_only_low_rays_meet(tmp_path):
    """The check itself: a wall (seen by the laser) is no problem; a kerb and a doll's head
    in the way of a start pose, below the laser, are, and so is anything ahead of a pose
    above the ground; moved out of the way, they are not."""
    (tmp_path / "LowThings.yaml").write_text(ARENA.format(kerb_y=0.0, pillar_y=6.0))
    problems = hidden_ahead(load_world(tmp_path / "LowThings.yaml"))
    assert len(problems) == 3, problems
    doll, kerb, floating = sorted(problems)
    assert kerb.startswith("LowThings FacingAKerb: world/kerb 1.14 m ahead of the robot")  # 9.9 - 8.5 - 0.26
    assert doll.startswith("LowThings FacingADoll: falsealarm/doll_head/Head 0.44 m ahead of the robot")
    assert (
        floating == "LowThings Floating: world/pillar 1.45 m ahead of the pose, at its height (3.0 m above the ground)"
    )

    moved = ARENA.format(kerb_y=3.0, pillar_y=8.0).replace("-8.8, 0.1", "-8.8, 1.0")
    (tmp_path / "LowThings.yaml").write_text(moved)
    assert hidden_ahead(load_world(tmp_path / "LowThings.yaml")) == []
