"""The control server over real TCP sockets (protocol.md sections 1-7, 16, 18).

Every test runs its own in-process lock-step server on port 0 (``server`` fixture), so the
world only moves when a test sends ``STEP``; nothing waits on the wall clock.
"""

from __future__ import annotations

import math
import re

import pytest

from helpers import (
    Client,
    ground_truth,
    segment_list,
    segments,
    sensor_lines,
    vec,
    wait_for,
)
from usarsim.protocol.messages import StartPoses, parse_message

NFO_ON_CONNECT = b"NFO {Gametype BotDeathMatch} {Level DM-USAR_yellow} {TimeLimit 0}\r\n"
ROBOT_GEO = (
    "GEO {Type GroundVehicle} {Name P2AT} {Dimensions 0.5238,0.4968,0.2913} {COG 0.0000,0.0000,0.0000} "
    "{WheelRadius 0.1300} {WheelSeparation 0.4712} {WheelBase 0.2884}"
)
ROBOT_CONF = (
    "CONF {Type GroundVehicle} {Name P2AT} {SteeringType SkidSteered} {Mass 14.0000} {MaxSpeed 5.3850} "
    "{MaxTorque 60.0000} {MaxFrontSteer 0.0000} {MaxRearSteer 0.0000}"
)
SCANNER_CONF = (
    "CONF {Type RangeScanner} {Name Scanner1} {MaxRange 20.0000} {MinRange 0.1000} {Resolution 0.0174} "
    "{Fov 3.1415} {Paning True} {Tilting False}"
)
SCANNER_GEO = (
    "GEO {Type RangeScanner} {Name Scanner1 Location 0.1440,0.0000,-0.0920 Orientation 0.0000,0.0000,0.0000 Mount HARD}"
)
# protocol.md 9.1: x, y, yaw of the P2AT sonar rings
SONAR_LAYOUT = {
    "F1": (0.145, -0.130, -1.5708),
    "F2": (0.185, -0.115, -0.8727),
    "F3": (0.220, -0.080, -0.5236),
    "F4": (0.240, -0.025, -0.1745),
    "F5": (0.240, 0.025, 0.1745),
    "F6": (0.220, 0.080, 0.5236),
    "F7": (0.185, 0.115, 0.8727),
    "F8": (0.145, 0.130, 1.5708),
    "R1": (-0.145, 0.130, 1.5708),
    "R2": (-0.185, 0.115, 2.2689),
    "R3": (-0.220, 0.080, 2.6180),
    "R4": (-0.240, 0.025, 2.9671),
    "R5": (-0.240, -0.025, -2.9671),
    "R6": (-0.220, -0.080, -2.6180),
    "R7": (-0.185, -0.115, -2.2689),
    "R8": (-0.145, -0.130, -1.5708),
}
SONAR_NAMES = list(SONAR_LAYOUT)


def init(client: Client, start: str = "PlayerStart1", name: str = "R1", class_name: str = "USARBot.P2AT") -> None:
    client.send(f"INIT {{ClassName {class_name}}} {{Name {name}}} {{Start {start}}}")


def spawn(client: Client, start: str = "PlayerStart1", name: str = "R1", settle: float = 0.6) -> list:
    """INIT and step until the robot rests on the floor; return the lines of that step."""
    client.nfo()
    init(client, start, name)
    lines = client.step(settle)
    assert sensor_lines(lines, "GroundTruth"), "the robot did not spawn"
    return lines


def last_gt(lines):
    gt = ground_truth(lines)
    assert gt, "no GroundTruth line"
    return gt[-1]


def horizontal_distance(a, b) -> float:
    return math.hypot(a[0] - b[0], a[1] - b[1])


# --------------------------------------------------------------------------- greeting and start poses


def test_nfo_on_connect_is_exact(server):
    with server.connect() as c:
        assert c.next_line().raw == NFO_ON_CONNECT


def test_getstartposes_lists_at_least_four_poses(server):
    with server.connect() as c:
        c.nfo()
        line = c.ask("GETSTARTPOSES", "NFO {StartPoses")
        assert line.raw.endswith(b"\r\n")
        msg = parse_message(line.text)
        assert isinstance(msg, StartPoses)
        assert len(msg.poses) >= 4
        assert segments(line.text)["StartPoses"] == str(len(msg.poses))
        assert len(segment_list(line.text)) == 2  # all poses in ONE segment (protocol.md 5.2)
        names = [p.name for p in msg.poses]
        assert "PlayerStart1" in names and len(set(names)) == len(names)


