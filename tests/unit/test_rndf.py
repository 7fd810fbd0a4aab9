"""DARPA Urban Challenge route network (RNDF) and mission (MDF) files: the shipped pair
parses, broken files are rejected with the line number of the fault, and ``usarsim
validate`` checks them."""

from __future__ import annotations

import re

import pytest

from usarsim.cli import main as cli_main
from usarsim.config.catalog import WORLDS_DIR, file_kind
from usarsim.config.rndf import (
    FEET_TO_M,
    check_mdf,
    load_mdf,
    load_rndf,
    parse_mdf,
    parse_rndf,
    route_file_kind,
    to_world,
)
from usarsim.config.world import GeoReference
from usarsim.errors import ConfigError
from usarsim.sensors.gps import world_to_geographic

ROAD = WORLDS_DIR / "DM-Road_UrbanChallenge"
RNDF_PATH = ROAD.with_suffix(".rndf")
MDF_PATH = ROAD.with_suffix(".mdf")

# A small, complete RNDF: two segments, a zone with one spot; every kind of line.
MINI = """\
RNDF_name\tmini
num_segments\t2
num_zones\t1
format_version\t1.0
creation_date\t2007-11-03
/* a comment line */
segment\t1
num_lanes\t2
segment_name\tMain_Street
lane\t1.1
num_waypoints\t2
lane_width\t12
left_boundary\tdouble_yellow
right_boundary\tsolid_white
checkpoint\t1.1.2\t1
stop\t1.1.2
exit\t1.1.2\t2.1.1
1.1.1\t34.000000\t-117.000000
1.1.2\t34.001000\t-117.000000   /* a trailing comment */
end_lane
lane\t1.2
num_waypoints\t2
1.2.1\t34.001000\t-117.000100
1.2.2\t34.000000\t-117.000100
end_lane
end_segment
segment\t2
num_lanes\t1
lane\t2.1
num_waypoints\t2
exit\t2.1.2\t3.0.1
2.1.1\t34.001100\t-117.000000
2.1.2\t34.002000\t-117.000000
end_lane
end_segment
zone\t3
num_spots\t1
zone_name\tLot
perimeter\t3.0
num_perimeterpoints\t3
exit\t3.0.1\t1.2.1
3.0.1\t34.002100\t-117.000000
3.0.2\t34.002500\t-117.000000
3.0.3\t34.002500\t-117.000500
end_perimeter
spot\t3.1
spot_width\t10
checkpoint\t3.1.2\t2
3.1.1\t34.002300\t-117.000200
3.1.2\t34.002300\t-117.000300
end_spot
end_zone
end_file
"""

MINI_MDF = """\
MDF_name\tmini_mission
RNDF\tmini
format_version\t1.0
checkpoints
num_checkpoints\t3
1
2
1
end_checkpoints
speed_limits
num_speed_limits\t2
1\t5\t25
3\t0\t10
end_speed_limits
end_file
"""


def line_no(text: str, line: str) -> int:
    """1-based number of the first line of ``text`` equal to ``line``."""
    return text.splitlines().index(line) + 1


def edit(text: str, old: str, new: str | None, *, first: bool = False) -> str:
    """Replace (or with None delete) the one line ``old`` (``first``: its first occurrence)."""
    lines = text.splitlines()
    assert lines.count(old) == 1 or (first and old in lines), old
    i = lines.index(old)
    if new is None:
        del lines[i]
    else:
        lines[i] = new
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- good files


