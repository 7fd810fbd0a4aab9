"""The brains (usarsim.brains) against a real simulator: lock-step servers started with
usarsim.client.launch, the robots' true poses (GroundTruth) and the world file as the
referee.  Each brain only sees what its robot's sensors report."""

from __future__ import annotations

import dataclasses
import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from usarsim.brains import Bounds, FrontierExplorer, Team, VictimApproacher, WallFollower, Wander, run
from usarsim.brains.coverage import FloorMap, Referee
from usarsim.brains.grid import OccupancyGrid
from usarsim.brains.team import decode, encode
from usarsim.client import launch
from usarsim.client.radio import Radio
from usarsim.config.catalog import resolve_world

ARENA = Bounds(-6.0, -7.2, 6.0, 7.2)  # DM-USAR_yellow inside its outer walls
P2AT_HALF = (0.262, 0.249)  # chassis origin to the front and to the side (robot file)


@pytest.fixture(scope="module")
def yellow():
    return resolve_world("DM-USAR_yellow")


@pytest.fixture(scope="module")
def walls(yellow):
    """The floor map of the world's tall solids only (walls, stacks, table legs: what the
    brains must never touch; low boxes may be driven against or over)."""

    def top(o) -> float:
        return -(o.center[2] - (o.size[2] if o.shape == "box" else 2 * o.radius_m) / 2.0)

    tall = tuple(o for o in yellow.objects if o.mass_kg == 0 and top(o) > 0.5)
    fm = FloorMap.from_world(dataclasses.replace(yellow, objects=tall))
    i, j = np.nonzero(~fm.floor)
    return fm, fm.x0 + (i + 0.5) * fm.resolution, fm.y0 + (j + 0.5) * fm.resolution


def wall_distance(walls, x: float, y: float) -> float:
    """From (x, y) to the nearest cell a tall solid stands in (cells are padded by half a cell)."""
    _, wx, wy = walls
    return float(np.min(np.hypot(wx - x, wy - y)))


def footprint_on_walls(walls, x: float, y: float, yaw: float, shrink: float = 0.1) -> bool:
    """Whether the robot's footprint (less ``shrink``: the cells' padding and size) lies on a
    tall solid's cell."""
    fm = walls[0]
    hx, hy = P2AT_HALF[0] - shrink, P2AT_HALF[1] - shrink
    u, v = np.meshgrid(np.linspace(-hx, hx, 9), np.linspace(-hy, hy, 9))
    c, s = math.cos(yaw), math.sin(yaw)
    px, py = x + u * c - v * s, y + u * s + v * c
    i = np.floor((px - fm.x0) / fm.resolution).astype(int)
    j = np.floor((py - fm.y0) / fm.resolution).astype(int)
    return bool(np.any(~fm.floor[i, j]))


def path_length(points: list[tuple[float, float]]) -> float:
    return sum(math.dist(a, b) for a, b in zip(points, points[1:]))


# ------------------------------------------------------------------------------ wander


def test_wander_drives_far_without_touching_a_wall(walls):
    with launch(world="DM-USAR_yellow", seed=1) as server, server.connect() as world:
        robot = world.spawn("P2AT", "W1", location=(0.8, -1.5, -0.25))  # the centre-south room
        brain = Wander(robot, seed=1, origin=(0.8, -1.5, 0.0))
        world.step(0.2)
        trail, touches, clearance = [], 0, math.inf

        def watch(t: float) -> None:
            nonlocal touches, clearance
            (x, y, _), (_, _, yaw) = robot.ground_truth()
            trail.append((x, y))
            touches += brain.touching()
            clearance = min(clearance, float(brain.clearance(robot.scan()).min()))
            assert not footprint_on_walls(walls, x, y, yaw), f"on a wall at {x:.2f}, {y:.2f} (t={t:.1f})"

        run(world, [brain], 120.0, period=0.1, on_step=watch)
    assert path_length(trail) > 25.0, f"drove only {path_length(trail):.1f} m in 120 s"
    assert touches == 0
    assert clearance > 0.05, f"the laser saw something {clearance:.3f} m from the robot's body"
    # it went places: not round one spot
    xs, ys = zip(*trail)
    assert max(xs) - min(xs) > 3.0 or max(ys) - min(ys) > 3.0
    assert abs(brain.distance - path_length(trail)) < 0.1 * path_length(trail)  # its odometer agrees


# ------------------------------------------------------------------------------ wall follower


