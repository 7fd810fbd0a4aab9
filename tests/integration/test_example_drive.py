"""examples/drive_p2at.py against a real server: it spawns a P2AT at the first start pose the
server lists, drives at the P2AT's maximum wheel speed (--speed max), turns away from a wall
its laser sees ahead, and exits 0; without a server, or with one that never answers, it exits
non-zero within a few seconds, saying why."""

from __future__ import annotations

import math
import re
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from usarsim.config.world import load_world

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "drive_p2at.py"
WALL_FACE_X = 3.0
# The first start pose faces a wall 3 m ahead; the second comes first in alphabetical order,
# so a controller that sorted the names would pick it.
WORLD = f"""\
name: WallAhead
floor: {{center: [0.0, 0.0], size: [24.0, 24.0]}}
objects:
  - {{name: wall, shape: box, center: [{WALL_FACE_X + 0.05}, 0.0, -0.6], size: [0.1, 16.0, 1.2]}}
start_poses:
  - {{name: Zeta, location: [0.0, 0.0, -0.2], rotation: [0.0, 0.0, 0.0]}}
  - {{name: Alpha, location: [-6.0, -6.0, -0.2], rotation: [0.0, 0.0, 1.5708]}}
"""


def run_example(*args: str, timeout: float) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(EXAMPLE), *args], capture_output=True, text=True, timeout=timeout)


@pytest.mark.alone  # a real-time closed loop: how far it drives before turning depends on its latency
def test_the_example_spawns_at_the_first_pose_and_turns_before_the_wall(server_factory, tmp_path):
    (tmp_path / "WallAhead.yaml").write_text(WORLD)
    srv = server_factory(world=load_world(tmp_path / "WallAhead.yaml"), lockstep=False, speed=1.0)  # real time
    proc = subprocess.Popen([sys.executable, str(EXAMPLE), "--port", str(srv.port), "--speed", "max",
                             "--seconds", "8"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    poses = []  # the robot's ground truth while the example drives it
    deadline = time.monotonic() + 40.0
    while proc.poll() is None and time.monotonic() < deadline:
        pose = srv.on_sim(lambda sim: next((sim.pose_of(u) for u in sim.robots), None))
        if pose is not None:
            poses.append(pose)
        time.sleep(0.05)
    out, err = proc.communicate(timeout=10)
    assert proc.returncode == 0, err
    assert err == ""
    assert "start poses: Zeta, Alpha" in out and "INIT: a P2AT at start pose Zeta" in out
    assert "driving at 5.38 rad/s" in out  # the P2AT's MaxSpeed (GETCONF {Type Robot})

    (x0, y0, _), (_, _, yaw0) = poses[0]
    assert math.hypot(x0, y0) < 0.3 and abs(yaw0) < 0.1  # spawned at Zeta, facing the wall
    turns = [(float(m.group(1)), m.group(2)) for m in
             re.finditer(r"(\d+\.\d+) m ahead: turning (left|right) on the spot", out)]
    assert turns, out
    # it turns when something is nearer than 1 m ahead (printed to 2 decimals: 0.996 m reads 1.00)
    assert all(ahead <= 1.0 for ahead, _ in turns)
    assert re.search(r"m ahead: forward\n(.*\n)*.*turning .* on the spot\n(.*\n)*.*m ahead: forward", out), out
    (x1, y1, _), (_, _, yaw1) = poses[-1]
    assert abs(math.remainder(yaw1 - yaw0, math.tau)) > math.radians(45)  # it really turned
    front = 0.27  # half the P2AT's length: its front, ahead of its centre
    assert max(p[0][0] for p in poses) + front < WALL_FACE_X - 0.1  # and never reached the wall
    assert max(p[0][0] for p in poses) > 1.0  # after driving up to it
    assert srv.on_sim(lambda sim: sim.resets) == 0


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_without_a_server_it_exits_non_zero_at_once_saying_why():
    t0 = time.monotonic()
    out = run_example("--port", str(free_port()), "--seconds", "5", timeout=20)
    assert out.returncode != 0
    assert time.monotonic() - t0 < 10
    assert "cannot connect to 127.0.0.1:" in out.stderr and "is 'usarsim serve' running?" in out.stderr


def test_a_server_that_never_answers_is_given_up_after_a_timeout():
    listener = socket.create_server(("127.0.0.1", 0))
    accepted = []
    threading.Thread(target=lambda: accepted.append(listener.accept()), daemon=True).start()
    try:
        t0 = time.monotonic()
        out = run_example("--port", str(listener.getsockname()[1]), "--seconds", "30", timeout=30)
        took = time.monotonic() - t0
    finally:
        for conn, _ in accepted:
            conn.close()
        listener.close()
    assert out.returncode != 0
    assert 4.0 < took < 15.0  # its 5 s timeout, not the 30 s it was asked to drive
    assert "did not answer within 5 s" in out.stderr


@pytest.mark.parametrize("speed", ["fast", "-"])
def test_a_bad_speed_is_refused_by_the_argument_parser(speed):
    out = run_example("--speed", speed, timeout=20)
    assert out.returncode == 2 and "--speed" in out.stderr
