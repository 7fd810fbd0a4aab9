"""A control session with no socket and no physics: lines in, wire lines out, the facade a
test double (fakes.FakeFacade).  What is checked is the session's own logic: its state
machine, its refusals, what it asks of the simulation and the exact lines it answers with."""

from __future__ import annotations

import logging
from concurrent.futures import Future

import pytest
from fakes import FakeFacade

from usarsim.controls import WheelSpeeds
from usarsim.protocol import messages as M
from usarsim.server.session import ALIVE, NEW, SPAWNING, Session, SessionContext


class Wire:
    """A session and what it wrote, as the client would read it."""

    def __init__(self, world, *, admit=lambda: None, **fake):
        self.facade = FakeFacade(world, **fake)
        self.sent: list = []
        ctx = SessionContext(
            facade=self.facade, peer="test:1", emit=self.sent.append, threadsafe=lambda fn: fn, admit=admit
        )
        self.session = Session(ctx, uid=7)

    def __call__(self, line: str) -> str:
        """Send ``line``; the lines written back since, as bytes on the wire would read."""
        before = len(self.sent)
        self.session.handle_line(line)
        return "".join(M.format_message(m) for m in self.sent[before:])

    def calls(self, name: str) -> list[tuple]:
        return [args for n, args in self.facade.calls if n == name]


@pytest.fixture
def wire(yellow_world):
    return lambda **kw: Wire(yellow_world, **kw)


def test_getstartposes_lists_the_worlds_poses_exactly(wire, yellow_world):
    w = wire()
    out = w("GETSTARTPOSES")
    n = len(yellow_world.start_poses)
    assert out.startswith(f"NFO {{StartPoses {n}}} {{PlayerStart1 -9.50,0.00,-0.25 0.00,0.00,0.00 PlayerStart2 ")
    assert out.endswith(" PlayerStart8 -9.50,8.00,-0.25 0.00,0.00,0.00}\r\n") and out.count("\r\n") == 1


def test_init_at_a_start_pose_spawns_there_set_down_and_the_robot_is_alive(wire):
    w = wire()
    assert w("INIT {ClassName USARBot.P2AT} {Start PlayerStart2} {Name scout}") == ""
    assert w.calls("spawn") == [(7, "P2AT", "scout", (-9.5, -4.0, -0.25), (0.0, 0.0, 0.0), True)]
    assert w.session.state == ALIVE and w.session.robot_name == "scout"


def test_init_at_a_location_copied_from_getstartposes_is_that_pose(wire):
    w = wire()
    w("INIT {ClassName USARBot.P2AT} {Location -9.50,4.00,-0.25} {Rotation 0,0,0}")
    (spawn,) = w.calls("spawn")
    assert spawn[3] == (-9.5, 4.0, -0.25) and spawn[5] is True  # PlayerStart3's own numbers, set down
    assert spawn[2] == "Robot7"  # no Name: named after the connection


@pytest.mark.parametrize(
    ("line", "reason"),
    [
        ("INIT {Start PlayerStart1}", "INIT needs (ClassName USARBot.<class>)"),  # braces in a reason would end it
        ("INIT {ClassName USARBot.NoSuchBot} {Start PlayerStart1}", "NoSuchBot"),
        ("INIT {ClassName USARBot.P2AT} {Start Nowhere}", "unknown start pose 'Nowhere' (known: PlayerStart1, "),
        ("INIT {ClassName USARBot.P2AT} {Location nan,0,0}", "all finite (NaN and infinity are not allowed)"),
    ],
)
def test_a_bad_init_is_answered_with_an_error_and_nothing_spawns(wire, line, reason):
    w = wire()
    out = w(line)
    assert out.startswith("ERROR {Command INIT} {Reason ") and reason in out and out.endswith("}\r\n")
    assert w.calls("spawn") == [] and w.session.state == NEW


def test_init_inside_a_wall_is_refused_with_the_solid_named(wire, yellow_world):
    inside = next(
        (x, y, -0.3)
        for x in range(-12, 13)
        for y in range(-12, 13)
        if yellow_world.solid_at((x, y, -0.3), movable=False)
    )
    w = wire()
    out = w("INIT {ClassName USARBot.P2AT} {Location %d,%d,-0.3}" % inside[:2])
    assert out.startswith("ERROR {Command INIT} {Reason location ") and "is inside" in out
    assert w.calls("spawn") == []


def test_a_second_init_and_a_full_server_are_refused(wire):
    w = wire()
    w("INIT {ClassName USARBot.P2AT} {Start PlayerStart1}")
    assert w("INIT {ClassName USARBot.P2AT} {Start PlayerStart2}").startswith(
        "ERROR {Command INIT} {Reason this connection has its robot already"
    )
    full = wire(admit=lambda: "the server has 4 robots (serve --max-robots 4)")
    assert full("INIT {ClassName USARBot.P2AT} {Start PlayerStart1}") == (
        "ERROR {Command INIT} {Reason the server has 4 robots (serve --max-robots 4)}\r\n"
    )
    assert full.calls("spawn") == []


def test_a_spawn_the_simulation_refuses_is_an_error_and_init_may_be_sent_again(wire):
    w = wire(spawn_error="robot name 'scout' is taken")
    assert w("INIT {ClassName USARBot.P2AT} {Start PlayerStart1} {Name scout}") == (
        "ERROR {Command INIT} {Reason robot name 'scout' is taken}\r\n"
    )
    assert w.session.state == NEW and w.session.robot is None
    w("INIT {ClassName USARBot.P2AT} {Start PlayerStart1} {Name scout2}")
    assert w.session.state == ALIVE