def test_init_by_start_name_and_by_copied_pose_put_the_robot_at_the_same_place(server_factory):
    """INIT {Start name} and INIT {Location}{Rotation} copied from the GETSTARTPOSES reply give
    byte-identical GroundTruth (two fresh servers, same seed)."""
    by_name, by_pose = server_factory(seed=5), server_factory(seed=5)
    with by_name.connect() as a, by_pose.connect() as b:
        a.nfo()
        b.nfo()
        poses = b.ask("GETSTARTPOSES", "NFO {StartPoses")
        tokens = segment_list(poses.text)[1].split()
        i = tokens.index("PlayerStart4")  # a pose with a yaw (0,0,1.57)
        location, rotation = tokens[i + 1], tokens[i + 2]
        assert rotation == "0.00,0.00,1.57"
        a.send("INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart4}")
        b.send(f"INIT {{ClassName USARBot.P2AT}} {{Name R1}} {{Location {location}}} {{Rotation {rotation}}}")
        la, lb = a.step(1.0), b.step(1.0)
        gta = [ln.text for ln in sensor_lines(la, "GroundTruth")]
        gtb = [ln.text for ln in sensor_lines(lb, "GroundTruth")]
        assert len(gta) == 11  # t = 0.0, 0.1, ... 1.0
        assert gta == gtb
        t0, loc0, ori0 = ground_truth(la)[0]
        assert loc0[:2] == pytest.approx(vec(location)[:2], abs=1e-4)
        assert ori0[2] == pytest.approx(1.57, abs=1e-3)


@pytest.mark.parametrize("class_name", ["USARBot.P2AT", "P2AT", "usarbot.p2at"])
def test_classname_variants_spawn_a_p2at(server, class_name):
    with server.connect() as c:
        c.nfo()
        init(c, class_name=class_name)
        assert c.ask("GETGEO {Type Robot}", "GEO").text == ROBOT_GEO
        lines = c.step(0.2)
        assert sensor_lines(lines, "GroundTruth") and sensor_lines(lines, "Sonar")
        assert server.robot_count() == 1


def test_unknown_classname_spawns_nothing_and_a_later_init_works(server):
    with server.connect() as c:
        c.nfo()
        init(c, class_name="USARBot.NoSuchBot")
        error, stepped = (ln.text for ln in c.step(0.2))  # nothing but the ERROR that says why
        assert error.startswith("ERROR {Command INIT} {Reason unknown robot class 'USARBot.NoSuchBot'")
        assert stepped == "STEPPED {Time 0.2000}"
        assert server.robot_count() == 0
        init(c)
        assert sensor_lines(c.step(0.2), "GroundTruth")
        assert server.robot_count() == 1


def test_moast_two_commands_in_one_write_and_mixed_case(server):
    with server.connect() as c:
        c.nfo()
        c.send_raw(b"GETSTARTPOSES\r\nINIT {Classname USARBot.P2AT} {Name R1} {Start PlayerStart1}\r\n")
        assert c.wait_line("NFO").text.startswith("NFO {StartPoses")
        start = last_gt(c.step(0.6))[1]
        c.send("Drive {left 2} {RIGHT 2}")
        end = last_gt(c.step(2.0))[1]
        assert end[0] - start[0] > 0.3  # it drove forward (+X at yaw 0)


@pytest.mark.parametrize("term", [b"\r\n", b"\n\r", b"\n", b"\r"], ids=["CRLF", "LFCR", "LF", "CR"])
def test_line_terminators(server, term):
    with server.connect() as c:
        c.nfo()
        # two commands in one write, then one command per write
        c.send_raw(b"INIT {ClassName USARBot.P2AT} {Start PlayerStart1}" + term + b"GETGEO {Type Robot}" + term)
        assert c.wait_line("GEO").text == ROBOT_GEO
        c.send_raw(b"GETCONF {Type Robot}" + term)
        assert c.wait_line("CONF").text == ROBOT_CONF
        c.send_raw(b"STEP {Time 0.2}" + term)
        lines = c.lines_until("STEPPED")
        assert lines[-1].text == "STEPPED {Time 0.2000}"
        assert sensor_lines(lines, "GroundTruth")


