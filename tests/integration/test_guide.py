"""docs/building-worlds.md stays true: its arena validates (and a misspelt key is reported as
the guide shows), serves, and behaves as the guide says (the doorway lets a robot in, the ramp
leads onto the platform, the ground-truth service knows the victim); step 4's commands work
as written: the server, the example controller and the lines typed by hand."""

from __future__ import annotations

import math
import queue
import re
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from helpers import drive_skid
from usarsim.config.catalog import resolve_robot
from usarsim.config.world_file import load_world
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
    shown = re.search(r"```\n(usarsim: error: MyArena\.yaml: [^\n]*)\n```", GUIDE.read_text()).group(1)
    assert out.returncode != 0
    assert out.stderr.strip() == shown.replace("MyArena.yaml", str(bad))  # as the guide shows it


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


# --------------------------------------------------------------------------- step 4: serve it

EXAMPLE = GUIDE.parents[1] / "examples" / "drive_p2at.py"
LISTENING = re.compile(r"usarsim: (\w+) listening on 127\.0\.0\.1:(\d+)")


@pytest.fixture
def served(arena):
    """Step 4's ``usarsim serve --world MyArena.yaml``, every listener on a free port: the
    ports by listener name (control, truth)."""
    args = [
        "--port",
        "0",
        "--truth-port",
        "0",
        "--image-port",
        "0",
        "--wcs-port",
        "0",
        "--wss-port",
        "0",
        "--cominterface-port",
        "0",
        "--no-web",
    ]
    proc = subprocess.Popen(
        [sys.executable, "-m", "usarsim", "serve", "--world", str(arena), *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
        text=True,
    )
    lines: queue.Queue = queue.Queue()
    reader = threading.Thread(target=lambda: [lines.put(ln) for ln in proc.stdout], daemon=True)
    reader.start()
    ports: dict[str, int] = {}
    try:
        while not {"control", "truth"} <= ports.keys():
            m = LISTENING.match(lines.get(timeout=60))
            if m:
                ports[m.group(1)] = int(m.group(2))
        yield ports
    finally:
        proc.kill()
        proc.wait(10)
        reader.join(10)
        proc.stdout.close()


def ask_truth(conn: socket.socket, f, request: str) -> list[str]:
    conn.sendall(request.encode() + b"\r\n")
    out = []
    while (line := f.readline().decode().strip()) != "{End}":
        out.append(line)
    return out


def test_step_4_the_example_drives_a_p2at_from_the_first_start_pose_through_the_doorway(served):
    proc = subprocess.Popen(
        [sys.executable, str(EXAMPLE), "--port", str(served["control"]), "--seconds", "18"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    track = []  # where the ground-truth service sees the robot while the example drives it
    with socket.create_connection(("127.0.0.1", served["truth"]), timeout=10) as conn, conn.makefile("rb") as f:
        deadline = time.monotonic() + 60
        while proc.poll() is None and time.monotonic() < deadline:
            for line in ask_truth(conn, f, "{Name Robot1}"):
                x, y, _ = (float(v) for v in re.search(r"\{Location ([^}]*)\}", line).group(1).split(","))
                track.append((x, y))
            time.sleep(0.2)
        victims = ask_truth(conn, f, "{Class Victim}")  # the guide's printf | nc line
    out, err = proc.communicate(timeout=10)
    assert proc.returncode == 0, err
    assert "start poses: Start1, Start2" in out and "INIT: a P2AT at start pose Start1" in out
    assert track and math.dist(track[0], (-3.0, 0.0)) < 0.3  # Start1, outside the doorway
    inside = [(x, y) for x, y in track if x > 0.6]
    assert inside, (track[-1], out)  # in the room: through the doorway (x = 0, |y| < 0.7)
    assert all(abs(y) < 0.45 for x, y in track if -0.4 < x < 0.4)
    assert len(victims) == 1 and victims[0].startswith("{Name Dora} {Class Victim}")
    assert "{Location 6.3000,-1.5000,-0.4000}" in victims[0]


def test_step_4_the_lines_typed_by_hand(served):
    with socket.create_connection(("127.0.0.1", served["control"]), timeout=10) as conn, conn.makefile("rb") as f:
        assert f.readline().startswith(b"NFO {Gametype BotDeathMatch} {Level MyArena}")
        conn.sendall(b"GETSTARTPOSES\r\n")
        assert f.readline().decode().startswith("NFO {StartPoses 2} {Start1 -3.00,0.00,-0.25 0.00,0.00,0.00 Start2 ")
        conn.sendall(b"INIT {ClassName USARBot.P2AT} {Name Robot1} {Start Start1}\r\n")
        conn.sendall(b"DRIVE {Left 2} {Right 2}\r\n")
        seen = set()
        while not {b"STA", b"SEN"} <= seen:
            line = f.readline()
            assert not line.startswith(b"ERROR"), line
            seen.add(line.split(b" ", 1)[0])