def test_drive_before_init_is_ignored_and_after_it_reaches_the_robot(wire, caplog):
    w = wire()
    with caplog.at_level(logging.INFO, logger="usarsim.server"):
        assert w("DRIVE {Left 1.0} {Right 1.0}") == ""
    assert w.calls("drive") == [] and "before the robot exists" in caplog.text
    w("INIT {ClassName USARBot.P2AT} {Start PlayerStart1}")
    w("DRIVE {Left 1.5} {Right -0.5} {Light true}")
    ((uid, command),) = w.calls("drive")
    assert uid == 7 and command.parts == (WheelSpeeds(left=1.5, right=-0.5),) and command.light is True


def test_step_is_answered_with_stepped_at_the_new_time_and_holds_nothing_after(wire):
    w = wire()
    w("INIT {ClassName USARBot.P2AT} {Start PlayerStart1}")
    assert w("STEP {Time 0.25}") == "STEPPED {Time 0.2500}\r\n"
    assert w("STEP {Time 0.1}") == "STEPPED {Time 0.3500}\r\n"
    assert w.calls("step") == [(0.25,), (0.1,)] and not w.session.holding


def test_a_step_too_long_runs_no_time(wire):
    w = wire()
    assert w("STEP {Time 7200}") == "STEPPED {Time 0.0000}\r\n"
    assert w.calls("step") == [(0.0,)]


def test_requests_after_the_simulation_stopped_get_errors_not_silence(wire):
    w = wire()
    w("INIT {ClassName USARBot.P2AT} {Start PlayerStart1}")
    w.facade.fail(RuntimeError("boom"))
    assert w("STEP {Time 0.1}").startswith("ERROR {Command STEP} {Reason the simulation has stopped: boom}")
    assert w("PING {Id 3}") == "PONG {Id 3}\r\n"
    assert not w.session.holding


def test_ping_is_answered_with_the_time(wire):
    w = wire()
    w("STEP {Time 0.5}")
    assert w("PING {Id 9}") == "PONG {Id 9} {Time 0.5000}\r\n"


def test_reports_are_named_in_order_and_need_a_robot(wire):
    w = wire()
    assert w("REPORT {Type Victim} {Location 1,2,3}").startswith("ERROR {Command REPORT}")
    w("INIT {ClassName USARBot.P2AT} {Start PlayerStart1}")
    w("REPORT {Type Victim} {Location 1,2,3}")
    w("REPORT {Type Victim} {Location 4,5,6} {Name Anna}")
    w("REPORT {Type Victim} {Location 7,8,9}")
    assert [(n, loc) for _, n, loc in w.calls("report_victim")] == [
        ("Victim1", (1.0, 2.0, 3.0)),
        ("Anna", (4.0, 5.0, 6.0)),
        ("Victim3", (7.0, 8.0, 9.0)),
    ]


def test_getgeo_and_getconf_of_the_robot_format_the_drives_numbers(wire):
    w = wire()
    assert w("GETGEO {Type Robot}").startswith("ERROR {Command GETGEO}")
    w("INIT {ClassName USARBot.P2AT} {Start PlayerStart1}")
    geo = w("GETGEO {Type Robot}")
    assert geo.startswith("GEO {Type GroundVehicle} {Name P2AT} {Dimensions 0.5000,0.4000,0.3000}")
    conf = w("GETCONF {Type Robot}")
    assert conf.startswith("CONF {Type GroundVehicle} {Name P2AT} {SteeringType SkidSteered} {Mass 14.0000}")
    assert w("GETGEO {Type Sonar} {Name F9}") == "GEO {Type Sonar} {Name F9}\r\n"  # nothing of that name


def test_a_malformed_request_is_answered_and_a_malformed_drive_is_ignored(wire, caplog):
    w = wire()
    assert w("STEP {Time abc}").startswith("ERROR {Command STEP} {Reason ")
    with caplog.at_level(logging.INFO, logger="usarsim.server"):
        assert w("DRIVE {Left}") == ""
        assert w("FROBNICATE {X 1}") == ""
    assert "FROBNICATE" in caplog.text


def test_the_session_holds_its_lines_while_the_spawn_is_under_way(yellow_world):
    """A spawn not answered yet (the simulation thread is busy) holds the lines after it."""
    pending = []
    facade = FakeFacade(yellow_world)
    facade.spawn = lambda uid, robot, name, loc, rot, **kw: pending.append(Future()) or pending[-1]
    sent: list = []
    session = Session(
        SessionContext(facade=facade, peer="t", emit=sent.append, threadsafe=lambda fn: fn, admit=lambda: None), uid=1
    )
    session.handle_line("INIT {ClassName USARBot.P2AT} {Start PlayerStart1}")
    assert session.state == SPAWNING and session.holding
    pending[0].set_result(1)
    assert session.state == ALIVE and not session.holding


def test_a_spawned_robot_is_in_the_directory_under_its_name_with_its_controller(wire):
    w = wire()
    w("INIT {ClassName USARBot.P2AT} {Start PlayerStart1} {Name Scout}")
    (entry,) = w.facade.robots()
    assert (entry.uid, entry.name, entry.robot.class_name, entry.controller) == (7, "Scout", "P2AT", "test:1")
    assert w.facade.find_robot("scout") is entry and w.facade.robot(7) is entry
