"""The shipped robots that carry the manual's effecters (section 11): GripperP2AT's Pioneer
Gripper (11.1) closes on a brick, lifts it, carries it and lets it go; RollerP2AT's roller
table (11.3) carries a parcel along its top and off the front.  Over real sockets, in
lock-step servers, in small test worlds written here."""

from __future__ import annotations

import re

import pytest

from helpers import ground_truth

# A clay brick (ASTM C216 modular brick: 7 5/8 x 3 5/8 x 2 1/4 in = 0.194 x 0.092 x 0.057 m) of
# 2.3 kg, the heaviest of the arenas' bricks, lying lengthwise between the open paddles of a
# GripperP2AT at the origin (its paddles reach 0.305..0.465 m ahead of the robot's centre).
BRICK_WORLD = """\
name: BrickYard
description: a brick in front of a robot with a gripper (tests only)
floor: {center: [0, 0], size: [10, 10]}
materials: {brick: {rgba: [0.7, 0.3, 0.2, 1], friction: 0.8}}
objects:
  - {name: brick, shape: box, center: [0.41, 0.0, -0.0285], size: [0.194, 0.092, 0.057], mass_kg: 2.3,
     material: brick}
start_poses:
  - {name: Here, location: [0.0, 0.0, -0.2], rotation: [0, 0, 0]}
"""
# A parcel on the roller table of a RollerP2AT at the origin, towards the back of the table.
PARCEL_WORLD = """\
name: Dispatch
description: a parcel on a robot's roller table (tests only)
floor: {center: [0, 0], size: [10, 10]}
objects:
  - {name: parcel, shape: box, center: [-0.12, 0.0, -0.40], size: [0.15, 0.15, 0.1], mass_kg: 1.0}
start_poses:
  - {name: Here, location: [0.0, 0.0, -0.2], rotation: [0, 0, 0]}
"""


def _serve(server_factory, tmp_path, text: str, name: str):
    from usarsim.config.world_file import load_world

    path = tmp_path / f"{name}.yaml"
    path.write_text(text)
    srv = server_factory(world=load_world(path))
    c = srv.connect()
    c.nfo()
    return srv, c


def _body(srv, name: str) -> tuple[float, float, float]:
    """A movable object's position (MuJoCo frame: z up)."""
    return srv.on_sim(lambda sim: tuple(float(v) for v in sim.data.xpos[sim.model.body(f"movable/{name}").id]))


def _replies(c, line: str, seconds: float) -> list[str]:
    c.send(line)
    return [ln.text for ln in c.step(seconds) if ln.text.startswith(("RES", "EFF"))]


def test_the_gripper_p2at_grasps_lifts_carries_and_drops_a_brick(server_factory, tmp_path):
    srv, c = _serve(server_factory, tmp_path, BRICK_WORLD, "BrickYard")
    c.send("INIT {ClassName USARBot.GripperP2AT} {Name Picker} {Start Here}")
    c.step(1.5)
    assert c.ask("GETCONF {Type Gripper}", "CONF").text == "CONF {Type Gripper} {Name Gripper}"
    x0, _, z0 = _body(srv, "brick")
    assert z0 == pytest.approx(0.0285, abs=0.005)  # on the floor, between the paddles

    got = _replies(c, "SET {Type Gripper} {Name Gripper} {Opcode Open}", 2.5)
    assert re.fullmatch(r"RES \{Time \d+\.\d{2}\} \{Type Gripper\} \{Name Gripper\} \{Status OK\}", got[0]), got
    assert got[1].endswith("{Type Gripper} {Name Gripper} {Status OPEN}"), got
    got = _replies(c, "SET {Type Gripper} {Name Gripper} {Opcode Close}", 5.0)  # the paddles at 2 cm/s
    assert got[1].endswith("{Status CLOSED}"), got

    # the lift, mission package GripperLift, raises the paddles to its top, 10 cm, at 2 cm/s
    c.send("MISPKG {Name GripperLift} {Link 1} {Value 0.10}")
    c.step(6.0)
    _, _, z1 = _body(srv, "brick")
    assert z1 - z0 > 0.08  # lifted with the paddles, 2.3 kg (the lift's servo sags a centimetre under it)

    # the robot carries it 2 m at 0.3 m/s (2.3077 rad/s x 0.13 m), and it stays in the paddles
    gts = ground_truth(c.step(0.2))
    rx0 = gts[-1][1][0]
    c.send("DRIVE {Left 2.3077} {Right 2.3077}")
    for _ in range(7):
        gts = ground_truth(c.step(1.0))
        moved = gts[-1][1][0] - rx0
        bx, _, bz = _body(srv, "brick")
        assert bx - x0 == pytest.approx(moved, abs=0.02) and bz - z1 == pytest.approx(0.0, abs=0.003), (moved, bx, bz)
    c.send("DRIVE {Left 0} {Right 0}")
    c.step(0.5)
    assert moved > 2.0

    # open: the brick drops to the floor
    got = _replies(c, "SET {Type Gripper} {Name Gripper} {Opcode Grip} {Params 0}", 2.5)
    assert got[1].endswith("{Status OPEN}"), got
    assert _body(srv, "brick")[2] == pytest.approx(z0, abs=0.01)


