"""The range imager (USARSim's KinectDepth, protocol.md 6.3) on the wire: silent until a SCAN,
then the RES and one picture in ``Frames`` lines under the 4096 bytes old clients read, whose
depths match the geometry (a wall at a known distance reads that distance within the Kinect's
noise, the floor reads where it lies); CONF and GEO; settings that cannot fit are refused."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from helpers import WALL_FACE_X, segments, vec
from usarsim.config.catalog import resolve_robot
from usarsim.errors import ConfigError
from usarsim.protocol import messages as M
from usarsim.readings import RangeImageReading
from usarsim.sensors import make_item
from usarsim.sensors.imager import RangeImagerConfig
from usarsim.sensors.scanner import LINE_LIMIT

D = r"\d+\.\d{3}"
FRAME_LINE = re.compile(  # protocol.md 6.3, the UDK RangeImager
    rf"SEN \{{Time (\d+\.\d{{4}})\}} \{{Type RangeImager\}} \{{Name KinectDepth\}} \{{Frames (\d+)\}} \{{Frame (\d+)\}} "
    rf"\{{Resolution 320,240\}} \{{FOV 1\.0122,0\.7854\}} \{{Range ({D}(?:,{D})*)\}}"
)
MOUNT_X = {"P3AT": 0.16, "Kurt3D": 0.19}  # KinectDepth's location in the robot files
SCAN = "SET {Type RangeImager} {Name KinectDepth} {Opcode SCAN}"


def start(server_factory, test_world, robot: str):
    srv = server_factory(world=test_world)
    c = srv.connect()
    c.nfo()
    c.send(f"INIT {{ClassName USARBot.{robot}}} {{Name K}} {{Start FacingWall}}")
    return c


def picture(lines) -> tuple[float, np.ndarray]:
    """(Time, depths as 240 rows of 320) from the RangeImager lines of one SCAN: every frame
    once, in order, all with the same Time, each under the line limit."""
    frames = [ln for ln in lines if ln.text.startswith("SEN") and "{Type RangeImager}" in ln.text]
    assert frames, "no RangeImager line"
    assert max(len(ln.raw) for ln in frames) < LINE_LIMIT
    matches = [FRAME_LINE.fullmatch(ln.text) for ln in frames]
    assert all(matches), frames[0].text[:300]
    n = int(matches[0][2])
    assert [int(m[3]) for m in matches] == list(range(n)) and {int(m[2]) for m in matches} == {n}
    assert len({m[1] for m in matches}) == 1  # one instant
    depths = np.array([v for m in matches for v in vec(m[4])])
    return float(matches[0][1]), depths.reshape(240, 320)


@pytest.mark.parametrize("robot", ["P3AT", "Kurt3D"])
def test_a_scan_reads_the_wall_at_its_distance_and_the_floor_where_it_lies(server_factory, test_world, robot):
    c = start(server_factory, test_world, robot)
    settle = c.step(1.0)
    assert not [ln for ln in settle if "{Type RangeImager}" in ln.text]  # nothing until asked
    c.send("GETGEO {Type Robot}")
    c.step(0.01)
    c.send(SCAN)
    lines = c.step(0.01)
    res = next(i for i, ln in enumerate(lines) if ln.text.startswith("RES"))
    assert lines[res].text.endswith("{Type RangeImager} {Name KinectDepth} {Status OK}")
    t, depth = picture(lines[res + 1 :])
    truth = [segments(ln.text) for ln in lines if "{Type GroundTruth}" in ln.text]
    x = vec(truth[-1]["Location"])[0] if truth else 3.0
    wall = WALL_FACE_X - (x + MOUNT_X[robot])
    # the wall is a plane square to the optical axis: every pixel above the horizon reads its
    # distance (a depth, not a range), within the Kinect's noise there (Nguyen et al. 2012)
    sigma = 0.0012 + 0.0019 * (wall - 0.4) ** 2
    upper = depth[:110]
    assert upper.mean() == pytest.approx(wall, abs=0.01)
    assert 0.5 * sigma < upper.std() < 2.0 * sigma
    assert np.all(np.abs(upper - wall) < 6 * sigma + 0.001)
    # a row below the horizon sees the floor at the height of the lens over the ground:
    # depth = height / tan(the row's angle below the axis), the same along the row
    cfg = RangeImagerConfig()
    _, fy = cfg.focal_px
    row = 200
    below = (row + 0.5 - 120) / fy
    floor = depth[row]
    assert floor.std() < 0.02
    height = float(np.median(floor)) * below
    assert 0.05 < height < 0.6
    nearer = depth[row + 20]  # further down: nearer floor, by the same height
    assert float(np.median(nearer)) == pytest.approx(height / ((row + 20.5 - 120) / fy), abs=0.02)
    # what lies nearer than MinRange reads MinRange (the bottom rows on the floor by the robot)
    assert np.all(depth[-1] == pytest.approx(cfg.min_range_m))


def test_moast_scan_with_a_value_is_answered_and_a_second_scan_sends_a_new_picture(server_factory, test_world):
    c = start(server_factory, test_world, "P3AT")
    c.step(0.5)
    c.send(SCAN + " {Value 0.0}")  # as MOAST sends it (protocol.md 5.4)
    t1, first = picture(c.step(0.01))
    c.step(0.5)
    c.send(SCAN)
    t2, second = picture(c.step(0.01))
    assert t2 > t1
    assert not np.array_equal(first, second)  # a new picture: new noise
    assert np.abs(first[:110] - second[:110]).mean() < 0.02  # of the same wall


def test_conf_and_geo_give_the_picture_its_intrinsics_and_the_mount(server_factory, test_world):
    c = start(server_factory, test_world, "P3AT")
    c.step(0.2)
    c.send("GETCONF {Type RangeImager} {Name KinectDepth}")
    c.send("GETGEO {Type RangeImager} {Name KinectDepth}")
    texts = [ln.text for ln in c.step(0.01)]
    conf = next(t for t in texts if t.startswith("CONF"))
    fx = 160 / math.tan(1.01226 / 2)
    fy = 120 / math.tan(0.7854 / 2)
    assert conf == (
        "CONF {Type RangeImager} {Name KinectDepth} {ScanInterval 0.2000} {MaxRange 4.0000} {MinRange 0.8000} "
        f"{{Resolution 320,240}} {{Fov 1.0122,0.7854}} {{Frames 120}} {{FocalLength {fx:.4f},{fy:.4f}}} "
        "{PrincipalPoint 160.0000,120.0000}"
    )
    geo = next(t for t in texts if t.startswith("GEO"))
    assert "{Name KinectDepth Location 0.1600,0.0000,-0.1700 Orientation 0.0000,0.0000,0.0000 Mount HARD}" in geo


def test_a_picture_is_split_into_frames_that_fit_a_line_and_read_back(tmp_path):
    p3at = resolve_robot("P3AT")
    (item,) = [i for i in p3at.items if i.item_type == "RangeImager"]
    sensor = make_item(item, p3at, 0, "t")
    assert sensor.frames == 120  # 2 rows of 320 depths a line at most 4.000 m
    assert RangeImagerConfig(max_range_m=12.0).frame_count("KinectDepth") == 240  # one row a line
    assert RangeImagerConfig(pixels_x=160, pixels_y=120).frame_count("KinectDepth") == 30
    # a whole picture's lines parse back to its depths, row after row
    r = RangeImageReading("K", (4, 6), (1.0, 0.5), tuple(float(i) / 8 for i in range(24)), frames=3)
    text = M.format_message(M.SensorMessage(time=2.0, reading=r))
    parts = [M.parse_message(line).reading for line in text.split("\r\n")[:-1]]
    assert [p.frame for p in parts] == [0, 1, 2] and {p.frames for p in parts} == {3}
    assert sum((p.ranges_m for p in parts), ()) == r.ranges_m


@pytest.mark.parametrize(
    "settings, message",
    [
        ({"PixelsX": 800}, r"one row of 800 depths .* more than the 4095"),
        ({"FrameCount": 20}, r"20 frames of 12 rows .* more than the 4095"),
        ({"frames": 7}, r"frames must divide the 240 rows"),
        ({"FovX": 3.5}, r"fov_x_rad must be within \(0, pi\)"),
    ],
)
def test_settings_whose_lines_cannot_fit_are_refused_with_what_to_change(settings, message):
    import dataclasses

    p3at = resolve_robot("P3AT")
    (item,) = [i for i in p3at.items if i.item_type == "RangeImager"]
    item = dataclasses.replace(item, params={**item.params, **settings})
    with pytest.raises(ConfigError, match=message):
        make_item(item, p3at, 0, "t")
