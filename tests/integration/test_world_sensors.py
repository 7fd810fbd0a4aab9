"""Sensors that look for things in the world: glass for IR and lasers, victims and false
alarms for the victim sensor, RFID tags, the tag dropper, camera zoom, the 3D scanner.

A world with everything at known places (ENTITY_WORLD); physics and readings are checked
on the Simulation directly, the protocol lines through a lock-step server.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from helpers import drive_skid, segments
from usarsim.config.robot import load_robot
from usarsim.config.world_file import load_world
from usarsim.errors import ConfigError
from usarsim.readings import RangeReading, RangeScan3DReading, RangeScanReading, RfidReading, VictimReading
from usarsim.sim.simulation import Simulation

REST_Z = -0.1455  # P2AT chassis origin above the floor (Z down)

ENTITY_WORLD = """\
name: EntityArena
description: glass, victims, false alarms and RFID tags at known places (tests only)
floor: {center: [0.0, 0.0], size: [40.0, 40.0]}
materials:
  wall: {rgba: [0.9, 0.8, 0.4, 1.0]}
  glass: {rgba: [0.7, 0.9, 1.0, 0.3], see_through: [ir, camera]}
objects:
  # lane y = 0: a glass pane whose face is at x = 1.0, a wall whose face is at x = 1.4
  - {name: pane, shape: box, center: [1.01, 0.0, -0.6], size: [0.02, 2.0, 1.2], material: glass}
  - {name: back, shape: box, center: [1.45, 0.0, -0.6], size: [0.1, 2.0, 1.2], material: wall}
  # lane y = 5: a wall at y = 6.0 between the reader and tag 3
  - {name: tagwall, shape: box, center: [0.5, 6.0, -0.6], size: [2.0, 0.1, 1.2], material: wall}
  # lane y = 15: a wall behind the victim... in front of it, so that it is hidden
  - {name: hide, shape: box, center: [1.5, 15.0, -0.6], size: [0.1, 3.0, 1.2], material: wall}
victims:
  - {name: Alice, location: [2.5, 10.0, -0.1], rotation: [0.0, 0.0, 1.5708],
     sound: {loudness_db: 70.0, period_s: 4.0, duration_s: 2.0}}
  - {name: Bob, location: [2.5, -10.0, -0.1], rotation: [0.0, 0.0, 1.5708], waving: true}
  - {name: Carol, location: [3.0, 15.0, -0.1], rotation: [0.0, 0.0, 1.5708],
     sound: {loudness_db: 70.0, period_s: 3.0, duration_s: 1.0}}
false_alarms:
  - {name: glove, center: [2.0, -5.0, -0.1], size: [0.2, 0.2, 0.2], part: Hand}
rfid_tags:
  - {id: 11137, location: [1.0, 5.0, -0.02], memory: found-nothing}
  - {id: 11138, location: [6.0, 5.0, -0.02]}
  - {id: 11139, location: [0.5, 6.8, -0.02]}
start_poses:
  - {name: Glass, location: [0.0, 0.0, -0.2], rotation: [0.0, 0.0, 0.0]}
  - {name: Tags, location: [0.0, 5.0, -0.2], rotation: [0.0, 0.0, 0.0]}
  - {name: TagsOpposite, location: [2.0, 5.0, -0.2], rotation: [0.0, 0.0, 3.14159]}
  - {name: Victim, location: [0.0, 10.0, -0.2], rotation: [0.0, 0.0, 0.0]}
  - {name: Waver, location: [0.0, -10.0, -0.2], rotation: [0.0, 0.0, 0.0]}
  - {name: Alarm, location: [0.0, -5.0, -0.2], rotation: [0.0, 0.0, 0.0]}
  - {name: Hidden, location: [0.0, 15.0, -0.2], rotation: [0.0, 0.0, 0.0]}
  - {name: Away, location: [0.0, 10.0, -0.2], rotation: [0.0, 0.0, 3.14159]}
"""


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    p = tmp_path_factory.mktemp("entity") / "EntityArena.yaml"
    p.write_text(ENTITY_WORLD)
    return load_world(p)


def probe_robot(tmp_path, sensors: str, name: str = "Probe"):
    """A P2AT body with only the given sensor lines (YAML list items)."""
    from usarsim.config.catalog import ROBOTS_DIR

    head = (
        (ROBOTS_DIR / "P2AT.yaml").read_text().split("\nsensors:")[0].replace("class_name: P2AT", f"class_name: {name}")
    )
    path = tmp_path / f"{name}.yaml"
    path.write_text(head + "\nsensors:\n" + sensors)
    return load_robot(path)


def settled(world, robot, pose: str, seed: int = 5, uid: int = 1, sim: Simulation | None = None) -> Simulation:
    sim = sim or Simulation(world, seed=seed)
    p = world.start_pose(pose)
    sim.spawn(uid, robot, f"R{uid}", p.location, p.rotation)
    sim.advance(1.0)
    sim.take_outputs()
    return sim


def set_res(c, line: str, seconds: float = 0.05):
    """Lock-step: send a SET, step, and return its RES line (applied at the next STEP)."""
    c.send(line)
    res = [ln for ln in c.step(seconds) if ln.text.startswith("RES")]
    assert len(res) == 1, (line, res)
    return res[0]


def values(sim, kind, seconds, uid=1):
    sim.advance(seconds)
    return [o.value for o in sim.take_outputs() if isinstance(o.value, kind) and o.uid == uid]


# --------------------------------------------------------------------------- glass


def test_ir_sees_through_glass_where_laser_and_sonar_stop(world, tmp_path):
    robot = probe_robot(
        tmp_path,
        """\
  - {type: IR, name: IR1, location: [0.27, 0.0, -0.1]}
  - {type: RangeSensor, name: Beam, location: [0.27, 0.0, -0.1]}
  - {type: Sonar, name: S1, location: [0.27, 0.0, -0.1]}
  - {type: IRScanner, name: IRScan, location: [0.27, 0.0, -0.1]}
  - {type: RangeScanner, name: Laser, location: [0.27, 0.0, -0.1], preset: SICK}
