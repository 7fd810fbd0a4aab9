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
        c.send(
            f"INIT {{ClassName USARBot.P2AT}} {{Name R1}} {{Location {p.location[0]},{p.location[1]},{z}}} "
            f"{{Rotation {rotation}}}"
        )
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


def test_a_robot_removed_while_being_righted_is_forgotten_and_the_other_is_righted(server):
    from usarsim.sim.systems.righting import Righting

    first = spawn(server, rotation="3.1416,0,0", z=-0.5)
    p = server.app.world.start_pose("PlayerStart2")
    second = server.connect()
    second.nfo()
    second.send(
        f"INIT {{ClassName USARBot.P2AT}} {{Name R2}} {{Location {p.location[0]},{p.location[1]},-0.5}} "
        "{Rotation 3.1416,0,0}"
    )
    second.step(2.0)

    def righting():
        return server.on_sim(
            lambda sim: sorted(uid for s in sim.systems if isinstance(s, Righting) for uid in s.righting)
        )

    def up(uid):
        return server.on_sim(lambda sim: float(sim.data.xmat[sim.robots[uid].handle.body_id][8]))

    first.send("DRIVE {Flip True}")
    second.send("DRIVE {Flip True}")
    second.step(0.2)
    assert righting() == [1, 2]
    first.close()  # removed half way over
    for _ in range(50):
        if server.on_sim(lambda sim: len(sim.robots)) == 1:
            break
        second.step(0.05)
    second.step(4.0)
    assert up(2) > 0.95 and righting() == []


TEST_GRIPPER = """\
class_name: TestGripper
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
     shapes: [{center: [0.0, 0.0, 0.0], size: [0.1, 0.01, 0.08], mass_kg: 0.1, friction: 2.0}]}
  - {name: RightFinger, parent: Lift, location: [0.15, 0.06, 0.08], joint: prismatic, axis: [0, 1, 0], min_range: -0.05,
     max_range: 0.05, max_speed: 0.1, max_torque: 30.0, armature: 0.2,
     shapes: [{center: [0.0, 0.0, 0.0], size: [0.1, 0.01, 0.08], mass_kg: 0.1, friction: 2.0}]}
mission_packages:
  - {name: Lifter, links: [Lift]}
sensors:
  - {type: Gripper, name: Gripper1, fingers: [LeftFinger, RightFinger], open_value: 0.02, closed_value: -0.04}
  - {type: GroundTruth, name: GroundTruth}
"""
GRIP_WORLD = """\
name: GripArena
description: a brick in front of a robot with a gripper (tests only)
floor: {center: [0, 0], size: [10, 10]}
materials: {brick: {rgba: [0.8, 0.3, 0.2, 1], friction: 1.0}}
objects:
  - {name: brick, shape: box, center: [0.48, 0.0, -0.03], size: [0.1, 0.06, 0.06], mass_kg: 0.2, material: brick}
start_poses:
  - {name: Here, location: [0.0, 0.0, -0.2], rotation: [0, 0, 0]}
"""


def test_the_gripper_grasps_and_lifts_a_brick(server_factory, tmp_path):
    import re

    from usarsim.config.world_file import load_world

    (tmp_path / "robots").mkdir()
    (tmp_path / "robots" / "TestGripper.yaml").write_text(TEST_GRIPPER)
    (tmp_path / "GripArena.yaml").write_text(GRIP_WORLD)
    srv = server_factory(world=load_world(tmp_path / "GripArena.yaml"), robot_dirs=(str(tmp_path / "robots"),))
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.TestGripper} {Name R1} {Location 0,0,-0.15} {Rotation 0,0,0}")
    c.step(2.0)

    def brick_z():
        return srv.on_sim(lambda sim: float(sim.data.xpos[sim.model.body("movable/brick").id][2]))

    def set_and_step(line, seconds):
        c.send(line)
        return [ln.text for ln in c.step(seconds) if ln.text.startswith(("RES", "EFF"))]

    got = set_and_step("SET {Type Gripper} {Name Gripper1} {Opcode Open}", 1.0)
    assert re.fullmatch(r"RES \{Time \d+\.\d{2}\} \{Type Gripper\} \{Name Gripper1\} \{Status OK\}", got[0]), got
    assert re.fullmatch(r"EFF \{Time \d+\.\d+\} \{Type Gripper\} \{Name Gripper1\} \{Status OPEN\}", got[1]), got
    z0 = brick_z()
    got = set_and_step("SET {Type Gripper} {Name Gripper1} {Opcode Close}", 1.5)
    assert got[1].endswith("{Status CLOSED}")
    c.send("MISPKG {Name Lifter} {Link 1} {Value 0.15}")
    c.step(2.5)
    assert brick_z() - z0 > 0.10  # lifted by more than 10 cm
    c.step(1.0)
    assert brick_z() - z0 > 0.10  # and held
    got = set_and_step("SET {Type Gripper} {Name Gripper1} {Opcode Grip} {Params 0}", 1.5)  # Grip 0 opens
    assert got[1].endswith("{Status OPEN}")
    assert brick_z() - z0 < 0.02  # dropped back onto the floor
    assert set_and_step("SET {Type Gripper} {Name Gripper1} {Opcode Squeeze}", 0.1)[0].endswith("{Status Failed}")
    assert c.ask("GETCONF {Type Gripper}", "CONF").text == "CONF {Type Gripper} {Name Gripper1}"


