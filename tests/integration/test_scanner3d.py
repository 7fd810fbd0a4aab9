"""The 3D laser on the wire (protocol.md 6.3, 7.3): each sweep is one SEN line of the spec's
form, row-major, under the 4096 bytes old clients read (protocol.md 1), at the configured
ScanInterval of simulated time; the split form (one line per row, ``{Frames n} {Frame k}``) only
when the robot file or a SET asks for it; a configuration whose lines would be longer is
refused."""

from __future__ import annotations

import dataclasses
import math
import re

import pytest

from helpers import WALL_FACE_X, segments, sen_type, vec
from usarsim.cli import main as cli_main
from usarsim.config.catalog import ROBOTS_DIR
from usarsim.config.robot import load_robot
from usarsim.errors import ConfigError
from usarsim.protocol import messages as M
from usarsim.readings import RangeScan3DReading
from usarsim.sensors import make_item
from usarsim.sensors.base import build_config
from usarsim.sensors.scanner import LINE_LIMIT, RangeScanner3D, RangeScanner3DConfig

F = r"\d+\.\d{4}"
SWEEP_LINE = re.compile(  # protocol.md 6.3: SEN {Time t} {Type RangeScanner3D} {Name Scanner} ...
    rf"SEN \{{Time ({F})\}} \{{Type RangeScanner3D\}} \{{Name Scanner3D\}} "
    rf"\{{Resolution 0\.0436,0\.0436\}} \{{FOV 0\.4363,1\.0472\}} \{{Range ({F}(?:,{F})*)\}}"
)
ROW_LINE = re.compile(  # the opt-in split form in RangeScanner3D's docstring
    rf"SEN \{{Time ({F})\}} \{{Type RangeScanner3D\}} \{{Name Scanner3D\}} \{{Frames (\d+)\}} \{{Frame (\d+)\}} "
    rf"\{{Resolution ({F},{F})\}} \{{FOV 0\.4363,1\.0472\}} \{{Range ({F}(?:,{F})*)\}}"
)
# USARSim's own grid (USARBot.ini [USARBot.RangeScanner3D], protocol.md 7.3): 31 x 51 beams
USARSIM_GRID = "horizontal_resolution_rad: 0.0209, vertical_resolution_rad: 0.0145"
KURT3D_MOUNT_X = 0.05  # Scanner3D location in Kurt3D.yaml


def scanner_config(robot: str) -> RangeScanner3DConfig:
    r = load_robot(ROBOTS_DIR / f"{robot}.yaml")
    (item,) = [i for i in r.items if i.item_type == "RangeScanner3D"]
    return build_config(RangeScanner3D, item, r.path)


def kurt3d_variant(directory, name: str, settings: str) -> str:
    """Kurt3D.yaml as robot class ``name`` with its scanner's resolutions (and more) replaced
    by ``settings``; returns the file's path."""
    text = (ROBOTS_DIR / "Kurt3D.yaml").read_text().replace("class_name: Kurt3D", f"class_name: {name}")
    old = "horizontal_resolution_rad: 0.0436,\n     vertical_fov_rad: 0.4363, vertical_resolution_rad: 0.0436"
    assert old in text
    path = directory / f"{name}.yaml"
    path.write_text(text.replace(old, f"vertical_fov_rad: 0.4363, {settings}"))
    return str(path)


def sweeps(lines) -> dict[float, tuple[float, ...]]:
    """The ranges of every RangeScanner3D line, by Time: each must be one whole sweep."""
    out: dict[float, tuple[float, ...]] = {}
    for ln in lines:
        if sen_type(ln) == "RangeScanner3D":
            m = SWEEP_LINE.fullmatch(ln.text)
            assert m, ln.text[:300]
            assert float(m[1]) not in out  # one line a sweep
            out[float(m[1])] = vec(m[2])
    return out


def rows_by_time(lines) -> dict[float, list[tuple[int, int, tuple[float, ...]]]]:
    """(Frames, Frame, ranges) of every RangeScanner3D line of the split form, by Time."""
    out: dict[float, list] = {}
    for ln in lines:
        if sen_type(ln) == "RangeScanner3D":
            m = ROW_LINE.fullmatch(ln.text)
            assert m, ln.text[:300]
            out.setdefault(float(m[1]), []).append((int(m[2]), int(m[3]), vec(m[5])))
    return out