def test_the_roller_p2at_carries_a_parcel_off_its_front(server_factory, tmp_path):
    srv, c = _serve(server_factory, tmp_path, PARCEL_WORLD, "Dispatch")
    c.send("INIT {ClassName USARBot.RollerP2AT} {Name Porter} {Start Here}")
    c.step(1.5)
    assert c.ask("GETCONF {Type RollerTable}", "CONF").text.startswith(
        "CONF {Type RollerTable} {Name Roller} {MaxSpeed "
    )
    x0, _, z0 = _body(srv, "parcel")
    assert z0 > 0.3  # it lies on the table on the robot's back (MuJoCo z is up)
    c.step(1.0)
    assert abs(_body(srv, "parcel")[0] - x0) < 0.01  # the rollers stand: it stays

    got = _replies(c, "SET {Type RollerTable} {Name Roller} {Opcode Roll} {Params 0.2}", 1.0)
    assert got and got[0].endswith("{Type RollerTable} {Name Roller} {Status OK}"), got
    x1, _, z1 = _body(srv, "parcel")
    assert x1 - x0 == pytest.approx(0.2, abs=0.06) and z1 == pytest.approx(z0, abs=0.01)  # rolled along the top
    c.step(3.0)
    assert _body(srv, "parcel")[2] < 0.1  # off the front, on the floor
    got = _replies(c, "SET {Type RollerTable} {Name Roller} {Opcode Stop}", 0.1)
    assert got[0].endswith("{Status OK}")


@pytest.mark.parametrize("speed", [0.1, 0.3, -0.2])
def test_the_roller_table_carries_a_resting_load_at_its_speed(server_factory, tmp_path, speed):
    """The load's speed along the table, from 0.2 s after the rollers start, is within 10 % of
    what they were told (the robot stands)."""
    srv, c = _serve(
        server_factory, tmp_path, PARCEL_WORLD.replace("[-0.12, 0.0, -0.40]", "[0.0, 0.0, -0.40]"), "Dispatch"
    )
    c.send("INIT {ClassName USARBot.RollerP2AT} {Name Porter} {Start Here}")
    c.step(1.5)
    c.send(f"SET {{Type RollerTable}} {{Name Roller}} {{Opcode Roll}} {{Params {speed}}}")
    c.step(0.2)
    xs = []
    for _ in range(5):
        xs.append(_body(srv, "parcel")[0])
        c.step(0.1)
    for a, b in zip(xs, xs[1:]):
        assert (b - a) / 0.1 == pytest.approx(speed, rel=0.10), xs


def _jaws(c, robot: str, start: str, arm: str, fingers: list[int]) -> None:
    """A robot whose jaws are its Gripper: SET and ACT open and close them (RES, then EFF),
    CONF and GEO list it, and the finger links of its arm move."""
    c.send(f"INIT {{ClassName USARBot.{robot}}} {{Name J}} {{Start {start}}}")
    c.step(1.0)
    assert c.ask("GETCONF {Type Gripper}", "CONF").text == "CONF {Type Gripper} {Name Gripper}"
    assert c.ask("GETGEO {Type Gripper}", "GEO").text.startswith("GEO {Type Gripper} {Name Gripper Location ")
    got = _replies(c, "SET {Type Gripper} {Name Gripper} {Opcode Open}", 5.0)
    assert got[0].endswith("{Type Gripper} {Name Gripper} {Status OK}") and got[1].endswith("{Status OPEN}"), got
    opened = _links(c, arm, fingers)
    assert all(v > 0.5 for v in opened), opened
    got = _replies(c, f"ACT {{Name {arm}}} {{Gripper 1}}", 5.0)
    assert got[0].endswith("{Type Gripper} {Name Gripper} {Status OK}") and got[1].endswith("{Status CLOSED}"), got
    closed = _links(c, arm, fingers)
    assert all(v < 0.05 for v in closed), closed


def _links(c, arm: str, links: list[int]) -> list[float]:
    """The values MISSTA reports of links of a mission package."""
    line = next(
        ln.text for ln in reversed(c.step(0.2)) if ln.text.startswith("MISSTA") and f"{{Name {arm}}}" in ln.text
    )
    return [float(re.search(r"\{Link %d\} \{Value (-?[\d.]+)\}" % k, line).group(1)) for k in links]


def test_the_telemax_jaws_are_a_gripper(server):
    c = server.connect()
    c.nfo()
    _jaws(c, "TeleMax", "PlayerStart1", "TeleMaxArm", [8, 9])


def test_the_talon_jaw_is_a_gripper(server):
    c = server.connect()
    c.nfo()
    _jaws(c, "Talon", "PlayerStart1", "TalonArm", [4])
