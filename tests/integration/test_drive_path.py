"""One typed DRIVE path (protocol.md 5.3): every part of a DRIVE goes to the robot's drive
model, which applies the parts its kind understands and ignores the rest.  Tried over the
wire, in a lock-step server, as the clients that send them do."""

from __future__ import annotations

import logging
import math

import pytest

from helpers import ground_truth

# NIST's Iridium test UI sends this line for its Stop button, whatever the robot.
IRIDIUM_STOP = (
    "DRIVE {Left 0} {Right 0} {Speed 0} {AltitudeVelocity 0} {LinearVelocity 0} {LateralVelocity 0} "
    "{RotationalVelocity 0}"
)


def travelled(c, seconds: float) -> tuple[float, float]:
    """(distance in the plane, turn) over ``seconds`` of stepping, from the GroundTruth lines."""
    gts = ground_truth(c.step(seconds))
    (_, p0, o0), (_, p1, o1) = gts[0], gts[-1]
    return math.hypot(p1[0] - p0[0], p1[1] - p0[1]), math.remainder(o1[2] - o0[2], 2 * math.pi)


@pytest.mark.parametrize(
    "cls, go",
    [
        ("P2AT", "DRIVE {Left 3} {Right 3}"),
        ("AirRobot", "DRIVE {LinearVelocity 1}"),
        ("Sedan", "DRIVE {Speed 5} {FrontSteer 0}"),
        ("ERS", "DRIVE {LinearVelocity 0.1}"),
    ],
)
def test_the_iridium_stop_line_stops_every_kind_of_robot(server_factory, test_world, cls, go):
    srv = server_factory(world=test_world, seed=3)
    c = srv.connect()
    c.nfo()
    c.send(f"INIT {{ClassName USARBot.{cls}}} {{Name R}} {{Location -7,0,-0.9}} {{Rotation 0,0,0}}")
    c.step(1.0)
    c.send(go)
    c.step(2.0)
    moving, _ = travelled(c, 1.0)
    assert moving > 0.08, f"{cls} did not drive off ({moving:.3f} m in 1 s)"
    c.send(IRIDIUM_STOP)
    c.step(2.0)  # time to stop
    still, turn = travelled(c, 2.0)
    assert still < 0.02 and abs(turn) < 0.02, f"{cls} went on after Stop: {still:.3f} m, {turn:.3f} rad in 2 s"


def test_a_walking_robot_walks_and_turns_on_left_and_right(server_factory, test_world):
    from usarsim.config.catalog import resolve_robot
    from usarsim.robots.legged import Legged

    gait = Legged.settings_of(resolve_robot("ERS"))
    srv = server_factory(world=test_world, seed=3)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.ERS} {Name Dog} {Location -6,0,-0.5} {Rotation 0,0,0}")
    c.step(1.0)
    c.send("DRIVE {Left 50} {Right 50} {Normalized True}")  # both sides half ahead: half its walking speed
    c.step(2.0)
    gts = ground_truth(c.step(4.0))
    (t0, p0, _), (t1, p1, _) = gts[0], gts[-1]
    assert (p1[0] - p0[0]) / (t1 - t0) == pytest.approx(0.5 * gait.max_linear_m_s, rel=0.2)
    c.send("DRIVE {Left 4} {Right -4}")  # rad/s: half of MaxSpeed 8 each way: a right turn on the spot
    c.step(2.0)
    dist, turn = travelled(c, 4.0)
    assert turn / 3.8 == pytest.approx(0.5 * gait.max_yaw_rate_rad_s, rel=0.2)  # clockwise: yaw grows
    c.send("DRIVE {Left 0} {Right 0}")
    c.step(2.0)
    dist, turn = travelled(c, 2.0)
    assert dist < 0.02 and abs(turn) < 0.02


def test_parts_a_robot_does_not_understand_are_ignored_and_logged_once(server_factory, test_world, caplog):
    srv = server_factory(world=test_world, seed=3)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R} {Location -7,0,-0.9} {Rotation 0,0,0}")
    c.step(1.0)
    with caplog.at_level(logging.INFO, logger="usarsim.server"):
        for _ in range(3):
            c.send("DRIVE {Speed 5} {FrontSteer 0.3}")  # an Ackermann command: a P2AT ignores it
        dist, turn = travelled(c, 1.0)
    assert dist < 0.01 and abs(turn) < 0.01
    notes = [r.getMessage() for r in caplog.records if "ignores AckermannDrive" in r.getMessage()]
    assert len(notes) == 1, notes


