"""Mission packages and joints (protocol.md 5.3f, 5.3g, 5.6, 5.7, 6.4, 6.7, 6.8): the P2AT's
CameraPanTilt moved by MISPKG (link groups and the older Rotation form), DRIVE joint groups,
MULTIDRIVE, SET {Type Joint} and CAMERA; MISSTA every status period; GEO/CONF lines; the
camera and victim sensor ride on the tilt link."""

from __future__ import annotations

import math
import re

import pytest

from helpers import segments
from usarsim.sim import frames

# the real P2AT's line (protocol.md 6.8): link 1's frame turned over, link 2 above it along its Z
GEO = (
    "GEO {Type MisPkg} {Name CameraPanTilt} {Link 1} {ParentLink -1} {Location 0.1239,0.0000,-0.2036} "
    "{Orientation 3.1415,0.0000,0.0000} {Link 2} {ParentLink 1} {Location 0.0000,0.0000,0.0599} "
    "{Orientation 1.5707,0.0000,0.0000}"
)
CONF = (
    "CONF {Type MisPkg} {Name CameraPanTilt} {Link 1} {JointType Revolute} {MaxSpeed 0.1700} "
    "{MaxTorque 20.0000} {MinRange 1.0000} {MaxRange 0.0000} {Link 2} {JointType Revolute} "
    "{MaxSpeed 0.1700} {MaxTorque 20.0000} {MinRange -0.1600} {MaxRange 0.4000}"
)
MISSTA = re.compile(
    r"MISSTA \{Time \d+\.\d{2}\} \{Name CameraPanTilt\} \{Link 1\} \{Value (-?\d+\.\d{4})\} "
    r"\{Torque (-?\d+\.\d{4})\} \{Link 2\} \{Value (-?\d+\.\d{4})\} \{Torque (-?\d+\.\d{4})\}"
)


@pytest.fixture
def robot(server):
    c = server.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}")
    c.step(1.0)
    return c


def pantilt(lines) -> list[tuple[float, float]]:
    out = []
    for ln in lines:
        m = MISSTA.fullmatch(ln.text)
        if ln.text.startswith("MISSTA"):
            assert m, ln.text
            out.append((float(m.group(1)), float(m.group(3))))
    return out


def test_geo_and_conf_of_the_pan_tilt(robot):
    assert robot.ask("GETGEO {Type MisPkg}", "GEO").text == GEO
    # the actuator API reports the same frames (the UDK's numbers: rounded, Parent counted from 1)
    actuator = robot.ask("GETGEO {Type Actuator}", "GEO").text
    assert actuator.endswith(
        "{Link 1} {Parent 0} {Location 0.1239,0.0000,-0.2036} {Orientation 3.1416,0.0000,0.0000} "
        "{Link 2} {Parent 1} {Location 0.0000,0.0000,0.0599} {Orientation 1.5708,0.0000,0.0000}"
    )
    assert robot.ask("GETCONF {Type MisPkg} {Name CameraPanTilt}", "CONF").text == CONF
    assert (
        robot.ask("GETGEO {Type MisPkg} {Name NoSuchPackage}", "GEO").text == "GEO {Type MisPkg} {Name NoSuchPackage}"
    )


def test_missta_every_status_period_and_a_pan_at_its_max_speed(robot):
    lines = robot.step(1.0)
    states = pantilt(lines)
    stas = [ln for ln in lines if ln.text.startswith("STA")]
    assert len(states) == len(stas) == 5  # every 0.2 s, with STA
    assert all(abs(p) < 1e-3 and abs(t) < 1e-3 for p, t in states)  # held at 0
    robot.send("MISPKG {Name CameraPanTilt} {Link 1} {Value 0.5} {Link 2} {Value 1.0}")
    states = pantilt(robot.step(1.0))
    # 0.17 rad/s: after 1 s about 0.17 rad on both links
    assert states[-1][0] == pytest.approx(0.17, abs=0.03)
    assert states[-1][1] == pytest.approx(0.17, abs=0.03)
    states = pantilt(robot.step(4.0))
    assert states[-1][0] == pytest.approx(0.5, abs=0.01)  # reached
    assert states[-1][1] == pytest.approx(0.40, abs=0.01)  # the tilt stops at its MaxRange


def test_the_older_rotation_form_camera_and_joint_commands(robot, server):
    robot.send("MISPKG {Name CameraPanTilt} {Rotation 0,0.2,-0.3} {Order 0}")  # roll, tilt, pan
    pan, tilt = pantilt(robot.step(3.0))[-1]
    assert pan == pytest.approx(-0.3, abs=0.01) and tilt == pytest.approx(0.2, abs=0.01)
    robot.send("CAMERA {Rotation 0,-0.1,0.25}")
    pan, tilt = pantilt(robot.step(4.0))[-1]
    assert pan == pytest.approx(0.25, abs=0.01) and tilt == pytest.approx(-0.1, abs=0.01)
    robot.send("DRIVE {Name CameraPanTilt_Link1} {Value 0.1} {Order 0}")
    robot.send("SET {Type Joint} {Name CameraPanTilt_Link2} {Opcode Angle} {Params 0.3}")
    pan, tilt = pantilt(robot.step(3.0))[-1]
    assert pan == pytest.approx(0.1, abs=0.01) and tilt == pytest.approx(0.3, abs=0.01)
    robot.send("MULTIDRIVE {CameraPanTilt_Link1 -0.2} {CameraPanTilt_Link2 0.0}")
    pan, tilt = pantilt(robot.step(3.0))[-1]
    assert pan == pytest.approx(-0.2, abs=0.01) and tilt == pytest.approx(0.0, abs=0.01)
    # relative angle, and a speed order: the pan turns on at 0.1 rad/s (continuous joint)
    robot.send("DRIVE {Name CameraPanTilt_Link1} {Value 0.15} {Order 10}")
    pan, _ = pantilt(robot.step(2.0))[-1]
    assert pan == pytest.approx(-0.05, abs=0.01)
    robot.send("MISPKG {Name CameraPanTilt} {Link 1} {Value 0.1} {Order 1}")
    before = pantilt(robot.step(1.0))[-1][0]
    after = pantilt(robot.step(10.0))[-1][0]
    assert (after - before) == pytest.approx(1.0, abs=0.05)
    # the robot itself did not move while its camera did
    assert server.robot_count() == 1