def start(server_factory, test_world, robot: str, robot_dirs: tuple[str, ...] = ()):
    srv = server_factory(world=test_world, robot_dirs=robot_dirs)
    c = srv.connect()
    c.nfo()
    c.send(f"INIT {{ClassName USARBot.{robot}}} {{Name S}} {{Start FacingWall}}")
    return c


# --------------------------------------------------------------------------- the spec's form


@pytest.mark.parametrize("robot", ["Kurt3D", "Tarantula"])
def test_a_sweep_is_one_line_of_the_spec_form_that_reads_the_wall(server_factory, test_world, robot):
    cfg = scanner_config(robot)
    rows, cols = cfg.counts
    assert (rows, cols) == (11, 25) and not cfg.split_rows
    assert cfg.scan_interval_s == pytest.approx(0.4)
    c = start(server_factory, test_world, robot)
    lines = c.step(1.0)  # settle
    lines += c.step(2.0)
    # every line the server sent, CR LF included, stays under the 4096-byte client buffer
    too_long = [len(ln.raw) for ln in lines if len(ln.raw) >= 4096]
    assert not too_long, too_long
    got = sweeps(lines)
    times = sorted(got)
    assert len(times) >= 6
    # one line per sweep, rows x columns values each
    assert {len(r) for r in got.values()} == {rows * cols}
    # one sweep per ScanInterval of simulated time
    gaps = {round(b - a, 4) for a, b in zip(times, times[1:])}
    assert gaps == {round(cfg.scan_interval_s, 4)}, gaps
    if robot != "Kurt3D":
        return
    # the middle of the sweep (middle row, middle beam) looks straight ahead, level, at the wall
    truth = {
        float(segments(ln.text)["Time"]): vec(segments(ln.text)["Location"])
        for ln in lines
        if "{Type GroundTruth}" in ln.text
    }
    for t in times[-3:]:
        d = WALL_FACE_X - (truth[t][0] + KURT3D_MOUNT_X)
        middle = got[t][(rows // 2) * cols : (rows // 2 + 1) * cols]
        assert middle[cols // 2] == pytest.approx(d, abs=0.01)
        # the first value is the rightmost beam; it reads the same plane further off: d / cos(yaw)
        assert middle[0] == pytest.approx(d / math.cos(cfg.horizontal_fov_rad / 2), abs=0.02)
        # the top row looks up: d / cos(pitch)
        assert got[t][cols // 2] == pytest.approx(d / math.cos(cfg.vertical_fov_rad / 2), abs=0.02)


def test_scan_opcode_sends_a_whole_sweep_after_its_res_in_the_chosen_form(server_factory, test_world):
    c = start(server_factory, test_world, "Kurt3D")
    c.step(0.5)

    def scan() -> list[str]:
        c.send("SET {Type RangeScanner3D} {Name Scanner3D} {Opcode SCAN}")
        texts = [ln.text for ln in c.step(0.01)]
        res = next(i for i, t in enumerate(texts) if t.startswith("RES"))
        assert texts[res].endswith("{Type RangeScanner3D} {Name Scanner3D} {Status OK}")
        return [t for t in texts[res + 1 :] if "{Type RangeScanner3D}" in t]

    def set_split(params: str) -> str:
        c.send(f"SET {{Type RangeScanner3D}} {{Name Scanner3D}} {{Opcode Split}} {{Params {params}}}")
        return next(ln.text for ln in c.step(0.01) if ln.text.startswith("RES"))

    (line,) = scan()
    assert SWEEP_LINE.fullmatch(line) and len(vec(segments(line)["Range"])) == 11 * 25
    # the split form at run time: one line per row, Frame 0 .. 10, 25 values each
    assert set_split("1").endswith("{Type RangeScanner3D} {Name Scanner3D} {Status OK}")
    rows = scan()
    assert [(int(segments(t)["Frames"]), int(segments(t)["Frame"])) for t in rows] == [(11, k) for k in range(11)]
    assert all(ROW_LINE.fullmatch(t) and len(vec(segments(t)["Range"])) == 25 for t in rows)
    # the periodic sweeps follow the form too
    assert {len(r) for r in rows_by_time(c.step(1.0)).values()} == {11}
    # and back to one line a sweep (True/False spelled out too); a Params of neither fails
    assert set_split("2").endswith("{Status Failed}")
    assert set_split("False").endswith("{Status OK}")
    (line,) = scan()
    assert SWEEP_LINE.fullmatch(line)


# --------------------------------------------------------------------------- the split form, opt-in


def test_split_rows_in_the_robot_file_sends_usarsims_grid_one_row_a_line(server_factory, test_world, tmp_path):
    robots = tmp_path / "robots"
    robots.mkdir()
    kurt3d_variant(robots, "Kurt3DFine", f"{USARSIM_GRID}, split_rows: true")
    c = start(server_factory, test_world, "Kurt3DFine", robot_dirs=(str(robots),))
    lines = c.step(1.0)
    lines += c.step(1.2)
    assert not [len(ln.raw) for ln in lines if len(ln.raw) >= 4096]
    got = rows_by_time(lines)
    assert len(got) >= 4
    for t, sweep in got.items():
        # Frames rows lines, Frame 0 .. rows - 1 in order, cols values each: USARSim's 31 x 51
        assert [(n, k) for n, k, _ in sweep] == [(31, k) for k in range(31)], t
        assert {len(r) for _, _, r in sweep} == {51}
    assert all("{Resolution 0.0145,0.0209}" in ln.text for ln in lines if "{Type RangeScanner3D}" in ln.text)
    # the middle row's middle beam reads the wall straight ahead
    truth = {
        float(segments(ln.text)["Time"]): vec(segments(ln.text)["Location"])
        for ln in lines
        if "{Type GroundTruth}" in ln.text
    }
    t = max(got)
    assert got[t][15][2][25] == pytest.approx(WALL_FACE_X - (truth[t][0] + KURT3D_MOUNT_X), abs=0.01)
    # one line a sweep would be 15 kB: a SET asking for it fails and the form stays split
    c.send("SET {Type RangeScanner3D} {Name Scanner3D} {Opcode Split} {Params 0}")
    lines = c.step(0.5)
    assert [ln.text for ln in lines if ln.text.startswith("RES")][0].endswith("{Status Failed}")
    assert {len(s) for s in rows_by_time(lines).values()} == {31}


# --------------------------------------------------------------------------- too long for a line


def test_a_robot_file_whose_sweep_is_too_long_for_one_line_fails_validation(tmp_path, capsys):
    path = kurt3d_variant(tmp_path, "Kurt3D", f"{USARSIM_GRID}, max_range_m: 1000.0")
    assert cli_main(["validate", path]) == 1
    err = capsys.readouterr().err
    assert "sensors[0] (RangeScanner3D 'Scanner3D')" in err
    assert "a sweep of 31 x 51 beams up to 1000 m makes SEN lines of up to 15931 bytes" in err
    assert "at most 397 beams a sweep at this MaxRange" in err
    assert "coarser vertical_resolution_rad or horizontal_resolution_rad" in err and "split_rows: true" in err
    # the same grid split into rows fits; a row too long for one line does not, even split
    ok = kurt3d_variant(tmp_path, "Kurt3D", f"{USARSIM_GRID}, max_range_m: 1000.0, split_rows: true")
    assert cli_main(["validate", ok]) == 0
    assert capsys.readouterr().out.startswith("ok: robot Kurt3D: ")
    wide = kurt3d_variant(tmp_path, "Kurt3D", "horizontal_resolution_rad: 0.0020, split_rows: true")
    assert cli_main(["validate", wide]) == 1
    err = capsys.readouterr().err
    assert "a row of 524 beams up to 20 m makes SEN lines of up to" in err and "even in the split form" in err


def test_an_init_of_a_robot_whose_sweep_is_too_long_is_refused(server_factory, test_world, tmp_path):
    robots = tmp_path / "robots"
    robots.mkdir()
    kurt3d_variant(robots, "Kurt3DLong", USARSIM_GRID)
    c = start(server_factory, test_world, "Kurt3DLong", robot_dirs=(str(robots),))
    reply = c.ask("GETCONF {Type Robot}", "ERROR")  # the INIT's ERROR comes first
    assert reply.text.startswith("ERROR {Command INIT} {Reason ")
    assert "a sweep of 31 x 51 beams up to 20 m" in reply.text and "split_rows: true" in reply.text


def test_the_bound_counts_the_scanners_max_range_and_name():
    """A sweep's longest line is reckoned with every range at MaxRange and Time at its widest,
    as the codec writes it; the bound is the protocol layer's (lines under 4096 bytes, CR LF
    included)."""
    assert LINE_LIMIT == M.LINE_LIMIT == 4096
    cfg = RangeScanner3DConfig()
    rows, cols = cfg.counts
    widest = RangeScan3DReading("Scanner3D", (0.0436, 0.0436), (0.4363, 1.0472), (1000.0,) * (rows * cols), frames=rows)
    line = M.format_reading(widest, 999999999.9999)
    assert len(line.encode()) == cfg.longest_line("Scanner3D", False) == 2871
    split = M.format_reading(dataclasses.replace(widest, split=True), 999999999.9999).split("\r\n")
    assert max(len(r) + 2 for r in split) == cfg.longest_line("Scanner3D", True)
    # 16 x 26 beams: 8 bytes a range up to 20.0000 fit, 10 bytes up to 1000.0000 do not
    fine = {"horizontal_resolution_rad": 0.0418, "vertical_resolution_rad": 0.029}
    assert RangeScanner3DConfig(**fine).counts == (16, 26)
    assert RangeScanner3DConfig(max_range_m=20.0, **fine).line_problem("Scanner3D", False) is None
    assert "at most 397 beams a sweep" in RangeScanner3DConfig(**fine).line_problem("Scanner3D", False)
    # the sensor refuses a name that makes the default sweep's line too long
    robot = load_robot(ROBOTS_DIR / "Tarantula.yaml")
    (item,) = [i for i in robot.items if i.item_type == "RangeScanner3D"]
    assert isinstance(make_item(item, robot, 0, "t"), RangeScanner3D)
    with pytest.raises(ConfigError, match="more than the 4095 old clients read in one line"):
        make_item(dataclasses.replace(item, name="N" * 1300), robot, 0, "t")


# --------------------------------------------------------------------------- the codec


def test_a_sweep_formats_as_one_line_and_reads_back():
    ranges = tuple(1.0 + i / 8 for i in range(11 * 25))
    sweep = RangeScan3DReading("Scanner", (0.0436, 0.0436), (0.4363, 1.0472), ranges, frames=11)
    line = M.format_message(M.SensorMessage(12.5, sweep))
    assert line == (
        "SEN {Time 12.5000} {Type RangeScanner3D} {Name Scanner} {Resolution 0.0436,0.0436} "
        "{FOV 0.4363,1.0472} {Range " + ",".join("%.4f" % v for v in ranges) + "}\r\n"
    )
    assert len(line) < M.LINE_LIMIT
    back = M.parse_message(line[:-2])
    assert isinstance(back, M.SensorMessage) and back.time == 12.5
    r = back.reading
    assert (r.name, r.resolution_rad, r.fov_rad, r.ranges_m) == (
        sweep.name,
        sweep.resolution_rad,
        sweep.fov_rad,
        ranges,
    )
    assert (r.frame, r.split) == (None, False)
    assert M.format_message(back) == line
    # the 3DRangeScanner spelling reads back as itself
    alias = M.parse_message(line.replace("RangeScanner3D", "3DRangeScanner"))
    assert alias.reading.sensor_type == "3DRangeScanner" and alias.reading.ranges_m == ranges
    # a sweep too long for one line is still one line unless it asks to be split
    big = RangeScan3DReading("S", (0.0145, 0.0209), (0.4363, 1.0472), tuple(1000.0 for _ in range(31 * 51)), frames=31)
    assert M.format_message(M.SensorMessage(1.0, big)).count("\r\n") == 1


def test_a_split_sweep_formats_one_line_per_row_and_a_row_reads_back():
    big = RangeScan3DReading(
        "S", (0.0145, 0.0209), (0.4363, 1.0472), tuple(1000.0 for _ in range(31 * 51)), frames=31, split=True
    )
    text = M.format_message(M.SensorMessage(12.5, big))
    rows = text.split("\r\n")[:-1]
    assert len(rows) == 31 and text.endswith("\r\n")
    assert max(len(r) + 2 for r in rows) < M.LINE_LIMIT
    assert rows[3].startswith(
        "SEN {Time 12.5000} {Type RangeScanner3D} {Name S} {Frames 31} {Frame 3} "
        "{Resolution 0.0145,0.0209} {FOV 0.4363,1.0472} {Range 1000.0000,"
    )
    back = M.parse_message(rows[3])
    assert isinstance(back, M.SensorMessage)
    assert (back.reading.frames, back.reading.frame, back.reading.split, len(back.reading.ranges_m)) == (
        31,
        3,
        True,
        51,
    )
    assert M.format_message(back) == rows[3] + "\r\n"
