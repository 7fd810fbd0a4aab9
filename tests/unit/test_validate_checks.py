"""What ``usarsim validate`` catches beyond a key's type and range: a misspelt key named with
the closest valid one, errors deep in a list naming the object, a Gripper's fingers and a
RollerTable's surface checked against the robot, a robot file's class_name against its file
name, and start poses inside solids (WorldConfig.solid_at)."""

from __future__ import annotations

import math

import pytest
import yaml

from usarsim.cli import check_robot_items
from usarsim.cli import main as cli_main
from usarsim.config.catalog import resolve_robot, robot_files, world_files
from usarsim.config.robot import class_name_problem, load_robot
from usarsim.config.world_file import check_world_file, load_world
from usarsim.errors import ConfigError

WORLD = """\
name: Checks
floor: {center: [0.0, 0.0], size: [20.0, 20.0]}
objects:
  - {name: wall_north, shape: box, center: [5.0, 0.0, -0.5], size: [0.2, 8.0, 1.0]}
  - {name: skew, shape: box, center: [0.0, 5.0, -0.5], size: [4.0, 0.2, 1.0], rotation: [0, 0, 0.7853981634]}
  - {name: post, shape: cylinder, center: [-5.0, 0.0, -1.0], radius: 0.3, length: 2.0}
  - {name: log, shape: cylinder, center: [-5.0, 5.0, -0.2], radius: 0.2, length: 3.0, rotation: [1.5707963268, 0, 0]}
  - {name: platform, shape: box, center: [5.0, 5.0, -0.25], size: [2.0, 2.0, 0.5]}
  - {name: brick, shape: box, center: [0.0, -5.0, -0.05], size: [0.3, 0.2, 0.1], mass_kg: 1.0}
  - {name: r1, shape: ramp, foot: [-5.0, -5.0, 0.0], length: 2.0, width: 1.0, rise: 0.4}
  - {name: st, shape: stairs, foot: [0.0, -8.0, 0.0], width: 1.0, steps: 3, step_rise: 0.2, step_run: 0.3}
false_alarms:
  - {name: doll, center: [8.0, -8.0, -0.2], size: [0.4, 0.4, 0.4]}
start_poses:
  - {name: Start1, location: [0.0, 0.0, -0.2]}
"""

ROBOT = """\
class_name: Checker
vehicle_type: GroundVehicle
steering_type: SkidSteered
drive: skid
mass_kg: 12.9
max_speed_rad_s: 5.0
max_torque_nm: 60.0
geometry: {dimensions: [0.6, 0.4, 0.3]}
chassis:
  - {center: [0.0, 0.0, 0.0], size: [0.5, 0.3, 0.15], mass_kg: 10.0}
  - {center: [0.0, 0.0, -0.085], size: [0.6, 0.3, 0.02], mass_kg: 0.5}
wheels:
  - {name: LF, position: [0.15, -0.2, 0.05], radius_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: left}
  - {name: RF, position: [0.15, 0.2, 0.05], radius_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: right}
  - {name: LR, position: [-0.15, -0.2, 0.05], radius_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: left}
  - {name: RR, position: [-0.15, 0.2, 0.05], radius_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: right}
links:
  - {name: Lift, location: [0.33, 0.0, 0.0], joint: prismatic, axis: [0, 0, -1], min_range: 0.0, max_range: 0.2,
     max_speed: 0.1, max_torque: 100.0, shapes: [{center: [-0.05, 0.0, 0.0], size: [0.04, 0.2, 0.04], mass_kg: 0.2}]}
  - {name: LeftFinger, parent: Lift, location: [0.15, -0.06, 0.08], joint: prismatic, axis: [0, -1, 0],
     min_range: -0.05, max_range: 0.05, max_speed: 0.1, max_torque: 30.0,
     shapes: [{center: [0.0, 0.0, 0.0], size: [0.1, 0.01, 0.08], mass_kg: 0.1}]}
  - {name: RightFinger, parent: Lift, location: [0.15, 0.06, 0.08], joint: prismatic, axis: [0, 1, 0],
     min_range: -0.05, max_range: 0.05, max_speed: 0.1, max_torque: 30.0,
     shapes: [{center: [0.0, 0.0, 0.0], size: [0.1, 0.01, 0.08], mass_kg: 0.1}]}
sensors:
  - {type: GroundTruth, name: GroundTruth}
  - {type: Sonar, name: F1, location: [0.25, 0.0, 0.0]}
  - {type: Gripper, name: Gripper1, fingers: [LeftFinger, RightFinger]}
  - {type: RollerTable, name: Roller, surface: 1}
"""


def write(tmp_path, text: str, name: str) -> str:
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def validate(path: str, capsys) -> tuple[int, str]:
    code = cli_main(["validate", path])
    out, err = capsys.readouterr()
    return code, out + err


