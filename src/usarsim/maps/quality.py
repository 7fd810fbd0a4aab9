"""Scoring a team's map against the ground truth: how much of the arena it covers, how much of
what it holds is right, and which victims it puts where they are.

The measures follow those the RoboCup Rescue virtual robots league scored maps by (coverage,
accuracy and the attribution of victims to the map: B. Balaguer, S. Balakirsky, S. Carpin and
A. Visser, "Evaluating maps produced by urban search and rescue robots: lessons learned from
RoboCup", Autonomous Robots 27(4):449-464, 2009), computed cell by cell after the team's map is
aligned with the ground truth (:func:`usarsim.maps.align.align`).

All of them are taken in the ground truth's map frame, with the team's cell centres moved there
by the alignment, and a distance ``tolerance_m`` (by default :data:`TOLERANCE_CELLS` times the
larger of the two maps' cell sizes: 0.075 m for two maps of 5 cm cells):

* **coverage**: the share of the ground truth's FREE cells (the floor reachable from a start
  pose) that are covered: a ground-truth cell is covered when the centre of a team FREE cell,
  moved into the ground truth's frame, falls in a ground-truth cell whose centre is within
  ``tolerance_m`` of its centre.
* **occupied_accuracy**: the share of the team's OCCUPIED cells whose moved centre is within
  ``tolerance_m`` of the centre of a ground-truth OCCUPIED cell (the one nearest the
  ground-truth cell it falls in).
* **free_accuracy**: the share of the team's FREE cells whose moved centre is within
  ``tolerance_m`` of the centre of a ground-truth FREE cell (likewise).  A FREE cell on a wall,
  in a closed-off pocket or off the ground truth's floor is wrong.
* **accuracy**: the harmonic mean of ``occupied_accuracy`` and ``free_accuracy``,
  2 a_occ a_free / (a_occ + a_free) (0 when both are 0; when the team's map has cells of one
  kind only, that kind's share).  It is high only when both kinds of cells are right, however
  much open floor the map holds: a map of the wrong place has most of its FREE cells on the
  ground truth's floor all the same, but few of its OCCUPIED cells on its walls.
* **cell_accuracy**: the plain share of right cells (by the two rules above) among all the
  team's known cells (``cells_team_known``: its FREE and OCCUPIED cells); on an arena of
  mostly open floor it is dominated by the FREE cells.
* **victims_on_map**: the ground truth's victims the team reported on its map: every report
  (in the team's frame, moved like the cells) is paired with at most one victim and every
  victim with at most one report, the closest pairs first, a pair counting when the two are
  at most :data:`VICTIM_RADIUS_M` apart.  Reports left unpaired (a second report of a victim
  among them) are ``false_reports``.
* **residual_m**: the alignment's residual (:class:`usarsim.maps.align.Alignment`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from usarsim.maps.align import Alignment, FloatArray, NearestCells, align
from usarsim.maps.grid import OccupancyMap
from usarsim.maps.mapfile import MapFile
from usarsim.maps.truth import GroundTruthMap

# the distance within which a report names a victim (metres): as the run's scorer counts
# reports (docs/scoring.md)
VICTIM_RADIUS_M = 1.0
# the default tolerance, in cells of the coarser of the two maps
TOLERANCE_CELLS = 1.5


@dataclass(frozen=True)
class MapScore:
    """The score of a team's map against a ground-truth map (the module's docstring defines
    each measure)."""

    coverage: float
    accuracy: float
    occupied_accuracy: float
    free_accuracy: float
    cell_accuracy: float
    alignment: Alignment
    tolerance_m: float
    victims_on_map: int
    victims_reported: int
    victims_total: int
    false_reports: int
    victims_found: tuple[str, ...]
    cells_team_known: int
    cells_team_occupied: int
    cells_team_free: int

    @property
    def residual_m(self) -> float:
        return self.alignment.residual_m

    def as_dict(self) -> dict[str, Any]:
        """The score as JSON takes it (a residual or matched share not measured is None)."""
        a = self.alignment
        return {
            "coverage": round(self.coverage, 6),
            "accuracy": round(self.accuracy, 6),
            "occupied_accuracy": round(self.occupied_accuracy, 6),
            "free_accuracy": round(self.free_accuracy, 6),
            "cell_accuracy": round(self.cell_accuracy, 6),
            "residual_m": _finite(a.residual_m),
            "alignment": {
                "theta_deg": round(a.theta_deg, 6),
                "tx": round(a.tx, 6),
                "ty": round(a.ty, 6),
                "matched_share": _finite(a.matched_share),
            },
            "tolerance_m": round(self.tolerance_m, 6),
            "victims_on_map": self.victims_on_map,
            "victims_reported": self.victims_reported,
            "victims_total": self.victims_total,
            "false_reports": self.false_reports,
            "victims_found": list(self.victims_found),
            "cells_team_known": self.cells_team_known,
            "cells_team_occupied": self.cells_team_occupied,
            "cells_team_free": self.cells_team_free,
        }


def _finite(value: float) -> float | None:
    return round(value, 6) if math.isfinite(value) else None


def default_tolerance(team: OccupancyMap, truth: OccupancyMap) -> float:
    """:data:`TOLERANCE_CELLS` cells of the coarser of the two maps (metres)."""
    return TOLERANCE_CELLS * max(team.resolution, truth.resolution)


def score_map(
    team: MapFile | OccupancyMap,
    truth: GroundTruthMap,
    *,
    victims: Iterable[Sequence[Any]] = (),
    tolerance_m: float | None = None,
    alignment: Alignment | None = None,
) -> MapScore:
    """Score ``team``'s map against ``truth``.  ``victims`` are the team's reports, (name, x, y)
    or (x, y) in the team map's frame; when none are given, a MapFile's own victims are.
    ``alignment`` carries the team's frame onto the truth's; by default :func:`align` finds it
    (the identity when the team's map has no occupied cell)."""
    grid = team.grid if isinstance(team, MapFile) else team
    reports = [_report(v, i) for i, v in enumerate(victims)]
    if not reports and isinstance(team, MapFile):
        reports = list(team.victims)
    tgrid = truth.grid
    tol = default_tolerance(grid, tgrid) if tolerance_m is None else float(tolerance_m)
    if not tol >= 0:
        raise ValueError(f"the tolerance must be >= 0 m, got {tolerance_m!r}")
    if alignment is None:
        alignment = align(grid, tgrid) if grid.occupied.any() and tgrid.occupied.any() else Alignment.identity()

    free_pts = alignment.apply(grid.centres(grid.free))
    occ_pts = alignment.apply(grid.centres(grid.occupied))
    coverage = _coverage(free_pts, tgrid, tol)
    occ_right = _within(occ_pts, NearestCells(tgrid, tgrid.occupied), tol)
    free_right = _within(free_pts, NearestCells(tgrid, tgrid.free), tol)
    known = len(occ_pts) + len(free_pts)
    found, false_reports = _match_victims(reports, alignment, truth)
    return MapScore(
        coverage=coverage,
        accuracy=_combined(occ_right, free_right),
        occupied_accuracy=float(occ_right.mean()) if len(occ_right) else 0.0,
        free_accuracy=float(free_right.mean()) if len(free_right) else 0.0,
        cell_accuracy=(int(occ_right.sum()) + int(free_right.sum())) / known if known else 0.0,
        alignment=alignment,
        tolerance_m=tol,
        victims_on_map=len(found),
        victims_reported=len(reports),
        victims_total=len(truth.victims()),
        false_reports=false_reports,
        victims_found=tuple(found),
        cells_team_known=known,
        cells_team_occupied=len(occ_pts),
        cells_team_free=len(free_pts),
    )


def _report(item: Sequence[Any], index: int) -> tuple[str, float, float]:
    values = list(item)
    if len(values) == 2:
        return (f"victim{index + 1}", float(values[0]), float(values[1]))
    if len(values) == 3:
        return (str(values[0]), float(values[1]), float(values[2]))
    raise ValueError(f"a victim report is (name, x, y) or (x, y), got {item!r}")


def _combined(occ_right: npt.NDArray[np.bool_], free_right: npt.NDArray[np.bool_]) -> float:
    """The harmonic mean of the two shares of right cells (of those kinds the map has)."""
    shares = [float(right.mean()) for right in (occ_right, free_right) if len(right)]
    if not shares:
        return 0.0
    if len(shares) == 1:
        return shares[0]
    a, b = shares
    return 2.0 * a * b / (a + b) if a + b > 0 else 0.0


def _coverage(free_pts: FloatArray, truth: OccupancyMap, tol: float) -> float:
    """The share of ``truth``'s FREE cells within ``tol`` (centre to centre) of a cell holding
    one of ``free_pts``."""
    import cv2

    target = truth.free
    total = int(target.sum())
    if total == 0:
        return 0.0
    rows, cols, inside = truth.cell_of(free_pts)
    hit: npt.NDArray[np.uint8] = np.zeros(truth.shape, np.uint8)
    hit[rows[inside], cols[inside]] = 1
    reach = int(math.floor(tol / truth.resolution + 1e-9))
    if reach > 0:
        dr, dc = np.mgrid[-reach : reach + 1, -reach : reach + 1]
        disc = (np.hypot(dr, dc) * truth.resolution <= tol + 1e-9).astype(np.uint8)
        hit = np.asarray(cv2.dilate(hit, disc, borderType=cv2.BORDER_CONSTANT, borderValue=0), np.uint8)
    return int((target & (hit > 0)).sum()) / total


def _within(points: FloatArray, cells: NearestCells, tol: float) -> npt.NDArray[np.bool_]:
    """Whether each point is within ``tol`` of its nearest cell of ``cells``."""
    _centres, dist = cells.nearest(points)
    out: npt.NDArray[np.bool_] = dist <= tol + 1e-9
    return out


def _match_victims(
    reports: list[tuple[str, float, float]], alignment: Alignment, truth: GroundTruthMap
) -> tuple[list[str], int]:
    """(the names of the victims paired with a report, the reports left unpaired): closest
    pairs first, each victim and each report at most once, pairs at most VICTIM_RADIUS_M apart."""
    if not reports:
        return [], 0
    people = truth.victims()
    moved = alignment.apply(np.array([(x, y) for _name, x, y in reports], np.float64))
    pairs = sorted(
        (float(math.hypot(px - v.x, py - v.y)), i, j)
        for i, (px, py) in enumerate(moved)
        for j, v in enumerate(people)
        if math.hypot(px - v.x, py - v.y) <= VICTIM_RADIUS_M + 1e-9
    )
    used_reports: set[int] = set()
    used_victims: set[int] = set()
    for _dist, i, j in pairs:
        if i in used_reports or j in used_victims:
            continue
        used_reports.add(i)
        used_victims.add(j)
    found = [people[j].name for j in sorted(used_victims)]
    return found, len(reports) - len(used_reports)