@pytest.mark.parametrize("side,y", [("right", -7.95), ("left", 7.95)])
def test_wall_follower_keeps_its_distance_along_the_arena(walls, side, y):
    """Outside the arena's west (right side) or east (left side) wall, heading north: it
    follows the wall 0.7 m from the robot's centre, round the corner and along the north wall
    to the arena's far side."""
    with launch(world="DM-USAR_yellow", seed=1) as server, server.connect() as world:
        robot = world.spawn("P2AT", "F1", location=(-4.0, y, -0.25))
        brain = WallFollower(robot, side=side, distance=0.7)
        world.step(0.2)
        trail, gaps, touches = [], [], 0

        def watch(t: float) -> None:
            nonlocal touches
            (x, yy, _), _ = robot.ground_truth()
            trail.append((x, yy))
            touches += brain.touching()
            if brain.time > 5.0:
                gaps.append(wall_distance(walls, x, yy))

        run(world, [brain], 80.0, period=0.1, on_step=watch)
    gaps = np.asarray(gaps)
    in_band = np.mean((gaps > 0.5) & (gaps < 0.9))
    assert in_band > 0.85, f"within 0.5-0.9 m of the wall {100 * in_band:.0f} % of the time"
    assert abs(np.median(gaps) - 0.7) < 0.1, np.median(gaps)
    assert gaps.min() > 0.3
    assert touches == 0
    assert path_length(trail) > 20.0
    assert max(x for x, _ in trail) > 6.0  # round the north-west (north-east) corner
    assert max(-math.copysign(1.0, y) * yy for _, yy in trail) > 7.5  # along the north wall to its other end


# ------------------------------------------------------------------------------ frontier explorer


def test_frontier_explorer_sees_most_of_the_arena_in_300_s(yellow):
    """From PlayerStart1, in front of the entrance, with odometry and the laser (its pose
    corrected by scan matching): the laser sweeps at least 60 % of the arena's reachable
    floor within 300 simulated seconds (measured from the robot's true poses), and its own
    map ends where the robot really is."""
    with launch(world="DM-USAR_yellow", seed=1) as server, server.connect() as world:
        start = next(p for p in world.start_poses if p.name == "PlayerStart1")
        referee = Referee(yellow, start.location[:2])
        robot = world.spawn("P2AT", "X1", start=start.name)
        brain = FrontierExplorer(robot, bounds=ARENA, origin=(start.location[0], start.location[1], start.rotation[2]))
        world.step(0.2)
        shares = {}

        def watch(t: float) -> None:
            referee.observe([robot])
            shares[round(t)] = referee.arena_share()

        wall = time.monotonic()
        ran = run(world, [brain], 300.0, period=0.2, on_step=watch)
        wall = time.monotonic() - wall
        truth = robot.ground_truth()
    share, near = referee.arena_share(), referee.arena_share(near=True)
    print(
        f"frontier: {ran:.0f} simulated s in {wall:.1f} s wall; arena floor swept {100 * share:.1f} %, within "
        f"3 m {100 * near:.1f} %; done {brain.done}"
    )
    assert share >= 0.6
    assert near >= 0.6
    assert shares[min(shares, key=lambda t: abs(t - 120))] >= 0.6  # well before the end
    assert brain.done or ran >= 299.0
    # the map and the pose agree with the world: scan matching kept the odometry's drift out
    x, y, yaw = brain.pose()
    assert math.dist((x, y), truth[0][:2]) < 0.3
    assert abs(math.remainder(yaw - truth[1][2], math.tau)) < 0.05
    assert referee.arena.sum() * 0.01 > 130.0  # the reachable arena floor, m2: most of its 173 m2


# ------------------------------------------------------------------------------ victim


def test_victim_approacher_finds_a_victim_it_could_not_see_from_its_start():
    with launch(world="DM-USAR_yellow", seed=1) as server, server.connect() as world:
        robot = world.spawn("P2AT", "V1", start="PlayerStart1")
        start = next(p for p in world.start_poses if p.name == "PlayerStart1")
        brain = VictimApproacher(robot, bounds=ARENA, origin=(start.location[0], start.location[1], 0.0))
        world.step(1.0)  # one whole VictSensor sweep (0.8 s)
        assert "VictSensor" in robot.readings and robot.victims() == []  # nobody in view at the start
        run(world, [brain], 300.0, period=0.2)
        victims = world.truth(class_name="Victim")
        alarms = world.truth(class_name="FalseAlarm")
        truth = robot.ground_truth()
    assert brain.done and brain.found is not None
    nearest = min(victims, key=lambda v: math.dist(v.location[:2], brain.found))
    assert math.dist(nearest.location[:2], brain.found) < 0.5, (nearest, brain.found)  # where its pelvis lies
    assert all(math.dist(a.location[:2], brain.found) > 1.0 for a in alarms)  # not a false alarm
    assert math.dist(truth[0][:2], nearest.location[:2]) < brain.reach + 0.5
    assert math.dist(brain.pose()[:2], brain.found) <= brain.reach


# ------------------------------------------------------------------------------ team