def world_error(tmp_path, text: str) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        check_world_file(write(tmp_path, text, "Checks.yaml"))
    return info.value


# --------------------------------------------------------------------------- misspelt keys


def test_a_misspelt_required_key_names_the_key_found_and_the_closest_valid_one(tmp_path):
    err = world_error(tmp_path, WORLD.replace("center: [5.0, 0.0, -0.5]", "centre: [5.0, 0.0, -0.5]"))
    assert err.key == "objects[0].centre"
    assert "unknown key 'centre' (did you mean 'center'?)" in str(err)
    assert "required key is missing" not in str(err)


@pytest.mark.parametrize(
    "old, new, key, word",
    [
        ("floor: {center", "flor: {center", "flor", "floor"),  # top level
        ("size: [0.2, 8.0, 1.0]", "sise: [0.2, 8.0, 1.0]", "objects[0].sise", "size"),
        ("{name: Start1, location:", "{name: Start1, locaton:", "start_poses[0].locaton", "location"),
        ("{name: doll,", "{nmae: doll,", "false_alarms[0].nmae", "name"),
    ],
)
def test_every_world_section_names_a_misspelt_required_key(tmp_path, old, new, key, word):
    err = world_error(tmp_path, WORLD.replace(old, new))
    assert err.key == key
    assert f"unknown key '{key.rsplit('.', 1)[-1]}' (did you mean '{word}'?)" in str(err)


def test_a_misspelt_required_key_of_a_robot_file(tmp_path):
    p = write(
        tmp_path,
        ROBOT.replace(
            "radius_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: right}\n  - {name: LR",
            "raduis_m: 0.1, width_m: 0.04, mass_kg: 0.5, side: right}\n  - {name: LR",
        ),
        "Checker.yaml",
    )
    with pytest.raises(ConfigError) as info:
        load_robot(p)
    assert info.value.key == "wheels[1].raduis_m"
    assert "did you mean 'radius_m'?" in str(info.value) and "wheels[1] is wheel 'RF'" in str(info.value)


def test_a_valid_key_read_later_is_not_taken_for_a_misspelling(tmp_path):
    # step_run is a key of stairs of its own, close to step_rise: the missing one is reported
    err = world_error(tmp_path, WORLD.replace("step_rise: 0.2, ", ""))
    assert err.key == "objects[7].step_rise" and "required key is missing" in str(err)


# --------------------------------------------------------------------------- errors name the entry


def test_an_error_deep_in_the_objects_names_the_object(tmp_path):
    err = world_error(tmp_path, WORLD.replace("size: [2.0, 2.0, 0.5]}", "size: [2.0, 2.0, 0.5], colour: red}"))
    assert err.key == "objects[4].colour"
    assert "(objects[4] is box 'platform')" in str(err)


def test_an_error_about_an_unnamed_entry_names_its_kind(tmp_path):
    p = write(
        tmp_path,
        ROBOT.replace("size: [0.6, 0.3, 0.02], mass_kg: 0.5}", "size: [0.6, 0.3, 0], mass_kg: 0.5}"),
        "Checker.yaml",
    )
    with pytest.raises(ConfigError) as info:
        load_robot(p)
    assert info.value.key == "chassis[1].size"
    assert "(chassis[1] is a box)" in str(info.value)


def test_nested_entries_are_all_named(tmp_path):
    p = write(
        tmp_path,
        ROBOT.replace(
            "size: [0.1, 0.01, 0.08], mass_kg: 0.1}]}\n  - {name: RightFinger",
            "size: [0.1, 0.01, 0.08], mass_kg: -1}]}\n  - {name: RightFinger",
        ),
        "Checker.yaml",
    )
    with pytest.raises(ConfigError) as info:
        load_robot(p)
    assert info.value.key == "links[1].shapes[0].mass_kg"
    assert "(links[1] is link 'LeftFinger'; links[1].shapes[0] is a box)" in str(info.value)


def test_a_sensor_setting_error_names_the_sensor(tmp_path, capsys):
    p = write(tmp_path, ROBOT.replace("{type: Sonar, name: F1,", "{type: Sonar, name: F1, MaxRang: 3,"), "Checker.yaml")
    code, text = validate(p, capsys)
    assert code == 1
    assert "sensors[1].MaxRang: unknown Sonar setting 'MaxRang'" in text and "(sensors[1] is Sonar 'F1')" in text


def test_an_error_about_the_sensor_itself_names_it_after_its_index(tmp_path, capsys):
    p = write(tmp_path, ROBOT.replace("fingers: [LeftFinger, RightFinger]", "fingers: []"), "Checker.yaml")
    code, text = validate(p, capsys)
    assert code == 1
    assert "sensors[2] (Gripper 'Gripper1'): invalid Gripper settings" in text