def test_the_mini_rndf_parses_with_every_element():
    r = parse_rndf(MINI, "mini.rndf")
    assert r.name == "mini" and r.format_version == "1.0" and r.creation_date == "2007-11-03"
    assert [s.id for s in r.segments] == [1, 2] and r.segments[0].name == "Main_Street"
    lane = r.lane("1.1")
    assert [w.id for w in lane.waypoints] == ["1.1.1", "1.1.2"]
    assert lane.waypoints[1].lat == pytest.approx(34.001) and lane.waypoints[1].lon == pytest.approx(-117.0)
    assert lane.width_ft == 12 and lane.width_m == pytest.approx(12 * FEET_TO_M)
    assert (lane.left_boundary, lane.right_boundary) == ("double_yellow", "solid_white")
    assert lane.stops == ("1.1.2",)
    assert r.lane("1.2").width_ft is None
    assert r.checkpoints() == {1: "1.1.2", 2: "3.1.2"}
    assert [(e.exit, e.entry) for e in r.exits()] == [("1.1.2", "2.1.1"), ("2.1.2", "3.0.1"), ("3.0.1", "1.2.1")]
    (zone,) = r.zones
    assert zone.id == 3 and zone.name == "Lot" and zone.perimeter.id == "3.0"
    assert [p.id for p in zone.perimeter.points] == ["3.0.1", "3.0.2", "3.0.3"]
    (spot,) = zone.spots
    assert spot.id == "3.1" and spot.width_ft == 10 and [w.id for w in spot.waypoints] == ["3.1.1", "3.1.2"]
    assert len(r.points()) == 2 + 2 + 2 + 3 + 2


def test_the_mini_mdf_parses_and_matches_its_rndf():
    r = parse_rndf(MINI, "mini.rndf")
    m = parse_mdf(MINI_MDF, "mini.mdf", r)
    assert m.name == "mini_mission" and m.rndf_name == "mini" and m.format_version == "1.0"
    assert m.checkpoints == (1, 2, 1)  # a mission may come back to a checkpoint
    assert [(s.id, s.min_mph, s.max_mph) for s in m.speed_limits] == [(1, 5, 25), (3, 0, 10)]


def test_the_shipped_rndf_and_mdf_parse():
    r = load_rndf(RNDF_PATH)
    assert r.name == "DM-Road_UrbanChallenge"
    assert len(r.segments) == 8 and len(r.zones) == 1
    assert all(len(s.lanes) == 2 for s in r.segments)
    for lane in r.lanes():
        assert lane.width_ft == 12 and len(lane.waypoints) == 12
    assert len(r.checkpoints()) == 20 and len(r.zones[0].spots) == 4
    m = load_mdf(MDF_PATH, r)
    assert m.rndf_name == r.name and len(m.checkpoints) == 12
    assert {s.id for s in m.speed_limits} == set(range(1, 10))
    assert all(s.max_mph <= 30 for s in m.speed_limits)  # the Urban Challenge speed cap


def test_to_world_inverts_the_gps_conversion():
    geo = GeoReference(
        latitude_deg=34.585, longitude_deg=-117.365, scale_latitude_m=110940.0, scale_longitude_m=91780.0
    )
    for x, y in ((0.0, 0.0), (123.4, -56.7), (-250.0, 310.0)):
        lat, lon = world_to_geographic(x, y, geo)
        assert to_world(lat, lon, geo) == pytest.approx((x, y), abs=1e-6)
    # north is +x, east is +y
    assert to_world(34.586, -117.365, geo)[0] == pytest.approx(110.94)
    assert to_world(34.585, -117.364, geo)[1] == pytest.approx(91.78)


def test_route_files_are_told_apart(tmp_path):
    assert file_kind(RNDF_PATH) == "rndf" and file_kind(MDF_PATH) == "mdf"
    assert file_kind(ROAD.with_suffix(".yaml")) == "world"
    plain = tmp_path / "network.txt"
    plain.write_text("/* no suffix */\nRNDF_name x\n")
    assert route_file_kind(plain) == "rndf"


# --------------------------------------------------------------------------- broken RNDFs