def test_a_command_split_across_two_writes(server):
    with server.connect() as c:
        c.nfo()
        c.send_raw(b"INIT {ClassName USAR")
        # the server holds the partial line until the rest arrives
        wait_for(
            lambda: (
                server.on_loop(lambda: [x.buffer.pending_bytes for x in server.app.control.connections.values()])
                == [20]
            ),
            what="the server to hold 20 pending bytes",
        )
        c.send_raw(b"Bot.P2AT} {Start PlayerStart1}\r\nGETSTA")
        wait_for(
            lambda: (
                server.on_loop(lambda: [x.buffer.pending_bytes for x in server.app.control.connections.values()]) == [6]
            ),
            what="the server to hold 6 pending bytes",
        )
        c.send_raw(b"RTPOSES\r\n")
        assert c.next_line().text.startswith("NFO {StartPoses")
        assert c.ask("GETGEO {Type Robot}", "GEO").text == ROBOT_GEO
        assert server.robot_count() == 1


# --------------------------------------------------------------------------- GETGEO / GETCONF


def wait_alive(server, count: int = 1) -> None:
    """Wait until ``count`` sessions have a spawned robot (the spawn runs on the simulation
    thread and is confirmed to the session asynchronously)."""

    def alive() -> int:
        return server.on_loop(
            lambda: sum(
                1
                for x in server.app.control.connections.values()
                if x.session is not None and x.session.state == "alive"
            )
        )

    wait_for(lambda: alive() == count, what=f"{count} spawned robot(s)")


def wait_no_spawn_in_flight(server) -> None:
    wait_for(
        lambda: server.on_loop(
            lambda: (
                not any(
                    x.session is not None and x.session.state == "spawning"
                    for x in server.app.control.connections.values()
                )
            )
        ),
        what="no spawn in flight",
    )


@pytest.fixture
def robot(server):
    """A client with a spawned P2AT at PlayerStart1, simulated time still 0."""
    c = server.connect()
    c.nfo()
    init(c)
    wait_alive(server)
    return c


def test_robot_geo_and_conf_are_exact(robot):
    assert robot.ask("GETGEO {Type Robot}", "GEO").raw == (ROBOT_GEO + "\r\n").encode()
    assert robot.ask("GETCONF {Type Robot}", "CONF").raw == (ROBOT_CONF + "\r\n").encode()
    # MOAST asks with the robot's name; the reply carries the class name (protocol.md 5.1)
    assert robot.ask("GETCONF {Type Robot} {Name R1}", "CONF").text == ROBOT_CONF
    assert robot.ask("getgeo {type robot}", "GEO").text == ROBOT_GEO


def test_sonar_geo_packs_sixteen_items_f1_first(robot):
    line = robot.ask("GETGEO {Type Sonar}", "GEO").text
    segs = segment_list(line)
    assert segs[0] == "Type Sonar"
    items = segs[1:]
    assert len(items) == 16
    assert items[1] == "Name F2 Location 0.1850,-0.1150,0.0000 Orientation 0.0000,0.0000,-0.8727 Mount HARD"
    assert items[0] == "Name F1 Location 0.1450,-0.1300,0.0000 Orientation 0.0000,0.0000,-1.5708 Mount HARD"
    for item, name in zip(items, SONAR_NAMES):
        tok = item.split(" ")
        assert len(tok) == 8 and tok[0] == "Name" and tok[2] == "Location" and tok[4] == "Orientation"
        assert tok[1] == name
        x, y, yaw = SONAR_LAYOUT[name]
        assert vec(tok[3]) == pytest.approx((x, y, 0.0), abs=1e-4)
        assert vec(tok[5]) == pytest.approx((0.0, 0.0, yaw), abs=2e-4)
        assert tok[6:] == ["Mount", "HARD"]


def test_sonar_conf_repeats_groups_f1_first(robot):
    line = robot.ask("GETCONF {Type Sonar}", "CONF").text
    segs = segment_list(line)
    assert segs[0] == "Type Sonar"
    groups = [segs[i : i + 4] for i in range(1, len(segs), 4)]
    assert [g[0] for g in groups] == [f"Name {n}" for n in SONAR_NAMES]
    for g in groups:
        assert g[1:] == ["MaxRange 5.0000", "MinRange 0.1000", "BeamAngle 0.3491"]


