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
    _, copied = _truth_after_init(b, "INIT {ClassName USARBot.P2AT} {Name R1} {Location -15.50,-4.00,-0.25} "
                                     "{Rotation 0.00,0.00,1.57}")
    assert by_name[-1][1] == copied[-1][1]
    assert by_name[-1][2] == copied[-1][2]
