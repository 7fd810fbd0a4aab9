"""The ROS 2 tests' fixtures: a simulator, the bridge in a process of its own, a relay between
them and a probe node (ros2_parts).

Every test gets a ROS domain of its own (``ROS_DOMAIN_ID``), so that parallel test workers and
tests one after another never see each other's nodes."""

from __future__ import annotations

import itertools
import os
import re
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

rclpy = pytest.importorskip("rclpy", reason="the ROS 2 extra is not installed (pip install -e '.[ros2]')")

from ros2_parts import Bridge, Probe  # noqa: E402

from helpers import Tap  # noqa: E402
from usarsim.ros2.tf2_build import ensure_tf2_msgs  # noqa: E402

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
# announce every 0.5 s, so that a subscriber that joins late finds the bridge quickly
os.environ.setdefault(
    "FASTDDS_DEFAULT_PROFILES_FILE",
    str(Path(__file__).resolve().parents[2] / "tools" / "ros2" / "fastdds_quick_discovery.xml"),
)

ROS_WORLD = """\
# The ROS 2 tests' world: a 40 m x 40 m floor and one wall whose face is at x = 5.0 m.
name: Ros2TestArena
description: flat floor, one wall (ROS 2 tests only)
floor:
  center: [0.0, 0.0]
  size: [40.0, 40.0]
materials:
  wall: {rgba: [0.9, 0.8, 0.4, 1.0], friction: 0.8}
objects:
  - {name: wall_n, shape: box, center: [5.05, 0.0, -0.6], size: [0.1, 12.0, 1.2], material: wall}
start_poses:
  - {name: Skid, location: [-6.0, 0.0, -0.2], rotation: [0.0, 0.0, 0.0]}
  - {name: Car, location: [-12.0, 10.0, -0.5], rotation: [0.0, 0.0, 0.0]}
  - {name: Air, location: [-6.0, -8.0, -0.5], rotation: [0.0, 0.0, 0.0]}
  - {name: Spare, location: [-12.0, -14.0, -0.2], rotation: [0.0, 0.0, 0.0]}
"""
WALL_FACE_X = 5.0

_domains = itertools.count(0)


@pytest.fixture(scope="session")
def tf2_ready() -> None:
    ensure_tf2_msgs()


@pytest.fixture
def domain(worker_id: str) -> int:
    """A ROS domain no other test uses now: 40 per test worker, from 20."""
    worker = 0 if worker_id == "master" else int(re.sub(r"\D", "", worker_id) or 0)
    return 20 + 40 * (worker % 5) + next(_domains) % 40


@pytest.fixture(scope="session")
def ros_world(tmp_path_factory: pytest.TempPathFactory) -> Path:
    p = tmp_path_factory.mktemp("ros2") / "Ros2TestArena.yaml"
    p.write_text(ROS_WORLD)
    return p


@pytest.fixture
def probe(domain: int) -> Iterator[Probe]:
    p = Probe(domain)
    yield p
    p.close()


@pytest.fixture
def ros_sim(ros_world: Path, domain: int, tf2_ready: None) -> Iterator[Callable[..., tuple[Bridge, Tap]]]:
    """``ros_sim(*bridge_args, lockstep=True, image=False)``: a simulator of the ROS test world
    (with its image server when ``image``), a Tap and
    a bridge through it; all stopped at teardown, where the bridge must exit 0 without a
    traceback."""
    from usarsim.client.launch import launch

    made: list[tuple[Any, Tap, Bridge]] = []

    def make(*args: str, lockstep: bool = True, image: bool = False) -> tuple[Bridge, Tap]:
        server = launch(str(ros_world), lockstep=lockstep, speed=1.0, image=image)
        tap = Tap(server.port)
        more = ("--image-port", str(server.ports["image"])) if image else ("--camera-hz", "0")
        bridge = Bridge(tap.port, domain, *(("--lockstep",) if lockstep else ()), *more, *args)
        made.append((server, tap, bridge))
        if not bridge.ready:
            bridge.stop()
            raise AssertionError(f"the bridge did not start: {bridge.ready_line!r}\n{bridge.stderr[-3000:]}")
        return bridge, tap

    yield make
    for server, tap, bridge in made:
        rc = bridge.stop()
        tap.close()
        server.close()
        assert "Traceback" not in bridge.stderr, bridge.stderr[-3000:]
        assert rc == 0, f"the bridge exited {rc}: {bridge.stderr[-3000:]}"
