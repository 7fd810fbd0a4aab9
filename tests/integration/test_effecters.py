"""Effecters every robot has (protocol.md 8): the headlight and self-righting."""

from __future__ import annotations

import math

import pytest

from helpers import segments


def spawn(server, start="PlayerStart1", rotation=None, z=None):
    c = server.connect()
    c.nfo()
    if rotation is None:
        c.send(f"INIT {{ClassName USARBot.P2AT}} {{Name R1}} {{Start {start}}}")
    else:
        p = server.app.world.start_pose(start)
        c.send(f"INIT {{ClassName USARBot.P2AT}} {{Name R1}} {{Location {p.location[0]},{p.location[1]},{z}}} "
               f"{{Rotation {rotation}}}")
    c.step(2.0)
    return c


def test_the_headlight_turns_on_and_off_in_the_scene_and_in_sta(server):
    c = spawn(server)

    def lamp():
        return server.on_sim(lambda sim: bool(sim.model.light_active[sim.robots[1].handle.light]))

    assert not lamp()
    c.send("DRIVE {Light True}")
    sta = [ln for ln in c.step(0.4) if ln.text.startswith("STA")][-1]
    assert segments(sta.text)["LightToggle"] == "True" and segments(sta.text)["LightIntensity"] == "100"
    assert lamp()
    c.send("DRIVE {Left 0} {Right 0} {Light False}")
    sta = [ln for ln in c.step(0.4) if ln.text.startswith("STA")][-1]
    assert segments(sta.text)["LightToggle"] == "False" and not lamp()


def test_flip_rights_an_overturned_robot_and_is_ignored_when_upright(server):
    c = spawn(server, rotation="3.1416,0,0", z=-0.5)  # dropped upside down

    def up():
        def get(sim):
            return float(sim.data.xmat[sim.robots[1].handle.body_id][8])
        return server.on_sim(get)

    assert up() < -0.9
    c.send("DRIVE {Flip True}")
    c.step(4.0)
    assert up() > 0.95  # back on its wheels
    (x, y, z), _ = server.on_sim(lambda sim: sim.pose_of(1))
    assert z == pytest.approx(-0.1455, abs=0.02)
    # upright: Flip does nothing
    before = server.on_sim(lambda sim: sim.pose_of(1))
    c.send("DRIVE {Flip True}")
    c.step(2.0)
    after = server.on_sim(lambda sim: sim.pose_of(1))
    assert math.dist(before[0], after[0]) < 0.01
