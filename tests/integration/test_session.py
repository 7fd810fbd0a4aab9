"""A control session without sockets (design.md 5): lines in, typed messages out, the
simulation behind a real facade in lock-step.  The session's context stands in for the
connection: what it emits is collected, callbacks from the simulation thread run at once."""

from __future__ import annotations

import logging
import threading
import time

import pytest

from usarsim.protocol import messages as M
from usarsim.server.session import ALIVE, NEW, Session, SessionContext
from usarsim.sim.facade import SimFacade


class Harness:
    def __init__(self, world, admit=lambda: None):
        self.facade = SimFacade(world, seed=1, lockstep=True)
        self.outputs = []
        self.facade.set_deliver(self.outputs.extend)
        self.sent: list = []
        self._event = threading.Event()

        def emit(msg):
            self.sent.append(msg)
            self._event.set()

        ctx = SessionContext(facade=self.facade, peer="test:1", emit=emit, threadsafe=lambda fn: fn, admit=admit)
        self.session = Session(ctx, uid=1)
        self.facade.start()

    def line(self, text: str) -> None:
        self.session.handle_line(text)

    def wait(self, kind: type, timeout: float = 10.0):
        """The first message of ``kind`` emitted (waiting for the simulation thread)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            found = [m for m in self.sent if isinstance(m, kind)]
            if found:
                self.sent.remove(found[0])
                return found[0]
            self._event.wait(0.05)
            self._event.clear()
        raise AssertionError(f"no {kind.__name__} within {timeout} s; emitted: {self.sent}")

    def step(self, seconds: float) -> None:
        self.line(f"STEP {{Time {seconds}}}")
        self.wait(M.Stepped)

    def pose(self):
        return self.facade.call(lambda sim: sim.pose_of(1)).result(10)

    def close(self):
        self.facade.stop()


@pytest.fixture
def harness(yellow_world):
    made = []

    def make(**kw):
        h = Harness(yellow_world, **kw)
        made.append(h)
        return h

    yield make
    for h in made:
        h.close()


def test_init_spawns_and_queries_get_typed_replies(harness):
    h = harness()
    h.line("GETSTARTPOSES")
    poses = h.wait(M.StartPoses)
    assert poses.poses and poses.poses[0].name
    h.line(f"INIT {{ClassName USARBot.P2AT}} {{Name R1}} {{Start {poses.poses[0].name}}}")
    h.step(0.2)
    assert h.session.state == ALIVE and h.pose() is not None
    h.line("GETGEO {Type Robot}")
    geo = h.wait(M.RobotGeometry)
    assert geo.class_name == "P2AT" and geo.wheel_radius == pytest.approx(0.13, abs=0.01)
    h.line("GETCONF {Type Sonar}")
    conf = h.wait(M.ItemConfiguration)
    assert conf.item_type == "Sonar" and len(conf.items) == 16


def test_a_drive_before_init_and_a_refused_init_are_logged_once_and_change_nothing(harness, caplog):
    h = harness(admit=lambda: "the world is full (test)")
    with caplog.at_level(logging.INFO, logger="usarsim.server"):
        for _ in range(3):
            h.line("DRIVE {Left 1} {Right 1}")
        h.line("INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}")
        h.step(0.2)
    assert h.session.state == NEW and h.pose() is None
    msgs = [r.getMessage() for r in caplog.records]
    assert sum("before the robot exists" in m for m in msgs) == 1
    assert any("INIT refused: the world is full (test)" in m for m in msgs)


def test_drive_parts_go_to_the_robots_drive_model(harness, caplog):
    h = harness()
    h.line("INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}")
    h.step(1.0)
    (x0, y0, _), _ = h.pose()
    with caplog.at_level(logging.INFO, logger="usarsim.server"):
        h.line("DRIVE {Speed 10} {FrontSteer 0.4}")  # Ackermann: a P2AT ignores it
        h.line("DRIVE {Speed 10} {FrontSteer 0.4}")
        h.step(1.0)
    (x1, y1, _), _ = h.pose()
    assert abs(x1 - x0) + abs(y1 - y0) < 0.01
    assert sum("ignores AckermannDrive" in r.getMessage() for r in caplog.records) == 1
    h.line("DRIVE {Left 3} {Right 3}")
    h.step(1.0)
    (x2, y2, _), _ = h.pose()
    assert abs(x2 - x1) + abs(y2 - y1) > 0.15  # 3 rad/s x 0.13 m: about 0.4 m/s


def test_viewports_reply_comes_back_from_the_simulation_thread(harness):
    h = harness()
    h.line("INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}")
    h.step(0.2)
    h.line("SET {Type Viewports} {Config SingleView} {Viewport1 NoSuchCamera}")
    res = h.wait(M.ViewportsResult)
    assert res.config == "SingleView" and res.viewports[0].status == "Failed"