""",
    )
    sim = settled(world, robot, "Glass")
    x = sim.pose_of(1)[0][0] + 0.27
    readings = values(sim, RangeReading, 1.0)
    ir = [r.items[0].range_m for r in readings if r.sensor_type == "IR"]
    beam = [r.items[0].range_m for r in readings if r.sensor_type == "RangeSensor"]
    sonar = [r.items[0].range_m for r in readings if r.sensor_type == "Sonar"]
    assert ir and beam and sonar
    assert np.mean(ir) == pytest.approx(1.4 - x, abs=0.01)  # through the pane, onto the wall
    assert np.mean(beam) == pytest.approx(1.0 - x, abs=0.01)  # the pane
    assert np.mean(sonar) == pytest.approx(1.0 - x, abs=0.01)
    scans = values(sim, RangeScanReading, 1.0)
    ir_scan = [s for s in scans if s.sensor_type == "IRScanner"][-1]
    laser = [s for s in scans if s.sensor_type == "RangeScanner"][-1]
    mid_ir = ir_scan.ranges_m[len(ir_scan.ranges_m) // 2]
    assert mid_ir == pytest.approx(1.4 - x, abs=0.01)
    assert laser.ranges_m[90] == pytest.approx(1.0 - x, abs=0.01)


# --------------------------------------------------------------------------- victims


VICT = "  - {type: VictSensor, name: VictSensor, location: [0.2, 0.0, -0.3]}\n"


def victim_reports(world, tmp_path, pose, seconds=3.2, seed=5):
    sim = settled(world, probe_robot(tmp_path, VICT), pose, seed=seed)
    return sim, values(sim, VictimReading, seconds)


def test_victim_sensor_reports_body_parts_where_the_victim_lies(world, tmp_path):
    sim, reports = victim_reports(world, tmp_path, "Victim")
    assert len(reports) == 4  # every 4th scan of 0.2 s: 4 reports in 3.2 s
    parts = [p for r in reports for p in r.parts]
    names = {p.part_name for p in parts}
    assert {"Chest", "Pelvis"} <= names and names <= {"Head", "Chest", "Pelvis", "Arm", "Hand", "Leg", "Foot"}
    # Alice lies across the lane 2.5 m ahead (pelvis at x = 2.5, body along +Y), 0.1 m up
    (rx, ry, _), _ = sim.pose_of(1)
    sensor_x = rx + 0.2
    pelvis = [p.location for p in parts if p.part_name == "Pelvis"]
    xs = np.array([loc[0] for loc in pelvis])
    assert np.all(np.abs(xs - (2.5 - sensor_x)) < 0.2 + 0.05 * 3 * 2.5)
    assert abs(float(np.median(xs)) - (2.5 - 0.17 - sensor_x)) < 0.15  # the near face of the pelvis
    # her head is on her right (+Y): heads right of the chest
    heads = [p.location[1] for p in parts if p.part_name == "Head"]
    chests = [p.location[1] for p in parts if p.part_name == "Chest"]
    if heads:
        assert np.median(heads) > np.median(chests)


def test_nothing_seen_gives_no_victims(world, tmp_path):
    _, reports = victim_reports(world, tmp_path, "Away")
    assert reports and all(r.parts == () for r in reports)
    _, hidden = victim_reports(world, tmp_path, "Hidden")
    assert hidden and all(r.parts == () for r in hidden)  # Carol lies behind a wall


def test_a_false_alarm_is_reported_as_its_part(world, tmp_path):
    _, reports = victim_reports(world, tmp_path, "Alarm", seconds=6.4)
    parts = [p for r in reports for p in r.parts]
    assert parts and {p.part_name for p in parts} == {"Hand"}
    # the Gaussian test lets most rays through at 2 m (|2 (g - 0)| > 0.05 x 4 / 3 for most g)
    rays = sum(1 for _ in parts)
    assert rays >= 8


def test_victim_location_noise_grows_with_distance(world, tmp_path):
    _, reports = victim_reports(world, tmp_path, "Victim", seconds=16.0, seed=9)
    chest = np.array([p.location for r in reports for p in r.parts if p.part_name == "Chest"])
    assert len(chest) > 20
    d = np.linalg.norm(chest, axis=1).mean()
    spread_z = chest[:, 2].std()  # the chest's top is flat: z varies by noise mostly
    assert 0.5 * 0.05 * d < spread_z < 2.0 * 0.05 * d + 0.05


def test_a_waving_victim_moves_its_arm(world, tmp_path):
    sim = settled(world, probe_robot(tmp_path, VICT), "Waver")
    m, d = sim.model, sim.data
    mocap = m.body_mocapid[m.body("victim/Bob/shoulder").id]
    quats = []
    for _ in range(8):
        sim.advance(0.25)
        quats.append(d.mocap_quat[mocap].copy())
    angles = {round(2 * math.acos(min(1.0, abs(float(q @ quats[0])))), 3) for q in quats}
    assert len(angles) >= 3 and max(angles) > 0.5  # it swings by up to 2 x 0.6 rad


def test_victim_sensor_conf_and_sen_lines(server_factory, world):
    srv = server_factory(world=world, seed=2)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Start Victim}")
    c.step(1.0)
    conf = c.ask("GETCONF {Type VictSensor}", "CONF").text
    assert (
        conf == "CONF {Type VictSensor} {Name VictSensor} {MaxRange 6.0000} {HorizontalFOV 0.6981} {VerticalFOV 0.6981}"
    )
    lines = [ln.text for ln in c.step(2.0) if ln.text.startswith("SEN") and "{Type VictSensor}" in ln.text]
    assert lines
    for text in lines:
        assert re.fullmatch(
            r"SEN \{Time \d+\.\d{4}\} \{Type VictSensor\} \{Name VictSensor\}"
            r"( \{PartName (Head|Chest|Pelvis|Arm|Hand|Leg|Foot)\} \{Location -?\d+\.\d{4},-?\d+\.\d{4},-?\d+\.\d{4}\})+",
            text,
        ), text
    c.send("INIT {ClassName USARBot.P2AT} {Name R2} {Start Away}")  # ignored: one robot per connection
    d = srv.connect()
    d.nfo()
    d.send("INIT {ClassName USARBot.P2AT} {Name R2} {Start Away}")
    d.step(1.0)
    away = [ln.text for ln in d.step(1.6) if "{Type VictSensor}" in ln.text]
    assert away and all(
        re.fullmatch(r"SEN \{Time \d+\.\d{4}\} \{Type VictSensor\} \{Status NoVictims\}", t) for t in away
    )


# --------------------------------------------------------------------------- sound, human motion


def test_a_groaning_victim_is_heard_louder_near_and_quieter_behind_a_wall(world, tmp_path):
    """Alice groans 2 s in 4, Carol 1 s in 3; from the Hidden pose a wall stands between
    the microphone and Carol (and nothing between it and Alice)."""
    from usarsim.readings import SoundReading

    robot = probe_robot(tmp_path, "  - {type: Sound, name: Mic, location: [0.0, 0.0, -0.2]}\n")
    alice, carol = (2.5, 10.78, -0.1), (3.0, 15.78, -0.1)  # their heads
    for pose, carol_walls in (("Victim", 0), ("Hidden", 1)):
        sim = settled(world, robot, pose)
        heard = values(sim, SoundReading, 12.0)
        assert len(heard) == 120  # every 0.1 s
        (x, y, z), _ = sim.pose_of(1)
        mic = (x, y, z - 0.2)
        level_a = 70.0 - 20.0 * math.log10(math.dist(mic, alice))
        level_c = 70.0 - 20.0 * math.log10(math.dist(mic, carol)) - 20.0 * carol_walls
        as_a = [h for h in heard if h.loudness_db == pytest.approx(level_a, abs=0.3)]
        as_c = [h for h in heard if h.loudness_db == pytest.approx(level_c, abs=0.3)]
        quiet = [h for h in heard if h.loudness_db == 0.0]
        assert len(as_a) + len(as_c) + len(quiet) == len(heard)  # nothing else is heard
        assert 50 <= len(as_a) <= 70  # Alice, the louder one, whenever she groans: half the time
        assert as_c and quiet
        assert all(h.duration_s == 2.0 for h in as_a) and all(h.duration_s == 1.0 for h in as_c)
        assert all(h.duration_s == 0.0 for h in quiet)


def test_human_motion_sees_the_waving_victim_only(world, tmp_path):
    from usarsim.readings import HumanMotionReading

    robot = probe_robot(tmp_path, "  - {type: HumanMotion, name: HM, location: [0.2, 0.0, -0.3]}\n")
    sim = settled(world, robot, "Waver")
    probs = np.array([r.probability for r in values(sim, HumanMotionReading, 5.0)])
    (x, y, _), _ = sim.pose_of(1)
    d = math.dist((x + 0.2, y), (2.5 + 0.0, -10.0 + 0.24 * 1.0 + 0.38))  # Bob's right shoulder, roughly
    assert len(probs) == 50
    assert abs(probs.mean() - (1.0 - d / 10.0)) < 0.05 and 0.02 < probs.std() < 0.08
    for pose in ("Victim", "Away"):  # Alice does not move; nobody behind
        still = [r.probability for r in values(settled(world, robot, pose), HumanMotionReading, 1.0)]
        assert still and all(p == 0.0 for p in still)


# --------------------------------------------------------------------------- RFID


RFID = "  - {{type: RFID, name: RFID, location: [0.0, 0.0, 0.0]{extra}}}\n"


def rfid_reading(world, tmp_path, pose="Tags", extra="", seed=5) -> tuple[Simulation, RfidReading]:
    sim = settled(world, probe_robot(tmp_path, RFID.format(extra=extra)), pose, seed=seed)
    return sim, values(sim, RfidReading, 0.4)[-1]


def test_rfid_detects_tags_in_range_at_their_place(world, tmp_path):
    sim, r = rfid_reading(world, tmp_path)
    ids = {t.tag_id for t in r.tags}
    assert 11137 in ids and 11138 not in ids  # 1 m away; 6 m is beyond the 3 m range
    assert 11139 in ids  # radius mode: the wall does not matter
    (rx, ry, rz), _ = sim.pose_of(1)
    tag = next(t for t in r.tags if t.tag_id == 11137)
    assert tag.location == pytest.approx((1.0 - rx, 5.0 - ry, -0.02 - rz), abs=0.01)
    assert tag.memory == "found-nothing"


def test_rfid_occlusion_and_signal_modes(world, tmp_path):
    _, occl = rfid_reading(world, tmp_path, extra=", SensingMode: 1")
    assert {t.tag_id for t in occl.tags} == {11137}  # 11139 is behind the wall
    _, sig = rfid_reading(world, tmp_path, extra=", SensingMode: 2, ObstacleLoss: 40.0")
    assert {t.tag_id for t in sig.tags} == {11137}  # one wall costs 40 dB: below the threshold
    # 11139 is 1.9 m away: -40 - 20 log10(1.9) = -45.6 dBm; one wall at 20 dB leaves -65.6,
    # above the -75 dBm threshold (a wall counted twice, entering and leaving, would not)
    _, weak = rfid_reading(world, tmp_path, extra=", SensingMode: 2, ObstacleLoss: 20.0")
    assert {t.tag_id for t in weak.tags} == {11137, 11139}


def test_rfid_conf_names_each_readers_sensing_mode(server_factory, world, tmp_path):
    """GETCONF {Type RFID} lists each reader's SensingMode by the names of the UT2004 RFID
    sensor's setting (manual 10.9.3: Radius, Obstacle, Attenuation); the robot file gives the
    mode as its number or its name, and the reader senses as its CONF says."""
    robots = tmp_path / "robots"
    robots.mkdir()
    probe_robot(
        robots,
        RFID.format(extra=", SensingMode: obstacle")
        + "  - {type: RFID, name: Far, location: [0.0, 0.0, 0.0], MaxRange: 5.0, SensingMode: 2}\n",
        name="Readers",
    )
    srv = server_factory(world=world, seed=4, robot_dirs=(str(robots),))
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.Readers} {Start Tags}")
    c.step(1.0)
    assert c.ask("GETCONF {Type RFID}", "CONF").text == (
        "CONF {Type RFID} {Name RFID} {ScanInterval 0.2000} {MaxRange 3.0000} {SensingMode Obstacle}"
        " {Name Far} {ScanInterval 0.2000} {MaxRange 5.0000} {SensingMode Attenuation}"
    )
    assert c.ask("GETCONF {Type RFID} {Name Far}", "CONF").text == (
        "CONF {Type RFID} {Name Far} {ScanInterval 0.2000} {MaxRange 5.0000} {SensingMode Attenuation}"
    )
    # "obstacle" is mode 1: 11139, behind the wall, is not sensed (test_rfid_occlusion_and_signal_modes)
    sen = next(ln for ln in c.step(0.4) if ln.text.startswith("SEN") and "{Name RFID}" in ln.text)
    assert "{ID 11137} " in sen.text and "{ID 11139}" not in sen.text, sen.text


def test_an_unknown_rfid_sensing_mode_is_refused_with_the_names(tmp_path):
    from usarsim.sensors import make_item

    for bad in ("Sonar", "3", "true", "1.0"):
        robot = probe_robot(tmp_path, RFID.format(extra=f", SensingMode: {bad}"))
        with pytest.raises(ConfigError, match=r"0 \(Radius\), 1 \(Obstacle\) or 2 \(Attenuation\)"):
            make_item(robot.items[0], robot, 0, "R1")


def test_a_tag_written_by_one_robot_is_read_back_by_another(server_factory, world):
    srv = server_factory(world=world, seed=2)
    a, b = srv.connect(), srv.connect()
    a.nfo()
    b.nfo()
    a.send("INIT {ClassName USARBot.P2AT} {Name Writer} {Start Tags}")
    b.send("INIT {ClassName USARBot.P2AT} {Name Reader} {Start TagsOpposite}")
    a.step(1.0)
    b.sync()
    res = set_res(a, "SET {Type RFID} {Name RFID} {Opcode Write} {Params 11137 victim Alice, 2 m north}")
    assert re.fullmatch(r"RES \{Time \d+\.\d+\} \{Type RFID\} \{Name RFID\} \{Status OK\}", res.text), res.text
    b.send("SET {Type RFID} {Name RFID} {Opcode Read} {Params 11137}")
    a.step(0.2)
    got = b.wait_line("RES")
    assert re.fullmatch(
        r"RES \{Time \d+\.\d+\} \{Type RFID\} \{Name RFID\} \{Status OK\} \{ID 11137\} "
        r"\{Mem victim Alice, 2 m north\}",
        got.text,
    ), got.text
    # the reader's SEN carries the memory too
    sen = b.wait_line(lambda ln: ln.text.startswith("SEN") and "{Type RFID}" in ln.text)
    assert "{ID 11137} {Location " in sen.text and "{Mem victim Alice, 2 m north}" in sen.text
    # a tag out of range, an unknown tag, a bad opcode: Failed
    for line in (
        "SET {Type RFID} {Name RFID} {Opcode Read} {Params 11138}",
        "SET {Type RFID} {Name RFID} {Opcode Read} {Params 4242}",
        "SET {Type RFID} {Name RFID} {Opcode Read} {Params x}",
        "SET {Type RFID} {Name RFID} {Opcode Burn} {Params 11137}",
    ):
        assert set_res(a, line).segment("Status") == "Failed", line
    # erase
    assert set_res(a, "SET {Type RFID} {Name RFID} {Opcode Erase} {Params 11137}").segment("Status") == "OK"
    b.send("SET {Type RFID} {Name RFID} {Opcode Read} {Params 11137}")
    a.step(0.1)
    assert b.wait_line("RES").text.endswith("{ID 11137} {Mem }")


def test_the_gun_drops_tags_until_its_magazine_is_empty(server_factory, world):
    srv = server_factory(world=world, seed=2)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Start Glass}")
    c.step(1.0)
    before = srv.on_sim(lambda sim: set(sim.entities.tags))
    statuses = []
    for _ in range(11):
        res = set_res(c, "SET {Type RFIDReleaser} {Name Gun} {Opcode Release}")
        assert res.text.startswith("RES {Time ") and "{Type RFIDReleaser} {Name Gun}" in res.text
        statuses.append(res.segment("Status"))
    assert statuses == ["OK"] * 10 + ["Failed"]  # a magazine of 10
    new = srv.on_sim(lambda sim: {i: sim.entities.tags[i].location for i in set(sim.entities.tags) - before})
    assert len(new) == 10
    (x, y, _), _ = srv.on_sim(lambda sim: sim.pose_of(1))
    for loc in new.values():  # on the floor under the back of the robot
        assert loc[2] == pytest.approx(0.0, abs=0.01)
        assert math.hypot(loc[0] - (x - 0.2), loc[1] - y) < 0.05
    # the robot's own reader sees them
    sen = c.step(0.3)
    rfid = [ln.text for ln in sen if "{Type RFID}" in ln.text][-1]
    assert all(f"{{ID {i}}}" in rfid for i in new)
    conf = c.ask("GETCONF {Type RFIDReleaser}", "CONF").text
    assert conf == "CONF {Type RFIDReleaser} {Name Gun}"


# --------------------------------------------------------------------------- camera


def test_camera_zoom_is_clamped_and_answered(server_factory, world):
    srv = server_factory(world=world, seed=2)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Start Glass}")
    c.step(0.5)
    # USARSim's keys, then the pinhole's intrinsics for its 320 x 240 pictures (an extension):
    # focal length 160 / tan(FOV / 2) pixels both ways, principal point the picture's centre
    assert c.ask("GETCONF {Type Camera}", "CONF").text == (
        "CONF {Type Camera} {Name Camera} {CameraDefFov 0.8727} {CameraMinFov 0.3491} {CameraMaxFov 1.5708} "
        "{CameraFov 0.8727} {FocalLength %.4f,%.4f} {PrincipalPoint 160.0000,120.0000}"
        % (160 / math.tan(0.8727 / 2), 160 / math.tan(0.8727 / 2))
    )
    assert c.ask("GETGEO {Type Camera}", "GEO").text == (
        "GEO {Type Camera} {Name Camera Location 0.0820,0.0002,0.0613 Orientation 0.0000,0.0000,0.0000 "
        "Mount CameraPanTilt_Link2}"
    )
    cases = [
        ("{Params 0.5}", "0.5000", "OK"),
        ("{Params 3.0}", "1.5708", "Failed"),
        ("{Params 0.1}", "0.3491", "Failed"),
        ("{0.6}", "0.6000", "OK"),
        ("{Params 0}", "0.8727", "Failed"),
    ]
    for params, fov, status in cases:
        res = set_res(c, f"SET {{Type Camera}} {{Name Camera}} {{Opcode Zoom}} {params}").text
        assert re.fullmatch(
            r"RES \{Time \d+\.\d+\} \{Type Camera\} \{Name Camera\} \{FOV %s\} \{Status %s\}"
            % (re.escape(fov), status),
            res,
        ), (params, res)
    set_res(c, "SET {Type Camera} {Name Camera} {Opcode Zoom} {Params 0.7}")
    zoomed = 160 / math.tan(0.7 / 2)  # zoom changes the intrinsics
    assert c.ask("GETCONF {Type Camera} {Name Camera}", "CONF").text.endswith(
        "{CameraFov 0.7000} {FocalLength %.4f,%.4f} {PrincipalPoint 160.0000,120.0000}" % (zoomed, zoomed)
    )
    # cameras send no SEN on the control port
    assert not [ln for ln in c.step(1.0) if "{Type Camera}" in ln.text]


# --------------------------------------------------------------------------- 3D scanner


def test_range_scanner_3d_is_row_major_top_row_first(world, tmp_path):
    robot = probe_robot(tmp_path, "  - {type: RangeScanner3D, name: Scanner3D, location: [0.27, 0.0, -0.1]}\n")
    sim = settled(world, robot, "Glass")
    scan = values(sim, RangeScan3DReading, 0.4)[-1]
    rows, cols = 11, 25  # the defaults: 2.5 degree steps over 25 x 60 degrees
    assert len(scan.ranges_m) == rows * cols and scan.frames == rows
    grid = np.array(scan.ranges_m).reshape(rows, cols)
    x = sim.pose_of(1)[0][0] + 0.27
    d = 1.0 - x  # the glass pane (lasers do not pass it)
    assert grid[rows // 2, cols // 2] == pytest.approx(d, abs=0.01)
    # a vertical plane: each beam reads d / (cos(pitch) cos(yaw)); the top row looks up
    pitch_top, yaw_right = 0.4363 / 2, 1.0472 / 2
    assert grid[0, cols // 2] == pytest.approx(d / math.cos(pitch_top), abs=0.02)
    assert grid[rows // 2, 0] == pytest.approx(d / math.cos(yaw_right), abs=0.02)
    # the bottom rows see the floor before the pane? (0.245 m up, 12.5 degrees down: 1.1 m) no:
    # all rows end on the pane at this distance
    assert grid.max() < d / (math.cos(pitch_top) * math.cos(yaw_right)) + 0.02


# --------------------------------------------------------------------------- every sensor at once


EVERY_SENSOR = """\
  - {type: Sonar, name: F1, location: [0.145, -0.130, 0.0], orientation: [0, 0, -1.570796]}
  - {type: Sonar, name: F4, location: [0.240, -0.025, 0.0], orientation: [0, 0, -0.174533]}
  - {type: IR, name: IR1, location: [0.27, 0.0, -0.1]}
  - {type: RangeSensor, name: Range1, location: [0.27, 0.0, -0.1]}
  - {type: RangeScanner, name: Scanner1, location: [0.144, 0.0, -0.092], preset: SICK}
  - {type: IRScanner, name: IRScanner1, location: [0.2, 0.0, -0.12]}
  - {type: RangeScanner3D, name: Scanner3D, location: [0.1, 0.0, -0.2]}
  - {type: Odometry, name: Odometry, left_wheel: LeftFWheel, right_wheel: RightFWheel}
  - {type: Encoder, name: ECLeft, wheel: LeftFWheel}
  - {type: Encoder, name: ECRight, wheel: RightFWheel}
  - {type: Tachometer, name: Tach}
  - {type: GPS, name: GPS, location: [0.0, 0.0, -0.16]}
  - {type: INS, name: INS}
  - {type: IMU, name: IMU}
  - {type: INU, name: INU}
  - {type: Touch, name: Bumper, location: [0.28, 0.0, 0.05], Diameter: 0.02}
  - {type: GroundTruth, name: GroundTruth}
  - {type: RFID, name: RFID, location: [0.0, 0.0, 0.08]}
  - {type: RFIDReleaser, name: Gun, location: [-0.2, 0.0, 0.08]}
  - {type: VictSensor, name: VictSensor, location: [0.2059, 0.0002, -0.1423], MaxRange: 6.0}
  - {type: Sound, name: Mic, location: [0.0, 0.0, -0.2]}
  - {type: HumanMotion, name: HM, location: [0.2, 0.0, -0.2]}
  - {type: Camera, name: Camera, location: [0.2059, 0.0002, -0.1423]}
  - {type: OmniCam, name: Omni, location: [0.0, 0.0, -0.3]}
