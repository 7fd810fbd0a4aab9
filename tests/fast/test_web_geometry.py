"""What the console's world view is given: shapes seen from above (outline after roll, pitch
and yaw; how high they reach), a world's geometry and start poses as JSON, robot classes."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from usarsim.web.geometry import convex_hull, footprint, robot_class_json, shape_points, world_json

DATA = Path(__file__).resolve().parent.parent / "data"


def area(poly) -> float:
    return 0.5 * abs(sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in zip(poly, poly[1:] + poly[:1])))


def test_a_box_turned_by_45_degrees_is_a_diamond_reaching_its_height():
    poly, top, bottom = footprint(shape_points("box", (2.0, 2.0, 1.0)), (5.0, 1.0, -0.5), (0.0, 0.0, math.pi / 4))
    assert len(poly) == 4
    r = math.sqrt(2.0)
    assert sorted((round(x, 3), round(y, 3)) for x, y in poly) == sorted(
        [(round(5 - r, 3), 1.0), (round(5 + r, 3), 1.0), (5.0, round(1 - r, 3)), (5.0, round(1 + r, 3))]
    )
    assert top == pytest.approx(1.0) and bottom == pytest.approx(0.0)


def test_a_cylinder_lying_on_its_side_is_a_rectangle_of_its_length():
    # its axis (own Z) turned by 90 degrees of pitch to lie along X
    poly, top, _ = footprint(
        shape_points("cylinder", radius=0.1, length=2.0), (0.0, 0.0, -0.1), (0.0, math.pi / 2, 0.0)
    )
    xs = [p[0] for p in poly]
    ys = [p[1] for p in poly]
    assert max(xs) - min(xs) == pytest.approx(2.0, abs=1e-3) and max(ys) - min(ys) == pytest.approx(0.2, abs=1e-3)
    assert top == pytest.approx(0.2, abs=1e-3)
    upright, _, _ = footprint(shape_points("cylinder", radius=0.5, length=1.0), (0.0, 0.0, -0.5), (0.0, 0.0, 0.0))
    assert area(upright) == pytest.approx(math.pi * 0.25, rel=0.02)  # a circle


def test_a_mesh_outline_comes_from_its_vertices():
    poly, top, _ = footprint(
        shape_points("mesh", mesh_file=str(DATA / "wedge.obj"), scale=(2.0, 1.0, 1.0)), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    )
    assert area(poly) == pytest.approx(2.0) and top == pytest.approx(0.5)


def test_the_hull_of_collinear_or_repeated_points():
    assert convex_hull([(0, 0), (0, 0)]) == [[0.0, 0.0]]
    assert len(convex_hull([(0, 0), (1, 1), (2, 2), (0, 2), (2, 0)])) == 4


def test_a_world_as_json(yellow_world):
    w = json.loads(json.dumps(world_json(yellow_world)))  # plain JSON types only
    assert w["name"] == "DM-USAR_yellow"
    assert len(w["objects"]) == len(yellow_world.objects)
    movable = [o for o in w["objects"] if o["movable"]]
    assert movable and all("local" in o and "yaw" in o for o in movable)
    tops = [o["top"] for o in w["objects"] if not o["movable"]]
    assert tops == sorted(tops)  # drawn from the lowest to the highest
    assert len(w["victims"]) == len(yellow_world.victims) and len(w["rfid_tags"]) == len(yellow_world.rfid_tags)
    assert w["start_poses"][0] == {"name": "PlayerStart1", "location": [-9.5, 0.0, -0.25], "rotation": [0.0, 0.0, 0.0]}


def test_the_arena_is_what_the_world_is_made_of_without_the_floor_around_it(yellow_world):
    w = world_json(yellow_world)
    x0, y0, x1, y1, top = w["arena"]
    # DM-USAR_yellow: the outer walls, 12.1 m by 14.5 m and 1.2 m high, on a floor of 28 m by 22 m
    assert (x0, y0, x1, y1) == pytest.approx((-6.05, -7.25, 6.05, 7.25), abs=1e-3)
    assert top == pytest.approx(1.2)
    bx0, by0, bx1, by1 = w["bounds"]
    assert (bx1 - bx0) * (by1 - by0) > 3 * (x1 - x0) * (y1 - y0)  # the floor reaches far beyond it
    for o in w["objects"]:
        for x, y in o["poly"]:
            assert x0 - 1e-3 <= x <= x1 + 1e-3 and y0 - 1e-3 <= y <= y1 + 1e-3, o["name"]
    for v in w["victims"]:
        assert x0 <= v["location"][0] <= x1 and y0 <= v["location"][1] <= y1, v


def test_a_world_with_nothing_on_its_floor_frames_the_floor(tmp_path):
    from usarsim.config.catalog import resolve_world

    path = tmp_path / "Bare.yaml"
    path.write_text("name: Bare\nfloor:\n  center: [10.0, -2.0]\n  size: [8.0, 4.0]\n")
    w = world_json(resolve_world(str(path)))
    assert w["arena"] == [6.0, -4.0, 14.0, 0.0, 0.0]


def test_a_robot_class_as_json():
    from usarsim.config.catalog import resolve_robot

    robot = resolve_robot("P2AT")
    p2at = robot_class_json(robot, robot.body_lowest_point_m)
    assert p2at["drive"] == "skid" and p2at["cameras"] == ["Camera"] and p2at["max_speed"] == pytest.approx(5.385)
    assert -0.3 < p2at["spawn_z"] < -0.1  # stands on a floor at z = 0 (Z down)
    stereo = resolve_robot("StereoP2AT")
    assert robot_class_json(stereo, stereo.body_lowest_point_m)["cameras"] == ["CameraLeft", "CameraRight"]
