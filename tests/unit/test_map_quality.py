"""Map scoring (usarsim.maps.quality) and map alignment (usarsim.maps.align) on the yellow arena:
the ground truth handed in as a team's map scores full marks, in its own frame or moved (the
alignment recovers the move), a map missing a room loses that room's share of the coverage,
victims count within 1 m and once each, and a wrong map scores low accuracy."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from usarsim.config.catalog import resolve_world
from usarsim.maps.align import Alignment, align
from usarsim.maps.grid import UNKNOWN, OccupancyMap
from usarsim.maps.mapfile import read_map, write_map
from usarsim.maps.quality import MapScore, score_map
from usarsim.maps.truth import GroundTruthMap, ground_truth_map

CELL = 0.05


@pytest.fixture(scope="module")
def truth() -> GroundTruthMap:
    gt = ground_truth_map(resolve_world("DM-USAR_yellow"), resolution=CELL)
    assert gt.grid.shape == (440, 560)
    return gt


@pytest.fixture(scope="module")
def truth_score(truth: GroundTruthMap) -> MapScore:
    return score_map(truth.grid, truth)


def rotation(theta_deg: float) -> np.ndarray:
    th = math.radians(theta_deg)
    return np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])


def moved_map(grid: OccupancyMap, theta_deg: float, shift: tuple[float, float]) -> OccupancyMap:
    """``grid`` drawn in a frame where its points p lie at R(theta) p + shift: every cell of the
    new map holds the cell of ``grid`` its centre comes from (nearest neighbour)."""
    rot, s = rotation(theta_deg), np.asarray(shift, float)
    res = grid.resolution
    rows, cols = grid.shape
    corners = np.array([[0, 0], [cols, 0], [0, rows], [cols, rows]]) * res + np.asarray(grid.origin)
    moved = corners @ rot.T + s
    low = np.floor(moved.min(axis=0) / res) * res - res
    high = moved.max(axis=0) + res
    shape = (math.ceil((high[1] - low[1]) / res), math.ceil((high[0] - low[0]) / res))
    out = OccupancyMap(res, (float(low[0]), float(low[1])), np.full(shape, UNKNOWN, np.int8))
    source = (out.centres() - s) @ rot  # R^T (p - shift), row by row
    r, c, inside = grid.cell_of(source)
    out.data.reshape(-1)[inside] = grid.data[r[inside], c[inside]]
    return out


def test_ground_truth_as_the_team_map_scores_full_marks(truth, truth_score, tmp_path):
    mapfile = read_map(write_map(tmp_path / "team.yaml", truth.grid))
    score = score_map(mapfile, truth)
    assert score.coverage > 0.99
    assert score.accuracy > 0.99
    assert score.occupied_accuracy > 0.99 and score.free_accuracy > 0.99
    assert score.residual_m < CELL
    assert abs(score.alignment.theta_deg) < 0.1 and math.hypot(score.alignment.tx, score.alignment.ty) < CELL
    assert score.cells_team_known == int(truth.grid.known.sum())
    doc = json.loads(json.dumps(score.as_dict()))
    for key in ("coverage", "accuracy", "occupied_accuracy", "free_accuracy", "residual_m", "alignment"):
        assert key in doc
    assert set(doc["alignment"]) >= {"theta_deg", "tx", "ty"}
    assert doc["victims_total"] == 3 and doc["victims_on_map"] == 0
    assert doc["tolerance_m"] == pytest.approx(1.5 * CELL)
    assert truth_score.coverage == pytest.approx(score.coverage)


def test_moved_map_is_aligned_back_and_scores_the_same(truth, truth_score):
    theta_deg, shift = 10.0, (0.5, 0.0)
    team = moved_map(truth.grid, theta_deg, shift)
    found = align(team, truth.grid)
    # the team frame is the truth's turned by +10 degrees and shifted by 0.5 m: the way back
    # turns by -10 degrees and shifts by -R^T shift
    expected_t = -(rotation(theta_deg).T @ np.asarray(shift))
    assert abs(found.theta_deg + theta_deg) < 0.5
    assert math.hypot(found.tx - expected_t[0], found.ty - expected_t[1]) < CELL
    assert found.residual_m < CELL
    assert found.matched_share > 0.99
    back = found.apply(np.array([[1.0, 2.0]]) @ rotation(theta_deg).T + np.asarray(shift))
    assert np.allclose(back, [[1.0, 2.0]], atol=CELL)
    score = score_map(team, truth, alignment=found)
    assert score.coverage == pytest.approx(truth_score.coverage, abs=0.01)
    assert score.accuracy == pytest.approx(truth_score.accuracy, abs=0.01)


def test_map_missing_a_room_loses_its_share_of_the_coverage(truth, truth_score):
    # the SE room of DM-USAR_yellow.yaml: USARSim x -6..-3, y 2.4..7.2 between its walls, so
    # map x -6..-3, y -7.2..-2.4; its inside, clear of the walls, is blanked
    team = truth.grid.copy()
    centres = team.centres()
    room = (centres[:, 0] > -5.9) & (centres[:, 0] < -3.1) & (centres[:, 1] > -7.1) & (centres[:, 1] < -2.5)
    room = room.reshape(team.shape)
    blanked_share = int((room & truth.grid.free).sum()) / int(truth.grid.free.sum())
    assert blanked_share > 0.015
    team.data[room] = UNKNOWN
    score = score_map(team, truth)
    assert score.coverage == pytest.approx(truth_score.coverage - blanked_share, abs=0.005)
    assert score.accuracy > 0.99


def test_victims_count_within_one_metre_and_once(truth, tmp_path):
    people = {v.name: v for v in truth.victims()}
    assert set(people) == {"Anna", "Ben", "Carl"}
    anna, ben, carl = people["Anna"], people["Ben"], people["Carl"]
    reports = [
        ("A1", anna.x + 0.6, anna.y + 0.3),  # 0.67 m off: counts
        ("A2", anna.x - 0.2, anna.y),  # Anna again: counts once
        ("B", ben.x + 1.5, ben.y),  # 1.5 m off: does not count
        ("C", carl.x, carl.y - 0.9),  # 0.9 m off: counts
    ]
    mapfile = read_map(write_map(tmp_path / "team.yaml", truth.grid, victims=reports))
    score = score_map(mapfile, truth, alignment=Alignment(0.0, 0.0, 0.0))
    assert score.victims_on_map == 2
    assert set(score.victims_found) == {"Anna", "Carl"}
    assert score.victims_reported == 4 and score.victims_total == 3
    assert score.false_reports == 2
    doc = json.loads(json.dumps(score.as_dict()))  # an alignment given by hand has no residual
    assert doc["residual_m"] is None and doc["victims_found"] == ["Anna", "Carl"]
    # reported in a moved map's frame, they are moved back with the map
    theta_deg, shift = 10.0, (0.5, 0.0)
    rot = rotation(theta_deg)
    moved_reports = [(n, *(rot @ np.array([x, y]) + np.asarray(shift))) for n, x, y in reports]
    back_t = -(rot.T @ np.asarray(shift))
    back = Alignment(math.radians(-theta_deg), float(back_t[0]), float(back_t[1]))
    moved = score_map(truth.grid, truth, victims=moved_reports, alignment=back)
    assert moved.victims_on_map == 2 and moved.false_reports == 2


def test_wrong_map_scores_low_accuracy(truth, truth_score):
    red = ground_truth_map(resolve_world("DM-USAR_red"), resolution=CELL)
    score = score_map(red.grid, truth)
    assert score.accuracy < 0.4
    assert score.occupied_accuracy < 0.3
    assert score.accuracy < truth_score.accuracy - 0.6
    rng = np.random.default_rng(7)
    noise = rng.choice(np.array([0, 100, -1], np.int8), size=(200, 240), p=[0.6, 0.2, 0.2])
    random_map = OccupancyMap(CELL, (-6.0, -6.0), noise)
    assert score_map(random_map, truth).accuracy < 0.4