"""
F = r"-?\d+\.\d{4}"
V3 = rf"{F},{F},{F}"
T = r"\{Time \d+\.\d{4}\} "
SEN_FORMS = {  # the exact shape of each SEN line (protocol.md 6.3)
    "Sonar": rf"SEN {T}\{{Type Sonar\}} \{{Name F1 Range {F}\}} \{{Name F4 Range {F}\}}",
    "IR": rf"SEN {T}\{{Type IR\}} \{{Name IR1 Range {F}\}}",
    "RangeSensor": rf"SEN {T}\{{Type RangeSensor\}} \{{Name Range1 Range {F}\}}",
    "RangeScanner": rf"SEN {T}\{{Type RangeScanner\}} \{{Name Scanner1\}} \{{Resolution 0\.0174\}} \{{FOV 3\.1415\}} "
    rf"\{{Range {F}(,{F}){{180}}\}}",
    "IRScanner": rf"SEN {T}\{{Type IRScanner\}} \{{Name IRScanner1\}} \{{Resolution 0\.0870\}} \{{FOV 3\.1400\}} "
    rf"\{{Range {F}(,{F}){{36}}\}}",
    "RangeScanner3D": rf"SEN {T}\{{Type RangeScanner3D\}} \{{Name Scanner3D\}} "
    rf"\{{Resolution 0\.0436,0\.0436\}} \{{FOV 0\.4363,1\.0472\}} \{{Range {F}(,{F}){{274}}\}}",
    "Odometry": rf"SEN {T}\{{Type Odometry\}} \{{Name Odometry\}} \{{Pose {V3}\}}",
    "Encoder": rf"SEN {T}\{{Type Encoder\}} \{{Name ECLeft Tick -?\d+\}} \{{Name ECRight Tick -?\d+\}}",
    "Tachometer": rf"SEN {T}\{{Type Tachometer\}} \{{Name Tach\}} \{{Vel {F}(,{F}){{3}}\}} \{{Pos {F}(,{F}){{3}}\}}",
    "GPS": rf"SEN {T}\{{Type GPS\}} \{{Name GPS\}} \{{Latitude \d+,\d+\.\d{{4}},[NS]\}} "
    rf"\{{Longitude \d+,\d+\.\d{{4}},[EW]\}} \{{Fix 1\}} \{{Satellites \d+\}}",
    "INS": rf"SEN {T}\{{Type INS\}} \{{Name INS\}} \{{Location {V3}\}} \{{Orientation {V3}\}}",
    "IMU": rf"SEN {T}\{{Type IMU\}} \{{Name IMU\}} \{{XYZAcceleration {V3}\}} \{{AngularVel {V3}\}} "
    rf"\{{AngularAccel {V3}\}} \{{Rotation {V3}\}}",
    "INU": rf"SEN {T}\{{Type INU\}} \{{Name INU\}} \{{Orientation {V3}\}}",
    "Touch": rf"SEN {T}\{{Type Touch\}} \{{Name Bumper Touch (True|False)\}}",
    "GroundTruth": rf"SEN {T}\{{Type GroundTruth\}} \{{Name GroundTruth\}} \{{Location {V3}\}} \{{Orientation {V3}\}}",
    "RFID": rf"SEN {T}\{{Type RFID\}} \{{Name RFID\}}( \{{ID \d+\}} \{{Location {V3}\}}( \{{Mem [^{{}}]*\}})?)*",
    "VictSensor": rf"SEN {T}\{{Type VictSensor\}} (\{{Status NoVictims\}}|\{{Name VictSensor\}}"
    rf"( \{{PartName (Head|Chest|Pelvis|Arm|Hand|Leg|Foot)\}} \{{Location {V3}\}})+)",
    "Sound": rf"SEN {T}\{{Type Sound\}} \{{Name Mic\}} \{{Loudness {F}\}} \{{Duration {F}\}}",
    "HumanMotion": rf"SEN {T}\{{Type HumanMotion\}} \{{Name HM\}} \{{Prob {F}\}}",
}
RATES = {
    "Sonar": 0.2,
    "IR": 0.2,
    "RangeSensor": 0.2,
    "RangeScanner": 0.2,
    "IRScanner": 0.2,
    "RangeScanner3D": 0.4,
    "Odometry": 0.2,
    "Encoder": 0.1,
    "Tachometer": 0.2,
    "GPS": 0.2,
    "INS": 0.2,
    "IMU": 0.1,
    "INU": 0.1,
    "Touch": 0.1,
    "GroundTruth": 0.1,
    "RFID": 0.2,
    "VictSensor": 0.8,
    "Sound": 0.1,
    "HumanMotion": 0.1,
}


def test_a_robot_with_every_sensor_drives_through_the_world(server_factory, world, tmp_path):
    """Done when of issue 3: every sensor reports in the exact format of the spec, at its
    rate, while the robot drives past glass, victims, false alarms and RFID tags."""
    robots = tmp_path / "robots"
    robots.mkdir()
    probe_robot(robots, EVERY_SENSOR, name="AllSensors")
    srv = server_factory(world=world, seed=4, robot_dirs=(str(robots),))
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.AllSensors} {Name Full} {Start Tags}")
    c.step(0.5)
    lines = []
    for left, right in ((1.5, 1.5), (-1.0, 1.0), (2.0, 2.0), (1.0, -1.0), (1.5, 1.5)):
        c.send(f"DRIVE {{Left {left}}} {{Right {right}}}")
        lines += c.step(2.0)
    sen = [ln.text for ln in lines if ln.text.startswith("SEN")]
    by_type: dict[str, list[str]] = {}
    for text in sen:
        by_type.setdefault(segments(text)["Type"], []).append(text)
    assert set(by_type) == set(SEN_FORMS), set(by_type) ^ set(SEN_FORMS)
    for stype, texts in by_type.items():
        for text in texts:
            assert re.fullmatch(SEN_FORMS[stype], text), (stype, text[:300])
        times = sorted({float(segments(t)["Time"]) for t in texts})
        assert len(times) == len(texts), stype  # one line a reading (a 3D sweep too)
        gaps = {round(b - a, 4) for a, b in zip(times, times[1:])}
        assert gaps == {RATES[stype]}, (stype, gaps)
    assert all(ln.raw.endswith(b"\r\n") for ln in lines)
    # cameras and the tag dropper answer CONF/GEO; every item type has a GEO line
    for stype in list(SEN_FORMS) + ["Camera", "OmniCam", "RFIDReleaser"]:
        geo = c.ask(f"GETGEO {{Type {stype}}}", "GEO").text
        mount = "Mount LeftFWheel}" if stype == "Encoder" else "Mount HARD}"
        assert geo.startswith(f"GEO {{Type {stype}}} {{Name ") and mount in geo, geo
        conf = c.ask(f"GETCONF {{Type {stype}}}", "CONF").text
        assert conf.startswith(f"CONF {{Type {stype}}} {{Name "), conf


def test_an_item_mounted_on_a_wheel_turns_with_it(world, tmp_path):
    """Mount a beam on the left front wheel (its hub, pointing forward): as the wheel rolls
    the beam sweeps round, down to the floor (0.13 m below the hub) and up into the sky."""
    robot = probe_robot(
        tmp_path, "  - {type: RangeSensor, name: Spoke, location: [0.0, 0.0, 0.0], mount: LeftFWheel, MaxRange: 3.0}\n"
    )
    from usarsim.sim.simulation import describe_items

    (desc,) = describe_items(robot)
    assert desc.mount == "LeftFWheel"
    sim = settled(world, robot, "Victim")
    drive_skid(sim, 1, 0.8, 0.8)  # 0.8 rad/s: a quarter turn in 2 s, readings every 0.2 s
    ranges = [r.items[0].range_m for r in values(sim, RangeReading, 8.0)]
    assert len(ranges) == 40
    assert min(ranges) < 0.2  # pointing (nearly) straight down: the floor right under the hub
    assert max(ranges) == 3.0  # pointing up: nothing within 3 m
    assert len({round(v, 2) for v in ranges}) > 10  # it really sweeps


CONF_LINES = (  # protocol.md 6.7: all items of a type in one line, repeated-key groups
    "CONF {Type Sonar} {Name F1} {MaxRange 5.0000} {MinRange 0.1000} {BeamAngle 0.3491} {Name F4} {MaxRange 5.0000} {MinRange 0.1000} {BeamAngle 0.3491}",
    "CONF {Type IR} {Name IR1} {MaxRange 1.5000} {MinRange 0.2000}",
    "CONF {Type RangeSensor} {Name Range1} {MaxRange 3.0000} {MinRange 0.0000}",
    "CONF {Type RangeScanner} {Name Scanner1} {MaxRange 20.0000} {MinRange 0.1000} {Resolution 0.0174} {Fov 3.1415} {Paning True} {Tilting False}",
    "CONF {Type IRScanner} {Name IRScanner1} {MaxRange 10.0000} {MinRange 0.1000} {Resolution 0.0870} {Fov 3.1400} {Paning True} {Tilting False}",
    "CONF {Type RangeScanner3D} {Name Scanner3D} {MaxRange 1000.0000} {MinRange 0.1000} {Resolution 0.0436,0.0436} {Fov 0.4363,1.0472} {Paning False} {Tilting True}",
    "CONF {Type Odometry} {Name Odometry} {ScanInterval 0.2000} {EncoderResolution 0.0099} {TrackWidth 0.4712}",
    "CONF {Type Encoder} {Name ECLeft} {Resolution 0.0174} {Name ECRight} {Resolution 0.0174}",
    "CONF {Type Tachometer} {Name Tach} {ScanInterval 0.2000}",
    "CONF {Type GPS} {Name GPS} {ScanInterval 0.2000}",
    "CONF {Type INS} {Name INS} {ScanInterval 0.2000}",
    "CONF {Type IMU} {Name IMU} {ScanInterval 0.1000}",
    "CONF {Type INU} {Name INU} {ScanInterval 0.1000}",
    "CONF {Type Touch} {Name Bumper} {ScanInterval 0.1000}",
    "CONF {Type GroundTruth} {Name GroundTruth} {ScanInterval 0.1000}",
    "CONF {Type RFID} {Name RFID} {ScanInterval 0.2000} {MaxRange 3.0000} {SensingMode Radius}",
    "CONF {Type VictSensor} {Name VictSensor} {MaxRange 6.0000} {HorizontalFOV 0.6981} {VerticalFOV 0.6981}",
    "CONF {Type Sound} {Name Mic} {ScanInterval 0.1000}",
    "CONF {Type HumanMotion} {Name HM} {ScanInterval 0.1000}",
    "CONF {Type OmniCam} {Name Omni} {CameraDefFov 6.2832} {CameraMinFov 6.2832} {CameraMaxFov 6.2832} {CameraFov 6.2832}",
)


def test_conf_lines_of_every_sensor_type(server_factory, world, tmp_path):
    robots = tmp_path / "robots"
    robots.mkdir()
    probe_robot(robots, EVERY_SENSOR, name="AllSensors")
    srv = server_factory(world=world, seed=4, robot_dirs=(str(robots),))
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.AllSensors} {Start Tags}")
    c.step(0.2)
    for line in CONF_LINES:
        stype = segments(line)["Type"]
        assert c.ask(f"GETCONF {{Type {stype}}}", "CONF").text == line
    # by name, one item of a packed type
    assert c.ask("GETCONF {Type Sonar} {Name F4}", "CONF").text == (
        "CONF {Type Sonar} {Name F4} {MaxRange 5.0000} {MinRange 0.1000} {BeamAngle 0.3491}"
    )
    assert c.ask("GETGEO {Type Sonar} {Name F4}", "GEO").text == (
        "GEO {Type Sonar} {Name F4 Location 0.2400,-0.0250,0.0000 Orientation 0.0000,0.0000,-0.1745 Mount HARD}"
    )


def test_ir_noise_statistics_and_min_range_clamp(world, tmp_path):
    robot = probe_robot(
        tmp_path,
        """\
  - {type: IR, name: IR1, location: [0.27, 0.0, -0.1]}
  - {type: RangeSensor, name: Close, location: [0.93, 0.0, -0.1], MinRange: 0.2}
  - {type: RangeScanner3D, name: Scanner3D, location: [0.27, 0.0, -0.1]}