def test_an_unknown_sensor_type_names_the_file_and_the_entry(tmp_path, capsys):
    p = write(tmp_path, ROBOT.replace("{type: Sonar,", "{type: Sonr,"), "Checker.yaml")
    code, text = validate(p, capsys)
    assert code == 1
    assert f"{p}: sensors[1].type: unknown sensor type 'Sonr'" in text and "did you mean 'Sonar'" in text


# --------------------------------------------------------------------------- effecters against the robot


def test_the_checker_robot_itself_validates(tmp_path, capsys):
    code, text = validate(write(tmp_path, ROBOT, "Checker.yaml"), capsys)
    assert code == 0, text
    assert text.startswith("ok: robot Checker: ")


def test_a_gripper_finger_must_be_a_link_of_the_robot(tmp_path, capsys):
    p = write(
        tmp_path,
        ROBOT.replace("fingers: [LeftFinger, RightFinger]", "fingers: [LeftFinger, RightFingr]"),
        "Checker.yaml",
    )
    load_robot(p)  # the file itself reads
    code, text = validate(p, capsys)
    assert code == 1
    assert "sensors[2].fingers: unknown finger link 'RightFingr'" in text and "did you mean 'RightFinger'" in text
    assert "(sensors[2] is Gripper 'Gripper1')" in text


def test_a_gripper_on_a_robot_without_links(tmp_path):
    data = yaml.safe_load(ROBOT)
    del data["links"]
    data["mass_kg"] = 12.5
    data["sensors"] = [{"type": "Gripper", "name": "G", "Fingers": ["Jaw"]}]  # the setting's ini name
    p = write(tmp_path, yaml.safe_dump(data, sort_keys=False), "Checker.yaml")
    with pytest.raises(ConfigError) as info:
        check_robot_items(load_robot(p))
    assert info.value.key == "sensors[0].Fingers"
    assert "unknown finger link 'Jaw'" in str(info.value) and "this robot has no links" in str(info.value)


@pytest.mark.parametrize("surface, ok", [(0, True), (1, True), (2, False), (7, False)])
def test_a_roller_table_surface_must_be_a_chassis_piece(tmp_path, capsys, surface, ok):
    p = write(tmp_path, ROBOT.replace("surface: 1}", f"surface: {surface}}}"), "Checker.yaml")
    code, text = validate(p, capsys)
    assert (code == 0) == ok, text
    if not ok:
        assert f"sensors[3].surface: surface {surface} is out of range" in text
        assert "this robot has 2 (chassis[0] to chassis[1])" in text and "RollerTable 'Roller'" in text


# --------------------------------------------------------------------------- class_name and file name


def test_validate_refuses_a_class_name_other_than_the_file_name(tmp_path, capsys):
    p = write(tmp_path, ROBOT, "Checkr.yaml")
    code, text = validate(p, capsys)
    assert code == 1
    assert f"{p}: class_name: class_name is 'Checker' but the file is Checkr.yaml" in text
    assert class_name_problem(load_robot(p)) is not None
    assert class_name_problem(load_robot(write(tmp_path, ROBOT, "Checker.yaml"))) is None


def test_a_robot_class_asked_for_by_name_must_declare_that_name(tmp_path):
    (tmp_path / "robots").mkdir()
    write(tmp_path / "robots", ROBOT.replace("class_name: Checker", "class_name: Other"), "Checker.yaml")
    with pytest.raises(ConfigError) as info:
        resolve_robot("Checker", extra_dirs=(str(tmp_path / "robots"),))
    assert info.value.key == "class_name" and "'Other'" in str(info.value)
    (tmp_path / "robots2").mkdir()
    write(tmp_path / "robots2", ROBOT, "Checker.yaml")
    assert resolve_robot("USARBot.Checker", extra_dirs=(str(tmp_path / "robots2"),)).class_name == "Checker"


# --------------------------------------------------------------------------- solids


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    return load_world(write(tmp_path_factory.mktemp("solids"), WORLD, "Checks.yaml"))


