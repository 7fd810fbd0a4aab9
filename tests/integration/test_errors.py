"""Requests that cannot be carried out are answered ``ERROR {Command c} {Reason r}`` (our
extension, README "Errors"), where a client would otherwise block on readline() forever."""

from __future__ import annotations

import pytest

from helpers import broken_advance


def errors(lines) -> list[str]:
    return [ln.text for ln in lines if ln.text.startswith("ERROR")]


@pytest.fixture
def client(server_factory, test_world):
    srv = server_factory(world=test_world, seed=3)
    c = srv.connect()
    c.nfo()
    c.srv = srv
    return c


def test_queries_before_init_are_answered_with_an_error(client):
    for line, word in (
        ("GETGEO {Type Robot}", "GETGEO"),
        ("GETCONF {Type Robot}", "GETCONF"),
        ("SET {Type Odometry} {Opcode RESET}", "SET"),
    ):
        reply = client.ask(line, "ERROR")
        assert reply.text == f"ERROR {{Command {word}}} {{Reason no robot on this connection: send INIT first}}"


@pytest.mark.parametrize(
    "line, reason",
    [
        ("INIT {ClassName USARBot.P2ATT} {Location 0,0,-0.3}", "unknown robot class 'USARBot.P2ATT'"),
        ("INIT {ClassName USARBot.P2AT} {Start Nowhere}", "unknown start pose 'Nowhere'"),
        ("INIT {ClassName USARBot.P2AT} {Location 500,0,-0.3}", "outside the world"),
        ("INIT {Name R}", "INIT needs (ClassName USARBot.<class>)"),
    ],
)
def test_an_init_that_spawns_nothing_says_why_and_no_robot_answers_after_it(client, line, reason):
    client.send(line)
    lines = client.step(0.2)
    assert any(e.startswith("ERROR {Command INIT} {Reason ") and reason in e for e in errors(lines)), lines
    assert not [ln for ln in lines if ln.text.startswith("STA")]
    # no robot exists: its data are not given out
    assert client.ask("GETCONF {Type Robot}", "ERROR").text.endswith(
        "{Reason no robot on this connection: send INIT first}"
    )


def test_a_second_init_and_bad_steps_are_answered(client):
    client.send("INIT {ClassName USARBot.P2AT} {Location -6,0,-0.3}")
    client.step(0.2)
    client.send("INIT {ClassName USARBot.P2AT} {Location -3,0,-0.3}")
    (second,) = errors(client.step(0.2))
    assert second.startswith("ERROR {Command INIT} {Reason this connection has its robot already")
    for bad in ("STEP", "STEP {Time 0}", "STEP {Time -1}", "STEP {Time abc}"):
        reply = client.ask(bad, "ERROR")
        assert reply.text.startswith("ERROR {Command STEP} {Reason STEP: ") and "Time" in reply.text, reply.text


def test_a_set_to_a_robot_without_power_is_answered(client):
    client.send("INIT {ClassName USARBot.P2AT} {Name R} {Location -6,0,-0.3}")
    client.step(0.2)
    client.srv.on_sim(lambda sim: setattr(sim.robots[1], "battery_used_s", sim.robots[1].config.battery_s))
    client.step(0.2)  # the battery runs out
    client.send("SET {Type Odometry} {Opcode RESET}")
    lines = client.step(0.2)
    assert errors(lines) == ["ERROR {Command SET} {Reason robot 'R' has no power: its battery is empty}"]


def test_a_step_after_the_simulation_stopped_on_an_error_is_answered(client):
    """A bug stops the simulation (its thread ends on the error, logged): a lock-step
    controller's STEP gets an ERROR instead of a STEPPED that would never come."""
    client.send("INIT {ClassName USARBot.P2AT} {Name R} {Location -6,0,-0.3}")
    client.step(0.2)

    client.srv.sim.advance = broken_advance
    for _ in range(2):  # the STEP it stopped on, and the next
        reply = client.ask("STEP {Time 0.2}", lambda ln: ln.text.startswith(("ERROR", "STEPPED")))
        assert reply.text == "ERROR {Command STEP} {Reason the simulation has stopped: the world was not advanced}"


def test_a_set_or_report_after_the_simulation_stopped_on_an_error_is_answered(client):
    """Once the simulation has stopped, a SET on an item and a REPORT get an ERROR instead of
    the RES that would never come."""
    client.send("INIT {ClassName USARBot.P2AT} {Name R} {Location -6,0,-0.3}")
    client.step(0.2)

    client.srv.sim.advance = broken_advance
    client.ask("STEP {Time 0.2}", "ERROR")  # the STEP it stopped on
    stopped = "{Reason the simulation has stopped: the request was not carried out}"
    assert client.ask("SET {Type Odometry} {Opcode RESET}", "ERROR").text == f"ERROR {{Command SET}} {stopped}"
    assert client.ask("REPORT {Type Victim} {Location 1,2,0}", "ERROR").text == f"ERROR {{Command REPORT}} {stopped}"


def test_a_set_that_fails_on_an_unexpected_error_is_answered(client):
    """A bug in an item's operation is logged and the SET answered, and the world goes on."""
    client.send("INIT {ClassName USARBot.P2AT} {Name R} {Location -6,0,-0.3}")
    client.step(0.2)

    def broken_operate(*args, **kwargs):
        raise RuntimeError("an operation that fails")

    client.srv.sim.operate = broken_operate
    client.send("SET {Type Odometry} {Opcode RESET}")
    lines = client.step(0.2)
    assert errors(lines) == [
        "ERROR {Command SET} {Reason the request failed on an unexpected error (RuntimeError; "
        "the server's log has the traceback)}"
    ]
    assert [ln for ln in client.step(0.2) if ln.text.startswith("STEPPED")]  # the world goes on
