"""Every request that expects a reply gets one, over real sockets: the UDK's path-node queries,
CONTROL's GetSTA, ACT's Gripper on an actuator without one, the ground-truth port's empty line
and ``{Class Robot}``, and GEO/CONF after the battery ran out (README: a documented deviation
from protocol.md 4.6)."""

from __future__ import annotations

import pytest

from helpers import Client
from usarsim.config.world_file import load_world

WORLD = """\
name: NodeArena
description: a floor with two path nodes (tests only)
floor: {center: [0, 0], size: [20, 20]}
start_poses:
  - {name: Here, location: [-5.0, 0.0, -0.2], rotation: [0, 0, 0]}
  - {name: There, location: [5.0, 0.0, -0.2], rotation: [0, 0, 3.1416]}
path_nodes:
  - {name: Door, location: [1.5, -2.25, -0.3], rotation: [0, 0, 1.5708]}
  - {name: Corner, location: [-4.0, 6.0, -0.3]}
"""


@pytest.fixture
def nodes_server(server_factory, tmp_path):
    (tmp_path / "NodeArena.yaml").write_text(WORLD)
    return server_factory(world=load_world(tmp_path / "NodeArena.yaml"))


def test_path_nodes_are_listed_and_the_closest_is_found_before_init(nodes_server):
    c = nodes_server.connect()
    c.nfo()
    assert c.ask("GETPATHNODES", "NFO").text == (
        "NFO {PathNodes 2} {Door 1.50,-2.25,-0.30 0.00,0.00,1.57 Corner -4.00,6.00,-0.30 0.00,0.00,0.00}"
    )
    assert (
        c.ask("GETCLOSESTPATHNODE {Location 1,-1,0}", "NFO").text == "NFO {Pathnode Door} {Location 1.50,-2.25,-0.30}"
    )
    assert c.ask("GETCLOSESTPATHNODE {Location -3 5 0}", "NFO").text == (
        "NFO {Pathnode Corner} {Location -4.00,6.00,-0.30}"
    )
    assert c.ask("GETCLOSESTPATHNODE", "ERROR").text.startswith("ERROR {Command GETCLOSESTPATHNODE} {Reason ")


def test_a_world_without_path_nodes_says_so(server):
    c = server.connect()
    c.nfo()
    assert c.ask("GETPATHNODES", "NFO").text == "NFO {PathNodes 0}"
    reply = c.ask("GETCLOSESTPATHNODE {Location 0,0,0}", "ERROR").text
    assert reply == (
        "ERROR {Command GETCLOSESTPATHNODE} {Reason world DM-USAR_yellow has no path nodes (a world file "
        "lists them under path_nodes)}"
    )


def test_control_getsta_is_answered_with_an_error(server):
    c = server.connect()
    c.nfo()
    reply = c.ask("CONTROL {Type GetSTA} {ClassName USARPhysObj.Box}", "ERROR").text
    assert reply.startswith("ERROR {Command CONTROL} {Reason this simulator has no world controller")
    c.send("CONTROL {Type KillAll}")  # no reply, and the connection stays up
    c.sync()


def test_act_gripper_on_an_actuator_without_one_is_answered_failed(server):
    c = server.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R} {Start PlayerStart1}")
    c.step(0.2)
    c.send("ACT {Name CameraPanTilt} {Gripper 1}")
    c.send("PING")
    lines = [ln.text for ln in c.lines_until("PONG")]
    assert "RES {Time 0.20} {Type Gripper} {Name CameraPanTilt} {Status Failed}" in lines, lines


def test_the_ground_truth_port_answers_an_empty_line_and_class_robot(nodes_server):
    robots = []
    for cls, start in (("P2AT", "Here"), ("AirRobot", "There")):
        r = nodes_server.connect()
        r.nfo()
        r.send(f"INIT {{ClassName USARBot.{cls}}} {{Name {cls}1}} {{Start {start}}}")
        r.sync()
        robots.append(r)
    robots[0].step(0.2)
    truth = Client(nodes_server.app.truth.port)
    nodes_server.clients.append(truth)
    truth.send_raw(b"\r\n")
    assert [ln.text for ln in truth.lines_until("{End}")] == ["{End}"]
    truth.send("{Class Robot}")
    lines = [ln.text for ln in truth.lines_until("{End}")]
    names = sorted(ln.split("}", 1)[0] for ln in lines[:-1])
    assert names == ["{Name AirRobot1", "{Name P2AT1"], lines
    assert all("{Class P2AT}" in ln or "{Class AirRobot}" in ln for ln in lines[:-1])  # each its own class
    truth.send("{Class robot} {Name p2at1}")
    assert len(truth.lines_until("{End}")) == 2


def test_geo_and_conf_are_answered_after_the_battery_ran_out(server):
    c = server.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R} {Start PlayerStart1}")
    c.step(0.2)
    server.on_sim(lambda sim: setattr(sim.robots[1], "battery_used_s", sim.robots[1].config.battery_s))
    lines = c.step(0.4)
    assert [ln for ln in lines if ln.text.startswith("STA") and "{Battery 0}" in ln.text]
    assert c.ask("GETGEO {Type Robot}", "GEO").text.startswith("GEO {Type GroundVehicle} {Name P2AT}")
    assert c.ask("GETCONF {Type Sonar}", "CONF").text.startswith("CONF {Type Sonar}")