def test_range_scanner_conf_and_geo(robot):
    assert robot.ask("GETCONF {Type RangeScanner}", "CONF").text == SCANNER_CONF
    assert robot.ask("GETGEO {Type RangeScanner}", "GEO").text == SCANNER_GEO
    # type and name match case-insensitively; the reply uses the canonical spelling
    assert robot.ask("GETCONF {Type rangescanner} {Name SCANNER1}", "CONF").text == SCANNER_CONF


@pytest.mark.parametrize(
    "query, reply",
    [
        (
            "GETCONF {Type Odometry}",
            "CONF {Type Odometry} {Name Odometry} {ScanInterval 0.2000} {EncoderResolution 0.0099} {TrackWidth 0.5520}",
        ),
        ("GETCONF {Type GroundTruth}", "CONF {Type GroundTruth} {Name GroundTruth} {ScanInterval 0.1000}"),
        ("GETCONF {Type INS}", "CONF {Type INS} {Name INS} {ScanInterval 0.2000}"),
        (
            "GETGEO {Type Odometry}",
            "GEO {Type Odometry} {Name Odometry Location 0.0000,0.0000,0.0000 Orientation 0.0000,0.0000,0.0000 Mount HARD}",
        ),
        (
            "GETGEO {Type Encoder}",
            "GEO {Type Encoder} {Name ECLeft Location 0.0000,0.0000,0.0000 Orientation 0.0000,0.0000,0.0000 Mount LeftFWheel} "
            "{Name ECRight Location 0.0000,0.0000,0.0000 Orientation 0.0000,0.0000,0.0000 Mount RightFWheel}",
        ),
    ],
)
def test_other_items_geo_and_conf(robot, query, reply):
    assert robot.ask(query, query[3:7]).text == reply


def test_encoder_conf_groups(robot):
    segs = segment_list(robot.ask("GETCONF {Type Encoder}", "CONF").text)
    assert segs[0] == "Type Encoder"
    assert [s for s in segs if s.startswith("Name")] == ["Name ECLeft", "Name ECRight"]
    assert all(s.startswith("Resolution 0.017") for s in segs if s.startswith("Resolution"))


def test_encoder_conf_matches_the_ut_example(robot):
    assert (
        robot.ask("GETCONF {Type Encoder}", "CONF").text
        == "CONF {Type Encoder} {Name ECLeft} {Resolution 0.0174} {Name ECRight} {Resolution 0.0174}"
    )


def test_geo_and_conf_by_name(robot):
    assert (
        robot.ask("GETGEO {Type Sonar} {Name F5}", "GEO").text
        == "GEO {Type Sonar} {Name F5 Location 0.2400,0.0250,0.0000 Orientation 0.0000,0.0000,0.1745 Mount HARD}"
    )
    assert (
        robot.ask("GETCONF {Type Sonar} {Name r8}", "CONF").text
        == "CONF {Type Sonar} {Name R8} {MaxRange 5.0000} {MinRange 0.1000} {BeamAngle 0.3491}"
    )
    assert robot.ask("GETCONF {Type Encoder} {Name ECRight}", "CONF").text.startswith(
        "CONF {Type Encoder} {Name ECRight} {Resolution "
    )
    assert "ECLeft" not in robot.history[-1].text


@pytest.mark.parametrize(
    "query, reply",
    [
        ("GETGEO {Type Gripper}", "GEO {Type Gripper}"),
        ("GETCONF {Type Gripper}", "CONF {Type Gripper}"),
        ("GETCONF {Type Camera} {Name Camera2}", "CONF {Type Camera} {Name Camera2}"),
        ("GETGEO {Type Sonar} {Name X9}", "GEO {Type Sonar} {Name X9}"),
        ("GETCONF {Type MisPkg} {Name TeleMaxArm}", "CONF {Type MisPkg} {Name TeleMaxArm}"),
    ],
)
def test_bare_replies_when_nothing_matches(robot, query, reply):
    line = robot.ask(query, query[3:7])
    assert line.raw == (reply + "\r\n").encode()


# --------------------------------------------------------------------------- periodic messages