def _broken_rndfs():
    cases = []

    def case(name, text, marker, *fragments):
        cases.append(pytest.param(text, line_no(text, marker), fragments, id=name))

    t = edit(MINI, "end_lane", None, first=True)
    case("missing end_lane", t, "lane\t1.2", "'lane' is not allowed here", "end_lane")
    t = edit(MINI, "num_waypoints\t2", "num_waypoints\t3", first=True)
    case(
        "num_waypoints above the waypoints",
        t,
        "end_lane",
        "lane 1.1 has 2 points",
        f"num_waypoints (line {line_no(t, 'num_waypoints' + chr(9) + '3')}) is 3",
    )
    t = edit(MINI, "num_waypoints\t2", "num_waypoints\t1", first=True)
    case(
        "num_waypoints below the waypoints",
        t,
        "1.1.2\t34.001000\t-117.000000   /* a trailing comment */",
        "one point too many in lane 1.1",
        "num_waypoints",
    )
    t = edit(MINI, "1.2.2\t34.000000\t-117.000100", "1.2.3\t34.000000\t-117.000100")
    case("waypoint id out of order", t, "1.2.3\t34.000000\t-117.000100", "expected waypoint 1.2.2", "1.2.3")
    t = edit(MINI, "1.2.2\t34.000000\t-117.000100", "1.2.x\t34.000000\t-117.000100")
    case("malformed waypoint id", t, "1.2.x\t34.000000\t-117.000100", "1.2.x")
    t = edit(MINI, "lane_width\t12", "lane_widht\t12")
    case("unknown keyword", t, "lane_widht\t12", "unknown keyword 'lane_widht'", "did you mean 'lane_width'")
    t = edit(MINI, "2.1.1\t34.001100\t-117.000000", "2.1.1\t34.00x100\t-117.000000")
    case("bad latitude", t, "2.1.1\t34.00x100\t-117.000000", "latitude of 2.1.1 must be a number", "34.00x100")
    t = edit(MINI, "2.1.1\t34.001100\t-117.000000", "2.1.1\t94.001100\t-117.000000")
    case("latitude out of range", t, "2.1.1\t94.001100\t-117.000000", "within [-90, 90]")
    t = edit(MINI, "lane_width\t12", "lane_width\ttwelve")
    case("bad lane width", t, "lane_width\ttwelve", "lane_width (feet) must be a number")
    t = edit(MINI, "num_lanes\t2", "num_lanes\ttwo")
    case("bad count", t, "num_lanes\ttwo", "num_lanes must be an integer")
    t = edit(MINI, "exit\t1.1.2\t2.1.1", "exit\t1.1.2\t2.1.9")
    case("exit to a missing waypoint", t, "exit\t1.1.2\t2.1.9", "exit 1.1.2 leads to 2.1.9", "lane 2.1 has 2")
    t = edit(MINI, "exit\t1.1.2\t2.1.1", "exit\t1.1.2\t7.1.1")
    case("exit to a missing segment", t, "exit\t1.1.2\t7.1.1", "no segment or zone 7")
    t = edit(MINI, "exit\t2.1.2\t3.0.1", "exit\t2.1.2\t3.0.4")
    case("exit to a missing perimeter point", t, "exit\t2.1.2\t3.0.4", "perimeter 3.0 has 3 points")
    t = edit(MINI, "exit\t1.1.2\t2.1.1", "exit\t1.2.2\t2.1.1")
    case("exit from another lane", t, "exit\t1.2.2\t2.1.1", "exit 1.2.2 is not a point of lane 1.1")
    t = edit(MINI, "stop\t1.1.2", "stop\t1.1.5")
    case("stop at a missing waypoint", t, "stop\t1.1.5", "stop 1.1.5 is not a point of lane 1.1")
    t = edit(MINI, "checkpoint\t3.1.2\t2", "checkpoint\t3.1.2\t1")
    case(
        "duplicate checkpoint id",
        t,
        "checkpoint\t3.1.2\t1",
        "checkpoint id 1 is already given to waypoint 1.1.2",
        f"line {line_no(MINI, 'checkpoint' + chr(9) + '1.1.2' + chr(9) + '1')}",
    )
    t = edit(MINI, "lane\t1.2", "lane\t1.3")
    case("lane id out of order", t, "lane\t1.3", "expected lane 1.2")
    t = edit(MINI, "segment\t2", "segment\t3")
    case("segment id out of order", t, "segment\t3", "expected segment 2")
    t = edit(MINI, "num_segments\t2", "num_segments\t3")
    case("too few segments", t, "zone\t3", "num_segments (line 2) is 3 but only 2 segments")
    t = edit(MINI, "num_zones\t1", "num_zones\t0")
    case("zone not announced", t, "zone\t3", "one zone too many", "num_zones (line 3) is 0")
    t = edit(MINI, "left_boundary\tdouble_yellow", "left_boundary\tdotted_blue")
    case("unknown boundary", t, "left_boundary\tdotted_blue", "unknown lane boundary 'dotted_blue'", "broken_white")
    t = edit(MINI, "num_spots\t1", "num_spots\t2")
    case("too few spots", t, "end_zone", "zone 3 has 1 spots but num_spots")
    t = edit(MINI, "3.1.2\t34.002300\t-117.000300", None)
    case("spot with one waypoint", t, "end_spot", "spot 3.1 has 1 points", "exactly 2 waypoints")
    t = edit(MINI, "perimeter\t3.0", "perimeter\t3.1")
    case("bad perimeter id", t, "perimeter\t3.1", "expected perimeter 3.0")
    t = edit(MINI, "num_lanes\t2", "num_lanes\t2\t3")
    case("extra value", t, "num_lanes\t2\t3", "'num_lanes' takes a value, got 2")
    t = MINI + "segment\t3\n"
    case("text after end_file", t, "segment\t3", "nothing may follow 'end_file'")
    return cases


