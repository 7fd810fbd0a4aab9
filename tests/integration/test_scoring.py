"""The score of a run (usarsim.scoring, serve --score and --score-file) on constructed cases:
a victim in view counts and one out of view does not; a straight corridor driven end to end is
explored as far as its area; a push into a wall is a collision; reports within a metre count;
an empty battery, a robot upside down and one that never moves are lost."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys

import pytest

from usarsim.client import launch
from usarsim.scoring import COLLISION_FORCE_N, REPORT_RADIUS_M

ENV = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}

CORRIDOR = """\
# A straight corridor 10 m long and 2 m wide, closed at both ends (tests only).
name: Corridor
description: a straight closed corridor, 10 m x 2 m inside
floor: {center: [5.0, 0.0], size: [12.0, 4.0]}
materials:
  wall: {rgba: [0.8, 0.8, 0.7, 1.0]}
objects:
  - {name: west, shape: box, center: [-0.05, 0.0, -0.5], size: [0.1, 2.2, 1.0], material: wall}
  - {name: east, shape: box, center: [10.05, 0.0, -0.5], size: [0.1, 2.2, 1.0], material: wall}
  - {name: north, shape: box, center: [5.0, -1.05, -0.5], size: [10.2, 0.1, 1.0], material: wall}
  - {name: south, shape: box, center: [5.0, 1.05, -0.5], size: [10.2, 0.1, 1.0], material: wall}
start_poses:
  - {name: WestEnd, location: [0.6, 0.0, -0.3], rotation: [0.0, 0.0, 0.0]}
