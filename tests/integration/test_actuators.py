"""The UDK actuator API (protocol.md 5.8, 6.4, 6.7, 6.8) over real sockets: GETCONF and GETGEO
{Type Actuator} describe a robot's arms and pan-tilts link by link, ACT moves them (one or
several Link/Value pairs, MOAST's Order, the Gripper), ASTA reports them every status period
once a client uses the API, and the arm UI's exchange (INIT, one line, GETCONF, exactly one
line) gets the CONF as its very next line."""

from __future__ import annotations

import re

import pytest

from helpers import Client
from usarsim.protocol import messages as M

P2AT_CONF = (
    "CONF {Type Actuator} {Name CameraPanTilt} {Link 1} {JointType Revolute} {MaxTorque 20.0000} "
    "{MinValue -3.1416} {MaxValue 3.1416} {Link 2} {JointType Revolute} {MaxTorque 20.0000} "
    "{MinValue -0.1600} {MaxValue 0.4000}"
)
P2AT_GEO = (
    "GEO {Type Actuator} {Name CameraPanTilt} {Location 0.0000,0.0000,0.0000} "
    "{Orientation 0.0000,0.0000,0.0000} {Mount P2AT} {Link 1} {Parent 0} {Location 0.1239,0.0000,-0.2036} "
    "{Orientation 3.1416,0.0000,0.0000} {Link 2} {Parent 1} {Location 0.0000,0.0000,0.0599} "
    "{Orientation 1.5708,0.0000,0.0000}"
)
ASTA = re.compile(
    r"ASTA \{Time (\d+\.\d{4})\} \{Name (\w+)\}((?: \{Link \d+\} \{Value -?\d+\.\d{4}\} "
    r"\{Torque -?\d+\.\d{4}\})+)"
)


@pytest.fixture
def p2at(server):
    c = server.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}")
    c.step(0.5)
    return c


def asta(lines, name: str) -> list[M.ActuatorStatus]:
    out = []
    for ln in lines:
        if ln.text.startswith("ASTA"):
            assert ASTA.fullmatch(ln.text), ln.text
            msg = M.parse_message(ln.text)
            if msg.name == name:
                out.append(msg)
    return out


def test_conf_and_geo_of_the_pan_tilt_with_and_without_a_name(p2at):
    assert p2at.ask("GETCONF {Type Actuator}", "CONF").text == P2AT_CONF
    assert p2at.ask("GETCONF {Type Actuator} {Name CameraPanTilt}", "CONF").text == P2AT_CONF
    assert p2at.ask("GETGEO {Type Actuator}", "GEO").text == P2AT_GEO
    assert p2at.ask("GETGEO {Type Actuator} {Name camerapantilt}", "GEO").text == P2AT_GEO
    # an actuator the robot does not have: the empty reply, as for any item type
    assert p2at.ask("GETCONF {Type Actuator} {Name Arm}", "CONF").text == "CONF {Type Actuator} {Name Arm}"
    assert p2at.ask("GETGEO {Type Actuator} {Name Arm}", "GEO").text == "GEO {Type Actuator} {Name Arm}"
    # the lines read back into the typed messages
    conf = M.parse_message(P2AT_CONF)
    assert isinstance(conf, M.ActuatorConfiguration)
    assert conf.actuators[0].links[1].max_value == pytest.approx(0.4)
    geo = M.parse_message(P2AT_GEO)
    assert isinstance(geo, M.ActuatorGeometry) and geo.actuators[0].mount == "P2AT"
    assert [k.parent for k in geo.actuators[0].links] == [0, 1]  # the parent's index plus one (UDK)
    assert M.format_message(conf) == P2AT_CONF + "\r\n" and M.format_message(geo) == P2AT_GEO + "\r\n"


def test_a_robot_without_actuators_answers_the_empty_conf(server):
    c = server.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.Kurt2D} {Name K} {Start PlayerStart1}")
    c.step(0.3)
    assert c.ask("GETCONF {Type Actuator}", "CONF").text == "CONF {Type Actuator}"
    assert c.ask("GETGEO {Type Actuator}", "GEO").text == "GEO {Type Actuator}"


def test_no_asta_until_the_client_uses_the_actuator_api(p2at):
    lines = p2at.step(1.0)
    assert not [ln for ln in lines if ln.text.startswith("ASTA")]  # a UT2004 client sees MISSTA only
    assert [ln for ln in lines if ln.text.startswith("MISSTA")]
    p2at.ask("GETCONF {Type Actuator}", "CONF")
    lines = p2at.step(1.0)
    states = asta(lines, "CameraPanTilt")
    missta = [ln for ln in lines if ln.text.startswith("MISSTA")]
    assert len(states) == len(missta) == 5  # every status period (0.2 s), beside MISSTA


def test_act_moves_several_links_in_one_line(p2at):
    # ACT counts links from 0 (UDK): {Link 0} is CONF's and ASTA's Link 1, the pan
    p2at.send("ACT {Name CameraPanTilt} {Link 0} {Value 0.3} {Link 1} {Value -0.1}")
    states = asta(p2at.step(3.0), "CameraPanTilt")
    assert states, "ACT turns ASTA on"
    last = states[-1]
    assert [k.link for k in last.links] == [1, 2]
    assert last.links[0].value == pytest.approx(0.3, abs=0.02)  # 0.17 rad/s: there within 2 s
    assert last.links[1].value == pytest.approx(-0.1, abs=0.02)
    # MOAST's UDK form carries an Order per link: 0 is an absolute angle
    p2at.send("ACT {Name CameraPanTilt} {Link 0} {Value 0.0} {Order 0}")
    states = asta(p2at.step(3.0), "CameraPanTilt")
    assert states[-1].links[0].value == pytest.approx(0.0, abs=0.02)
    assert states[-1].links[1].value == pytest.approx(-0.1, abs=0.02)  # untouched