""",
    )
    sim = settled(world, robot, "Glass", seed=21)
    x = sim.pose_of(1)[0][0]
    readings = values(sim, RangeReading, 20.0)
    ir = np.array([r.items[0].range_m for r in readings if r.sensor_type == "IR"])
    close = [r.items[0].range_m for r in readings if r.sensor_type == "RangeSensor"]
    true = 1.4 - (x + 0.27)
    assert len(ir) == 100
    # relative uniform noise of 0.001 (protocol.md 7.1): bounded, unbiased, spread 0.001 d / sqrt(3)
    assert np.all(np.abs(ir - true) <= 0.001 * true + 1e-4)
    assert abs(ir.mean() - true) < 3e-4
    assert 0.6 < ir.std() / (0.001 * true / math.sqrt(3)) < 1.4
    assert set(close) == {0.2}  # the pane is 7 cm away: clamped to MinRange
    # the 3D scanner's noise is the same relative model
    sim2 = settled(world, robot, "Glass", seed=22)
    centre = np.array([s.ranges_m[5 * 25 + 12] for s in values(sim2, RangeScan3DReading, 20.0)])
    d = 1.0 - (sim2.pose_of(1)[0][0] + 0.27)
    assert len(centre) == 50
    assert np.all(np.abs(centre - d) <= 0.001 * d + 1e-4) and centre.std() > 0.2 * 0.001 * d / math.sqrt(3)
