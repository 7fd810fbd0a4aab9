"""World and robot files: strict loading with errors that name the file, the key path,
the value received and what is allowed; ``usarsim validate`` on good and bad files."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from usarsim.cli import main as cli_main
from usarsim.config import catalog
from usarsim.config import robot as R
from usarsim.config import world as W
from usarsim.config.catalog import ROBOTS_DIR, WORLDS_DIR, resolve_robot, resolve_world
from usarsim.config.reader import FieldDefaults
from usarsim.config.robot import load_robot
from usarsim.config.world_file import check_world_file, load_world
from usarsim.errors import ConfigError, UsarsimError
from usarsim.robots.aerial import AerialLimits
from usarsim.robots.base import drive_class, make_drive
from usarsim.robots.legged import Gait, Leg
from usarsim.robots.nautical import NauticalSpec
from usarsim.sim.simulation import describe_items

WORLD_OK = """\
name: Tiny
floor: {center: [0.0, 0.0], size: [10.0, 8.0]}
materials:
  wall: {rgba: [0.9, 0.8, 0.4, 1.0], friction: 0.8}
  wood: {friction: 0.9}
objects:
  - {name: w1, shape: box, center: [4.0, 0.0, -0.5], size: [0.1, 4.0, 1.0], material: wall}
  - {name: pipe, shape: cylinder, center: [0.0, 2.0, -0.06], radius: 0.06, length: 1.0, rotation: [1.5708, 0, 0]}
start_poses:
  - {name: A, location: [0.0, 0.0, -0.2]}
  - {name: B, location: [-2.0, 0.0, -0.2], rotation: [0, 0, 1.5708]}
"""

ROBOT_OK = """\
class_name: Tiny2W
vehicle_type: GroundVehicle
steering_type: SkidSteered
drive: skid
mass_kg: 3.0
max_speed_rad_s: 4.0
max_torque_nm: 10.0
geometry: {dimensions: [0.3, 0.3, 0.2], wheel_radius: 0.05, wheel_separation: 0.3, wheel_base: 0.0}
chassis:
  - {center: [0.0, 0.0, 0.0], size: [0.3, 0.2, 0.1], mass_kg: 2.0}
wheels:
  - {name: L, position: [0.0, -0.15, 0.05], radius_m: 0.05, width_m: 0.02, mass_kg: 0.5, side: left}
  - {name: R, position: [0.0, 0.15, 0.05], radius_m: 0.05, width_m: 0.02, mass_kg: 0.5, side: right}
sensors:
  - {type: Sonar, name: S1, location: [0.15, 0.0, 0.0]}
  - {type: GroundTruth, name: GroundTruth}