"""


def scored(
    path, steps: int, *, world: str = "DM-USAR_yellow", spawn: dict, drive=None, before=None, step_s: float = 0.1
) -> dict:
    """Run one robot in lock-step for ``steps`` steps and return the --score-file JSON."""
    with launch(world=world, extra_args=("--score-file", str(path))) as srv, srv.connect() as w:
        robot = w.spawn("P2AT", name="R1", **spawn)
        if before is not None:
            before(robot)
        for k in range(steps):
            if drive is not None:
                drive(robot, k)
            w.step(step_s)
    return json.loads(path.read_text())


@pytest.fixture(scope="module")
def corridor(tmp_path_factory):
    p = tmp_path_factory.mktemp("corridor") / "Corridor.yaml"
    p.write_text(CORRIDOR)
    return str(p)


def test_a_robot_facing_a_victim_counts_it_and_one_facing_away_does_not(tmp_path):
    # Ben lies at (3.1, 6.1): 1.8 m straight ahead of the first robot, behind the second
    facing = scored(tmp_path / "a.json", 20, spawn={"location": (1.3, 6.1, -0.3), "rotation": (0, 0, 0)})
    assert facing["robots"]["R1"]["victims_found"] == ["Ben"]
    assert facing["team"]["victims_found"] == 1 and facing["team"]["score"] >= 50.0
    away = scored(tmp_path / "b.json", 20, spawn={"location": (1.3, 6.1, -0.3), "rotation": (0, 0, 3.1416)})
    assert away["robots"]["R1"]["victims_found"] == [] and away["team"]["victims_found"] == 0
    assert away["world"] == "DM-USAR_yellow" and away["time_s"] == pytest.approx(2.0)


def test_driving_a_straight_corridor_explores_its_area(tmp_path, corridor):
    def drive(robot, k):
        robot.drive(left=3.0, right=3.0)

    result = scored(tmp_path / "c.json", 360, world=corridor, spawn={"start": "WestEnd"}, drive=drive)
    r = result["robots"]["R1"]
    # the laser sits 0.144 m ahead of the chassis origin, which starts 0.6 m from the west wall:
    # it sees the corridor ahead of it, 2 m wide, to the east wall
    expected = 2.0 * (10.0 - (0.6 + 0.144))
    assert r["area_m2"] == pytest.approx(expected, rel=0.10), (r, expected)
    assert result["team"]["area_m2"] == pytest.approx(r["area_m2"])
    # and it travelled most of the corridor's length (3 rad/s on 0.13 m wheels, 36 s: stopped by the east wall)
    assert 7.5 < r["distance_m"] < 9.2, r


def test_a_push_into_a_wall_is_a_collision_and_free_driving_is_not(tmp_path, corridor):
    def drive(robot, k):
        robot.drive(left=3.0, right=3.0)

    # 15 s at 0.4 m/s from x = 0.6: 6 m along the corridor, the east wall far ahead
    free = scored(tmp_path / "d.json", 150, world=corridor, spawn={"start": "WestEnd"}, drive=drive)
    assert free["robots"]["R1"]["collisions"] == 0 and free["team"]["collisions"] == 0
    # then on until it pushes against the east wall
    hit = scored(tmp_path / "e.json", 400, world=corridor, spawn={"start": "WestEnd"}, drive=drive)
    assert hit["robots"]["R1"]["collisions"] >= 1, hit
    assert hit["team"]["score"] < hit["team"]["area_m2"]  # a collision costs points
    assert COLLISION_FORCE_N > 0


def test_reports_within_a_metre_of_a_victim_count_once_and_others_are_false(tmp_path):
    def before(robot):
        res = robot.report_victim((3.3, 6.4, -0.1), name="ben")  # 0.36 m from Ben
        assert res.item_type == "Victim" and res.name == "ben" and res.status == "OK"
        robot.report_victim((3.0, 6.0, -0.1))  # Ben again: no second count
        robot.report_victim((0.4, 2.2 + REPORT_RADIUS_M + 0.3, -0.1))  # 1.3 m from Anna: false

    result = scored(tmp_path / "f.json", 5, spawn={"location": (-4.0, 0.0, -0.3)}, before=before)
    t = result["team"]
    assert t["victims_reported"] == 1 and t["false_reports"] == 2
    assert t["victims_found"] == 0  # the victim sensor saw nobody: the reports are what count
    assert t["score"] == pytest.approx(50.0 - 2 * 10.0 + t["area_m2"], abs=0.01)


def test_report_is_answered_and_refused_on_the_wire():
    with launch() as srv:
        with socket.create_connection(("127.0.0.1", srv.port), timeout=30) as s:
            f = s.makefile("rb")
            assert f.readline().startswith(b"NFO")
            s.sendall(b"REPORT {Type Victim} {Location 1,2,0}\r\n")  # no robot yet
            assert f.readline().startswith(b"ERROR {Command REPORT} {Reason ")
            s.sendall(
                b"INIT {ClassName USARBot.P2AT} {Name R1}\r\nREPORT {Type Dog} {Location 1,2,0}\r\n"
                b"REPORT {Type Victim} {Location 1,2,0}\r\nREPORT {Type victim} {Location 3,4,0} {Name V9}\r\n"
            )
            got = [f.readline().decode() for _ in range(3)]
        assert got[0].startswith("ERROR {Command REPORT} {Reason REPORT: (Type Dog) is not a kind of report")
        assert got[1] == "RES {Time 0.00} {Type Victim} {Name Victim1} {Status OK} {Location 1.0000,2.0000,0.0000}\r\n"
        assert got[2].startswith("RES {Time 0.00} {Type Victim} {Name V9} {Status OK}")
        with srv.connect() as w:  # the client library's way, which waits for the answer
            res = w.spawn("P2AT", name="R2").report_victim((1.0, 2.0, 0.0), name="here")
            assert res.name == "here" and dict(res.extra)["Location"] == "1.0000,2.0000,0.0000"


def test_robots_lost_by_battery_flip_and_standing_still(tmp_path):
    empty = scored(
        tmp_path / "g.json",
        30,
        spawn={"location": (-4.0, 0.0, -0.3)},
        before=None,
        drive=lambda r, k: r.drive(left=1.0, right=1.0),
    )
    assert empty["robots"]["R1"]["lost"] is None  # a short run of a robot that drives: not lost
    stuck = scored(tmp_path / "h.json", 62, spawn={"location": (-4.0, 0.0, -0.3)}, step_s=1.0)
    assert stuck["robots"]["R1"]["lost"] == "stuck" and stuck["team"]["robots_lost"] == 1
    flipped = scored(tmp_path / "i.json", 20, spawn={"location": (-4.0, 0.0, -0.6), "rotation": (3.1416, 0, 0)})
    assert flipped["robots"]["R1"]["lost"] == "flipped"


def test_serve_score_prints_the_live_score(tmp_path):
    """usarsim serve --score: a score line every 10 simulated seconds and one at the end."""
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "usarsim",
            "serve",
            "--lockstep",
            "--score",
            "--port",
            "0",
            "--truth-port",
            "0",
            "--no-web",
            "--no-image",
            "--no-wireless",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=ENV,
    )
    try:
        port = None
        while port is None:
            line = proc.stdout.readline()
            assert line, proc.stderr.read()
            if line.startswith("usarsim: control listening on"):
                port = int(line.rsplit(":", 1)[1])
        with socket.create_connection(("127.0.0.1", port), timeout=30) as s:
            f = s.makefile("rb")
            f.readline()  # NFO
            s.sendall(b"INIT {ClassName USARBot.P2AT} {Name R1} {Location 1.3,6.1,-0.3}\r\nPING {Id a}\r\n")
            while not f.readline().startswith(b"PONG"):
                pass
            for _ in range(25):
                s.sendall(b"STEP {Time 1.0}\r\n")
                while not f.readline().startswith(b"STEPPED"):
                    pass
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    lines = [ln for ln in out.splitlines() if ln.startswith("usarsim: score t=")]
    assert [ln.split("t=")[1].split(" ")[0] for ln in lines[:2]] == ["10.0", "20.0"], out
    assert "victims 1 found" in lines[-1] and lines[-1].startswith("usarsim: score t=25.0"), lines[-1]


def test_the_recording_and_the_score_share_the_frames_and_each_gets_what_it_asked(tmp_path):
    """With --record and --score-file and no wireless servers: the score counts radio contact
    under the world's model, the recording (which asked for no links) has no radio channels."""
    from mcap.reader import make_reader

    rec, score = tmp_path / "run.mcap", tmp_path / "score.json"
    with launch(record=rec, extra_args=("--score-file", str(score))) as srv, srv.connect() as w:
        w.spawn("P2AT", name="R1", start="PlayerStart1")
        w.spawn("P2AT", name="R2", start="PlayerStart2")
        for _ in range(25):
            w.step(0.1)
    result = json.loads(score.read_text())
    assert result["team"]["radio_contact_share"] > 0.5  # two robots side by side at the start
    with rec.open("rb") as f:
        topics = {c.topic for c in make_reader(f).get_summary().channels.values()}
    assert "/R1/pose" in topics and "/R2/pose" in topics
    assert not any(t.startswith("/usarsim/radio/") for t in topics)