@pytest.mark.parametrize(
    "point, solid",
    [
        ((0.0, 0.0, -0.2), None),
        ((5.0, 0.0, -0.5), "box 'wall_north'"),
        ((5.08, 3.9, -0.02), "box 'wall_north'"),  # 2 cm from three faces: inside
        ((5.095, 0.0, -0.5), None),  # 5 mm from its face: on it, not in it
        ((5.0, 4.5, -0.5), None),  # past its end
        ((0.0, 0.0, 0.02), "the floor"),  # below the floor's top surface
        ((0.0, 0.0, 0.005), None),  # resting on the floor
        ((5.0, 5.0, -0.505), None),  # resting on the platform
        ((5.0, 5.0, -0.47), "box 'platform'"),
        # the skewed wall runs from (-1.41, 3.59) to (1.41, 6.41): inside it only turned
        ((1.0, 6.0, -0.5), "box 'skew'"),
        ((1.5, 5.0, -0.5), None),  # inside its unturned extents, outside the turned wall
        ((-5.0, 0.25, -1.9), "cylinder 'post'"),
        ((-5.0, 0.35, -1.0), None),
        ((-5.0, 0.0, -2.05), None),  # above its top
        ((-5.0, 6.4, -0.2), "cylinder 'log'"),  # lying along Y (rolled a quarter turn)
        ((-4.7, 5.0, -0.2), None),  # beside it
        ((0.0, -5.0, -0.05), "box 'brick' (movable)"),
        ((-3.5, -5.0, -0.275), "ramp 'r1'"),  # 2.5 cm under its top face (z = -0.3 there), in the plate
        ((-3.5, -5.0, -0.5), None),  # above it
        ((0.75, -8.0, -0.55), "stairs 'st' (step 3)"),
        ((0.75, -8.0, -0.65), None),  # above the top step
        ((8.0, -8.0, -0.2), "false alarm 'doll'"),
    ],
)
def test_solid_at_finds_the_solid_a_point_lies_in(world, point, solid):
    assert world.solid_at(point) == solid


def test_solid_at_skips_movable_objects_when_asked(world):
    assert world.solid_at((0.0, -5.0, -0.05), movable=False) is None
    assert world.solid_at((5.0, 0.0, -0.5), movable=False) == "box 'wall_north'"


def test_solid_at_margin(world):
    point = (5.095, 0.0, -0.5)  # 5 mm inside the wall's face
    assert world.solid_at(point) is None
    assert world.solid_at(point, margin_m=0.001) == "box 'wall_north'"


CUBE_OBJ = """\
v -0.5 -0.5 -0.5
v 0.5 -0.5 -0.5
v 0.5 0.5 -0.5
v -0.5 0.5 -0.5
v -0.5 -0.5 0.5
v 0.5 -0.5 0.5
v 0.5 0.5 0.5
v -0.5 0.5 0.5
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
"""


@pytest.mark.parametrize(
    "scale, rotation, point, inside",
    [
        ((1, 1, 1), (0, 0, 0), (0.0, 0.0, -0.5), True),
        ((1, 1, 1), (0, 0, 0), (0.45, 0.45, -0.05), True),
        ((1, 1, 1), (0, 0, 0), (0.6, 0.0, -0.5), False),
        ((1, 1, 1), (0, 0, 0), (0.0, 0.0, -1.005), False),  # resting on its top
        ((2, 1, 1), (0, 0, 0), (0.9, 0.0, -0.5), True),  # scaled along X
        ((2, 1, 1), (0, 0, math.pi / 2), (0.9, 0.0, -0.5), False),  # ... then turned to lie along Y
        ((2, 1, 1), (0, 0, math.pi / 2), (0.0, 0.9, -0.5), True),
    ],
)
def test_solid_at_finds_points_inside_a_mesh(tmp_path, scale, rotation, point, inside):
    (tmp_path / "cube.obj").write_text(CUBE_OBJ)
    text = (
        "name: M\nfloor: {center: [0, 0], size: [10, 10]}\nobjects:\n"
        f"  - {{name: m, shape: mesh, file: cube.obj, center: [0, 0, -0.5], scale: {list(scale)}, "
        f"rotation: {list(rotation)}}}\n"
        "start_poses:\n  - {name: S, location: [3, 0, -0.2]}\n"
    )
    w = load_world(write(tmp_path, text, "M.yaml"))
    assert w.solid_at(point) == ("mesh 'm'" if inside else None)


def test_validate_refuses_a_start_pose_inside_a_wall(tmp_path, capsys):
    text = WORLD.replace(
        "{name: Start1, location: [0.0, 0.0, -0.2]}",
        "{name: Start1, location: [0.0, 0.0, -0.2]}\n  - {name: InWall, location: [5.0, 1.0, -0.2]}",
    )
    code, out = validate(write(tmp_path, text, "Checks.yaml"), capsys)
    assert code == 1
    assert "start_poses[1].location: start pose 'InWall' at [5, 1, -0.2] lies inside box 'wall_north'" in out
    code, out = validate(write(tmp_path, WORLD, "Checks.yaml"), capsys)
    assert code == 0, out


# --------------------------------------------------------------------------- the shipped files pass


@pytest.mark.parametrize("name", sorted(world_files()))
def test_no_shipped_start_pose_lies_inside_a_solid(name):
    w = load_world(world_files()[name])
    assert [(p.name, w.solid_at(p.location)) for p in w.start_poses if w.solid_at(p.location)] == []


@pytest.mark.parametrize("name", sorted(robot_files()))
def test_every_shipped_robot_passes_the_item_and_name_checks(name):
    r = load_robot(robot_files()[name])
    assert class_name_problem(r) is None
    check_robot_items(r)
