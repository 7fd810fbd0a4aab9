"""Where INIT puts a robot (protocol.md 5.1): a start pose exactly as the world file gives it
(not rounded to the 2 decimals GETSTARTPOSES prints), the same pose copied from the
GETSTARTPOSES reply into {Location} {Rotation}, and a location inside a solid refused with
an ERROR naming the solid."""

from __future__ import annotations

import pytest

from helpers import ground_truth


def _truth_after_init(server, init: str):
    c = server.connect()
    c.nfo()
    c.send(init)
    return c, ground_truth(c.step(0.6))


def test_a_start_pose_spawns_with_its_exact_yaw(server):
    # PlayerStart4 of DM-USAR_yellow turns 1.5708 rad (GETSTARTPOSES prints 1.57)
    c, truth = _truth_after_init(server, "INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart4}")
    yaw = truth[-1][2][2]
    assert yaw == pytest.approx(1.5708, abs=2e-4), truth[-1]
    assert abs(yaw - 1.57) > 5e-4  # not the printed 2-decimal value


def test_a_pose_copied_from_getstartposes_spawns_where_start_does(server_factory):
    a, b = server_factory(), server_factory()
    _, by_name = _truth_after_init(a, "INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart4}")
    _, copied = _truth_after_init(
        b, "INIT {ClassName USARBot.P2AT} {Name R1} {Location -15.50,-4.00,-0.25} {Rotation 0.00,0.00,1.57}"
    )
    assert by_name[-1][1] == copied[-1][1]
    assert by_name[-1][2] == copied[-1][2]


def test_an_init_inside_a_wall_is_refused_with_the_wall_named(server):
    c = server.connect()
    c.nfo()
    # the north outer wall of DM-USAR_yellow stands at x = 6.0, 0.1 m thick
    c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Location 6.0,1.0,-0.3} {Rotation 0,0,0}")
    err = c.wait_line("ERROR").text
    assert err.startswith(
        "ERROR {Command INIT} {Reason location 6.00,1.00,-0.30 is inside box 'outer_n' of DM-USAR_yellow"
    ), err
    assert "GETSTARTPOSES" in err
    # nothing was spawned: no robot to ask about, and the connection may INIT again, in the open
    assert c.ask("GETCONF {Type Robot}", "ERROR").text.startswith("ERROR {Command GETCONF}")
    c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Location 4.0,1.0,-0.3} {Rotation 0,0,0}")
    assert c.ask("GETCONF {Type Robot}", "CONF").text.startswith("CONF {Type GroundVehicle} {Name P2AT}")


def test_a_location_in_the_floor_is_lifted_onto_it_not_refused(server):
    # USARSim's clients give z values of their own maps: a level robot put into the floor is
    # lifted onto it, as before
    c = server.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Location 4.0,1.0,1.8} {Rotation 0,0,0}")
    truth = ground_truth(c.step(1.0))
    assert truth and -0.4 < truth[-1][1][2] < 0.0, truth[-1]
