"""Drive types through the protocol (protocol.md 5.3): Ackermann steering (Speed, FrontSteer,
RearSteer; partial commands keep the other values; STA reports the current angles) and
holonomic steered wheels (WheelNumber/WheelSpeed/WheelSteer groups), on small test robots
served with --robot-dir, in a lock-step server."""

from __future__ import annotations

import math
import re

import pytest

from helpers import drive_velocities, ground_truth, segments

TEST_CAR = """\
class_name: TestCar
description: test car
vehicle_type: GroundVehicle
steering_type: AckermanSteered
drive: ackermann
mass_kg: 1000.0
max_speed_rad_s: 40.0
max_torque_nm: 500.0
wheel_torque_nm: 400.0
max_front_steer_rad: 0.6
wheel_gain: 200.0
steer_torque_nm: 1500.0
geometry: {dimensions: [4.0, 1.7, 1.4], wheel_radius: 0.3, wheel_separation: 1.5, wheel_base: 2.6}
chassis:
  - {center: [0.0, 0.0, 0.1], size: [4.0, 1.6, 0.8], mass_kg: 920.0}
wheels:
  - {name: FL, position: [1.3, -0.75, 0.4], radius_m: 0.3, width_m: 0.2, mass_kg: 20, side: left, steer: front, driven: false}
  - {name: FR, position: [1.3, 0.75, 0.4], radius_m: 0.3, width_m: 0.2, mass_kg: 20, side: right, steer: front, driven: false}
  - {name: RL, position: [-1.3, -0.75, 0.4], radius_m: 0.3, width_m: 0.2, mass_kg: 20, side: left}
  - {name: RR, position: [-1.3, 0.75, 0.4], radius_m: 0.3, width_m: 0.2, mass_kg: 20, side: right}
sensors:
  - {type: GroundTruth, name: GroundTruth}
"""

TEST_OMNI = """\
class_name: TestOmni
description: test holonomic robot
vehicle_type: GroundVehicle
steering_type: HolonomSteered
drive: holonomic
mass_kg: 20.0
max_speed_rad_s: 10.0
max_torque_nm: 60.0
wheel_torque_nm: 10.0
wheel_gain: 10.0
steer_torque_nm: 20.0
geometry: {dimensions: [0.5, 0.5, 0.4], wheel_radius: 0.08, wheel_separation: 0.4, wheel_base: 0.0}
chassis:
  - {center: [0.0, 0.0, -0.05], size: [0.5, 0.3, 0.2], mass_kg: 18.0}
  - {shape: sphere, center: [0.2, 0.0, 0.13], radius: 0.07, mass_kg: 0.2, friction: 0.02}
  - {shape: sphere, center: [-0.2, 0.0, 0.13], radius: 0.07, mass_kg: 0.2, friction: 0.02}
wheels:
  - {name: W0, position: [0.0, -0.2, 0.12], radius_m: 0.08, width_m: 0.04, mass_kg: 0.8, side: left, steer: free, number: 0}
  - {name: W1, position: [0.0, 0.2, 0.12], radius_m: 0.08, width_m: 0.04, mass_kg: 0.8, side: right, steer: free, number: 1}
sensors:
  - {type: GroundTruth, name: GroundTruth}
"""


@pytest.fixture
def robots_dir(tmp_path):
    d = tmp_path / "robots"
    d.mkdir()
    (d / "TestCar.yaml").write_text(TEST_CAR)
    (d / "TestOmni.yaml").write_text(TEST_OMNI)
    return d


def spawn(server_factory, test_world, robots_dir, cls, x, y, yaw):
    srv = server_factory(world=test_world, seed=3, robot_dirs=(str(robots_dir),))
    c = srv.connect()
    c.nfo()
    c.send(f"INIT {{ClassName USARBot.{cls}}} {{Name R1}} {{Location {x},{y},-0.8}} {{Rotation 0,0,{yaw}}}")
    c.step(1.0)
    return c


def motion(c, seconds):
    """(speed m/s, yaw rate rad/s, last STA) over ``seconds`` of stepping."""
    lines = c.step(seconds)
    gts = ground_truth(lines)
    (t0, p0, o0), (t1, p1, o1) = gts[0], gts[-1]
    dt = t1 - t0
    speed = math.hypot(p1[0] - p0[0], p1[1] - p0[1]) / dt
    rate = math.remainder(o1[2] - o0[2], 2 * math.pi) / dt
    sta = [ln.text for ln in lines if ln.text.startswith("STA")][-1]
    return speed, rate, sta, (p0, p1)