def explore(yellow, robots: int, seconds: float, radio: bool) -> tuple[float, float, int]:
    """(arena floor swept, ... within 3 m, map messages received) by ``robots`` explorers."""
    with launch(world="DM-USAR_yellow", seed=1, wireless=radio) as server, server.connect() as world:
        poses = world.start_poses[:robots]
        referee = Referee(yellow, poses[0].location[:2])
        bots, explorers, radios = [], [], []
        for k, p in enumerate(poses):
            bots.append(world.spawn("P2AT", f"R{k + 1}", start=p.name))
            explorers.append(
                FrontierExplorer(bots[-1], bounds=ARENA, origin=(p.location[0], p.location[1], p.rotation[2]))
            )
            if radio:
                radios.append(Radio(server.host, server.ports["comserver"], bots[-1].name))
        team = Team(explorers, radios or None)
        world.step(0.2)
        run(world, [team], seconds, period=0.2, on_step=lambda t: referee.observe(bots))
        for r in radios:
            r.close()
    return referee.arena_share(), referee.arena_share(near=True), team.messages


def test_four_explorers_sharing_maps_over_the_radio_beat_one(yellow):
    wall = time.monotonic()
    team = explore(yellow, 4, 90.0, radio=True)
    team_wall = time.monotonic() - wall
    one = explore(yellow, 1, 90.0, radio=False)
    print(
        f"90 simulated s: 4 robots swept {100 * team[0]:.1f} % of the arena's floor ({100 * team[1]:.1f} % within "
        f"3 m; {team_wall:.1f} s wall), one robot {100 * one[0]:.1f} % ({100 * one[1]:.1f} %)"
    )
    assert team[2] > 4 * 3 * 30  # every robot heard every other several times a second
    assert team[1] > one[1] + 0.08  # more floor seen from near
    assert team[0] >= one[0] - 0.01


def test_map_messages_round_trip():
    grid = OccupancyGrid(ARENA, 0.1)
    grid.logodds[10:20, 30:40] = 2.5
    grid.logodds[50, 60] = -1.3
    msg = encode("R2", 12.5, (1.0, -2.0), None, grid.to_bytes())
    name, t, pos, goal, data = decode(msg)
    assert (name, t, pos, goal) == ("R2", 12.5, (1.0, -2.0), None)
    back = grid.from_bytes(data)
    assert np.allclose(back, grid.logodds, atol=0.05)
    assert len(data) < 2000  # a mostly unknown arena compresses to little
    with pytest.raises(ValueError):
        decode(b"something else")


# ------------------------------------------------------------------------------ command line


def test_a_brain_runs_from_the_command_line_against_a_real_time_server():
    """``python -m usarsim.brains.wander`` against a simulator in real time (here twice as
    fast), for 6 simulated seconds."""
    with launch(world="DM-USAR_yellow", seed=1, lockstep=False, speed=2.0) as server:
        env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
        proc = subprocess.run(
            [
                sys.executable,
                "-m",
                "usarsim.brains.wander",
                "--port",
                str(server.port),
                "--location",
                "0.8,-1.5,-0.25",
                "--seconds",
                "6",
            ],
            capture_output=True,
            text=True,
            timeout=120,
            env=env,
        )
    assert proc.returncode == 0, proc.stderr
    assert "Wander: ran" in proc.stdout
    metres = float(proc.stdout.split("drove ")[1].split(" m")[0])
    assert 0.5 < metres < 6.0, proc.stdout
    assert "RuntimeWarning" not in proc.stderr


def test_the_brains_load_no_mujoco_simulation_or_server():
    """A brain talks to the simulator over the wire only, as the client does: it runs where
    no simulator is installed to run (checked in a fresh interpreter)."""
    code = (
        "import sys\n"
        "import usarsim.brains.team, usarsim.brains.victim, usarsim.brains.wander, usarsim.brains.wall_follower\n"
        "print(' '.join(m for m in sys.modules if m.split('.')[0] == 'mujoco' or "
        "m.startswith(('usarsim.sim', 'usarsim.server', 'usarsim.sensors', 'usarsim.robots'))))\n"
        "print('usarsim.brains.frontier' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    loaded, probe = out.stdout.splitlines()
    assert loaded == ""
    assert probe == "True"


def test_the_team_under_a_subt_like_radio_reports_what_was_lost(capsys):
    from usarsim.brains.team import main

    radio = Path(__file__).resolve().parents[2] / "examples" / "subt_radio.yaml"
    assert main(["--robots", "2", "--seconds", "12", "--wireless-config", str(radio)]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    m = re.search(r"radio: (\d+) messages delivered, (\d+) lost \((\d+) out of range, (\d+) on the way, (\d+)", line)
    assert m is not None, line
    delivered, lost, by_range, on_way, queues = map(int, m.groups())
    assert delivered > 0 and lost == by_range + on_way + queues
