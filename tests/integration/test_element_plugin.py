"""A kind of world element added as a plugin (tests/plugins/beacon_element.py: one file, one
registered class) is part of the world over the wire: a robot's laser sees the beacon's post and
the ground-truth port lists it under its own class; a world without the section is unchanged."""

from __future__ import annotations

import socket

import pytest

import plugins.beacon_element  # noqa: F401  (registers the element kind "beacons")
from helpers import TEST_WORLD, ServerThread, segments, sen_type
from usarsim.config.world_file import load_world
from usarsim.errors import ConfigError
from usarsim.protocol.truth import format_truth_request, parse_truth_object

BEACON_X = -3.0  # 3 m ahead of the Open start pose (-6, 0), on its heading


def middle_range(world) -> tuple[float, list]:
    """The centre beam of a P2AT's laser at the Open pose, after a second; the ground truth's
    Beacon rows."""
    srv = ServerThread(world, seed=1).start()
    try:
        c = srv.connect()
        c.nfo()
        c.send("INIT {ClassName USARBot.P2AT} {Name R} {Start Open}")
        scans = [ln for ln in c.step(1.0) if sen_type(ln) == "RangeScanner"]
        ranges = [float(v) for v in segments(scans[-1].text)["Range"].split(",")]
        with socket.create_connection(("127.0.0.1", srv.app.truth.port), timeout=10) as t:
            t.sendall(format_truth_request("Beacon").encode())
            data = b""
            while not data.endswith(b"{End}\r\n"):
                data += t.recv(65536)
        rows = [parse_truth_object(ln) for ln in data.decode().split("\r\n") if ln]
        return ranges[len(ranges) // 2], [r for r in rows if r is not None]
    finally:
        srv.stop()


def test_a_beacon_stands_where_its_section_says_for_the_laser_and_the_ground_truth(tmp_path):
    plain = tmp_path / "Plain.yaml"
    plain.write_text(TEST_WORLD)
    beaconed = tmp_path / "Beaconed.yaml"
    beaconed.write_text(TEST_WORLD + f"beacons:\n  - {{name: B1, location: [{BEACON_X}, 0.0, 0.0], height: 1.0}}\n")
    far, none = middle_range(load_world(plain))
    near, rows = middle_range(load_world(beaconed))
    assert far > 10.0 and none == []  # the wall at x = 5, 11 m away; nothing of class Beacon
    # the post's face is 2.9 m from the robot's centre; the laser is mounted ahead of the centre
    assert 2.5 < near < 2.9
    (row,) = rows
    assert (row.name, row.class_name) == ("B1", "Beacon") and row.location == pytest.approx((BEACON_X, 0.0, 0.0))


def test_a_bad_entry_of_the_plugins_section_is_refused_with_its_key(tmp_path):
    p = tmp_path / "Bad.yaml"
    p.write_text(TEST_WORLD + "beacons:\n  - {name: B1, location: [1.0, 0.0, 0.0], hieght: 2.0}\n")
    with pytest.raises(ConfigError, match="hieght"):
        load_world(p)
