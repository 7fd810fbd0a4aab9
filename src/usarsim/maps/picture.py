"""Pictures of maps for people: a map alone (``usarsim map``), and a team's map laid over the
ground truth with the alignment the scorer found (``usarsim score-map --picture``, the
competition's leaderboard).

North is up: the map's X (USARSim's X, north) points up the page and its Y (west) to the left,
so east is on the right as on a plan of the arena.  Victims are red discs, RFID tags blue
squares, start poses green triangles; on an overlay, the victims the team reported are dark red
crosses.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from usarsim.maps.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap

# colours (RGB)
COLOURS: dict[Any, tuple[int, int, int]] = {
    FREE: (255, 255, 255),
    OCCUPIED: (30, 30, 30),
    UNKNOWN: (190, 190, 200),
    "victim": (220, 40, 40),
    "tag": (40, 120, 220),
    "start": (30, 160, 60),
}
# the overlay: the ground truth pale, the team's free floor green, its walls dark red
TRUTH_FREE, TRUTH_OCCUPIED, TRUTH_UNKNOWN = (250, 250, 250), (150, 150, 150), (215, 215, 222)
TEAM_FREE, TEAM_OCCUPIED = (150, 215, 160), (170, 20, 40)


def draw_grid(path: str | Path, grid: OccupancyMap, markers=(), *, scale: int = 2) -> Path:
    """A PNG of ``grid`` with ``markers`` (usarsim.maps.truth.Marker) drawn."""
    rgb = np.zeros((*grid.shape, 3), np.uint8)
    for value in (FREE, OCCUPIED, UNKNOWN):
        rgb[grid.data == value] = COLOURS[value]
    return _save(path, rgb, grid, markers, scale)


def draw_overlay(
    path: str | Path,
    team: OccupancyMap | None,
    truth: Any,
    score: dict | None,
    *,
    victims: Sequence[tuple[str, float, float]] = (),
    scale: int = 2,
) -> Path:
    """A PNG of ``truth`` (usarsim.maps.truth.GroundTruthMap) with ``team``'s map laid over it,
    moved by the alignment of ``score`` (usarsim.maps.quality's, as a dict), and the victims the
    team reported (``victims``, its map's frame) as dark red crosses; the ground truth alone
    when there is no team map."""
    g = truth.grid
    rgb = np.zeros((*g.shape, 3), np.uint8)
    rgb[g.data == FREE] = TRUTH_FREE
    rgb[g.data == OCCUPIED] = TRUTH_OCCUPIED
    rgb[g.data == UNKNOWN] = TRUTH_UNKNOWN
    a = (score or {}).get("alignment") or {}
    if team is not None and a:
        theta = math.radians(float(a.get("theta_deg", 0.0)))
        c, s = math.cos(theta), math.sin(theta)
        rot = np.array([[c, -s], [s, c]])
        shift = np.array([float(a.get("tx", 0.0)), float(a.get("ty", 0.0))])
        import cv2

        for mask, colour in ((team.free, TEAM_FREE), (team.occupied, TEAM_OCCUPIED)):
            pts = team.centres(mask) @ rot.T + shift
            rows, cols, inside = g.cell_of(pts)
            hit = np.zeros(g.shape, np.uint8)
            hit[rows[inside], cols[inside]] = 1
            if team.resolution <= g.resolution * 1.5:  # close the gaps a turned grid leaves
                hit = cv2.morphologyEx(hit, cv2.MORPH_CLOSE, np.ones((3, 3), np.uint8))
            else:  # a coarser map: each of its cells covers several of the ground truth's
                k = int(math.ceil(team.resolution / g.resolution))
                hit = cv2.dilate(hit, np.ones((k, k), np.uint8))
            rgb[hit.astype(bool)] = colour
    reports: list[Any] = []
    if team is not None and a and victims:
        moved = np.array([(x, y) for _, x, y in victims]) @ rot.T + shift
        reports = [_Report("report", name, float(x), float(y)) for (name, _, _), (x, y) in zip(victims, moved)]
    return _save(path, rgb, g, [*truth.markers, *reports], scale)


@dataclass(frozen=True)
class _Report:
    kind: str
    name: str
    x: float
    y: float


def _save(path: str | Path, rgb: np.ndarray, grid: OccupancyMap, markers, scale: int) -> Path:
    from PIL import Image, ImageDraw

    rows, cols = grid.shape
    # north up: the picture's row is the map's column (X) from the top, its column the map's
    # row (Y) from the right
    picture = np.ascontiguousarray(np.flip(rgb.transpose(1, 0, 2), axis=(0, 1)))
    im = Image.fromarray(picture).resize((rows * scale, cols * scale), Image.Resampling.NEAREST)
    draw = ImageDraw.Draw(im)
    px = scale / grid.resolution
    for m in markers:
        u = (rows - (m.y - grid.origin[1]) / grid.resolution) * scale
        v = (cols - (m.x - grid.origin[0]) / grid.resolution) * scale
        r = max(3.0, 0.25 * px)
        if m.kind == "victim":
            draw.ellipse((u - r, v - r, u + r, v + r), fill=COLOURS["victim"], outline=(0, 0, 0))
        elif m.kind == "report":  # a victim the team put on its map
            r *= 1.4
            draw.line((u - r, v - r, u + r, v + r), fill=TEAM_OCCUPIED, width=3)
            draw.line((u - r, v + r, u + r, v - r), fill=TEAM_OCCUPIED, width=3)
        elif m.kind == "tag":
            h = r * 0.6
            draw.rectangle((u - h, v - h, u + h, v + h), fill=COLOURS["tag"])
        else:
            draw.polygon([(u, v - r), (u - r, v + r), (u + r, v + r)], fill=COLOURS["start"])
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    im.save(path, optimize=True)
    return path