"""


@pytest.fixture(autouse=True)
def restore_logging():
    """``usarsim.cli.main`` configures logging on the (captured) stderr: undo that afterwards."""
    import logging

    root = logging.getLogger()
    handlers, level = list(root.handlers), root.level
    usarsim_level = logging.getLogger("usarsim").level
    yield
    for h in root.handlers[:]:
        if h not in handlers:
            root.removeHandler(h)
    root.setLevel(level)
    logging.getLogger("usarsim").setLevel(usarsim_level)


def write(tmp_path: Path, text: str, name: str = "file.yaml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def config_error(loader, path: Path) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        loader(path)
    return info.value


# --------------------------------------------------------------------------- the good files


def test_a_minimal_world_loads_with_its_values(tmp_path):
    w = load_world(write(tmp_path, WORLD_OK))
    assert w.name == "Tiny"
    assert w.floor.size == (10.0, 8.0)
    assert [o.name for o in w.objects] == ["w1", "pipe"]
    assert w.objects[0].material == "wall" and w.objects[1].material == "default"
    assert w.materials["wall"].friction == 0.8
    assert [p.name for p in w.start_poses] == ["A", "B"]
    assert w.start_poses[1].rotation == (0.0, 0.0, 1.5708)
    assert w.start_pose("b") is w.start_poses[1]  # case-insensitive look-up (protocol.md 5.1)


def test_a_minimal_robot_loads_with_its_values(tmp_path):
    r = load_robot(write(tmp_path, ROBOT_OK))
    assert r.class_name == "Tiny2W"
    assert r.battery_s == 1200.0  # default (protocol.md 7.12)
    assert [w.name for w in r.wheels] == ["L", "R"]
    assert [(i.item_type, i.name) for i in r.items] == [("Sonar", "S1"), ("GroundTruth", "GroundTruth")]
    assert [d.item_type for d in describe_items(r)] == ["Sonar", "GroundTruth"]


@pytest.mark.parametrize("name", sorted(catalog.robot_files()))
def test_every_shipped_robot_file_loads(name):
    assert load_robot(catalog.robot_files()[name]).class_name == name


@pytest.mark.parametrize("name", sorted(catalog.world_files()))
def test_every_shipped_world_file_loads(name):
    assert check_world_file(catalog.world_files()[name]).name == name


# --------------------------------------------------------------------------- defaults
# A key a file leaves out takes the default of the dataclass field it fills: the expected
# configs below are built with the dataclasses' own defaults, so a loader default that drifts
# from its field's fails here.

ROBOT_BARE = """\
class_name: Bare
vehicle_type: GroundVehicle
steering_type: SkidSteered
drive: skid
mass_kg: 4.0
max_speed_rad_s: 4.0
max_torque_nm: 10.0
geometry: {dimensions: [0.3, 0.3, 0.2]}
chassis:
  - {size: [0.3, 0.2, 0.1], mass_kg: 2.0}
  - {shape: capsule, radius: 0.02, length: 0.1, mass_kg: 0.5}
wheels:
  - {name: L, position: [0.0, -0.15, 0.05], radius_m: 0.05, width_m: 0.02, mass_kg: 0.5, side: left}
  - {name: R, position: [0.0, 0.15, 0.05], radius_m: 0.05, width_m: 0.02, mass_kg: 0.5, side: right}
links:
  - {name: arm, max_speed: 1.0, max_torque: 2.0, shapes: [{shape: sphere, radius: 0.05, mass_kg: 0.5}]}
mission_packages:
  - {name: Arm, links: [arm]}
sensors:
  - {type: Sonar, name: S1}
"""

# the top of a robot file of each special drive, and its chassis
BARE_BODY = """\
mass_kg: 2.0
max_speed_rad_s: 4.0
max_torque_nm: 10.0
geometry: {dimensions: [0.3, 0.3, 0.2]}
chassis:
  - {size: [0.3, 0.2, 0.1], mass_kg: 2.0}
"""

WORLD_BARE = """\
name: Bare
floor: {center: [0.0, 0.0], size: [10.0, 8.0]}
materials:
  glass: {}
objects:
  - {name: b, shape: box, center: [1.0, 1.0, -0.5], size: [1.0, 1.0, 1.0]}
  - {name: c, shape: cylinder, center: [2.0, 2.0, -0.5], radius: 0.1, length: 1.0}
  - {name: m, shape: mesh, file: tetra.obj, center: [0.0, 3.0, 0.0]}
start_poses:
  - {name: A, location: [0.0, 0.0, -0.2]}
victims:
  - {name: v, location: [1.0, 2.0, -0.1], sound: {}}
false_alarms:
  - {name: fa, center: [1.0, 1.0, -0.1], size: [0.1, 0.1, 0.1]}
rfid_tags:
  - {id: 3, location: [1.0, 1.0, 0.0]}
water:
  - {name: pool, center: [0.0, 5.0, 0.0], size: [1.0, 1.0, 1.0]}
lights:
  - {name: sun}