def test_ackermann_speed_steering_and_sta(server_factory, test_world, robots_dir):
    c = spawn(server_factory, test_world, robots_dir, "TestCar", -8.0, -8.0, 1.5708)
    assert c.ask("GETCONF {Type Robot}", "CONF").text == (
        "CONF {Type GroundVehicle} {Name TestCar} {SteeringType AckermanSteered} {Mass 1000.0000} "
        "{MaxSpeed 40.0000} {MaxTorque 500.0000} {MaxFrontSteer 0.6000} {MaxRearSteer 0.0000}"
    )
    c.send("DRIVE {Speed 10} {FrontSteer 0} {RearSteer 0}")
    c.step(2.0)
    speed, rate, sta, _ = motion(c, 1.0)
    assert speed == pytest.approx(0.3 * 10, rel=0.05) and abs(rate) < 0.01  # wheel radius 0.3 m
    assert re.fullmatch(
        r"STA \{Type GroundVehicle\} \{Time \d+\.\d{2}\} \{FrontSteer -?0\.0\d{3}\} "
        r"\{RearSteer 0\.0000\} \{LightToggle False\} \{LightIntensity 0\} \{Battery \d+\} "
        r"\{View -1\}",
        sta,
    ), sta
    c.send("DRIVE {Speed 5} {FrontSteer 0.3}")  # no RearSteer: it keeps its value
    c.step(2.0)
    speed, rate, sta, _ = motion(c, 1.0)
    # bicycle model: yaw rate = v tan(delta) / wheel base, to the right (clockwise: yaw grows)
    assert rate == pytest.approx(1.5 * math.tan(0.3) / 2.6, rel=0.1)
    assert float(segments(sta)["FrontSteer"]) == pytest.approx(0.3, abs=0.01)
    c.send("DRIVE {FrontSteer -2.0}")  # beyond MaxFrontSteer: limited to -0.6; speed kept
    c.step(1.5)
    speed, rate, sta, _ = motion(c, 0.5)
    assert float(segments(sta)["FrontSteer"]) == pytest.approx(-0.6, abs=0.02)
    assert rate < -0.2 and speed == pytest.approx(1.5, rel=0.1)
    c.send("DRIVE {Speed 0}")
    c.step(2.0)
    speed, _, _, _ = motion(c, 1.0)
    assert speed < 0.02
    c.send("DRIVE {Speed 25} {FrontSteer 0} {Normalized True}")  # 25 % of 40 rad/s
    c.step(3.0)
    speed, _, _, _ = motion(c, 0.5)
    assert speed == pytest.approx(0.3 * 10, rel=0.05)


def test_holonomic_wheel_groups(server_factory, test_world, robots_dir):
    c = spawn(server_factory, test_world, robots_dir, "TestOmni", -6.0, -6.0, 0.0)
    c.send("DRIVE {WheelNumber 0} {WheelSpeed 5} {WheelSteer 0} {WheelNumber 1} {WheelSpeed 5} {WheelSteer 0}")
    c.step(1.0)
    speed, rate, _, (p0, p1) = motion(c, 1.0)
    assert speed == pytest.approx(0.08 * 5, rel=0.05) and p1[0] > p0[0] and abs(rate) < 0.02  # forward
    c.send("DRIVE {WheelNumber 0} {WheelSteer 1.5708} {WheelNumber 1} {WheelSteer 1.5708}")  # speeds kept
    c.step(1.0)
    speed, rate, _, (p0, p1) = motion(c, 1.0)
    assert speed == pytest.approx(0.4, rel=0.05) and p1[1] - p0[1] > 0.35 and abs(rate) < 0.05  # sideways, right
    c.send("DRIVE {WheelNumber 0} {WheelSpeed 5} {WheelSteer 0} {WheelNumber 1} {WheelSpeed -5} {WheelSteer 0}")
    c.step(1.0)
    _, rate, _, _ = motion(c, 1.0)
    assert rate == pytest.approx(0.4 / 0.2, rel=0.1)  # turning on the spot, to the right