def test_every_sensor_line_arrives_crlf_terminated_with_a_name(robot):
    lines = robot.step(0.4)
    for ln in lines:
        assert ln.raw.endswith(b"\r\n") and b"\r" not in ln.raw[:-2] and b"\n" not in ln.raw[:-2], ln.raw
    by_type = {
        t: sensor_lines(lines, t) for t in ("Sonar", "RangeScanner", "Odometry", "GroundTruth", "INS", "Encoder")
    }
    for t, found in by_type.items():
        assert found, f"no SEN line of type {t}"
        for ln in found:
            assert "{Name" in ln.text, ln.text
            assert ln.text.startswith("SEN {Time ")

    sonar = segment_list(by_type["Sonar"][0].text)
    assert sonar[:2][1] == "Type Sonar"
    items = sonar[2:]
    assert [i.split()[1] for i in items] == SONAR_NAMES
    for i in items:
        name_kw, _, range_kw, value = i.split()
        assert name_kw == "Name" and range_kw == "Range"
        assert 0.1 <= float(value) <= 5.0

    scan = segments(by_type["RangeScanner"][0].text)
    assert scan["Name"] == "Scanner1" and scan["Resolution"] == "0.0174" and scan["FOV"] == "3.1415"
    ranges = vec(scan["Range"])
    assert len(ranges) == 181
    assert all(0.1 <= r <= 20.0 for r in ranges)

    odo = segments(by_type["Odometry"][0].text)
    assert odo["Name"] == "Odometry" and len(vec(odo["Pose"])) == 3

    gt = segments(by_type["GroundTruth"][-1].text)
    assert gt["Name"] == "GroundTruth"
    assert vec(gt["Location"])[:2] == pytest.approx((-9.5, 0.0), abs=0.01)
    ins = segments(by_type["INS"][-1].text)
    assert ins["Name"] == "INS" and len(vec(ins["Location"])) == 3 and len(vec(ins["Orientation"])) == 3

    enc = segment_list(by_type["Encoder"][0].text)[2:]
    assert [e.split()[:2] for e in enc] == [["Name", "ECLeft"], ["Name", "ECRight"]]
    assert all(e.split()[2] == "Tick" and re.fullmatch(r"-?\d+", e.split()[3]) for e in enc)


def test_sensor_rates_follow_scan_intervals(robot):
    robot.step(0.4)
    lines = robot.step(1.0)
    assert len(sensor_lines(lines, "GroundTruth")) == 10  # 0.1 s
    assert len(sensor_lines(lines, "Encoder")) == 10  # 0.1 s
    assert len(sensor_lines(lines, "RangeScanner")) == 5  # 0.2 s
    assert len(sensor_lines(lines, "Sonar")) == 5
    assert len([ln for ln in lines if ln.text.startswith("STA ")]) == 5  # status every 0.2 s
    times = [float(segments(ln.text)["Time"]) for ln in sensor_lines(lines, "GroundTruth")]
    assert times == pytest.approx([0.5 + 0.1 * k for k in range(10)], abs=1e-6)


def test_sta_battery_counts_down_from_1200(robot):
    lines = robot.step(0.2) + robot.step(5.0)
    sta = [ln for ln in lines if ln.text.startswith("STA ")]
    assert sta[0].text == (
        "STA {Type GroundVehicle} {Time 0.00} {FrontSteer 0.0000} {RearSteer 0.0000} "
        "{LightToggle False} {LightIntensity 0} {Battery 1200} {View 0}"
    )  # its camera: MultiView tile 0
    battery = [int(segments(ln.text)["Battery"]) for ln in sta]
    assert battery == sorted(battery, reverse=True)
    assert battery[0] == 1200
    assert battery[-1] == 1195  # 5.2 s later: ceil(1200 - 5.2)
    assert all(ln.raw.endswith(b"\r\n") for ln in sta)


def test_light_toggle_shows_in_sta(robot):
    robot.send("DRIVE {Light True}")
    sta = [ln for ln in robot.step(0.4) if ln.text.startswith("STA ")]
    assert segments(sta[-1].text)["LightToggle"] == "True"


# --------------------------------------------------------------------------- SET


def odometry_poses(lines):
    return [vec(segments(ln.text)["Pose"]) for ln in sensor_lines(lines, "Odometry")]