def test_act_to_an_unknown_actuator_or_link_changes_nothing(p2at):
    p2at.send("ACT {Name NoArm} {Link 1} {Value 0.3}")
    p2at.send("ACT {Name CameraPanTilt} {Link 7} {Value 0.3}")
    p2at.send("ACT {Name CameraPanTilt} {Link 2} {Value 0.3}")  # links 0 and 1 only
    p2at.send("ACT {Name CameraPanTilt} {Link -1} {Value 0.3}")
    states = asta(p2at.step(2.0), "CameraPanTilt")
    assert all(abs(k.value) < 0.01 for s in states for k in s.links)
    p2at.sync()  # the connection is alive and everything was handled


GRIPPER_ROBOT = """\
class_name: ArmGripper
description: a small robot with a lift and a two-finger gripper (tests only)
vehicle_type: GroundVehicle
steering_type: SkidSteered
drive: skid
mass_kg: 12.6
max_speed_rad_s: 5.0
max_torque_nm: 60.0
wheel_torque_nm: 6.0
geometry: {dimensions: [0.5, 0.4, 0.3], wheel_radius: 0.1, wheel_separation: 0.4, wheel_base: 0.3}
chassis:
  - {center: [0.0, 0.0, 0.0], size: [0.5, 0.3, 0.15], mass_kg: 10.0}
wheels:
  - {name: LF, position: [0.15, -0.2, 0.05], radius_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: left}
  - {name: RF, position: [0.15, 0.2, 0.05], radius_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: right}
  - {name: LR, position: [-0.15, -0.2, 0.05], radius_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: left}
  - {name: RR, position: [-0.15, 0.2, 0.05], radius_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: right}
links:
  - {name: Lift, location: [0.33, 0.0, 0.0], joint: prismatic, axis: [0, 0, -1], min_range: 0.0, max_range: 0.2,
     max_speed: 0.1, max_torque: 100.0, armature: 0.5, shapes: [{center: [-0.05, 0.0, 0.0], size: [0.04, 0.2, 0.04], mass_kg: 0.3}]}
  - {name: LeftFinger, parent: Lift, location: [0.15, -0.06, 0.08], joint: prismatic, axis: [0, -1, 0], min_range: -0.05,
     max_range: 0.05, max_speed: 0.1, max_torque: 30.0, armature: 0.2,
     shapes: [{center: [0.0, 0.0, 0.0], size: [0.1, 0.01, 0.08], mass_kg: 0.1}]}
  - {name: RightFinger, parent: Lift, location: [0.15, 0.06, 0.08], joint: prismatic, axis: [0, 1, 0], min_range: -0.05,
     max_range: 0.05, max_speed: 0.1, max_torque: 30.0, armature: 0.2,
     shapes: [{center: [0.0, 0.0, 0.0], size: [0.1, 0.01, 0.08], mass_kg: 0.1}]}
mission_packages:
  - {name: Arm, links: [Lift, LeftFinger, RightFinger]}
sensors:
  - {type: Gripper, name: Gripper1, fingers: [LeftFinger, RightFinger], open_value: 0.02, closed_value: -0.04}
"""


def test_act_gripper_closes_and_opens_the_arms_gripper(server_factory, tmp_path):
    (tmp_path / "ArmGripper.yaml").write_text(GRIPPER_ROBOT)
    srv = server_factory(robot_dirs=(str(tmp_path),))
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.ArmGripper} {Name G} {Start PlayerStart1}")
    c.step(0.5)
    conf = c.ask("GETCONF {Type Actuator} {Name Arm}", "CONF").text
    assert conf.startswith(
        "CONF {Type Actuator} {Name Arm} {Link 1} {JointType Prismatic} {MaxTorque 100.0000} "
        "{MinValue 0.0000} {MaxValue 0.2000} {Link 2} {JointType Prismatic}"
    ), conf
    c.send("ACT {Name Arm} {Gripper 1}")
    got = [ln.text for ln in c.step(1.5) if ln.text.startswith(("RES", "EFF"))]
    assert got[-1].endswith("{Type Gripper} {Name Gripper1} {Status CLOSED}"), got
    states = asta(c.step(0.2), "Arm")
    assert states[-1].links[1].value < 0.0 and states[-1].links[2].value < 0.0  # both fingers closed in
    c.send("ACT {Name Arm} {Gripper 0}")
    got = [ln.text for ln in c.step(1.5) if ln.text.startswith(("RES", "EFF"))]
    assert got[-1].endswith("{Status OPEN}"), got
    states = asta(c.step(0.2), "Arm")
    assert states[-1].links[1].value == pytest.approx(0.02, abs=0.005)


@pytest.mark.parametrize("attempt", range(3))
def test_the_arm_ui_reads_the_conf_as_the_very_next_line(server_factory, attempt):
    """The arm UI sends INIT, reads one line (the greeting), sends GETCONF {Type Actuator}
    and reads exactly one line: that line must be the CONF, on a server running in real time
    (the robot's status lines start as soon as it stands in the world)."""
    srv = server_factory(lockstep=False)
    with Client(srv.port) as c:
        c.send("INIT {ClassName USARBot.Talon} {Location -9.5,4.0,-0.3} {Rotation 0,0,0}")
        assert c.next_line().text.startswith("NFO {Gametype")
        c.send("GETCONF {Type Actuator}")
        conf = c.next_line().text
        assert conf.startswith("CONF {Type Actuator} {Name TalonArm} {Link 1} {JointType Revolute}"), conf
        assert "{Name CameraPanTilt}" in conf
