"""Aligning a team's map with the ground truth: the rigid transform (a turn and a shift) that
carries points of the team's map frame onto the ground truth's map frame.

A team's map is made in a frame of its own (where its first robot started, turned as that
robot was), so it is aligned before it is scored (:mod:`usarsim.maps.quality`).  Only the two
maps' OCCUPIED cells are matched; the alignment is found in two steps:

1. A coarse search over rotations, as in the rigid-transform search between occupancy grids of
   A. Birk and S. Carpin, "Merging occupancy grid maps from multiple robots", Proceedings of
   the IEEE 94(7):1384-1397, 2006.  Both maps' occupied cells are drawn on a coarse grid
   (:data:`COARSE_CELL_M`); for every rotation (every :data:`COARSE_STEP_DEG` degrees within
   ``max_rotation_deg``) the turned team picture is cross-correlated (by FFT) with a
   distance-weighted picture of the ground truth's occupied cells (1 on an occupied coarse
   cell, falling linearly to 0 two coarse cells away), which scores every translation at once.
   The best translation of each rotation is a candidate; the best few rotations, at least
   :data:`CANDIDATE_SEPARATION_DEG` apart, are refined.
2. Refinement by the iterative closest point algorithm (ICP: P. J. Besl and N. D. McKay, "A
   method for registration of 3-D shapes", IEEE Trans. PAMI 14(2):239-256, 1992) on the
   outlines of the occupied areas (the occupied cells with a 4-neighbour that is not
   occupied).  Every team outline cell centre is paired with the centre of the ground truth's
   outline cell nearest the cell it falls in (looked up in the labelled distance transform of
   the ground truth), and pairs farther apart than a gate are dropped (the gate shrinks from
   two coarse cells to :data:`INLIER_CELLS` cells, a distance threshold on the pairs as in
   Z. Zhang, "Iterative point matching for registration of free-form curves and surfaces",
   Int. J. Computer Vision 13(2):119-152, 1994).  Point-to-point steps come first, each
   solving the least-squares rigid transform of the pairs in closed form by the singular value
   decomposition (K. S. Arun, T. S. Huang and S. D. Blostein, "Least-squares fitting of two
   3-D point sets", IEEE Trans. PAMI 9(5):698-700, 1987); point-to-line steps follow
   (Y. Chen and G. Medioni, "Object modelling by registration of multiple range images",
   Image and Vision Computing 10(3):145-155, 1992), minimising the distances along the ground
   truth's outline normals, so that cells sliding along a wall are not pulled back to the
   cell centres of the wall they lie on.

The refined candidate with the largest share of team occupied cells within the inlier
distance of a ground-truth occupied cell wins (ties: the smaller residual).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from usarsim.maps.grid import OccupancyMap

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

# the cell of the coarse search's pictures (metres; at least two cells of either map)
COARSE_CELL_M = 0.2
# the step of the coarse search's rotations (degrees)
COARSE_STEP_DEG = 1.0
# how many of the coarse search's best rotations are refined, and how far apart (degrees)
CANDIDATES = 6
CANDIDATE_SEPARATION_DEG = 8.0
# a pair of cells is an inlier when their centres are at most this many cells apart (the
# coarser map's cells)
INLIER_CELLS = 3.0
# the ICP gate shrinks by this factor at every point-to-point step
GATE_SHRINK = 0.7
# ICP steps at most, and the change (radians, metres) below which it has converged
ICP_STEPS = 60
ICP_CONVERGED = 1e-6
# at most this many team cells take part in an ICP step (an even sample of them)
ICP_POINTS = 20000
# the turned team pictures cross-correlated in one batch
BATCH = 24


@dataclass(frozen=True)
class Alignment:
    """A rigid transform from a team's map frame to the ground truth's map frame: a point p
    goes to R(theta_rad) p + (tx, ty), R(theta) turning counter-clockwise by theta.
    ``residual_m`` is the root mean square distance from the team's occupied cell centres,
    moved by the transform, to the nearest ground-truth occupied cell centre, over the inliers
    (those within :data:`INLIER_CELLS` cells of the coarser map of one), and ``matched_share``
    the share of the team's occupied cells that are inliers; both are NaN when not measured
    (a transform given by hand, or the identity used for a map with no occupied cell)."""

    theta_rad: float
    tx: float
    ty: float
    residual_m: float = math.nan
    matched_share: float = math.nan

    @classmethod
    def identity(cls) -> Alignment:
        """No turn and no shift (the team's map is drawn in the ground truth's frame)."""
        return cls(0.0, 0.0, 0.0)

    @property
    def theta_deg(self) -> float:
        return math.degrees(self.theta_rad)

    @property
    def rotation(self) -> FloatArray:
        """The 2x2 rotation matrix R(theta_rad)."""
        return _rotation(self.theta_rad)

    def apply(self, points: npt.ArrayLike) -> FloatArray:
        """The ground-truth-frame (x, y) of the team-frame points ``points`` (N, 2)."""
        pts = np.asarray(points, np.float64).reshape(-1, 2)
        out: FloatArray = pts @ self.rotation.T + np.array([self.tx, self.ty])
        return out

    def inverse(self) -> Alignment:
        """The transform from the ground truth's frame back to the team's."""
        r = self.rotation
        t = -(r.T @ np.array([self.tx, self.ty]))
        return Alignment(-self.theta_rad, float(t[0]), float(t[1]), self.residual_m, self.matched_share)


class NearestCells:
    """The centres of the cells of ``mask`` on ``grid``, looked up by nearness: for any
    map-frame point, the centre of the mask cell nearest the grid cell holding it (OpenCV's
    labelled distance transform, 5x5 mask, of the grid; points off the grid are looked up at
    the border cell nearest them) and its exact distance from the point."""

    def __init__(self, grid: OccupancyMap, mask: npt.ArrayLike, *, outline_of: npt.ArrayLike | None = None) -> None:
        import cv2

        cells = np.asarray(mask, bool)
        self.grid = grid
        self.count = int(cells.sum())
        self._outline_of = cells if outline_of is None else np.asarray(outline_of, bool)
        self._labels: npt.NDArray[np.int32] | None = None
        self._centres: FloatArray = np.zeros((0, 2))
        self._normals: FloatArray | None = None
        self._cells = np.nonzero(cells)
        self._labels_of_cells: npt.NDArray[np.int32] = np.zeros(0, np.int32)
        if self.count == 0:
            return
        src = np.ascontiguousarray((~cells).astype(np.uint8))
        _dist, labels = cv2.distanceTransformWithLabels(
            src, cv2.DIST_L2, cv2.DIST_MASK_5, labelType=cv2.DIST_LABEL_PIXEL
        )
        self._labels = np.asarray(labels, np.int32)
        self._labels_of_cells = self._labels[self._cells]
        centres = np.zeros((int(self._labels.max()) + 1, 2))
        centres[self._labels_of_cells] = grid.centres(cells)
        self._centres = centres

    def labels(self, points: npt.ArrayLike) -> npt.NDArray[np.int32]:
        """The labels of the mask cells nearest ``points`` (N, 2); the mask must have a cell."""
        if self._labels is None:
            raise ValueError("no cell to look up")
        rows, cols, _inside = self.grid.cell_of(np.asarray(points, np.float64))
        nrows, ncols = self.grid.shape
        out: npt.NDArray[np.int32] = self._labels[np.clip(rows, 0, nrows - 1), np.clip(cols, 0, ncols - 1)]
        return out

    def centres_of(self, labels: npt.NDArray[np.int32]) -> FloatArray:
        out: FloatArray = self._centres[labels]
        return out

    def normals_of(self, labels: npt.NDArray[np.int32]) -> FloatArray:
        """The unit normals (N, 2) at the cells ``labels``: along the gradient of the mask (or
        of ``outline_of``) smoothed by a Gaussian of one cell; (0, 0) where that is flat."""
        if self._normals is None:
            self._normals = self._outline_normals()
        out: FloatArray = self._normals[labels]
        return out

    def nearest(self, points: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """(centres (N, 2), distances (N,)) of the mask cells nearest ``points`` (N, 2); the
        distances are infinite when the mask has no cell."""
        pts = np.asarray(points, np.float64).reshape(-1, 2)
        if self._labels is None:
            return np.full(pts.shape, np.nan), np.full(len(pts), np.inf)
        centres = self.centres_of(self.labels(pts))
        dist: FloatArray = np.hypot(*(centres - pts).T)
        return centres, dist

    def _outline_normals(self) -> FloatArray:
        import cv2

        smooth = cv2.GaussianBlur(self._outline_of.astype(np.float32), (0, 0), 1.0)
        gx = np.asarray(cv2.Sobel(smooth, cv2.CV_32F, 1, 0, ksize=3), np.float64)
        gy = np.asarray(cv2.Sobel(smooth, cv2.CV_32F, 0, 1, ksize=3), np.float64)
        rows, cols = self._cells
        grad = np.column_stack((gx[rows, cols], gy[rows, cols]))  # columns run along x, rows along y
        norm = np.hypot(*grad.T)
        flat = norm < 1e-3
        grad[~flat] /= norm[~flat, None]
        grad[flat] = 0.0
        out = np.zeros_like(self._centres)
        out[self._labels_of_cells] = grad
        return out


def align(team: OccupancyMap, truth: OccupancyMap, *, max_rotation_deg: float = 180.0) -> Alignment:
    """The rigid transform that carries ``team``'s map frame onto ``truth``'s, turned by at
    most ``max_rotation_deg`` degrees either way (180: any turn).  ValueError when either map
    has no occupied cell."""
    team_pts = team.centres(team.occupied)
    truth_pts = truth.centres(truth.occupied)
    if len(team_pts) == 0 or len(truth_pts) == 0:
        which = "team's" if len(team_pts) == 0 else "ground truth's"
        raise ValueError(f"the {which} map has no occupied cell to align by")
    max_rot = min(180.0, abs(float(max_rotation_deg)))
    coarse = max(COARSE_CELL_M, 2.0 * team.resolution, 2.0 * truth.resolution)
    inlier_m = INLIER_CELLS * max(team.resolution, truth.resolution)
    nearest = NearestCells(truth, truth.occupied)
    edges = NearestCells(truth, _edges(truth.occupied), outline_of=truth.occupied)
    team_edges = team.centres(_edges(team.occupied))
    sample = team_edges[:: max(1, math.ceil(len(team_edges) / ICP_POINTS))]
    best: tuple[float, float, FloatArray, FloatArray, FloatArray] | None = None
    for theta, shift in _coarse_candidates(team_pts, truth, coarse, max_rot):
        rot, t = _icp(sample, edges, _rotation(theta), shift, 2.0 * coarse, inlier_m)
        _centres, dist = nearest.nearest(team_pts @ rot.T + t)
        inliers = dist <= inlier_m
        share = float(inliers.mean())
        residual = float(np.sqrt(np.mean(dist[inliers] ** 2))) if inliers.any() else math.inf
        if best is None or (share, -residual) > (best[0], -best[1]):
            best = (share, residual, rot, t, dist)
    assert best is not None
    share, residual, rot, t, _dist = best
    theta = math.atan2(rot[1, 0], rot[0, 0])
    return Alignment(theta, float(t[0]), float(t[1]), residual, share)


def _edges(mask: BoolArray) -> BoolArray:
    """The cells of ``mask`` with a 4-neighbour outside it (or on the grid's border)."""
    import cv2

    cells = np.ascontiguousarray(mask.astype(np.uint8))
    cross = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
    inner = cv2.erode(cells, cross, borderType=cv2.BORDER_CONSTANT, borderValue=0)
    out: BoolArray = mask & (inner == 0)
    return out


def _rotation(theta: float) -> FloatArray:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


def _coarse_candidates(
    team_pts: FloatArray, truth: OccupancyMap, cell: float, max_rot_deg: float
) -> list[tuple[float, FloatArray]]:
    """The coarse search's best rotations, each with its best translation: (theta, t) with a
    team point p going to R(theta) p + t."""
    import cv2

    # the ground truth's picture: 1 on an occupied coarse cell, falling to 0 two cells away
    rows = math.ceil(truth.shape[0] * truth.resolution / cell)
    cols = math.ceil(truth.shape[1] * truth.resolution / cell)
    truth_pts = truth.centres(truth.occupied)
    occ = np.zeros((rows, cols), bool)
    r, c = _coarse_index(truth_pts, np.asarray(truth.origin, np.float64), cell)
    occ[np.clip(r, 0, rows - 1), np.clip(c, 0, cols - 1)] = True
    dist = cv2.distanceTransform(np.ascontiguousarray((~occ).astype(np.uint8)), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    weight = np.clip(1.0 - np.asarray(dist, np.float32) / 2.0, 0.0, 1.0).astype(np.float32)

    # one point per occupied half coarse cell of the team's map is enough for its pictures
    half = np.unique(np.floor(team_pts / (cell / 2.0)).astype(np.int64), axis=0)
    spread = (half + 0.5) * (cell / 2.0)
    centroid = spread.mean(axis=0)
    centred = spread - centroid
    reach = int(math.ceil(2.0 * float(np.hypot(*centred.T).max()) / cell)) + 2
    size = (cv2.getOptimalDFTSize(rows + reach), cv2.getOptimalDFTSize(cols + reach))
    truth_f = np.fft.rfft2(weight, s=size)

    steps = int(math.floor(max_rot_deg / COARSE_STEP_DEG + 1e-9))
    angles = np.radians(np.arange(-steps, steps + 1) * COARSE_STEP_DEG)
    if max_rot_deg >= 180.0 - 1e-9:
        angles = angles[angles > -math.pi + 1e-9]  # -180 and 180 are one turn
    scores = np.zeros(len(angles))
    shifts = np.zeros((len(angles), 2))
    for start in range(0, len(angles), BATCH):
        batch = angles[start : start + BATCH]
        pictures = np.zeros((len(batch), *size), np.float32)
        lows = np.zeros((len(batch), 2))
        counts = np.zeros(len(batch))
        for k, theta in enumerate(batch):
            turned = centred @ _rotation(float(theta)).T
            lows[k] = turned.min(axis=0)
            tr, tc = _coarse_index(turned, lows[k], cell)
            pictures[k, tr, tc] = 1.0
            counts[k] = pictures[k].sum()
        # circular cross-correlation: corr[u, v] = sum picture[r, c] weight[r + u, c + v]
        corr = np.fft.irfft2(np.conj(np.fft.rfft2(pictures)) * truth_f[None], s=size)
        flat = corr.reshape(len(batch), -1).argmax(axis=1)
        for k, idx in enumerate(flat):
            u, v = divmod(int(idx), size[1])
            scores[start + k] = float(corr[k, u, v]) / max(counts[k], 1.0)
            u = u - size[0] if u >= rows else u  # a shift down or left wraps around
            v = v - size[1] if v >= cols else v
            shifts[start + k] = (v, u)

    chosen: list[tuple[float, FloatArray]] = []
    for k in np.argsort(-scores, kind="stable"):
        theta = float(angles[k])
        if any(abs(_wrap(theta - other)) < math.radians(CANDIDATE_SEPARATION_DEG) for other, _t in chosen):
            continue
        # a team cell at turned point q lands in the truth's coarse cell of
        # origin + (q - low) + shift * cell
        rot = _rotation(theta)
        low = (centred @ rot.T).min(axis=0)
        t = np.asarray(truth.origin, np.float64) - low + shifts[k] * cell - rot @ centroid
        chosen.append((theta, t))
        if len(chosen) == CANDIDATES:
            break
    return chosen


def _coarse_index(points: FloatArray, low: FloatArray, cell: float) -> tuple[npt.NDArray[np.intp], ...]:
    idx = np.floor((points - low) / cell).astype(np.intp)
    return idx[:, 1], idx[:, 0]


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def _icp(
    points: FloatArray, truth: NearestCells, rot: FloatArray, t: FloatArray, gate: float, gate_min: float
) -> tuple[FloatArray, FloatArray]:
    """ICP from (rot, t): the transform that carries ``points`` onto the cells of ``truth``
    (which has normals).  Point-to-point steps while the gate shrinks to ``gate_min``, then
    point-to-line steps until the transform settles."""
    for _step in range(ICP_STEPS):
        labels = truth.labels(points @ rot.T + t)
        targets = truth.centres_of(labels)
        keep = np.hypot(*(points @ rot.T + t - targets).T) <= gate
        if keep.sum() < 3:
            break
        new_rot, new_t = _fit_rigid(points[keep], targets[keep])
        done = _change(rot, t, new_rot, new_t) < ICP_CONVERGED
        rot, t = new_rot, new_t
        if gate <= gate_min and done:
            break
        gate = max(gate_min, gate * GATE_SHRINK)
    for _step in range(ICP_STEPS):
        moved = points @ rot.T + t
        labels = truth.labels(moved)
        targets, normals = truth.centres_of(labels), truth.normals_of(labels)
        keep = (np.hypot(*(moved - targets).T) <= gate_min) & np.any(normals != 0.0, axis=1)
        if keep.sum() < 3:
            break
        new_rot, new_t = _fit_rigid_to_lines(moved[keep], targets[keep], normals[keep], rot, t)
        done = _change(rot, t, new_rot, new_t) < ICP_CONVERGED
        rot, t = new_rot, new_t
        if done:
            break
    return rot, t


def _change(rot: FloatArray, t: FloatArray, new_rot: FloatArray, new_t: FloatArray) -> float:
    turn = abs(_wrap(math.atan2(new_rot[1, 0], new_rot[0, 0]) - math.atan2(rot[1, 0], rot[0, 0])))
    return turn + float(np.hypot(*(new_t - t)))


def _fit_rigid_to_lines(
    moved: FloatArray, targets: FloatArray, normals: FloatArray, rot: FloatArray, t: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """One point-to-line step (Chen and Medioni 1992): the small turn about the points'
    centroid and the shift that minimise sum ((m_i - q_i) . n_i)^2 to first order, composed
    with (rot, t)."""
    centre = moved.mean(axis=0)
    arm = moved - centre
    jac = np.column_stack((normals[:, 1] * arm[:, 0] - normals[:, 0] * arm[:, 1], normals[:, 0], normals[:, 1]))
    resid = np.einsum("ij,ij->i", moved - targets, normals)
    step, *_rest = np.linalg.lstsq(jac, -resid, rcond=None)
    turn = _rotation(float(step[0]))
    return turn @ rot, turn @ (t - centre) + centre + step[1:]


def _fit_rigid(src: FloatArray, dst: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The rotation R and translation t minimising sum |R src_i + t - dst_i|^2 (Arun, Huang and
    Blostein 1987)."""
    ms, md = src.mean(axis=0), dst.mean(axis=0)
    h = (src - ms).T @ (dst - md)
    u, _s, vt = np.linalg.svd(h)
    rot = vt.T @ u.T
    if np.linalg.det(rot) < 0:  # a reflection: flip the least significant axis
        vt[1] *= -1.0
        rot = vt.T @ u.T
    t = md - rot @ ms
    return rot, t
