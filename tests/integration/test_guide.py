"""docs/building-worlds.md stays true: its arena validates, serves, and behaves as the guide
says (the doorway lets a robot in, the ramp leads onto the platform, the ground-truth
service knows the victim)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from helpers import drive_skid
from usarsim.config.catalog import resolve_robot
from usarsim.config.world import load_world
from usarsim.sim.simulation import Simulation

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "building-worlds.md"


@pytest.fixture(scope="module")
def arena(tmp_path_factory) -> Path:
    text = re.search(r"```yaml\n(# MyArena\.yaml\n.*?)```", GUIDE.read_text(), re.S).group(1)
    path = tmp_path_factory.mktemp("guide") / "MyArena.yaml"
    path.write_text(text)
    return path


def usarsim(*args):
    return subprocess.run([sys.executable, "-m", "usarsim", *args], capture_output=True, text=True, timeout=60)


def test_the_guide_arena_validates_as_the_guide_shows(arena):
    out = usarsim("validate", str(arena))
    assert out.returncode == 0
    shown = re.search(r"`(ok: world MyArena: [^`]*)`", GUIDE.read_text()).group(1)
    assert out.stdout.strip() == shown
    bad = arena.with_name("Bad.yaml")
    bad.write_text(arena.read_text().replace("rise: 0.3,", "rse: 0.3,"))
    out = usarsim("validate", str(bad))
    assert out.returncode != 0 and "objects[5].rise: required key is missing" in out.stderr


def test_a_robot_drives_through_the_doorway_and_up_the_ramp(arena):
    world = load_world(arena)
    sim = Simulation(world, seed=0)
    p2at = resolve_robot("P2AT")
    for uid, pose in enumerate(world.start_poses, start=1):
        sim.spawn(uid, p2at, f"R{uid}", pose.location, pose.rotation, set_down=True)
    sim.spawn(3, p2at, "Climber", (2.2, -1.5, -0.25), (0.0, 0.0, 0.0))  # before the ramp's foot
    sim.advance(1.0)
    (_, _, z0), _ = sim.pose_of(3)
    drive_skid(sim, 1, 3.0, 3.0)  # Start1 faces the doorway
    drive_skid(sim, 3, 3.0, 3.0)
    sim.advance(10.0)
    drive_skid(sim, 3, 0.0, 0.0)
    (x3, _, z3), (_, pitch, _) = sim.pose_of(3)
    sim.advance(4.0)
    (x1, y1, _), _ = sim.pose_of(1)
    assert x1 > 1.5 and abs(y1) < 0.5  # through the doorway, into the room
    assert x3 > 4.8 and z3 - z0 == pytest.approx(-0.3, abs=0.02) and abs(pitch) < 0.05  # on the platform
    assert [row[0] for row in sim.truth("Victim")] == ["Dora"]
    assert [row[0] for row in sim.truth("RFIDTag")] == ["42"]
    assert sim.resets == 0
