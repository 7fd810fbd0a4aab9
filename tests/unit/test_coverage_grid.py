"""The exploration's coverage grid: the compiled beam walk marks the floor a sweep sees."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usarsim.coverage import CoverageGrid


def cells_by_arrays(grid: CoverageGrid, origin, headings, lengths) -> np.ndarray:
    """The cells of the points every half cell along each beam, as an array expression."""
    step = grid.cell_m / 2.0
    ks = np.arange(0.0, float(lengths.max()) + step / 2, step)
    keep = ks[None, :] <= lengths[:, None]
    xs = (origin[0] + np.cos(headings)[:, None] * ks[None, :])[keep]
    ys = (origin[1] + np.sin(headings)[:, None] * ks[None, :])[keep]
    ix = np.floor((xs - grid.x0) / grid.cell_m).astype(np.intp)
    iy = np.floor((ys - grid.y0) / grid.cell_m).astype(np.intp)
    inside = (ix >= 0) & (ix < grid.nx) & (iy >= 0) & (iy < grid.ny)
    return np.unique(ix[inside] * grid.ny + iy[inside])


def test_a_beam_along_x_marks_the_cells_up_to_its_length():
    grid = CoverageGrid((0.0, 0.0, 10.0, 10.0), 0.5)
    new = grid.mark_beams((0.25, 5.25), np.array([0.0]), np.array([2.0]))
    # x from 0.25 to 2.25 m: cells 0 to 4 of the row y = 5.25 (iy 10)
    assert new.tolist() == [ix * grid.ny + 10 for ix in range(5)]
    assert grid.seen_m2 == pytest.approx(5 * 0.25)
    # the same beam again sees nothing new; a longer one only the cells beyond
    assert grid.mark_beams((0.25, 5.25), np.array([0.0]), np.array([2.0])).size == 0
    assert grid.mark_beams((0.25, 5.25), np.array([0.0]), np.array([3.0])).tolist() == [
        5 * grid.ny + 10,
        6 * grid.ny + 10,
    ]


def test_beams_leaving_the_grid_mark_only_the_cells_inside_it():
    grid = CoverageGrid((0.0, 0.0, 2.0, 2.0), 0.5)
    new = grid.mark_beams((1.0, 1.0), np.array([math.pi / 2, -math.pi / 2]), np.array([50.0, 50.0]))
    # along y through x = 1.0 (ix 2): all four cells of that column, each once
    assert sorted(new.tolist()) == [2 * grid.ny + iy for iy in range(4)]
    assert int(grid.seen.sum()) == 4


def test_the_compiled_walk_marks_the_same_cells_as_the_array_expression():
    rng = np.random.default_rng(7)
    for _ in range(60):
        bounds = (rng.uniform(-20, 0), rng.uniform(-20, 0), rng.uniform(1, 20), rng.uniform(1, 20))
        grid = CoverageGrid(bounds, float(rng.choice([0.1, 0.25, 0.3, 0.5])))
        seen = np.zeros_like(grid.seen)
        for _ in range(4):
            origin = (rng.uniform(-25, 25), rng.uniform(-25, 25))
            n = int(rng.integers(1, 300))
            headings = rng.uniform(-7, 7, n)
            lengths = rng.uniform(0, float(rng.choice([0.01, 1.0, 5.0, 20.0])), n)
            expected = cells_by_arrays(grid, origin, headings, lengths)
            expected = expected[~seen[expected]]
            seen[expected] = True
            got = grid.mark_beams(origin, headings, lengths)
            assert got.tolist() == expected.tolist()
            assert np.array_equal(grid.seen, seen)
