"""The 3D laser on the wire (protocol.md 6.3, 7.3): a sweep too long for one SEN line comes as
one line per row, every line under the 4096 bytes old clients read (protocol.md 1), the rows
adding up to the configured grid, at the configured ScanInterval of simulated time."""

from __future__ import annotations

import math
import re

import pytest

from helpers import WALL_FACE_X, segments, vec
from usarsim.config.catalog import ROBOTS_DIR
from usarsim.config.robot import load_robot
from usarsim.protocol import messages as M
from usarsim.readings import RangeScan3DReading
from usarsim.sensors.base import build_config
from usarsim.sensors.scanner import RangeScanner3D, RangeScanner3DConfig

F = r"\d+\.\d{4}"
ROW_LINE = re.compile(  # one row of a sweep: the form in RangeScanner3D's docstring
    rf"SEN \{{Time ({F})\}} \{{Type RangeScanner3D\}} \{{Name Scanner3D\}} \{{Frames (\d+)\}} \{{Frame (\d+)\}} "
    rf"\{{Resolution 0\.0145,0\.0209\}} \{{FOV 0\.4363,1\.0472\}} \{{Range ({F}(?:,{F})*)\}}")


def scanner_config(robot: str) -> RangeScanner3DConfig:
    r = load_robot(ROBOTS_DIR / f"{robot}.yaml")
    (item,) = [i for i in r.items if i.item_type == "RangeScanner3D"]
    return build_config(RangeScanner3D, item, r.path)


def sweeps(lines) -> dict[float, list[tuple[int, int, tuple[float, ...]]]]:
    """(Frames, Frame, ranges) of every RangeScanner3D line, by Time, in arrival order."""
    out: dict[float, list] = {}
    for ln in lines:
        if "{Type RangeScanner3D}" in ln.text:
            m = ROW_LINE.fullmatch(ln.text)
            assert m, ln.text[:300]
            out.setdefault(float(m[1]), []).append((int(m[2]), int(m[3]), vec(m[4])))
    return out


@pytest.mark.parametrize("robot", ["Kurt3D", "Tarantula"])
def test_a_3d_sweep_comes_one_row_per_line_under_4096_bytes(server_factory, test_world, robot):
    cfg = scanner_config(robot)
    rows, cols = cfg.counts
    assert (rows, cols) == (31, 51)  # USARSim's RangeScanner3D configuration (protocol.md 7.3)
    assert cfg.scan_interval_s == pytest.approx(0.4)
    srv = server_factory(world=test_world)
    c = srv.connect()
    c.nfo()
    c.send(f"INIT {{ClassName USARBot.{robot}}} {{Name S}} {{Start FacingWall}}")
    lines = c.step(1.0)  # settle
    lines += c.step(2.0)
    # every line the server sent, CR LF included, stays under the 4096-byte client buffer
    too_long = [len(ln.raw) for ln in lines if len(ln.raw) >= 4096]
    assert not too_long, too_long
    got = sweeps(lines)
    times = sorted(got)
    assert len(times) >= 6
    for t in times:
        sweep = got[t]
        # Frames rows lines, Frame 0 .. rows - 1 in order, cols values each: rows x cols points
        assert [(n, k) for n, k, _ in sweep] == [(rows, k) for k in range(rows)], t
        assert {len(r) for _, _, r in sweep} == {cols}
        assert sum(len(r) for _, _, r in sweep) == rows * cols
    # one sweep per ScanInterval of simulated time
    gaps = {round(b - a, 4) for a, b in zip(times, times[1:])}
    assert gaps == {round(cfg.scan_interval_s, 4)}, gaps
    # the middle row's middle beam looks straight ahead, level, at the wall
    if robot == "Kurt3D":
        truth = {float(segments(ln.text)["Time"]): vec(segments(ln.text)["Location"])
                 for ln in lines if "{Type GroundTruth}" in ln.text}
        mount_x = 0.05  # Scanner3D location in Kurt3D.yaml
        for t in times[-3:]:
            x = truth[t][0]
            middle = got[t][rows // 2][2]
            assert middle[cols // 2] == pytest.approx(WALL_FACE_X - (x + mount_x), abs=0.01)
            # the beams either side read the same plane further off: d / cos(yaw)
            yaw_right = cfg.horizontal_fov_rad / 2
            assert middle[0] == pytest.approx((WALL_FACE_X - (x + mount_x)) / math.cos(yaw_right), abs=0.02)


def test_scan_opcode_sends_a_whole_sweep_after_its_res(server_factory, test_world):
    srv = server_factory(world=test_world)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.Kurt3D} {Name S} {Start FacingWall}")
    c.step(0.5)
    c.send("SET {Type RangeScanner3D} {Name Scanner3D} {Opcode SCAN}")
    lines = c.step(0.01)
    texts = [ln.text for ln in lines]
    res = next(i for i, t in enumerate(texts) if t.startswith("RES"))
    assert texts[res].endswith("{Type RangeScanner3D} {Name Scanner3D} {Status OK}")
    after = [t for t in texts[res + 1:] if "{Type RangeScanner3D}" in t]
    assert [int(segments(t)["Frame"]) for t in after] == list(range(31))


def test_a_sweep_that_fits_stays_one_line_and_a_row_line_reads_back():
    small = RangeScan3DReading("S", (0.1, 0.1), (0.4, 0.4), tuple(float(i) for i in range(25)), frames=5)
    line = M.format_message(M.SensorMessage(1.0, small))
    assert line == ("SEN {Time 1.0000} {Type RangeScanner3D} {Name S} {Resolution 0.1000,0.1000} "
                    "{FOV 0.4000,0.4000} {Range " + ",".join("%d.0000" % i for i in range(25)) + "}\r\n")
    big = RangeScan3DReading("S", (0.0145, 0.0209), (0.4363, 1.0472), tuple(1000.0 for _ in range(31 * 51)),
                             frames=31)
    text = M.format_message(M.SensorMessage(12.5, big))
    rows = text.split("\r\n")[:-1]
    assert len(rows) == 31 and text.endswith("\r\n")
    assert max(len(r) + 2 for r in rows) < M.LINE_LIMIT
    assert rows[3].startswith("SEN {Time 12.5000} {Type RangeScanner3D} {Name S} {Frames 31} {Frame 3} "
                              "{Resolution 0.0145,0.0209} {FOV 0.4363,1.0472} {Range 1000.0000,")
    back = M.parse_message(rows[3])
    assert isinstance(back, M.SensorMessage)
    assert (back.reading.frames, back.reading.frame, len(back.reading.ranges_m)) == (31, 3, 51)
    assert M.format_message(back) == rows[3] + "\r\n"


def test_a_row_too_long_for_one_line_is_refused():
    with pytest.raises(ValueError, match="too long for one SEN line"):
        RangeScanner3DConfig(horizontal_fov_rad=math.pi, horizontal_resolution_rad=math.pi / 720)
    # 181 beams a row at the SICK's 20 m fit (8 bytes a value)
    assert RangeScanner3DConfig(max_range_m=20.0, horizontal_fov_rad=math.pi,
                                horizontal_resolution_rad=math.pi / 180).counts[1] == 181