def test_aerial_drive_hovers_climbs_flies_and_turns(server_factory, test_world):
    srv = server_factory(world=test_world, seed=3)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.AirRobot} {Name Air} {Location -6,0,-1.0} {Rotation 0,0,0}")
    lines = c.step(1.0)
    sta = [ln.text for ln in lines if ln.text.startswith("STA")][-1]
    assert re.fullmatch(
        r"STA \{Type AerialVehicle\} \{Time \d+\.\d{2}\} \{LightToggle False\} \{LightIntensity 0\} "
        r"\{Battery \d+\} \{View 0\}",
        sta,
    ), sta
    gts = ground_truth(lines)
    assert gts[-1][1][2] == pytest.approx(-1.0, abs=0.01)  # it hovers where it was put
    c.send("DRIVE {AltitudeVelocity 0.5}")
    c.step(1.0)
    lines = c.step(1.0)
    (_, p0, _), (_, p1, _) = ground_truth(lines)[0], ground_truth(lines)[-1]
    assert (p0[2] - p1[2]) == pytest.approx(0.5 * 0.9, rel=0.05)  # up is -Z
    c.send("DRIVE {AltitudeVelocity 0} {LinearVelocity 1.0}")  # the others keep their value
    c.step(1.0)
    speed, rate, _, (p0, p1) = motion(c, 1.0)
    assert speed == pytest.approx(1.0, rel=0.05) and p1[0] > p0[0] and abs(rate) < 0.01
    c.send("DRIVE {LinearVelocity 0} {RotationalVelocity 50} {Normalized True}")  # 50 % of 100 deg/s
    c.step(1.0)
    speed, rate, _, _ = motion(c, 1.0)
    assert rate == pytest.approx(0.5 * 1.7453, rel=0.05) and speed < 0.05  # clockwise: yaw grows
    c.send("DRIVE {RotationalVelocity 0}")
    c.step(1.0)
    speed, rate, _, _ = motion(c, 1.0)
    assert speed < 0.01 and abs(rate) < 0.01  # hovering again


POOL = """\
name: Pool
description: a 5 m deep pool (tests only)
floor: {center: [0, 0], size: [60, 60]}
water:
  - {name: pool, center: [0.0, 0.0, -2.5], size: [50.0, 50.0, 5.0]}
start_poses:
  - {name: Deep, location: [-15.0, 0.0, -2.0], rotation: [0, 0, 0]}
  - {name: Edge, location: [0.0, 28.0, -0.5], rotation: [0, 0, -1.5708]}
"""


def test_a_submarine_floats_drives_turns_and_dives(server_factory, tmp_path):
    from usarsim.config.world_file import load_world

    (tmp_path / "Pool.yaml").write_text(POOL)
    srv = server_factory(world=load_world(tmp_path / "Pool.yaml"), seed=3)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.Submarine} {Name Sub} {Start Deep}")
    lines = c.step(2.0)
    sta = [ln.text for ln in lines if ln.text.startswith("STA")][-1]
    assert sta.startswith("STA {Type NauticalVehicle} {Time ")
    gts = ground_truth(lines)
    assert abs(gts[-1][1][2] - gts[0][1][2]) < 0.2  # neutral within 1 %: it neither sinks nor shoots up
    c.send("DRIVE {Propeller 1} {Rudder 0} {SternPlane 0}")
    c.step(5.0)
    speed, rate, _, (p0, p1) = motion(c, 1.0)
    assert speed == pytest.approx(60.0 / 40.0, rel=0.05) and p1[0] > p0[0] and abs(rate) < 0.01  # thrust / drag
    c.send("DRIVE {Rudder 0.3}")  # propeller kept: turns right
    c.step(1.0)
    _, rate, _, _ = motion(c, 1.0)
    assert rate > 0.2
    c.send("DRIVE {Rudder 0} {SternPlane -0.3}")  # planes down: it dives (Z grows towards the floor)
    c.step(1.0)
    _, _, _, (p0, p1) = motion(c, 1.0)
    assert p1[2] - p0[2] > 0.3


def test_a_land_robot_loses_its_battery_in_water(server_factory, tmp_path):
    from usarsim.config.world_file import load_world

    (tmp_path / "Pool.yaml").write_text(POOL)
    srv = server_factory(world=load_world(tmp_path / "Pool.yaml"), seed=3)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name Diver} {Location -20,0,-6} {Rotation 0,0,0}")  # above the pool
    lines = c.step(3.0)
    sta = [segments(ln.text) for ln in lines if ln.text.startswith("STA")]
    assert sta[0]["Battery"] != "0" and sta[-1]["Battery"] == "0"
    assert not [ln for ln in c.step(1.0) if ln.text.startswith(("SEN", "MISSTA"))]


def _legged(server_factory, test_world, init: str, height: float):
    """A server and a client whose legged robot (``init``) stands on its feet, its chassis
    at ``height``, a second after its INIT."""
    srv = server_factory(world=test_world, seed=3)
    c = srv.connect()
    c.nfo()
    c.send(init)
    lines = c.step(1.0)
    sta = [ln.text for ln in lines if ln.text.startswith("STA")][-1]
    assert sta.startswith("STA {Type LeggedRobot} {Time ")
    assert ground_truth(lines)[-1][1][2] == pytest.approx(height, abs=0.01)
    return srv, c


def _joint_angle(srv, joint: str) -> float:
    return srv.on_sim(lambda sim: float(sim.data.qpos[sim.robots[1].handle.joint_qpos[joint]]))


