"""Small wire details over real sockets: a blank RFID tag's memory (protocol.md 5.4, 6.3) and
the mounts in the GEO of encoders and odometry (protocol.md 6.8)."""

from __future__ import annotations

import re

import pytest

from helpers import segment_list
from usarsim.config.catalog import ROBOTS_DIR
from usarsim.config.robot import load_robot
from usarsim.config.world_file import load_world

TAG_WORLD = """\
name: TagArena
description: one blank RFID tag and one written tag beside a start pose (tests only)
floor: {center: [0.0, 0.0], size: [20.0, 20.0]}
rfid_tags:
  - {id: 501, location: [1.0, 0.0, -0.02]}
  - {id: 502, location: [1.0, 0.5, -0.02], memory: exit north}
start_poses:
  - {name: Tags, location: [0.0, 0.0, -0.2], rotation: [0.0, 0.0, 0.0]}
"""
V3 = r"-?\d+\.\d{4},-?\d+\.\d{4},-?\d+\.\d{4}"


@pytest.fixture(scope="module")
def tag_world(tmp_path_factory):
    p = tmp_path_factory.mktemp("tags") / "TagArena.yaml"
    p.write_text(TAG_WORLD)
    return load_world(p)


def res_of(c, line: str):
    c.send(line)
    res = [ln for ln in c.step(0.05) if ln.text.startswith("RES")]
    assert len(res) == 1, (line, res)
    return res[0].text


def test_a_blank_tag_reads_an_empty_mem_and_its_sen_pair_has_none(server_factory, tag_world):
    srv = server_factory(world=tag_world)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R} {Start Tags}")
    lines = c.step(1.0)
    sen = [ln.text for ln in lines if "{Type RFID}" in ln.text][-1]
    # protocol.md 6.3: one ID/Location pair per tag, {Mem text} only after a tag written with data
    assert re.search(rf"\{{ID 501\}} \{{Location {V3}\}}( |$)", sen) and "{ID 501} {Location" in sen, sen
    after_501 = sen.split("{ID 501}", 1)[1].split("{ID", 1)[0]
    assert "{Mem" not in after_501, sen
    assert re.search(rf"\{{ID 502\}} \{{Location {V3}\}} \{{Mem exit north\}}", sen), sen
    # protocol.md 5.4: Read -> {ID id} {Mem data}; a blank tag has no data: {Mem }
    prefix = r"RES \{Time \d+\.\d{2}\} \{Type RFID\} \{Name RFID\} \{Status OK\} "
    blank = res_of(c, "SET {Type RFID} {Name RFID} {Opcode Read} {Params 501}")
    assert re.fullmatch(prefix + r"\{ID 501\} \{Mem \}", blank), blank
    assert segment_list(blank)[-1] == "Mem "  # key, blank, empty data: a "{Mem " search finds it
    written = res_of(c, "SET {Type RFID} {Name RFID} {Opcode Read} {Params 502}")
    assert re.fullmatch(prefix + r"\{ID 502\} \{Mem exit north\}", written), written
    # written, read back; erased, blank again
    assert res_of(c, "SET {Type RFID} {Name RFID} {Opcode Write} {Params 501 two victims}").endswith("{Status OK}")
    assert res_of(c, "SET {Type RFID} {Name RFID} {Opcode Read} {Params 501}").endswith("{ID 501} {Mem two victims}")
    assert res_of(c, "SET {Type RFID} {Name RFID} {Opcode Erase} {Params 501}").endswith("{Status OK}")
    assert res_of(c, "SET {Type RFID} {Name RFID} {Opcode Read} {Params 501}").endswith("{ID 501} {Mem }")
    sen = [ln.text for ln in c.step(0.4) if "{Type RFID}" in ln.text][-1]
    assert "{Mem" not in sen.split("{ID 501}", 1)[1].split("{ID", 1)[0], sen


ZERO = "Location 0.0000,0.0000,0.0000 Orientation 0.0000,0.0000,0.0000"


@pytest.mark.parametrize(
    "robot, left, right", [("P2AT", "LeftFWheel", "RightFWheel"), ("Kurt3D", "LeftMWheel", "RightMWheel")]
)
def test_encoders_are_mounted_on_their_wheels_and_odometry_on_the_chassis(
    server_factory, test_world, robot, left, right
):
    srv = server_factory(world=test_world)
    c = srv.connect()
    c.nfo()
    c.send(f"INIT {{ClassName USARBot.{robot}}} {{Name R}} {{Start Open}}")
    c.step(0.2)
    # protocol.md 6.8: packed, one segment per item, the pose relative to the mount; an
    # encoder rides on its wheel (a robot part, e.g. RightFWheel)
    enc = c.ask("GETGEO {Type Encoder}", "GEO").text
    assert enc == (f"GEO {{Type Encoder}} {{Name ECLeft {ZERO} Mount {left}}} {{Name ECRight {ZERO} Mount {right}}}")
    assert c.ask("GETGEO {Type Encoder} {Name ECRight}", "GEO").text == (
        f"GEO {{Type Encoder}} {{Name ECRight {ZERO} Mount {right}}}"
    )
    odo = c.ask("GETGEO {Type Odometry}", "GEO").text
    assert odo == f"GEO {{Type Odometry}} {{Name Odometry {ZERO} Mount HARD}}"
    # the UvA client's positional parse: the name, then exactly Location x Orientation r Mount m
    for seg in segment_list(enc)[1:] + segment_list(odo)[1:]:
        words = seg.split()
        assert len(words) == 8 and words[0::2] == ["Name", "Location", "Orientation", "Mount"], seg
    # the mounts are parts of the robot: the wheels the encoders count
    spec = load_robot(ROBOTS_DIR / f"{robot}.yaml")
    wheels = {i.name: i.params.get("wheel") for i in spec.items if i.item_type == "Encoder"}
    assert wheels == {"ECLeft": left, "ECRight": right}
    assert {left, right} <= {w.name for w in spec.wheels}