def test_the_camera_rides_on_the_tilt_link(robot, server):
    def camera_yaw_pitch():
        def get(sim):
            r = sim.robots[1]
            cam = next(s for s in r.sensors if s.TYPE == "Camera")
            _, rot = r.handle.sensor_frame(sim.data, cam.item.location, cam.item.orientation, cam.item.mount)
            return frames.mj_mat_to_usar_euler(rot), r.handle.orientation(sim.data)

        return server.on_sim(get)

    (_, p0, y0), (_, _, ry) = camera_yaw_pitch()
    assert abs(math.remainder(y0 - ry, 2 * math.pi)) < 0.01 and abs(p0) < 0.01
    robot.send("MISPKG {Name CameraPanTilt} {Link 1} {Value 0.5} {Link 2} {Value 0.3}")
    robot.step(5.0)
    (_, p1, y1), (_, _, ry) = camera_yaw_pitch()
    assert math.remainder(y1 - ry, 2 * math.pi) == pytest.approx(0.5, abs=0.02)  # panned right
    assert p1 == pytest.approx(0.3, abs=0.02)  # tilted up


def test_a_wheel_speed_joint_command_and_bad_joint_commands(robot):
    robot.send("DRIVE {Name LeftFWheel} {Order 1} {Value 3.0} {Name RightFWheel} {Order 1} {Value 3.0}")
    robot.step(1.0)
    lines = robot.step(1.0)
    ticks = [
        {n: int(t) for n, t in re.findall(r"\{Name (\w+) Tick (-?\d+)\}", ln.text)}
        for ln in lines
        if ln.text.startswith("SEN") and "{Type Encoder}" in ln.text
    ]
    left = ticks[-1]["ECLeft"] - ticks[0]["ECLeft"]
    right = ticks[-1]["ECRight"] - ticks[0]["ECRight"]
    assert left > 100 and right > 100  # both front wheels spin forward (~3 rad/s x 0.9 s / 0.0174)
    for line in (
        "DRIVE {Name NoSuchJoint} {Value 1} {Order 0}",
        "MULTIDRIVE {Nothing 1.0}",
        "MISPKG {Name CameraPanTilt} {Link 7} {Value 1}",
        "MISPKG {Name Nope} {Link 1} {Value 1}",
        "SET {Type Joint} {Name CameraPanTilt_Link1} {Opcode Fly} {Params 1}",
        "MISPKG {Name CameraPanTilt} {Link 1} {Value 1} {Order 99}",
    ):
        robot.send(line)
        lines = robot.step(0.2)
        assert not [ln for ln in lines if ln.text.startswith(("RES", "GEO", "CONF"))], line
    assert segments(robot.ask("GETGEO {Type Robot}", "GEO").text)["Type"] == "GroundVehicle"  # still served


def test_a_locked_link_stays_put_and_says_so_in_conf(server_factory, test_world):
    """MinRange == MaxRange locks a link: the AirRobot's camera only tilts."""
    srv = server_factory(world=test_world)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.AirRobot} {Name A} {Location -6,0,-1} {Rotation 0,0,0}")
    c.step(0.4)
    conf = c.ask("GETCONF {Type MisPkg}", "CONF").text
    assert (
        "{Link 1} {JointType Revolute} {MaxSpeed 0.1700} {MaxTorque 20.0000} {MinRange 0.0000} {MaxRange 0.0000}"
        in conf
    )
    c.send("MISPKG {Name CameraPanTilt} {Link 1} {Value 1.0} {Link 2} {Value -0.5}")
    pan, tilt = pantilt(c.step(4.0))[-1]
    assert abs(pan) < 1e-3 and tilt == pytest.approx(-0.5, abs=0.01)


def test_a_free_turning_pan_reports_its_angle_wrapped(server_factory, test_world):
    """The P2AT's pan turns without end (MinRange > MaxRange): after more than a whole turn
    MISSTA reports its angle within [-pi, pi], not 7 rad."""
    srv = server_factory(world=test_world, seed=3)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R} {Location -6,0,-0.3} {Rotation 0,0,0}")
    c.step(0.4)
    c.send("MISPKG {Name CameraPanTilt} {Link 1} {Value 0} {Order 1}")  # hold where it is
    c.step(0.2)

    def turn(sim):  # a turn and a half ago, as if it had been panned round and round
        r = sim.robots[1]
        sim.data.qpos[r.handle.joint_qpos["CameraPanTilt_Link1"]] = 2 * math.pi + 0.5
        sim.data.act[sim.model.actuator_actadr[r.handle.actuator["CameraPanTilt_Link1"]]] = 2 * math.pi + 0.5

    srv.on_sim(turn)
    lines = c.step(0.4)
    missta = [ln.text for ln in lines if ln.text.startswith("MISSTA")][-1]
    pan = float(missta.split("{Link 1} {Value ", 1)[1].split("}", 1)[0])
    assert pan == pytest.approx(0.5, abs=0.05)