geo_reference: {}
wireless: {}
"""


def test_a_bare_robot_file_gets_the_dataclass_defaults(tmp_path):
    p = write(tmp_path, ROBOT_BARE)
    wheel = {"radius_m": 0.05, "width_m": 0.02, "mass_kg": 0.5}
    assert load_robot(p) == R.RobotConfig(
        class_name="Bare",
        path=str(p),
        vehicle_type="GroundVehicle",
        steering_type="SkidSteered",
        drive="skid",
        mass_kg=4.0,
        max_speed_rad_s=4.0,
        max_torque_nm=10.0,
        geometry=R.RobotGeometryConfig(dimensions=(0.3, 0.3, 0.2)),
        chassis=(
            R.ChassisBox(size=(0.3, 0.2, 0.1), mass_kg=2.0),
            R.ChassisBox(shape="capsule", radius_m=0.02, length_m=0.1, mass_kg=0.5),
        ),
        wheels=(
            R.Wheel(name="L", position=(0.0, -0.15, 0.05), side="left", **wheel),
            R.Wheel(name="R", position=(0.0, 0.15, 0.05), side="right", **wheel),
        ),
        links=(
            R.Link(
                name="arm",
                max_speed=1.0,
                max_torque=2.0,
                shapes=(R.ChassisBox(shape="sphere", radius_m=0.05, mass_kg=0.5),),
            ),
        ),
        mission_packages=(R.MissionPackage(name="Arm", links=("arm",)),),
        items=(R.MountedItem(item_type="Sonar", name="S1", params={}, key_path="sensors[0]"),),
    )


@pytest.mark.parametrize(
    "head, expected",
    [
        ("vehicle_type: AerialVehicle\ndrive: aerial\naerial: {}\n", AerialLimits()),
        ("vehicle_type: AerialVehicle\ndrive: aerial\n", AerialLimits()),
        (
            "vehicle_type: NauticalVehicle\ndrive: nautical\nnautical: {volume_m3: 0.01}\n",
            NauticalSpec(volume_m3=0.01),
        ),
        (
            (
                "vehicle_type: LeggedRobot\ndrive: legged\nlinks:\n"
                "  - {name: hp, max_speed: 1.0, max_torque: 2.0}\n"
                "  - {name: hr, parent: hp, max_speed: 1.0, max_torque: 2.0}\n"
                "  - {name: kn, parent: hr, max_speed: 1.0, max_torque: 2.0}\n"
                "gait:\n  stand_height_m: 0.2\n  legs: [{hip_pitch: hp, hip_roll: hr, knee: kn, upper_m: 0.1, lower_m: 0.1}]\n"
            ),
            Gait(legs=(Leg(hip_pitch="hp", hip_roll="hr", knee="kn", upper_m=0.1, lower_m=0.1),), stand_height_m=0.2),
        ),
    ],
)
def test_a_bare_drive_section_gets_the_dataclass_defaults(tmp_path, head, expected):
    r = load_robot(write(tmp_path, f"class_name: Bare\nsteering_type: None\n{head}{BARE_BODY}"))
    assert drive_class(r).settings_of(r) == expected


def test_a_bare_world_file_gets_the_dataclass_defaults(tmp_path):
    (tmp_path / "tetra.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n")
    p = write(tmp_path, WORLD_BARE)
    assert load_world(p) == W.WorldConfig(
        name="Bare",
        path=str(p),
        floor=W.Floor(center=(0.0, 0.0), size=(10.0, 8.0)),
        materials={name: W.Material(name=name) for name in ("default", "glass", "floor")},
        objects=(
            W.StaticObject(name="b", shape="box", center=(1.0, 1.0, -0.5), size=(1.0, 1.0, 1.0)),
            W.StaticObject(name="c", shape="cylinder", center=(2.0, 2.0, -0.5), radius_m=0.1, length_m=1.0),
            W.StaticObject(
                name="m", shape="mesh", center=(0.0, 3.0, 0.0), mesh_file=str((tmp_path / "tetra.obj").resolve())
            ),
        ),
        start_poses=(W.StartPose(name="A", location=(0.0, 0.0, -0.2)),),
        victims=(W.Victim(name="v", location=(1.0, 2.0, -0.1)),),
        false_alarms=(W.FalseAlarm(name="fa", center=(1.0, 1.0, -0.1), size=(0.1, 0.1, 0.1)),),
        rfid_tags=(W.RfidTagConfig(tag_id=3, location=(1.0, 1.0, 0.0)),),
        water=(W.WaterVolume(name="pool", center=(0.0, 5.0, 0.0), size=(1.0, 1.0, 1.0)),),
        lights=(W.Light(name="sun"),),
        wireless=W.WirelessConfig(),
    )


def test_a_point_light_casts_no_shadow_unless_asked(tmp_path):
    p = write(
        tmp_path,
        WORLD_OK + "lights:\n  - {name: bulb, type: point}\n  - {name: lamp, type: point, cast_shadows: true}\n",
    )
    assert [light.cast_shadows for light in load_world(p).lights] == [False, True]


def test_field_defaults_reads_defaults_and_refuses_fields_without_one():
    assert FieldDefaults(R.RobotConfig).battery_s == 1200.0
    geo = FieldDefaults(W.WorldConfig).geo  # a default_factory: a fresh value each time
    assert geo == W.GeoReference() and geo is not FieldDefaults(W.WorldConfig).geo
    with pytest.raises(AttributeError, match="RobotConfig.mass_kg has no default"):
        _ = FieldDefaults(R.RobotConfig).mass_kg
    with pytest.raises(AttributeError, match="did you mean 'battery_s'"):
        _ = FieldDefaults(R.RobotConfig).battery
    with pytest.raises(TypeError, match="needs a dataclass"):
        FieldDefaults(dict)


# --------------------------------------------------------------------------- world errors


def test_world_unknown_top_level_key_suggests_the_right_one(tmp_path):
    p = write(tmp_path, WORLD_OK.replace("start_poses:", "start_pose:"))
    err = config_error(load_world, p)
    msg = str(err)
    assert str(p) in msg
    assert err.key == "start_pose"
    assert "unknown key 'start_pose'" in msg
    assert "did you mean 'start_poses'" in msg
    assert "allowed:" in msg and "floor" in msg  # the allowed keys are listed


def test_world_unknown_nested_key_names_the_key_path(tmp_path):
    p = write(tmp_path, WORLD_OK.replace("material: wall}", "matrial: wall}"))
    err = config_error(load_world, p)
    assert err.path == str(p)
    assert err.key == "objects[0].matrial"
    assert f"{p}: objects[0].matrial: unknown key 'matrial'" in str(err)
    assert "did you mean 'material'" in str(err)


def test_world_wrong_type_names_value_and_expectation(tmp_path):
    p = write(tmp_path, WORLD_OK.replace("size: [10.0, 8.0]", "size: [10.0, wide]"))
    err = config_error(load_world, p)
    assert err.key == "floor.size[1]"
    assert "expected a number" in str(err) and "'wide'" in str(err)
    assert str(p) in str(err)


def test_world_wrong_integer_type(tmp_path):
    p = write(tmp_path, "time_limit_min: ten\n" + WORLD_OK)
    err = config_error(load_world, p)
    assert err.key == "time_limit_min"
    assert "expected an integer" in str(err) and "'ten'" in str(err)


def test_world_bad_material_lists_the_known_ones(tmp_path):
    p = write(tmp_path, WORLD_OK.replace("material: wall}", "material: wal}"))
    err = config_error(load_world, p)
    msg = str(err)
    assert err.key == "objects[0].material"
    assert "unknown material 'wal'" in msg
    assert "did you mean 'wall'" in msg
    allowed = msg.split("allowed:", 1)[1]
    for name in ("default", "floor", "wall", "wood"):
        assert name in allowed


def test_world_bad_shape_lists_the_allowed_shapes(tmp_path):
    p = write(tmp_path, WORLD_OK.replace("shape: cylinder", "shape: cilinder"))
    err = config_error(load_world, p)
    assert err.key == "objects[1].shape"
    assert "did you mean 'cylinder'" in str(err)
    assert "box" in str(err).split("allowed:", 1)[1]


@pytest.mark.parametrize(
    "old, new, key, what",
    [
        ("{name: pipe,", "{name: w1,", "objects[1].name", "duplicate object name 'w1'"),
        ("{name: B,", "{name: a,", "start_poses[1].name", "duplicate start pose name 'a'"),
    ],
)
def test_world_duplicate_names(tmp_path, old, new, key, what):
    p = write(tmp_path, WORLD_OK.replace(old, new))
    err = config_error(load_world, p)
    assert err.key == key
    assert what in str(err)
    assert str(p) in str(err)


def test_world_missing_floor(tmp_path):
    text = "\n".join(ln for ln in WORLD_OK.splitlines() if not ln.startswith("floor:")) + "\n"
    p = write(tmp_path, text)
    err = config_error(load_world, p)
    assert err.key == "floor"
    assert "required key is missing" in str(err)


def test_world_missing_nested_key(tmp_path):
    p = write(tmp_path, WORLD_OK.replace("{name: A, location: [0.0, 0.0, -0.2]}", "{name: A}"))
    err = config_error(load_world, p)
    assert err.key == "start_poses[0].location"
    assert "required key is missing" in str(err)


def test_world_without_start_poses_fails_the_check(tmp_path):
    text = WORLD_OK.split("start_poses:")[0]
    p = write(tmp_path, text)
    assert load_world(p).start_poses == ()
    err = config_error(check_world_file, p)
    assert err.key == "start_poses"


def test_world_not_yaml_names_line(tmp_path):
    p = write(tmp_path, "name: x\nfloor: {center: [0, 0]\n")
    err = config_error(load_world, p)
    assert str(p) in str(err)
    assert "not valid YAML" in str(err) and "line" in str(err)


def test_world_missing_file(tmp_path):
    p = tmp_path / "nope.yaml"
    err = config_error(load_world, p)
    assert str(p) in str(err) and "cannot read file" in str(err)


# --------------------------------------------------------------------------- robot errors


def test_robot_bad_choice_lists_allowed_values(tmp_path):
    p = write(tmp_path, ROBOT_OK.replace("steering_type: SkidSteered", "steering_type: SkidSteer"))
    err = config_error(load_robot, p)
    msg = str(err)
    assert err.key == "steering_type"
    assert "'SkidSteer' is not allowed" in msg
    assert "did you mean 'SkidSteered'" in msg
    for allowed in ("AckermanSteered", "HolonomSteered", "SkidSteered"):
        assert allowed in msg.split("allowed:", 1)[1]


def test_robot_unknown_optional_key_did_you_mean(tmp_path):
    p = write(tmp_path, ROBOT_OK.replace("drive: skid", "drive: skid\nbatery_s: 600"))
    err = config_error(load_robot, p)
    assert err.key == "batery_s"
    assert "unknown key 'batery_s'" in str(err) and "did you mean 'battery_s'" in str(err)


def test_robot_wrong_type(tmp_path):
    p = write(tmp_path, ROBOT_OK.replace("mass_kg: 3.0", "mass_kg: heavy"))
    err = config_error(load_robot, p)
    assert err.key == "mass_kg"
    assert "expected a number" in str(err) and "'heavy'" in str(err)


def test_robot_duplicate_wheel_name(tmp_path):
    p = write(tmp_path, ROBOT_OK.replace("{name: R,", "{name: L,"))
    err = config_error(load_robot, p)
    assert err.key == "wheels[1].name"
    assert "duplicate wheel name 'L'" in str(err)


def test_robot_duplicate_sensor_name(tmp_path):
    p = write(tmp_path, ROBOT_OK + "  - {type: sonar, name: s1}\n")
    err = config_error(load_robot, p)
    assert err.key == "sensors[2].name"
    assert "duplicate" in str(err) and "s1" in str(err)


def test_robot_missing_key(tmp_path):
    text = "\n".join(ln for ln in ROBOT_OK.splitlines() if not ln.startswith("class_name")) + "\n"
    p = write(tmp_path, text)
    err = config_error(load_robot, p)
    assert err.key == "class_name"
    assert "required key is missing" in str(err)


def test_robot_masses_must_agree(tmp_path):
    p = write(tmp_path, ROBOT_OK.replace("mass_kg: 3.0", "mass_kg: 5.0"))
    err = config_error(load_robot, p)
    assert err.key == "mass_kg" and "add up to 3.000 kg" in str(err)


def test_robot_unknown_mount_lists_allowed(tmp_path):
    p = write(tmp_path, ROBOT_OK.replace("{type: Sonar, name: S1,", "{type: Sonar, name: S1, mount: Q,"))
    err = config_error(load_robot, p)
    assert err.key == "sensors[0].mount"
    assert "HARD" in str(err).split("allowed:", 1)[1]


def test_robot_unknown_sensor_setting_is_found_when_describing(tmp_path):
    p = write(tmp_path, ROBOT_OK.replace("location: [0.15, 0.0, 0.0]}", "location: [0.15, 0.0, 0.0], MaxRang: 3}"))
    r = load_robot(p)  # sensor settings are checked by the plugin
    with pytest.raises(ConfigError) as info:
        describe_items(r)
    err = info.value
    assert err.path == str(p)
    assert err.key == "sensors[0].MaxRang"
    assert "did you mean 'MaxRange'" in str(err)


def test_robot_unknown_sensor_type_names_the_registered_ones(tmp_path):
    p = write(tmp_path, ROBOT_OK.replace("{type: Sonar,", "{type: Sonr,"))
    r = load_robot(p)
    with pytest.raises(UsarsimError) as info:
        describe_items(r)
    msg = str(info.value)
    assert "unknown sensor type 'Sonr'" in msg and "did you mean 'Sonar'" in msg
    assert "RangeScanner" in msg.split("allowed:", 1)[1]


def test_robot_bad_sensor_value(tmp_path):
    p = write(tmp_path, ROBOT_OK.replace("location: [0.15, 0.0, 0.0]}", "location: [0.15, 0.0, 0.0], MaxRange: far}"))
    with pytest.raises(ConfigError) as info:
        describe_items(load_robot(p))
    assert info.value.key == "sensors[0].MaxRange"
    assert "expected a finite number" in str(info.value) and "'far'" in str(info.value)


# --------------------------------------------------------------------------- catalogue look-ups


@pytest.mark.parametrize("name", ["P2AT", "p2at", "USARBot.P2AT", "usarbot.p2at"])
def test_robot_class_names_resolve_case_insensitively(name):
    assert resolve_robot(name).class_name == "P2AT"


def test_unknown_robot_class_suggests():
    with pytest.raises(ConfigError, match=r"did you mean 'P2AT'"):
        resolve_robot("USARBot.P2ATT")


def test_unknown_world_lists_the_known_ones():
    with pytest.raises(ConfigError) as info:
        resolve_world("DM-USAR_yelow")
    assert "did you mean 'DM-USAR_yellow'" in str(info.value)
    assert "DM-USAR_yellow" in str(info.value).split("allowed:", 1)[1]


# --------------------------------------------------------------------------- usarsim validate (in-process)


def test_validate_shipped_world_prints_one_line(capsys):
    code = cli_main(["validate", str(WORLDS_DIR / "DM-USAR_yellow.yaml")])
    out, err = capsys.readouterr()
    assert code == 0
    assert err == ""
    lines = out.splitlines()
    assert len(lines) == 1
    assert re.match(r"ok: world DM-USAR_yellow: \d+ objects, 8 start poses", lines[0]), lines[0]


def test_validate_shipped_robot_prints_one_line(capsys):
    code = cli_main(["validate", str(ROBOTS_DIR / "P2AT.yaml")])
    out, err = capsys.readouterr()
    assert code == 0
    assert err == ""
    lines = out.splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("ok: robot P2AT: SkidSteered, 14 kg, 28 sensors")


def test_validate_bad_world_exits_1_with_the_message_on_stderr(tmp_path, capsys):
    p = write(tmp_path, WORLD_OK.replace("material: wall}", "material: wal}"), "bad_world.yaml")
    code = cli_main(["validate", str(p)])
    out, err = capsys.readouterr()
    assert code == 1
    assert out == ""
    assert err.startswith("usarsim: error: ")
    assert str(p) in err and "objects[0].material" in err and "did you mean 'wall'" in err


def test_validate_bad_robot_sensor_exits_1(tmp_path, capsys):
    p = write(tmp_path, ROBOT_OK.replace("{type: Sonar,", "{type: Sonr,"), "bad_robot.yaml")
    code = cli_main(["validate", str(p)])
    out, err = capsys.readouterr()
    assert code == 1
    assert out == ""
    assert "unknown sensor type 'Sonr'" in err


def test_validate_unrecognised_file_exits_1(tmp_path, capsys):
    p = write(tmp_path, "hello: world\n", "what.yaml")
    code = cli_main(["validate", str(p)])
    _, err = capsys.readouterr()
    assert code == 1
    assert str(p) in err and "class_name" in err


@pytest.mark.parametrize("knee_forward", [False, True])
@pytest.mark.parametrize("foot", [(0.0, 0.0, 0.2), (0.05, 0.0, 0.18), (-0.04, 0.03, 0.19), (0.02, -0.05, 0.15)])
def test_leg_ik_puts_the_foot_where_asked(knee_forward, foot):
    """Forward kinematics of the angles leg_ik returns (roll about X, then pitch and knee
    about the rolled Y; USARSim frame, Z down) reach the foot, the knee on its side."""
    import math

    from usarsim.robots.legged import leg_ik

    upper, lower = 0.11, 0.11
    pitch, roll, knee = leg_ik(*foot, upper, lower, knee_forward)
    # in the leg's plane: forward x, down d; positive pitch swings the leg forward
    kx, kd = upper * math.sin(pitch), upper * math.cos(pitch)
    fx, fd = kx + lower * math.sin(pitch + knee), kd + lower * math.cos(pitch + knee)
    got = (fx, -fd * math.sin(roll), fd * math.cos(roll))
    assert got == pytest.approx(foot, abs=1e-6)
    assert (knee < 0) == knee_forward  # a person's knee: forward of the hip-foot line
    assert (kx * fd - kd * fx > 0) == knee_forward


def test_robot_only_a_biped_sways(tmp_path):
    text = (ROBOTS_DIR / "QRIO.yaml").read_text().replace("phase: 0.5}", "phase: 0.25}")
    f = tmp_path / "Q.yaml"
    f.write_text(text)
    with pytest.raises(ConfigError, match=r"gait\.sway_m: only a biped sways"):
        make_drive(load_robot(f))  # the walking robot's drive reads its gait


def test_a_robot_files_colour_is_its_body_colour_in_pictures(tmp_path):
    assert resolve_robot("P2AT").color == (0.75, 0.10, 0.10)  # the default: the Pioneers' red
    assert resolve_robot("Talon").color == (0.33, 0.36, 0.22)
    text = (ROBOTS_DIR / "P2AT.yaml").read_text()
    bad = tmp_path / "P2AT.yaml"
    bad.write_text(text.replace("vehicle_type:", "color: [1.5, 0, 0]\nvehicle_type:", 1))
    with pytest.raises(Exception, match="color"):
        load_robot(bad)


def test_a_drive_section_belongs_to_its_drive_alone(tmp_path):
    """A kind's settings are read and checked by its drive model: another kind's section, or
    one no kind has, is refused when the robot is checked (usarsim validate, INIT)."""
    text = (ROBOTS_DIR / "P2AT.yaml").read_text()
    cases = {
        "aerial: {max_linear_m_s: 1.0}\n": r"aerial: the 'aerial' section is for robots of drive: aerial; this robot's drive is skid",
        "gaet: {period_s: 0.4}\n": r"gaet: unknown section 'gaet' \(did you mean 'gait'\?\)",
    }
    for extra, message in cases.items():
        f = tmp_path / "P2AT.yaml"
        f.write_text(extra + text)
        robot = load_robot(f)  # the loader keeps the section for the drive
        with pytest.raises(ConfigError, match=message):
            make_drive(robot)
    sub = (ROBOTS_DIR / "Submarine.yaml").read_text()
    f = tmp_path / "Submarine.yaml"
    f.write_text(sub.replace("nautical:", "nautical_x:", 1))
    with pytest.raises(ConfigError, match=r"nautical_x: unknown section 'nautical_x' \(did you mean 'nautical'\?\)"):
        make_drive(load_robot(f))