UNICYCLE_ROBOT = """\
class_name: UniBot
description: a differential base on casters driven as a unicycle (drive from the test tree)
vehicle_type: GroundVehicle
steering_type: SkidSteered
drive: unicycle
mass_kg: 10.6
max_speed_rad_s: 10.0
max_torque_nm: 20.0
geometry: {dimensions: [0.5, 0.4, 0.25], wheel_radius: 0.1, wheel_separation: 0.4, wheel_base: 0.0}
chassis:
  - {center: [0.0, 0.0, -0.05], size: [0.5, 0.3, 0.15], mass_kg: 10.0}
  - {shape: sphere, center: [0.2, 0.0, 0.06], radius: 0.04, mass_kg: 0.2, friction: 0.02}
  - {shape: sphere, center: [-0.2, 0.0, 0.06], radius: 0.04, mass_kg: 0.2, friction: 0.02}
wheels:
  - {name: L, position: [0.0, -0.2, 0.0], radius_m: 0.1, width_m: 0.05, mass_kg: 0.1, side: left}
  - {name: R, position: [0.0, 0.2, 0.0], radius_m: 0.1, width_m: 0.05, mass_kg: 0.1, side: right}
sensors:
  - {type: GroundTruth, name: GroundTruth}
"""


def test_a_new_drive_kind_from_one_file_in_the_test_tree_and_a_robot_file(server_factory, test_world, tmp_path):
    import plugins.unicycle_drive  # noqa: F401  (registers the drive "unicycle")

    robots = tmp_path / "robots"
    robots.mkdir()
    (robots / "UniBot.yaml").write_text(UNICYCLE_ROBOT)
    srv = server_factory(world=test_world, seed=3, robot_dirs=(str(robots),))
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.UniBot} {Name U} {Location -6,0,-0.5} {Rotation 0,0,0}")
    c.step(1.0)
    c.send("DRIVE {LinearVelocity 0.4}")
    c.step(1.0)
    gts = ground_truth(c.step(2.0))
    (t0, p0, _), (t1, p1, _) = gts[0], gts[-1]
    assert (p1[0] - p0[0]) / (t1 - t0) == pytest.approx(0.4, rel=0.1)
    c.send("DRIVE {LinearVelocity 0} {RotationalVelocity 0.5}")  # turn right on the spot
    c.step(1.0)
    dist, turn = travelled(c, 2.0)
    assert turn / 1.8 == pytest.approx(0.5, rel=0.25) and dist < 0.05
    c.send("DRIVE {Left 3} {Right 3}")  # not a unicycle command: ignored
    c.send("DRIVE {RotationalVelocity 0}")
    c.step(1.0)
    dist, turn = travelled(c, 1.0)
    assert dist < 0.01 and abs(turn) < 0.01


def test_a_robot_file_is_checked_by_its_drive_model(tmp_path):
    from usarsim.config.robot import load_robot
    from usarsim.errors import ConfigError
    from usarsim.sim.robotspec import robot_model_summary

    one_sided = UNICYCLE_ROBOT.replace("drive: unicycle", "drive: skid").replace("side: right", "side: left")
    p = tmp_path / "OneSided.yaml"
    p.write_text(one_sided)
    with pytest.raises(ConfigError, match="skid-steered robot needs at least one left and one right wheel"):
        robot_model_summary(load_robot(p))
    p.write_text(UNICYCLE_ROBOT.replace("drive: unicycle", "drive: skidd"))
    with pytest.raises(ConfigError, match=r"unknown drive type 'skidd'.*skid"):
        robot_model_summary(load_robot(p))


def test_an_init_of_a_robot_whose_drive_is_not_registered_is_refused(server_factory, test_world, tmp_path):
    robots = tmp_path / "robots"
    robots.mkdir()
    (robots / "HoverBot.yaml").write_text(
        UNICYCLE_ROBOT.replace("class_name: UniBot", "class_name: HoverBot").replace("drive: unicycle", "drive: hover")
    )
    srv = server_factory(world=test_world, seed=3, robot_dirs=(str(robots),))
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.HoverBot} {Location -6,0,-0.5}")
    reply = c.ask("GETCONF {Type Robot}", "ERROR")  # the INIT's ERROR comes first
    assert reply.text.startswith("ERROR {Command INIT} {Reason ") and "unknown drive type 'hover'" in reply.text
    assert c.ask("GETCONF {Type Robot}", "ERROR").text.endswith("send INIT first}")