def test_the_robot_dog_stands_trots_turns_and_takes_joint_commands(server_factory, test_world):
    # standing on its legs
    srv, c = _legged(
        server_factory,
        test_world,
        "INIT {ClassName USARBot.ERS} {Name Dog} {Location -6,0,-0.3} {Rotation 0,0,0}",
        -0.157,
    )
    c.send("DRIVE {LinearVelocity 0.1}")
    c.step(2.0)
    speed, rate, _, (p0, p1) = motion(c, 2.0)
    assert speed == pytest.approx(0.1, rel=0.15) and p1[0] > p0[0] and abs(rate) < 0.05
    c.send("DRIVE {LinearVelocity 0} {RotationalVelocity -0.4}")  # turn left on the spot
    c.step(1.0)
    _, rate, _, _ = motion(c, 2.0)
    assert rate == pytest.approx(-0.4, rel=0.2)
    c.send("DRIVE {RotationalVelocity 0}")
    c.step(1.0)
    # standing still, its joints obey joint commands: lift the left front paw
    c.send("MULTIDRIVE {LF_J1 1.2}")
    c.step(1.0)
    assert _joint_angle(srv, "LF_J1") == pytest.approx(1.2, abs=0.05)


def test_the_humanoid_stands_walks_turns_side_steps_and_takes_joint_commands(server_factory, test_world):
    # a start pose 1 m up: a walking robot is set down on its feet (trunk 0.36 m up), not dropped
    srv, c = _legged(
        server_factory,
        test_world,
        "INIT {ClassName USARBot.QRIO} {Name Q} {Location -6,0,-1.0} {Rotation 0,0,0}",
        -0.365,
    )
    c.send("DRIVE {LinearVelocity 0.1}")
    c.step(3.0)
    speed, rate, _, (p0, p1) = motion(c, 4.0)
    assert speed == pytest.approx(0.1, rel=0.15) and p1[0] > p0[0] and abs(rate) < 0.05
    c.send("DRIVE {LinearVelocity 0} {RotationalVelocity -0.4}")  # turn left on the spot
    c.step(2.0)
    speed, rate, _, _ = motion(c, 4.0)
    assert rate == pytest.approx(-0.4, rel=0.15) and speed < 0.02
    c.send("DRIVE {RotationalVelocity 0} {LateralVelocity 0.02}")  # step to the right
    c.step(2.0)
    t0, q0, o0 = ground_truth(c.step(0.2))[-1]
    t1, q1, _ = ground_truth(c.step(4.0))[-1]  # two whole periods: the sway cancels out
    right = ((q1[0] - q0[0]) * -math.sin(o0[2]) + (q1[1] - q0[1]) * math.cos(o0[2])) / (t1 - t0)
    assert right == pytest.approx(0.02, rel=0.15)
    c.send("DRIVE {LateralVelocity 0}")
    lines = c.step(4.0)
    _, p, o = ground_truth(lines)[-1]
    assert abs(o[0]) < 0.05 and abs(o[1]) < 0.05 and p[2] == pytest.approx(-0.365, abs=0.01)  # upright
    # at rest, its joints obey joint commands: turn the left foot out
    c.send("MULTIDRIVE {LHipYaw -0.3}")
    c.step(1.0)
    assert _joint_angle(srv, "LHipYaw") == pytest.approx(-0.3, abs=0.03)


def test_the_humanoid_keeps_its_feet_under_changing_commands(test_world):
    """Commands that change mid-step (speed, side step, turn, stop, in any mix) never
    topple the walking humanoid: the speed follows the command over half a period and
    each foot stays where it was put until it swings."""
    import random

    from usarsim.config.catalog import resolve_robot
    from usarsim.sim.simulation import Simulation

    robot = resolve_robot("QRIO")
    sim = Simulation(test_world, seed=0)
    sim.spawn(1, robot, "Q", (-6.0, 0.0, -0.4), (0.0, 0.0, 0.0))
    rng = random.Random(7)
    worst = 0.0
    for _ in range(12):
        drive_velocities(
            sim,
            1,
            None,
            rng.uniform(-0.1, 0.1),
            rng.choice([0.0, rng.uniform(-0.02, 0.02)]),
            rng.choice([0.0, rng.uniform(-0.4, 0.4)]),
        )
        for _ in range(rng.choice([2, 7, 15])):
            sim.advance(0.2)
            _, (roll, pitch, _) = sim.pose_of(1)
            worst = max(worst, abs(math.remainder(roll, 2 * math.pi)), abs(math.remainder(pitch, 2 * math.pi)))
    assert worst < 0.15 and sim.resets == 0