TEST_ROLLER = """\
class_name: TestRoller
description: a small robot with a roller table on its back (tests only)
vehicle_type: GroundVehicle
steering_type: SkidSteered
drive: skid
mass_kg: 12.5
max_speed_rad_s: 5.0
max_torque_nm: 60.0
wheel_torque_nm: 6.0
geometry: {dimensions: [0.6, 0.4, 0.3], wheel_radius: 0.1, wheel_separation: 0.4, wheel_base: 0.3}
chassis:
  - {center: [0.0, 0.0, 0.0], size: [0.5, 0.3, 0.15], mass_kg: 10.0}
  - {center: [0.0, 0.0, -0.085], size: [0.6, 0.3, 0.02], mass_kg: 0.5}
wheels:
  - {name: LF, position: [0.15, -0.2, 0.05], radius_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: left}
  - {name: RF, position: [0.15, 0.2, 0.05], radius_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: right}
  - {name: LR, position: [-0.15, -0.2, 0.05], radius_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: left}
  - {name: RR, position: [-0.15, 0.2, 0.05], radius_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: right}
sensors:
  - {type: RollerTable, name: Roller, surface: 1}
  - {type: GroundTruth, name: GroundTruth}
"""
ROLLER_WORLD = """\
name: RollerArena
description: a box on a robot's roller table (tests only)
floor: {center: [0, 0], size: [10, 10]}
objects:
  - {name: parcel, shape: box, center: [-0.1, 0.0, -0.35], size: [0.12, 0.12, 0.1], mass_kg: 0.5}
start_poses:
  - {name: Here, location: [0.0, 0.0, -0.2], rotation: [0, 0, 0]}
"""


def test_the_roller_table_carries_its_load_off_the_front(server_factory, tmp_path):
    from usarsim.config.world_file import load_world

    (tmp_path / "robots").mkdir()
    (tmp_path / "robots" / "TestRoller.yaml").write_text(TEST_ROLLER)
    (tmp_path / "RollerArena.yaml").write_text(ROLLER_WORLD)
    srv = server_factory(world=load_world(tmp_path / "RollerArena.yaml"), robot_dirs=(str(tmp_path / "robots"),))
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.TestRoller} {Name R1} {Location 0,0,-0.2} {Rotation 0,0,0}")
    c.step(1.5)

    def parcel():
        return srv.on_sim(lambda sim: tuple(float(v) for v in sim.data.xpos[sim.model.body("movable/parcel").id]))

    x0, _, z0 = parcel()
    assert z0 > 0.25  # it lies on the table, 0.3 m up (MuJoCo z is up)
    c.step(1.0)
    assert abs(parcel()[0] - x0) < 0.01  # rollers still: it stays
    c.send("SET {Type RollerTable} {Name Roller} {Opcode Roll} {Params 0.2}")
    res = [ln.text for ln in c.step(1.0) if ln.text.startswith("RES")]
    assert res and res[0].endswith("{Type RollerTable} {Name Roller} {Status OK}")
    x1, _, _ = parcel()
    assert x1 - x0 == pytest.approx(0.2 * 1.0, abs=0.06)  # carried forward at the rollers' speed
    c.step(2.0)
    assert parcel()[2] < 0.1  # off the front, on the floor
    c.send("SET {Type RollerTable} {Name Roller} {Opcode Stop}")
    assert [ln.text for ln in c.step(0.1) if ln.text.startswith("RES")][0].endswith("{Status OK}")
