"""The Python client's logic with no socket: the lines it writes go to a control session over a
fake facade (fakes.FakeFacade), and what the session answers is fed back to the client's
connection state byte by byte, as a network may cut it."""

from __future__ import annotations

import math

import pytest
from fakes import FakeFacade

from usarsim.client import core
from usarsim.protocol import messages as M
from usarsim.readings import RangeScanReading
from usarsim.server.session import Session, SessionContext


class Loop:
    """client line -> session -> wire bytes -> client state."""

    def __init__(self, world):
        self.facade = FakeFacade(world)
        self.out: list = []
        self.session = Session(
            SessionContext(
                facade=self.facade, peer="t", emit=self.out.append, threadsafe=lambda fn: fn, admit=lambda: None
            ),
            uid=3,
        )
        self.state = core.ConnectionState()

    def send(self, line: str, chunk: int = 7) -> list:
        assert line.endswith("\r\n")
        self.session.handle_line(line[:-2])
        data = "".join(M.format_message(m) for m in self.out).encode()
        self.out.clear()
        got = []
        for i in range(0, len(data), chunk):  # cut anywhere, even inside a key
            got += self.state.feed(data[i : i + chunk])
        return got


@pytest.fixture
def loop(yellow_world):
    return Loop(yellow_world)


def test_the_clients_init_line_spawns_where_it_asks(loop):
    line = core.init_line("P2AT", "scout", None, (-9.5, 4.0, -0.25), (0, 0, 0))
    assert line == "INIT {ClassName USARBot.P2AT} {Name scout} {Location -9.5,4.0,-0.25} {Rotation 0.0,0.0,0.0}\r\n"
    loop.send(line)
    assert [a for n, a in loop.facade.calls if n == "spawn"] == [
        (3, "P2AT", "scout", (-9.5, 4.0, -0.25), (0.0, 0.0, 0.0), True)
    ]


def test_replies_cut_anywhere_are_claimed_whole_and_an_error_is_raised(loop):
    loop.send(core.init_line("P2AT", None, "PlayerStart1", None, None))
    loop.send(core.query_line("GETGEO", "Robot", None), chunk=3)
    geo = loop.state.claim(core.accepts_reply("GETGEO", "Robot"), "GETGEO")
    assert isinstance(geo, M.RobotGeometry) and geo.class_name == "P2AT" and geo.wheel_radius == pytest.approx(0.1)
    assert loop.state.claim(core.accepts_reply("GETGEO", "Robot"), "GETGEO") is None  # claimed once
    loop.send(core.init_line("P2AT", None, "PlayerStart1", None, None), chunk=1)
    with pytest.raises(core.ServerError, match="this connection has its robot already") as err:
        loop.state.claim(lambda m: False, "INIT")
    assert err.value.command == "INIT"
    assert loop.state.bad_lines == 0


def test_stepped_advances_the_clients_time_and_drive_lines_reach_the_robot(loop):
    loop.send(core.init_line("P2AT", None, "PlayerStart1", None, None))
    loop.send("STEP {Time 0.2}\r\n")
    loop.send("STEP {Time 0.2}\r\n")
    assert loop.state.time == pytest.approx(0.4)
    loop.send(core.drive_line(left=1.0, right=0.5))
    (drive,) = [a for n, a in loop.facade.calls if n == "drive"]
    assert drive[1].parts[0].left == 1.0 and drive[1].parts[0].right == 0.5
    with pytest.raises(TypeError, match="unknown keys"):
        core.drive_line(lft=1.0)


def test_garbage_lines_are_counted_not_fatal():
    state = core.ConnectionState()
    got = state.feed(b"SEN {Time 1.0} {Type Sonar} {Name F1 Range 0.5}\r\nSTA {Time nan\r\nSTEPPED {Time 2.0}\r\n")
    assert [type(m) for m in got][-1] is M.Stepped and state.time == 2.0
    assert state.bad_lines >= 1


def test_a_scans_angles_run_right_to_left_symmetric_about_ahead():
    r = RangeScanReading(
        sensor_type="RangeScanner",
        name="Scanner1",
        resolution_rad=math.radians(1.0),
        fov_rad=math.radians(180.0),
        ranges_m=tuple([2.0] * 181),
    )
    scan = core.scan_of(1.0, r, 20.0)
    assert scan.angles[0] == pytest.approx(-math.pi / 2) and scan.angles[-1] == pytest.approx(math.pi / 2)
    x, y = scan.points()[0]  # the first beam: to the right, USARSim's +Y
    assert x == pytest.approx(0.0, abs=1e-9) and y == pytest.approx(2.0)