def test_set_odometry_reset(robot):
    robot.step(0.6)
    robot.send("DRIVE {Left 3} {Right 3}")
    driven = odometry_poses(robot.step(2.0))
    assert driven[-1][0] > 0.3
    robot.send("DRIVE {Left 0} {Right 0}")
    robot.step(0.6)
    robot.send("SET {Type Odometry} {Opcode RESET}")
    lines = robot.step(0.6)
    res = [ln for ln in lines if ln.text.startswith("RES ")]
    assert len(res) == 1
    assert re.fullmatch(r"RES \{Time \d+\.\d\d\} \{Type Odometry\} \{Name Odometry\} \{Status OK\}", res[0].text)
    after = odometry_poses(lines[lines.index(res[0]) :])
    assert after
    for x, y, theta in after:
        assert abs(x) < 0.01 and abs(y) < 0.01 and abs(math.remainder(theta, 2 * math.pi)) < 0.01


@pytest.mark.parametrize(
    "command, reply",
    [
        ("SET {Type Foo} {Name Bar} {Opcode Baz}", "{Type Foo} {Name Bar} {Status Failed}"),
        ("SET {Type Odometry} {Name Nope} {Opcode RESET}", "{Type Odometry} {Name Nope} {Status Failed}"),
        ("SET {Type Odometry} {Name Odometry} {Opcode Fly}", "{Type Odometry} {Name Odometry} {Status Failed}"),
    ],
)
def test_set_on_unknown_item_or_opcode_fails(robot, command, reply):
    robot.send(command)
    res = [ln.text for ln in robot.step(0.2) if ln.text.startswith("RES ")]
    assert len(res) == 1
    assert re.fullmatch(r"RES \{Time \d+\.\d\d\} " + re.escape(reply), res[0]), res[0]


def test_drive_right_after_init_in_one_write_is_applied(server):
    with server.connect() as c:
        c.nfo()
        c.send_raw(
            b"INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}\r\n"
            b"DRIVE {Left 3} {Right 3}\r\nSTEP {Time 2.0}\r\n"
        )
        lines = c.lines_until("STEPPED")
        gts = ground_truth(lines)
        assert gts[-1][1][0] - gts[0][1][0] > 0.3


# --------------------------------------------------------------------------- bad input


MALFORMED = {
    "unclosed-init": b"INIT {ClassName\r\n",
    "drive-not-a-number": b"DRIVE {Left abc} {Right 1}\r\n",
    "binary-garbage": bytes(range(256)).replace(b"\r", b"").replace(b"\n", b"") + b"\r\n",
    "braces": b"}}{{ {} {Left 1}\r\nDRIVE {Left {1}}\r\nGETGEO {Type\r\n",
    "drive-nan-inf": b"DRIVE {Left nan} {Right inf}\r\n",
    "drive-overflow": b"DRIVE {Left 1e999} {Right -1e999}\r\n",
    "step-bad": b"STEP {Time -1}\r\nSTEP {Time abc}\r\nSTEP\r\n",
    "init-bad-location": b"INIT {ClassName USARBot.P2AT} {Location 1e9,0,0}\r\n"
    b"INIT {ClassName USARBot.P2AT} {Location nan,0,0}\r\n",
}


@pytest.mark.parametrize("payload", list(MALFORMED.values()), ids=list(MALFORMED))
def test_malformed_input_keeps_connection_and_server_up(server, payload):
    with server.connect() as a:
        a.nfo()
        a.send_raw(payload)
        # only the probe's reply, after an ERROR for each request that waits for an answer
        *errors, probe = [ln.type for ln in a.sync()]
        assert probe == "NFO" and set(errors) <= {"ERROR"}
        wait_no_spawn_in_flight(server)  # a refused INIT (bad location) is refused asynchronously
        init(a, "PlayerStart1", "A")
        before = last_gt(a.step(0.6))[1]
        a.send_raw(payload)  # again, now with a robot alive
        a.sync()
        lines = a.step(1.0)
        after = last_gt(lines)[1]
        assert horizontal_distance(before, after) < 0.002  # nothing made it move
        for ln in lines:
            if ln.type != "ERROR":  # a reason may say "finite"
                assert "nan" not in ln.text.lower() and "inf" not in ln.text.lower(), ln.text
        with server.connect() as b:  # the server accepts and serves another client
            spawn(b, "PlayerStart3", "B")
        assert a.ask("GETGEO {Type Robot}", "GEO").text == ROBOT_GEO