@pytest.mark.parametrize("text, line, fragments", _broken_rndfs())
def test_a_broken_rndf_is_rejected_at_its_line(text, line, fragments):
    with pytest.raises(ConfigError) as info:
        parse_rndf(text, "broken.rndf")
    err = info.value
    assert err.path == "broken.rndf" and err.key == f"line {line}", str(err)
    assert str(err).startswith(f"broken.rndf: line {line}: ")
    for f in fragments:
        assert f in err.message, (f, err.message)


def test_a_truncated_rndf_names_its_last_line():
    text = MINI.split("end_zone")[0]
    with pytest.raises(ConfigError) as info:
        parse_rndf(text, "cut.rndf")
    assert info.value.key == f"line {len(text.splitlines())}"
    assert "the file ends here" in info.value.message and "end_zone" in info.value.message
    with pytest.raises(ConfigError, match=r"line 1: the file ends here; expected 'RNDF_name'"):
        parse_rndf("", "empty.rndf")


# --------------------------------------------------------------------------- broken MDFs


def _broken_mdfs():
    cases = []

    def case(name, text, marker, *fragments):
        line = marker if isinstance(marker, int) else line_no(text, marker)
        cases.append(pytest.param(text, line, fragments, id=name))

    t = MINI_MDF.replace("1\n2\n1\n", "1\n7\n1\n")
    case("checkpoint not in the RNDF", t, "7", "checkpoint 7 is not a checkpoint of the RNDF 'mini'")
    t = MINI_MDF.replace("num_checkpoints\t3", "num_checkpoints\t4")
    case(
        "num_checkpoints above the checkpoints",
        t,
        "end_checkpoints",
        "has 3 checkpoints",
        "num_checkpoints (line 5) is 4",
    )
    t = MINI_MDF.replace("num_checkpoints\t3", "num_checkpoints\t2")
    case("num_checkpoints below the checkpoints", t, 8, "one checkpoint too many")  # the third one
    t = MINI_MDF.replace("1\t5\t25", "1\t5\tfast")
    case("bad speed", t, "1\t5\tfast", "maximum speed (mph) must be a number")
    t = MINI_MDF.replace("3\t0\t10", "3\t20\t10")
    case("minimum above maximum", t, "3\t20\t10", "minimum speed 20 mph is above the maximum 10 mph")
    t = MINI_MDF.replace("3\t0\t10", "4\t0\t10")
    case("speed limit for a missing segment", t, "4\t0\t10", "4 is neither a segment nor a zone")
    t = MINI_MDF.replace("RNDF\tmini", "RNDF\tother")
    case("mission for another RNDF", t, "RNDF\tother", "the mission is for the RNDF 'other'")
    t = MINI_MDF.replace("end_speed_limits\n", "")
    case("missing end_speed_limits", t, "end_file", "'end_file' is not allowed here", "end_speed_limits")
    t = MINI_MDF.replace("speed_limits\n", "speed_limit\n", 1)
    case("unknown keyword", t, "speed_limit", "unknown keyword 'speed_limit'", "did you mean 'speed_limits'")
    return cases


