"""Typed values across the protocol boundary: CONF fields printed by the protocol layer
(protocol.md 6.7), the numbers of a SET's Params (5.4), and the typed results of an
operation turned into RES and EFF words (6.5, 6.6)."""

from __future__ import annotations

import pytest

from usarsim.protocol import messages as M
from usarsim.protocol.commands import format_command, parse_command
from usarsim.protocol.outputs import message_for
from usarsim.readings import (
    CommandResult,
    EffecterState,
    PackageLink,
    PackageState,
    RangeItem,
    RangeReading,
    RobotStatus,
    ZoomResult,
)

# --------------------------------------------------------------------------- CONF values


@pytest.mark.parametrize(
    "value, text",
    [
        (True, "True"),
        (False, "False"),
        (7, "7"),
        (-3, "-3"),
        (0.2, "0.2000"),
        (3.14159265, "3.1416"),
        (-0.0, "0.0000"),
        ((0.0174, 0.0349), "0.0174,0.0349"),
        ((1, 2.5), "1.0000,2.5000"),  # integers in a sequence print as numbers at 4 decimals
        ((True, "x"), "True,x"),
        ("SkidSteered", "SkidSteered"),
        ("", ""),
    ],
)
def test_conf_values_are_printed_as_usarsim_did(value, text):
    assert M.format_value(value) == text


def test_a_conf_line_from_typed_fields():
    msg = M.ItemConfiguration(
        item_type="RangeScanner",
        items=(
            M.ItemConf(
                name="Scanner1",
                fields=(
                    ("MaxRange", 20.0),
                    ("MinRange", 0.1),
                    ("Resolution", 0.0174),
                    ("Fov", 3.1415),
                    ("Paning", True),
                    ("Tilting", False),
                ),
            ),
        ),
    )
    assert M.format_message(msg) == (
        "CONF {Type RangeScanner} {Name Scanner1} {MaxRange 20.0000} {MinRange 0.1000} "
        "{Resolution 0.0174} {Fov 3.1415} {Paning True} {Tilting False}\r\n"
    )


def test_a_conf_line_read_back_prints_the_same():
    line = "CONF {Type Encoder} {Name ECLeft} {Resolution 0.0174} {Name ECRight} {Resolution 0.0174}"
    back = M.parse_message(line)
    assert M.format_message(back) == line + "\r\n"


# --------------------------------------------------------------------------- SET Params numbers


@pytest.mark.parametrize(
    "line, values",
    [
        ("SET {Type Camera} {Name Camera} {Opcode Zoom} {Params 0.5}", (0.5,)),
        ("SET {Type Camera} {Name cam} {Opcode Zoom} {0.87}", (0.87,)),  # the Player driver's bare number
        ("SET {Type INS} {Name INS} {Opcode POSE} {Params 1.0,2.0,-0.5,0,0,0.5}", (1.0, 2.0, -0.5, 0.0, 0.0, 0.5)),
        ("SET {Type Joint} {Name FRFlipper} {Opcode Angle} {Params 0.5, 0}", (0.5, 0.0)),
        ("SET {Type Joint} {Name FRFlipper} {Opcode Angle} {Params 1 2 3}", (1.0, 2.0, 3.0)),
        ("SET {Type RFID} {Name RFID} {Opcode Write} {Params 11137 victim is here}", None),  # text
        ("SET {Type INS} {Name INS} {Opcode POSE} {Params 1,2,3,4,5,nan}", None),  # not finite
        ("SET {Type Camera} {Name Camera} {Opcode Zoom} {Params inf}", None),
        ("SET {Type Odometry} {Opcode RESET}", None),  # no Params
        ("SET {Type Gripper} {Name G} {Opcode Grip} {Params}", None),  # empty Params
    ],
)
def test_set_params_numbers(line, values):
    cmd = parse_command(line)
    assert cmd.values == values


def test_set_keeps_its_params_text_for_the_round_trip():
    line = "SET {Type RFID} {Name RFID} {Opcode Write} {Params 11137 victim  is here}"
    cmd = parse_command(line)
    assert cmd.params == "11137 victim  is here" and cmd.values is None
    assert format_command(cmd) == line + "\r\n"
    zoom = parse_command("SET {Type Camera} {Name Camera} {Opcode Zoom} {Params 0.5}")
    assert format_command(zoom) == "SET {Type Camera} {Name Camera} {Opcode Zoom} {Params 0.5}\r\n"


# --------------------------------------------------------------------------- results -> RES / EFF words


def line_of(value, time=20.1) -> str:
    return M.format_message(message_for(value, time))


def test_an_operation_result_becomes_an_res_line():
    assert (
        line_of(CommandResult("Odometry", "Odometry", ok=True))
        == "RES {Time 20.10} {Type Odometry} {Name Odometry} {Status OK}\r\n"
    )
    assert (
        line_of(CommandResult("Foo", "Bar", ok=False)) == "RES {Time 20.10} {Type Foo} {Name Bar} {Status Failed}\r\n"
    )
    read = line_of(CommandResult("RFID", "RFID", ok=True, extra=(("ID", 11137), ("Mem", "victim here"))))
    assert read == "RES {Time 20.10} {Type RFID} {Name RFID} {Status OK} {ID 11137} {Mem victim here}\r\n"
    assert line_of(CommandResult("RFID", "RFID", ok=True, extra=(("ID", 7), ("Mem", "")))).endswith("{ID 7} {Mem }\r\n")


def test_res_words_read_back():
    for ok, word in ((True, "OK"), (False, "Failed")):
        back = M.parse_message(line_of(CommandResult("RFIDReleaser", "Gun", ok=ok))[:-2])
        assert isinstance(back, M.Result) and back.status == word and back.name == "Gun"


def test_an_effecter_state_becomes_an_eff_line():
    assert (
        line_of(EffecterState("Gripper", "Gripper1", closed=False))
        == "EFF {Time 20.1000} {Type Gripper} {Name Gripper1} {Status OPEN}\r\n"
    )
    closed = line_of(EffecterState("Gripper", "Gripper1", closed=True))
    assert closed == "EFF {Time 20.1000} {Type Gripper} {Name Gripper1} {Status CLOSED}\r\n"
    back = M.parse_message(closed[:-2])
    assert isinstance(back, M.EffecterStatus) and back.status == "CLOSED"


def test_a_zoom_result_becomes_a_camera_res_line():
    line = line_of(ZoomResult((("Camera", 0.5, True), ("Omni", 6.2832, False))), 5.0)
    assert line == (
        "RES {Time 5.00} {Type Camera} {Name Camera} {FOV 0.5000} {Status OK} "
        "{Name Omni} {FOV 6.2832} {Status Failed}\r\n"
    )
    back = M.parse_message(line[:-2])
    assert [(c.name, c.status) for c in back.cameras] == [("Camera", "OK"), ("Omni", "Failed")]


def test_other_outputs_keep_their_messages():
    ground, aerial = RobotStatus("GroundVehicle", battery_s=100), RobotStatus("AerialVehicle", battery_s=100)
    assert message_for(ground, 1.0) == M.StatusMessage(1.0, ground)  # the status is the message's payload
    assert message_for(aerial, 1.0) == M.StatusMessage(1.0, aerial)
    pkg = PackageState("CameraPanTilt", (PackageLink(1, 0.1, 0.0),))
    assert message_for(pkg, 1.0) == M.MisPkgMessage(1.0, pkg)  # the package's state is the payload
    sen = message_for(RangeReading("Sonar", (RangeItem("F1", 1.5),)), None)
    assert M.format_message(sen) == "SEN {Type Sonar} {Name F1 Range 1.5000}\r\n"