def test_a_100kb_line_is_dropped_and_the_next_line_served(server):
    with server.connect() as c:
        c.nfo()
        c.send_raw(b"DRIVE " + b"x" * 100_000)
        c.send_raw(b"{Left 1}\r\nGETSTARTPOSES\r\n")
        assert c.next_line().text.startswith("NFO {StartPoses")
        c.send_raw(b"A" * 100_000 + b"\r\n")
        init(c)
        assert c.ask("GETGEO {Type Robot}", "GEO").text == ROBOT_GEO
        assert sensor_lines(c.step(0.2), "GroundTruth")
    with server.connect() as other:
        other.nfo()
        assert other.ask("GETSTARTPOSES", "NFO").text.startswith("NFO {StartPoses")


def test_unknown_commands_are_ignored(server):
    with server.connect() as c:
        c.nfo()
        init(c)
        c.send("FOO {Bar 1}")
        c.send("HELLO")
        c.send("MISPKG {Name CameraPanTilt} {Link 1} {Value 1.0}")  # known, but this robot has none
        assert [ln.type for ln in c.sync()] == ["NFO"]
        assert sensor_lines(c.step(0.2), "GroundTruth")


def test_commands_before_init_are_ignored(server):
    with server.connect() as c:
        c.nfo()
        c.send("DRIVE {Left 5} {Right 5}")
        c.send("GETGEO {Type Robot}")
        c.send("GETCONF {Type Sonar}")
        c.send("SET {Type Odometry} {Opcode RESET}")
        # the queries are answered with an ERROR each (README "Errors"); the DRIVE is silent
        assert [ln.type for ln in c.sync()] == ["ERROR", "ERROR", "ERROR", "NFO"]
        assert [ln.text for ln in c.step(0.2)] == ["STEPPED {Time 0.2000}"]  # no RES, no STA, no SEN
        init(c)
        start = last_gt(c.step(0.4))[1]
        end = last_gt(c.step(1.0))[1]
        assert horizontal_distance(start, end) < 0.005  # the early DRIVE did not stick


def test_a_second_init_is_ignored(server):
    with server.connect() as c:
        c.nfo()
        init(c, "PlayerStart1", "R1")
        first = last_gt(c.step(0.4))[1]
        c.send("INIT {ClassName USARBot.P2AT} {Name R2} {Start PlayerStart7}")
        lines = c.step(0.5)
        assert server.robot_count() == 1
        gts = ground_truth(lines)
        assert len(gts) == 5  # one robot's GroundTruth only
        assert all(horizontal_distance(loc, first) < 0.01 for _, loc, _ in gts)


def test_closing_the_socket_removes_the_robot(server):
    a = server.connect()
    b = server.connect()
    spawn(a, "PlayerStart1", "A")
    spawn(b, "PlayerStart7", "B")
    assert server.robot_count() == 2
    a.close()
    wait_for(lambda: server.robot_count() == 1, what="the robot of the closed connection to be removed")
    lines = b.step(1.0)
    assert len(ground_truth(lines)) == 10
    b.send("DRIVE {Left 2} {Right 2}")
    p0 = last_gt(b.step(0.5))[1]
    p1 = last_gt(b.step(1.0))[1]
    assert horizontal_distance(p0, p1) > 0.1  # B still drives
    with server.connect() as c:
        assert c.next_line().raw == NFO_ON_CONNECT
        init(c, "PlayerStart1", "C")  # the place A left is free again
        assert sensor_lines(c.step(0.2), "GroundTruth")
    b.close()
    wait_for(lambda: server.robot_count() == 0, what="every robot to be removed")


def test_64_connections_accepted_the_65th_refused(server):
    clients = []
    try:
        for _ in range(64):
            c = server.connect()
            clients.append(c)
            assert c.next_line().raw == NFO_ON_CONNECT
        extra = server.connect()
        assert extra.wait_closed() == b""  # closed without a greeting
        extra.close()
        # the 64 are still served
        assert clients[0].sync()[-1].text.startswith("NFO {StartPoses")
        assert clients[-1].sync()[-1].text.startswith("NFO {StartPoses")
        # a freed place can be taken again
        clients.pop(0).close()
        wait_for(lambda: server.connection_count() == 63, what="the server to notice the closed connection")
        again = server.connect()
        clients.append(again)
        assert again.next_line().raw == NFO_ON_CONNECT
    finally:
        for c in clients:
            c.close()