@pytest.mark.parametrize("text, line, fragments", _broken_mdfs())
def test_a_broken_mdf_is_rejected_at_its_line(text, line, fragments):
    rndf = parse_rndf(MINI, "mini.rndf")
    with pytest.raises(ConfigError) as info:
        parse_mdf(text, "broken.mdf", rndf)
    err = info.value
    assert err.path == "broken.mdf" and err.key == f"line {line}", str(err)
    for f in fragments:
        assert f in err.message, (f, err.message)


def test_an_mdf_alone_is_checked_against_an_rndf_later():
    m = parse_mdf(MINI_MDF.replace("1\n2\n1\n", "1\n9\n1\n"), "m.mdf")  # no RNDF: parses
    with pytest.raises(ConfigError, match=r"m\.mdf: line 7: checkpoint 9 is not a checkpoint"):
        check_mdf(m, parse_rndf(MINI, "mini.rndf"))


# --------------------------------------------------------------------------- usarsim validate


def test_validate_the_shipped_rndf_and_mdf(capsys):
    assert cli_main(["validate", str(RNDF_PATH)]) == 0
    assert cli_main(["validate", str(MDF_PATH)]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    rndf_line, mdf_line = out.splitlines()
    assert re.fullmatch(
        r"ok: rndf DM-Road_UrbanChallenge: 8 segments, 16 lanes, 192 waypoints, 1 zones, "
        r"4 spots, 20 checkpoints, \d+ stops, \d+ exits",
        rndf_line,
    ), rndf_line
    assert mdf_line.startswith(
        "ok: mdf DM-Road_UrbanChallenge_tour: 12 checkpoints, 9 speed limits, checked "
        "against DM-Road_UrbanChallenge.rndf"
    ), mdf_line


def test_validate_reports_the_line_of_a_broken_rndf(tmp_path, capsys):
    p = tmp_path / "bad.rndf"
    p.write_text(edit(MINI, "exit\t1.1.2\t2.1.1", "exit\t1.1.2\t2.1.9"))
    assert cli_main(["validate", str(p)]) == 1
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith(f"usarsim: error: {p}: line {line_no(MINI, 'exit' + chr(9) + '1.1.2' + chr(9) + '2.1.1')}: ")
    assert "2.1.9" in err


def test_validate_checks_an_mdf_against_the_rndf_beside_it(tmp_path, capsys):
    (tmp_path / "mini.rndf").write_text(MINI)
    good = tmp_path / "tour.mdf"
    good.write_text(MINI_MDF)
    bad = tmp_path / "bad.mdf"
    bad.write_text(MINI_MDF.replace("1\n2\n1\n", "1\n2\n5\n"))
    alone = tmp_path / "sub" / "alone.mdf"
    alone.parent.mkdir()
    alone.write_text(MINI_MDF)
    assert cli_main(["validate", str(good)]) == 0
    assert cli_main(["validate", str(alone)]) == 0
    assert cli_main(["validate", str(bad)]) == 1
    out, err = capsys.readouterr()
    good_line, alone_line = out.splitlines()
    assert good_line == "ok: mdf mini_mission: 3 checkpoints, 2 speed limits, checked against mini.rndf"
    assert "not found beside it" in alone_line
    assert err.startswith(f"usarsim: error: {bad}: line 8: checkpoint 5 is not a checkpoint")
