"""Client commands: parsing real client lines, validation, round trips (protocol.md §5, §18)."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usarsim.errors import ProtocolError
from usarsim.protocol import commands as c
from usarsim.protocol.commands import format_command, parse_command
from usarsim.protocol.grammar import Segment

# --------------------------------------------------------------------------- real client lines

CLIENT_LINES = [
    # §5.1 INIT
    (
        "INIT {ClassName USARBot.P2AT} {Name Robot1} {Location 4.5,1.9,1.8} {Rotation 0,0,1.5708}",
        c.Init(
            class_name="USARBot.P2AT",
            name="Robot1",
            location=(4.5, 1.9, 1.8),
            rotation=(0.0, 0.0, 1.5708),
        ),
    ),
    (
        "INIT {ClassName USARBot.P2AT} {Name Robot1} {Start PlayerStart3}",
        c.Init(class_name="USARBot.P2AT", name="Robot1", start="PlayerStart3"),
    ),
    (  # MOAST key spelling
        "INIT {Classname USARBot.Zerg} {Name zerg1} {Start PlayerStart1}",
        c.Init(class_name="USARBot.Zerg", name="zerg1", start="PlayerStart1"),
    ),
    (  # NorthScientific Player driver / maldo Java client: space-separated location
        "INIT {ClassName P2AT} {Location 1.5 1.0 0.2}",
        c.Init(class_name="P2AT", location=(1.5, 1.0, 0.2)),
    ),
    (  # NIST Iridium: spaces after commas
        "INIT {ClassName USARBot.P2AT} {Location 0, 0, 0} {Rotation 0, 0, 0}",
        c.Init(class_name="USARBot.P2AT", location=(0.0, 0.0, 0.0), rotation=(0.0, 0.0, 0.0)),
    ),
    (  # USARGazebo battery extension
        "INIT {ClassName USARBot.P2AT} {Battery 3600}",
        c.Init(class_name="USARBot.P2AT", battery_s=3600.0),
    ),
    # §5.2
    ("GETSTARTPOSES", c.GetStartPoses()),
    ("getstartposes", c.GetStartPoses()),
    # §5.3a skid steering
    ("DRIVE {Left 1.5} {Right 1.5}", c.Drive(left=1.5, right=1.5)),
    ("Drive {Left 1} {Right 1}", c.Drive(left=1.0, right=1.0)),  # MOAST
    ("DRIVE {RIGHT 1.0} {LEFT -1.0}", c.Drive(left=-1.0, right=1.0)),  # RDK test code
    ("DRIVE {Left 0.0005} {Right -0.0005}", c.Drive(left=0.0005, right=-0.0005)),  # RDK zero
    (
        "DRIVE {Left -30} {Right 30} {Normalized True} {Light False} {Flip False}",
        c.Drive(left=-30.0, right=30.0, normalized=True, light=False, flip=False),
    ),
    (  # AUT toolbox misspelling
        "DRIVE {Left 50} {Right 50} {Normalize true}",
        c.Drive(left=50.0, right=50.0, normalized=True),
    ),
    ("DRIVE {Light True}", c.Drive(light=True)),
    ("DRIVE {Flip 1}", c.Drive(flip=True)),
    # §5.3b Ackermann
    (
        "DRIVE {Speed 3.0} {FrontSteer 0.5236} {RearSteer 0} {Normalized False} {Light False} {Flip False}",
        c.Drive(speed=3.0, front_steer=0.5236, rear_steer=0.0, normalized=False, light=False, flip=False),
    ),
    (
        "Drive {Speed 2} {FrontSteer 0.3} {RearSteer -0.3}",
        c.Drive(speed=2.0, front_steer=0.3, rear_steer=-0.3),
    ),
    ("DRIVE {Speed 0.0}", c.Drive(speed=0.0)),
    # §5.3c omni wheels
    (
        "DRIVE {WheelNumber 0} {WheelSpeed 3.14} {WheelSteer 1.5708} "
        "{WheelNumber 1} {WheelSpeed 3.14} {WheelSteer 1.5708}",
        c.Drive(
            wheels=(
                c.WheelDrive(number=0, speed=3.14, steer=1.5708),
                c.WheelDrive(number=1, speed=3.14, steer=1.5708),
            )
        ),
    ),
    (
        "DRIVE {WheelNumber 2} {WheelSteer 0.1} {WheelNumber 3}",
        c.Drive(wheels=(c.WheelDrive(number=2, steer=0.1), c.WheelDrive(number=3))),
    ),
    # §5.3d aerial
    (
        "DRIVE {AltitudeVelocity 0.2} {LinearVelocity 0} {LateralVelocity 0} "
        "{RotationalVelocity 0.3} {Normalized False}",
        c.Drive(
            altitude_velocity=0.2,
            linear_velocity=0.0,
            lateral_velocity=0.0,
            rotational_velocity=0.3,
            normalized=False,
        ),
    ),
    # §5.3e underwater
    (
        "DRIVE {Propeller 0.5} {Rudder 0.1} {SternPlane 0} {Normalized False} {Light False}",
        c.Drive(propeller=0.5, rudder=0.1, stern_plane=0.0, normalized=False, light=False),
    ),
    # §5.3f joints
    (
        "DRIVE {Name FRFlipper} {Value 1.57} {Order 0}",
        c.Drive(joints=(c.JointDrive(name="FRFlipper", value=1.57, order=0),)),
    ),
    (
        "DRIVE {Name LeftWheel} {Steer 0} {Order 1} {Value 3.0} {Name RightWheel} {Order 1} {Value 3.0}",
        c.Drive(
            joints=(
                c.JointDrive(name="LeftWheel", value=3.0, steer=0.0, order=1),
                c.JointDrive(name="RightWheel", value=3.0, order=1),
            )
        ),
    ),
    # Iridium extras are ignored
    ("DRIVE {Left 1} {Right 1} {Foo bar} {Bare}", c.Drive(left=1.0, right=1.0)),
    # §5.3g
    (
        "MULTIDRIVE {FRFlipper 1.5} {FLFlipper 1.5} {RRFlipper -1.5} {RLFlipper 0}",
        c.MultiDrive(joints=(("FRFlipper", 1.5), ("FLFlipper", 1.5), ("RRFlipper", -1.5), ("RLFlipper", 0.0))),
    ),
    ("MULTIDRIVE", c.MultiDrive()),
    # §5.4 SET
    (
        "SET {Type Camera} {Name Camera} {Opcode Zoom} {Params 0.5}",
        c.Set(type="Camera", name="Camera", opcode="Zoom", params="0.5"),
    ),
    (  # Player driver: bare zoom value
        "SET {Type Camera} {Name cam} {Opcode Zoom} {0.87}",
        c.Set(type="Camera", name="cam", opcode="Zoom", params="0.87"),
    ),
    (
        "SET {Type Camera} {Robot Robot1} {Name Camera} {Client 192.168.0.7}",
        c.Set(type="Camera", robot="Robot1", name="Camera", client="192.168.0.7"),
    ),
    (
        "SET {Type Viewports} {Config QuadView} {Viewport1 Camera} {Viewport2 Disable} "
        "{Viewport3 Robot2Cam} {Viewport4 Disable}",
        c.Set(
            type="Viewports",
            config="QuadView",
            viewports=((1, "Camera"), (2, "Disable"), (3, "Robot2Cam"), (4, "Disable")),
        ),
    ),
    ("SET {Type Odometry} {Opcode RESET}", c.Set(type="Odometry", opcode="RESET")),
    (  # MOAST
        "SET {Type RangeImager} {Name KinectDepth} {Opcode SCAN} {Value 0.0}",
        c.Set(type="RangeImager", name="KinectDepth", opcode="SCAN", value="0.0"),
    ),
    (
        "SET {Type RFID} {Name RFID} {Opcode Write} {Params 11137 victim  is here}",
        c.Set(type="RFID", name="RFID", opcode="Write", params="11137 victim  is here"),
    ),
    (
        "SET {Type RFIDReleaser} {Name Gun} {Opcode Release}",
        c.Set(type="RFIDReleaser", name="Gun", opcode="Release"),
    ),
    (
        "SET {Type Joint} {Name FRFlipper} {Opcode Angle} {Params 0.5,0} {Speed 2}",
        c.Set(
            type="Joint",
            name="FRFlipper",
            opcode="Angle",
            params="0.5,0",
            segments=(Segment("Speed", "2"),),
        ),
    ),
    # §5.5
    ("GETGEO {Type Sonar}", c.GetGeo(type="Sonar")),
    ("GETGEO {Type Camera} {Name Camera}", c.GetGeo(type="Camera", name="Camera")),
    ("GETCONF {Type Robot} {Name Robot1}", c.GetConf(type="Robot", name="Robot1")),
    ("getconf {type RangeScanner}", c.GetConf(type="RangeScanner")),
    ("GETGEO", c.GetGeo()),
    # §5.6
    (
        "MISPKG {Name CameraPanTilt} {Link 1} {Value 1.5} {Link 2} {Value 0}",
        c.MisPkg(
            name="CameraPanTilt",
            links=(c.LinkCommand(link=1, value=1.5), c.LinkCommand(link=2, value=0.0)),
        ),
    ),
    (
        "MISPKG {Name TeleMaxArm} {Link 2} {Value 2.356} {Order 0} {Link 4} {Value -2.356} {Order 1}",
        c.MisPkg(
            name="TeleMaxArm",
            links=(
                c.LinkCommand(link=2, value=2.356, order=0),
                c.LinkCommand(link=4, value=-2.356, order=1),
            ),
        ),
    ),
    (  # older API, Player ptz driver / Pyro
        "MISPKG {Name CameraPanTilt} {Rotation 0,0.2,-0.5} {Order 1}",
        c.MisPkg(name="CameraPanTilt", rotation=(0.0, 0.2, -0.5), order=1),
    ),
    (
        "MISPKG {Type PanTilt} {Name CameraPanTilt} {Rotation 0,0.1,0.2}",
        c.MisPkg(type="PanTilt", name="CameraPanTilt", rotation=(0.0, 0.1, 0.2)),
    ),
    # §5.7
    (
        "CAMERA {Rotation 0,0.1917,0} {Zoom 0.8727}",
        c.Camera(rotation=(0.0, 0.1917, 0.0), zoom=0.8727),
    ),
    # §5.8 UDK
    (
        "ACT {Name arm} {Link 1} {Value 0.5} {Link 2} {Value -0.3}",
        c.Act(name="arm", links=(c.LinkCommand(link=1, value=0.5), c.LinkCommand(link=2, value=-0.3))),
    ),
    ("ACT {Name arm} {Gripper 1}", c.Act(name="arm", gripper=1)),
    ("ACT {Name arm} {Sequence 2}", c.Act(name="arm", sequence=2)),
    ("ACT {Name arm} {Seq 3}", c.Act(name="arm", sequence=3)),
    ("CONTROL {Type Kill} {Name box1}", c.Control(type="Kill", name="box1")),
    (
        "CONTROL {Type Create} {ClassName USARPhysObj.WoodBox} {Name b} {Location 1,2,3} {Physics RigidBody}",
        c.Control(
            type="Create",
            name="b",
            segments=(
                Segment("ClassName", "USARPhysObj.WoodBox"),
                Segment("Location", "1,2,3"),
                Segment("Physics", "RigidBody"),
            ),
        ),
    ),
    (
        "MOVE {Type Walk_Forward} {Action New} {Location 1.5,2}",
        c.Move(type="Walk_Forward", action="New", location=(1.5, 2.0)),
    ),
    ("MOVE {Action Pause}", c.Move(action="Pause")),
    ("MOVE {Type Run} {Pathnode PathNode_3}", c.Move(type="Run", pathnode="PathNode_3")),
    ("GOTO {Name PathNode_12}", c.Goto(name="PathNode_12")),
    ("GETPATHNODES", c.GetPathNodes()),
    ("GETCLOSESTPATHNODE {Location 1,2,3}", c.GetClosestPathNode(location=(1.0, 2.0, 3.0))),
    ("TEST {Mode 1}", c.Test(segments=(Segment("Mode", "1"),))),
    # §18
    ("STEP {Time 0.2}", c.Step(time_s=0.2)),
    ("step {time 1}", c.Step(time_s=1.0)),
    # unknown commands are not errors
    ("PAUSE {Time 10}", c.UnknownCommand(type="PAUSE", segments=(Segment("Time", "10"),))),
    ("posall", c.UnknownCommand(type="POSALL")),
]


@pytest.mark.parametrize(("line", "expected"), CLIENT_LINES, ids=[x[0][:40] for x in CLIENT_LINES])
def test_client_lines(line: str, expected: c.Command) -> None:
    assert parse_command(line) == expected


@pytest.mark.parametrize(("line", "expected"), CLIENT_LINES, ids=[x[0][:40] for x in CLIENT_LINES])
def test_client_lines_round_trip_through_the_formatter(line: str, expected: c.Command) -> None:
    text = format_command(expected)
    assert text.endswith("\r\n") and text.count("\r\n") == 1
    assert parse_command(text) == expected


@pytest.mark.parametrize("key", ["Normalized", "Normalize", "Light", "Flip", "normalized", "LIGHT"])
def test_booleans_in_every_spelling(key: str) -> None:
    field = {"normalize": "normalized"}.get(key.lower(), key.lower())
    for spelling in ["True", "true", "TRUE", "1", "False", "false", "FALSE", "0", "tRuE"]:
        cmd = parse_command(f"DRIVE {{{key} {spelling}}}")
        assert getattr(cmd, field) is (spelling.lower() in ("true", "1")), spelling


def test_first_occurrence_of_a_repeated_key_wins() -> None:
    assert parse_command("DRIVE {Left 1} {Right 2} {Left 3}") == c.Drive(left=1.0, right=2.0)
    assert parse_command("DRIVE {Normalized True} {Normalize False}").normalized is True


def test_set_keeps_params_key_over_bare_number() -> None:
    cmd = parse_command("SET {Type Camera} {Opcode Zoom} {0.5} {Params 0.7}")
    assert cmd.params == "0.7"
    assert cmd.segments == (Segment("0.5", ""),)
    assert cmd.get("0.5") == ""


def test_set_bare_word_is_not_params() -> None:
    cmd = parse_command("SET {Type Camera} {Opcode Zoom} {Reset}")
    assert cmd.params is None
    assert cmd.segments == (Segment("Reset", ""),)


def test_control_get() -> None:
    cmd = parse_command("CONTROL {Type Create} {classname Box} {Name b}")
    assert cmd.get("ClassName") == "Box"
    assert cmd.get("Scale") is None


# --------------------------------------------------------------------------- rejections

NUMERIC_FIELDS = [
    "DRIVE {{Left {v}}}",
    "DRIVE {{Right {v}}}",
    "DRIVE {{Speed {v}}}",
    "DRIVE {{FrontSteer {v}}}",
    "DRIVE {{RearSteer {v}}}",
    "DRIVE {{AltitudeVelocity {v}}}",
    "DRIVE {{LinearVelocity {v}}}",
    "DRIVE {{LateralVelocity {v}}}",
    "DRIVE {{RotationalVelocity {v}}}",
    "DRIVE {{Propeller {v}}}",
    "DRIVE {{Rudder {v}}}",
    "DRIVE {{SternPlane {v}}}",
    "DRIVE {{WheelNumber 0}} {{WheelSpeed {v}}}",
    "DRIVE {{WheelNumber 0}} {{WheelSteer {v}}}",
    "DRIVE {{Name j}} {{Value {v}}}",
    "DRIVE {{Name j}} {{Steer {v}}}",
    "MULTIDRIVE {{FRFlipper {v}}}",
    "INIT {{Location {v},0,0}}",
    "INIT {{Rotation 0,{v},0}}",
    "INIT {{Battery {v}}}",
    "MISPKG {{Link 1}} {{Value {v}}}",
    "MISPKG {{Rotation 0,0,{v}}}",
    "ACT {{Link 1}} {{Value {v}}}",
    "CAMERA {{Zoom {v}}}",
    "CAMERA {{Rotation {v},0,0}}",
    "MOVE {{Location {v},1}}",
    "GETCLOSESTPATHNODE {{Location 1,2,{v}}}",
    "STEP {{Time {v}}}",
]


@pytest.mark.parametrize("template", NUMERIC_FIELDS)
def test_non_finite_numbers_are_rejected(template: str) -> None:
    for value in ["nan", "NaN", "inf", "-inf", "Infinity", "1e400"]:
        with pytest.raises(ProtocolError, match="finite|greater than 0"):
            parse_command(template.format(v=value))


@pytest.mark.parametrize("template", NUMERIC_FIELDS)
def test_non_numbers_are_rejected(template: str) -> None:
    with pytest.raises(ProtocolError, match="bad value"):
        parse_command(template.format(v="fast"))


@pytest.mark.parametrize(
    ("line", "fragments"),
    [
        ("DRIVE {Left fast}", ["DRIVE", "Left", "'fast'", "number"]),
        ("DRIVE {Light maybe}", ["DRIVE", "Light", "'maybe'", "True, False, 1 or 0"]),
        ("INIT {Location 1,2}", ["INIT", "Location", "'1,2'", "3 numbers"]),
        ("INIT {Battery -5}", ["INIT", "Battery", "'-5'", "greater than 0"]),
        ("DRIVE {Name j} {Order 5}", ["DRIVE", "Order", "'5'", "0, 1, 2, 3, 10, 11, 12"]),
        ("DRIVE {WheelNumber -1}", ["DRIVE", "WheelNumber", "'-1'", "0 or more"]),
        ("DRIVE {WheelNumber x}", ["DRIVE", "WheelNumber", "'x'", "integer"]),
        ("DRIVE {WheelSpeed 1}", ["DRIVE", "WheelSpeed", "WheelNumber"]),
        ("DRIVE {Value 1}", ["DRIVE", "Value", "Name"]),
        ("MISPKG {Link 1} {Value 1} {Order 3}", ["MISPKG", "Order", "'3'", "position"]),
        ("MISPKG {Order 7}", ["MISPKG", "Order", "'7'"]),
        ("MISPKG {Link 1} {Order 0}", ["MISPKG", "Link 1", "Value"]),
        ("MISPKG {Value 1}", ["MISPKG", "Value", "Link"]),
        ("MISPKG {Link one} {Value 1}", ["MISPKG", "Link", "'one'"]),
        ("ACT {Name g} {Gripper 2}", ["ACT", "Gripper", "'2'", "1 (close) or 0 (open)"]),
        ("MULTIDRIVE {FRFlipper}", ["MULTIDRIVE", "FRFlipper", "no value"]),
        ("MOVE {Location 1}", ["MOVE", "Location", "2 or 3"]),
        ("STEP", ["STEP", "Time"]),
        ("STEP {Time 0}", ["STEP", "Time", "greater than 0"]),
        ("STEP {Time -0.1}", ["STEP", "Time", "greater than 0"]),
        ("DRIVE {Left 1", ["DRIVE", "unclosed"]),
        ("DRIVE {Left 1} junk", ["DRIVE", "outside braces"]),
        ("", ["empty line"]),
    ],
)
def test_error_messages_name_command_key_value_and_what_is_allowed(line: str, fragments: list[str]) -> None:
    with pytest.raises(ProtocolError) as info:
        parse_command(line)
    for fragment in fragments:
        assert fragment in str(info.value)


def test_format_command_canonical_spelling() -> None:
    assert format_command(parse_command("drive {left 1} {RIGHT 2} {normalize 1}")) == (
        "DRIVE {Left 1.0} {Right 2.0} {Normalized True}\r\n"
    )
    assert format_command(c.Init(class_name="USARBot.P2AT", location=(1e-05, 0.0, -2.5))) == (
        "INIT {ClassName USARBot.P2AT} {Location 0.00001,0.0,-2.5}\r\n"
    )
    assert format_command(c.GetStartPoses()) == "GETSTARTPOSES\r\n"
    assert format_command(c.Step(time_s=0.2)) == "STEP {Time 0.2}\r\n"


@pytest.mark.parametrize(
    "cmd",
    [
        c.Init(name="bad}name"),
        c.Set(params="a{b"),
        c.Set(type="x\r\nDRIVE"),
        c.MultiDrive(joints=(("two words", 1.0),)),
        c.UnknownCommand(type="A B"),
    ],
)
def test_format_command_refuses_unsendable_text(cmd: c.Command) -> None:
    with pytest.raises(ProtocolError, match="cannot send"):
        format_command(cmd)


def test_format_command_rejects_non_commands() -> None:
    with pytest.raises(TypeError):
        format_command("DRIVE")  # type: ignore[arg-type]


# --------------------------------------------------------------------------- round trips

_names = st.text(
    alphabet=st.sampled_from("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-"),
    min_size=1,
    max_size=12,
)
_texts = st.text(
    alphabet=st.characters(min_codepoint=32, max_codepoint=126, blacklist_characters="{}"),
    max_size=24,
).map(str.strip)
_floats = st.floats(allow_nan=False, allow_infinity=False)
_positive = st.floats(min_value=1e-9, max_value=1e9, allow_nan=False)
_vec3 = st.tuples(_floats, _floats, _floats)


def _opt(strategy: st.SearchStrategy) -> st.SearchStrategy:
    return st.none() | strategy


def _extra_segments(excluded: set[str]) -> st.SearchStrategy[tuple[Segment, ...]]:
    keys = _names.filter(
        lambda k: k.lower() not in excluded and not k.lower().startswith("viewport") and k[0] not in "+-.0123456789"
    )
    return st.lists(st.builds(Segment, keys, _texts), max_size=4).map(tuple)


_link = st.builds(c.LinkCommand, link=st.integers(-1, 99), value=_floats, order=st.sampled_from(sorted(c.LINK_ORDERS)))

COMMAND_STRATEGIES = {
    "Init": st.builds(
        c.Init,
        class_name=_opt(_texts),
        name=_opt(_texts),
        location=_opt(_vec3),
        rotation=_opt(_vec3),
        start=_opt(_texts),
        battery_s=_opt(_positive),
    ),
    "GetStartPoses": st.just(c.GetStartPoses()),
    "Drive": st.builds(
        c.Drive,
        left=_opt(_floats),
        right=_opt(_floats),
        normalized=_opt(st.booleans()),
        light=_opt(st.booleans()),
        flip=_opt(st.booleans()),
        speed=_opt(_floats),
        front_steer=_opt(_floats),
        rear_steer=_opt(_floats),
        wheels=st.lists(
            st.builds(c.WheelDrive, number=st.integers(0, 64), speed=_opt(_floats), steer=_opt(_floats)),
            max_size=4,
        ).map(tuple),
        altitude_velocity=_opt(_floats),
        linear_velocity=_opt(_floats),
        lateral_velocity=_opt(_floats),
        rotational_velocity=_opt(_floats),
        propeller=_opt(_floats),
        rudder=_opt(_floats),
        stern_plane=_opt(_floats),
        joints=st.lists(
            st.builds(
                c.JointDrive,
                name=_texts,
                value=_opt(_floats),
                steer=_opt(_floats),
                order=st.sampled_from(sorted(c.JOINT_ORDERS)),
            ),
            max_size=4,
        ).map(tuple),
    ),
    "MultiDrive": st.builds(c.MultiDrive, joints=st.lists(st.tuples(_names, _floats), max_size=6).map(tuple)),
    "Set": st.builds(
        c.Set,
        type=_opt(_texts),
        name=_opt(_texts),
        opcode=_opt(_texts),
        params=_opt(_texts),
        robot=_opt(_texts),
        client=_opt(_texts),
        config=_opt(_texts),
        viewports=st.lists(st.tuples(st.integers(0, 999), _texts), max_size=4).map(tuple),
        value=_opt(_texts),
        segments=_extra_segments({"type", "name", "opcode", "params", "robot", "client", "config", "value"}),
    ),
    "GetGeo": st.builds(c.GetGeo, type=_opt(_texts), name=_opt(_texts)),
    "GetConf": st.builds(c.GetConf, type=_opt(_texts), name=_opt(_texts)),
    "MisPkg": st.builds(
        c.MisPkg,
        name=_opt(_texts),
        type=_opt(_texts),
        links=st.lists(_link, max_size=5).map(tuple),
        rotation=_opt(_vec3),
        order=_opt(st.sampled_from(sorted(c.LINK_ORDERS))),
    ),
    "Camera": st.builds(c.Camera, rotation=_opt(_vec3), zoom=_opt(_floats)),
    "Act": st.builds(
        c.Act,
        name=_opt(_texts),
        links=st.lists(_link, max_size=5).map(tuple),
        gripper=_opt(st.sampled_from([0, 1])),
        sequence=_opt(st.integers(-1000, 1000)),
    ),
    "Control": st.builds(
        c.Control,
        type=_opt(_texts),
        name=_opt(_texts),
        segments=_extra_segments({"type", "name"}),
    ),
    "Move": st.builds(
        c.Move,
        type=_opt(_texts),
        action=_opt(_texts),
        location=_opt(st.lists(_floats, min_size=2, max_size=3).map(tuple)),
        pathnode=_opt(_texts),
    ),
    "Goto": st.builds(c.Goto, name=_opt(_texts)),
    "GetPathNodes": st.just(c.GetPathNodes()),
    "GetClosestPathNode": st.builds(c.GetClosestPathNode, location=_opt(_vec3)),
    "Test": st.builds(c.Test, segments=_extra_segments(set())),
    "Step": st.builds(c.Step, time_s=_positive),
    "Ping": st.builds(c.Ping, id=_opt(_names)),
    "Report": st.builds(c.Report, type=st.just("Victim"), location=_vec3, name=_opt(_names)),
    "UnknownCommand": st.builds(
        c.UnknownCommand,
        type=_names.map(str.upper).filter(lambda t: t not in c._PARSERS),
        segments=_extra_segments(set()),
    ),
}


def test_every_command_type_has_a_round_trip_strategy() -> None:
    union_members = set(c.Command.__args__)
    assert {getattr(c, name) for name in COMMAND_STRATEGIES} == union_members


@pytest.mark.parametrize("name", sorted(COMMAND_STRATEGIES))
@settings(max_examples=25, deadline=None)
@given(data=st.data())
def test_round_trip(name: str, data: st.DataObject) -> None:
    cmd = data.draw(COMMAND_STRATEGIES[name])
    text = format_command(cmd)
    assert text.endswith("\r\n")
    assert "\r" not in text[:-2] and "\n" not in text[:-2]
    assert parse_command(text[:-2]) == cmd


# --------------------------------------------------------------------------- robustness

_KNOWN_WORDS = [
    "INIT", "Drive", "drive", "MULTIDRIVE", "SET", "GETGEO", "GETCONF", "MISPKG", "CAMERA",
    "ACT", "CONTROL", "MOVE", "GOTO", "GETPATHNODES", "GETCLOSESTPATHNODE", "TEST", "STEP",
    "GETSTARTPOSES", "XYZ",
]  # fmt: skip
_KNOWN_KEYS = [
    "ClassName", "Name", "Location", "Rotation", "Start", "Battery", "Left", "right", "Normalized",
    "Normalize", "Light", "Flip", "Speed", "FrontSteer", "RearSteer", "WheelNumber", "WheelSpeed",
    "WheelSteer", "AltitudeVelocity", "Propeller", "Value", "Steer", "Order", "Type", "Opcode",
    "Params", "Viewport1", "Viewport99999", "Config", "Link", "Zoom", "Gripper", "Sequence",
    "Seq", "Time", "Action", "Pathnode", "0.87", "FRFlipper",
]  # fmt: skip
_VALUES = st.one_of(
    _floats.map(repr),
    st.sampled_from(["", "nan", "inf", "-inf", "1e999", "True", "maybe", "1,2,3", "1 2", "1,,2",
                     "99999999999999999999", "2.0", "-1", "0", "1", "3", "12", "\x00", "\ufffd"]),
    st.text(alphabet=st.sampled_from(list("0123456789.,-+eE x\t")), max_size=12),
)  # fmt: skip
_segment_text = st.tuples(st.sampled_from(_KNOWN_KEYS), _VALUES).map(lambda kv: "{%s %s}" % kv)
_structured_lines = st.tuples(
    st.sampled_from(_KNOWN_WORDS),
    st.lists(st.one_of(_segment_text, st.text(max_size=6)), max_size=8),
).map(lambda t: t[0] + " " + " ".join(t[1]))


@settings(max_examples=200, deadline=None)
@given(st.one_of(_structured_lines, st.text(max_size=60)))
def test_parse_command_raises_only_protocol_error(line: str) -> None:
    try:
        parse_command(line)
    except ProtocolError:
        pass


# --------------------------------------------------------------------------- STEP, read directly


def _general(line: str):
    """What the general path (split, then typed) makes of a line, or the error it raises."""
    from usarsim.protocol.grammar import parse_line

    try:
        return c.command_from_raw(parse_line(line))
    except ProtocolError as exc:
        return type(exc)


def _either(line: str):
    try:
        return parse_command(line)
    except ProtocolError as exc:
        return type(exc)


@settings(max_examples=400, deadline=None)
@given(
    st.one_of(
        st.floats(min_value=0.0, max_value=1e6, allow_nan=False).map(repr),
        st.floats(min_value=0.0, max_value=1e6, allow_nan=False).map(lambda x: f"{x:g}"),
        st.floats(min_value=0.0, max_value=1e6, allow_nan=False).map(lambda x: f"{x:.3E}"),
        st.integers(min_value=0, max_value=10**6).map(str),
        st.sampled_from(["0", "1e-400", "1e999", ".5", "5.", "00.1", "1E+2", "-0.1", "nan", "0x1"]),
    )
)
def test_a_plain_step_line_reads_as_the_general_path_reads_it(text):
    for line in (f"STEP {{Time {text}}}", f"STEP {{Time  {text}}}", f"step {{time {text}}}"):
        assert _either(line) == _general(line), line


def test_a_plain_step_line_is_a_step():
    assert parse_command("STEP {Time 0.004}") == c.Step(time_s=0.004)
    with pytest.raises(ProtocolError, match="greater than 0"):
        parse_command("STEP {Time 0}")


# --------------------------------------------------------------------------- as parsed, without text

_DRIVE_NUMBER = st.one_of(
    st.none(),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(10**6), max_value=10**6),
    st.booleans(),
)
_DRIVE_FLAG = st.one_of(st.none(), st.booleans(), st.sampled_from([0, 1]))


@settings(max_examples=400, deadline=None)
@given(
    st.fixed_dictionaries({name: _DRIVE_NUMBER for name in c.DRIVE_NUMBERS} | {k: _DRIVE_FLAG for k in c.DRIVE_FLAGS})
)
def test_a_drive_as_parsed_is_what_the_server_parses_from_its_line(keys):
    cmd = c.Drive(**{k: v for k, v in keys.items() if v is not None})
    quick = c.as_parsed(cmd)
    if quick is None:  # not covered: the line is formatted and parsed instead
        return
    assert quick == parse_command(format_command(cmd).rstrip("\r\n"))
    assert all(type(getattr(quick, k)) is float for k in c.DRIVE_NUMBERS if getattr(quick, k) is not None)


def test_as_parsed_covers_a_plain_drive_and_leaves_the_rest_to_the_text():
    assert c.as_parsed(c.Drive(left=50, right=-12.5, normalized=True)) == c.Drive(
        left=50.0, right=-12.5, normalized=True
    )
    assert c.as_parsed(c.Drive(left=float("nan"), right=1.0)) is None  # the parser refuses it
    assert c.as_parsed(c.Drive(wheels=(c.WheelDrive(1, 1.0, 0.0),))) is None
    assert c.as_parsed(c.Step(time_s=0.1)) is None
