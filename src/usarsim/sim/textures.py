"""Procedural textures of the world's surfaces, for cameras.

Every texture is an RGB image made with NumPy from a seeded generator, so that the same name
and colour always give the same pixels.  A texture is made around its material's colour (the
``rgba`` of the world file): the image's average colour is close to it, the texture adds the
pattern (the strands of a board, the joints of a brick wall, the grain of asphalt), so
that the top-down map and the recording, which show the material's colour, still agree with
the cameras.  Images are made at first use and kept on disk under the user's cache folder
(``$XDG_CACHE_HOME/usarsim/textures``, by default ``~/.cache/usarsim/textures``); a folder
that cannot be written only means that they are made again next time.

Each texture has a natural tile size (metres along the image's width and height): one image
covers that much of a surface unless the material gives its own ``texture_scale`` (tiles per
metre).  A *fitted* texture (``road``) is laid along the longer side of a box, once across
its width and at its natural length along it.  A road's markings are not in its texture: they
are laid on the road as thin shapes (:func:`road_markings`, ``usarsim.sim.markings``).

Sizes of building materials are nominal trade sizes: 4 ft x 8 ft (1.22 x 2.44 m) sheets of
plywood and OSB (APA, "Engineered Wood Construction Guide", 2019); a concrete masonry unit's
face 397 x 194 mm with 10 mm joints (ASTM C90 nominal 8 x 16 in); a modular brick 194 x 57 mm
with 10 mm joints (BIA Technical Note 10); road markings after the MUTCD (FHWA, "Manual on
Uniform Traffic Control Devices", 2009 ed.): normal lines 4-6 in (0.10-0.15 m) wide, a double
centre line of two yellow lines, stop lines 12-24 in (0.30-0.61 m) wide (section 3B.16).
"""

from __future__ import annotations

import logging
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

log = logging.getLogger("usarsim.textures")

# Bumped whenever a generator changes, so that cached images of an older look are not reused.
VERSION = 3


@dataclass(frozen=True)
class TextureKind:
    """A texture the world files can name: its tile size (metres along the image's width and
    height), how shiny its surface is (MuJoCo's material specular, 0..1), whether it is
    fitted to a box's long side, and the function that draws it around a colour."""

    size_m: tuple[float, float]
    specular: float
    draw: Callable[[np.random.Generator, np.ndarray], np.ndarray]
    fitted: bool = False


# -- helpers -----------------------------------------------------------------------------


def _noise(rng: np.random.Generator, h: int, w: int, cells: int) -> np.ndarray:
    """Smooth value noise in [-1, 1] that repeats seamlessly across the image's edges."""
    cy, cx = max(1, cells * h // max(h, w)), max(1, cells * w // max(h, w))
    grid = rng.uniform(-1.0, 1.0, (cy, cx))
    y = np.arange(h) * cy / h
    x = np.arange(w) * cx / w
    y0, x0 = np.floor(y).astype(int), np.floor(x).astype(int)
    fy, fx = (y - y0)[:, None], (x - x0)[None, :]
    fy, fx = fy * fy * (3 - 2 * fy), fx * fx * (3 - 2 * fx)  # smoothstep
    y1, x1 = (y0 + 1) % cy, (x0 + 1) % cx
    a, b = grid[y0][:, x0], grid[y0][:, x1]
    c, d = grid[y1][:, x0], grid[y1][:, x1]
    return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy


def _fbm(rng: np.random.Generator, h: int, w: int, cells: int = 4, octaves: int = 4) -> np.ndarray:
    out = np.zeros((h, w))
    amp, total = 1.0, 0.0
    for _ in range(octaves):
        out += amp * _noise(rng, h, w, cells)
        total += amp
        amp *= 0.5
        cells *= 2
    return out / total


def _shade(base: np.ndarray, factor: np.ndarray) -> np.ndarray:
    """The colour ``base`` scaled pixel by pixel (an (h, w) factor around 1)."""
    return base[None, None, :] * factor[..., None]


def _lines(n: int, period: int, width: int, offset: int = 0) -> np.ndarray:
    """True on the pixels of lines ``width`` wide every ``period`` pixels of an axis of n."""
    return ((np.arange(n) - offset) % period) < width


def _stripes_mask(h: int, w: int, course_px: int, unit_px: int, joint_px: int) -> tuple[np.ndarray, np.ndarray]:
    """Running bond (masonry): a mask of the joints and the index of each unit."""
    yy, xx = np.mgrid[0:h, 0:w]
    course = yy // course_px
    shifted = xx + (course % 2) * (unit_px // 2)
    joints = ((yy % course_px) < joint_px) | ((shifted % unit_px) < joint_px)
    unit = course * 1000 + (shifted // unit_px) % (w // unit_px)
    return joints, unit


def _per_unit(rng: np.random.Generator, unit: np.ndarray, spread: float) -> np.ndarray:
    """A factor around 1 drawn once per unit (brick, block, tile)."""
    ids, inverse = np.unique(unit, return_inverse=True)
    return (1.0 + rng.uniform(-spread, spread, len(ids)))[inverse].reshape(unit.shape)


# -- the textures ------------------------------------------------------------------------


def _osb(rng, base):
    # oriented strand board: long wood strands pressed in layers, mostly along one direction
    h = w = 256
    img = _shade(base, 0.92 + 0.05 * _fbm(rng, h, w, 8))
    for _ in range(1400):
        y, x = rng.integers(0, h), rng.integers(0, w)
        length, width = rng.integers(10, 30), rng.integers(3, 7)
        ys = np.arange(y, y + width) % h
        xs = np.arange(x, x + length) % w
        img[np.ix_(ys, xs)] = base * rng.uniform(0.78, 1.22) * rng.uniform(0.95, 1.05, 3)
    seam = _lines(h, h, 2)[:, None] | _lines(w, w, 2)[None, :]
    img[seam] *= 0.55
    return img


def _plywood(rng, base):
    # rotary-cut veneer: long grain lines along the sheet, a sheet joint at the tile's edge
    h = w = 256
    warp = 18.0 * _fbm(rng, h, w, 3)
    yy = np.arange(h)[:, None] + warp
    grain = np.sin(yy * 0.45 + 3.0 * _noise(rng, h, w, 6))
    img = _shade(base, 1.0 + 0.07 * grain + 0.05 * _fbm(rng, h, w, 16))
    img[_lines(h, h, 2)[:, None] | _lines(w, w, 2)[None, :]] *= 0.6
    return img


def _painted_panel(rng, base):
    # plywood painted in the arena's colour: flat paint, the grain faintly through it, the
    # joints between sheets and a row of screw heads along them
    h = w = 256
    yy = np.arange(h)[:, None] + 10.0 * _fbm(rng, h, w, 3)
    img = _shade(base, 1.0 + 0.025 * np.sin(yy * 0.5) + 0.03 * _fbm(rng, h, w, 24))
    img[_lines(h, h, 3)[:, None] | _lines(w, w, 3)[None, :]] *= 0.5
    for k in range(8):
        c = 8 + k * 32
        img[c : c + 2, 6:8] *= 0.6
        img[6:8, c : c + 2] *= 0.6
    # scuffs near the floor: the lower tenth darker where robots bumped into it
    img[int(h * 0.9) :] *= (0.9 + 0.08 * _fbm(rng, h - int(h * 0.9), w, 16))[..., None]
    return img


def _concrete(rng, base):
    h = w = 256
    img = _shade(base, 1.0 + 0.10 * _fbm(rng, h, w, 4, 5))
    pores = rng.random((h, w)) < 0.0015
    img[pores] *= 0.8
    return img


def _tile(rng, base):
    # 300 mm floor tiles, 4 x 4 to a texture, with light grout joints
    h = w = 256
    unit = (np.arange(h)[:, None] // 64) * 10 + np.arange(w)[None, :] // 64
    joints = _lines(h, 64, 3)[:, None] | _lines(w, 64, 3)[None, :]
    img = _shade(base, _per_unit(rng, unit, 0.05) + 0.04 * _fbm(rng, h, w, 16))
    img[joints] = np.minimum(base * 1.25 + 0.1, 1.0)
    return img


def _masonry(rng, base, course_px, unit_px, joint_px, spread, mortar):
    h = w = 256
    joints, unit = _stripes_mask(h, w, course_px, unit_px, joint_px)
    img = _shade(base, _per_unit(rng, unit, spread) + 0.08 * _fbm(rng, h, w, 32, 3))
    img[joints] = mortar * (1.0 + 0.05 * _noise(rng, h, w, 64))[joints][:, None]
    return img


def _cinder(rng, base):
    # concrete masonry units: 4 courses of 0.2 m, 2 units of 0.4 m to a course, on 0.8 m
    return _masonry(rng, base, 64, 128, 3, 0.04, np.array([0.72, 0.71, 0.68]))


def _brick(rng, base):
    # modular bricks (0.2 m x 67 mm courses): 4 bricks across, 8 courses down on 0.8 x 0.53 m
    return _masonry(rng, base, 32, 64, 3, 0.10, np.array([0.74, 0.72, 0.66]))


def _paper(rng, base):
    # a printed sheet: a margin, then lines of text (grey dashes of word length)
    h = w = 256
    img = _shade(base, 1.0 + 0.01 * _fbm(rng, h, w, 8))
    for row in range(28, h - 28, 9):
        x = 28
        while x < w - 40:
            n = int(rng.integers(6, 26))
            img[row : row + 3, x : min(x + n, w - 28)] *= 0.45
            x += n + 5
    return img


def _pipe(rng, base):
    # steel pipe: streaks along its length, patches of rust
    h = w = 256
    streak = _noise(rng, h, w, 64)[:, :1] * np.ones((1, w))
    img = _shade(base, 1.0 + 0.08 * streak + 0.05 * _fbm(rng, h, w, 8))
    rust = _fbm(rng, h, w, 6) > 0.25
    img[rust] = np.array([0.40, 0.17, 0.07])  # rust (hue 18, saturation 0.8: not skin)
    return img


def _cells(rng, h, w, n):
    """Nearest and second-nearest distances (pixels) to n random points, wrapping at the edges."""
    pts = rng.uniform(0, 1, (n, 2)) * (h, w)
    yy, xx = np.mgrid[0:h, 0:w]
    dy = np.abs(yy[..., None] - pts[:, 0])
    dx = np.abs(xx[..., None] - pts[:, 1])
    d = np.hypot(np.minimum(dy, h - dy), np.minimum(dx, w - dx))
    order = np.partition(d, 1, axis=-1)
    return np.argmin(d, axis=-1), order[..., 0], order[..., 1]


def _rubble(rng, base):
    # broken concrete and brick: chunks of varied shade, dark gaps between them
    h = w = 256
    cell, d1, d2 = _cells(rng, h, w, 60)
    shade = rng.uniform(0.7, 1.25, 60)[cell] + 0.08 * _fbm(rng, h, w, 16)
    img = _shade(base, shade)
    img[(d2 - d1) < 2.5] *= 0.45
    return img


def _gravel(rng, base):
    # packed earth with small stones
    h = w = 256
    img = _shade(base, 1.0 + 0.12 * _fbm(rng, h, w, 8))
    disc = np.hypot(*np.mgrid[-3:4, -3:4]) <= 3.0
    for _ in range(500):
        y, x = rng.integers(0, h), rng.integers(0, w)
        ys, xs = np.arange(y, y + 7) % h, np.arange(x, x + 7) % w
        patch = img[np.ix_(ys, xs)]
        patch[disc] *= rng.uniform(0.7, 1.35)
        img[np.ix_(ys, xs)] = patch
    return img


def _asphalt(rng, base):
    # a dark binder with light and dark aggregate
    h = w = 256
    img = _shade(base, 1.0 + 0.08 * _fbm(rng, h, w, 8))
    grit = rng.random((h, w))
    img[grit < 0.06] *= 1.45
    img[grit > 0.96] *= 0.6
    return img


# The road world's streets (tools/make_road_world.py): two 12 ft lanes between two 8 ft
# parking strips (12.192 m kerb to kerb), crossings every 82 m, each approach's stop line
# 7.5 m before the crossing street's centre line (the RNDF stop waypoints).
ROAD_WIDTH_M = 12.192
ROAD_BLOCK_M = 82.0
ROAD_LANE_M = 3.6576
ROAD_STOP_M = 7.5
YELLOW = np.array([0.95, 0.75, 0.10])  # traffic yellow (MUTCD): a yellow centre line
WHITE = np.array([0.93, 0.93, 0.90])


def _road(rng, base):
    """One block of a street's asphalt (its markings are not painted into the texture: see
    :func:`road_markings`)."""
    return _asphalt_strip(rng, base, 304, 2048)


@dataclass(frozen=True)
class Marking:
    """A painted rectangle on a road: from ``start`` to ``end`` metres along the way the road
    runs, from ``left`` to ``right`` metres across it (from its centre line, positive on the
    right of the way it runs), of colour ``rgb``."""

    start: float
    end: float
    left: float
    right: float
    rgb: tuple[float, float, float]


def road_markings(length_m: float) -> list[Marking]:
    """The markings of a street ``length_m`` long that begins and ends at a crossing, block by
    block of ROAD_BLOCK_M (the last one cut at the street's end): each block is a crossing
    (its first 12.192 m), then a double yellow centre line, white lines between the travel
    lanes and the parking strips, and a stop line across each approach lane, 7.5 m before
    the crossing street's centre line (right-hand traffic: each way stops on its own lane, on
    the right).

    The markings are laid on the road as thin shapes rather than painted into its texture: far
    ahead of a camera near the ground the road is seen at a grazing angle, where a texel along
    the road shrinks on the picture many times more than one across it; the renderer picks the
    texture's mipmap from the larger shrinking (OpenGL 4.6 core profile, sec. 8.14.1; the
    anisotropic filtering that would not is thirty to forty times slower on a software
    renderer), so lines painted into the texture would be averaged across as much as along and
    smeared into streaks a few tens of metres ahead.  Shapes are drawn at their true size at any distance and
    smoothed at their edges by the renderer's multisampling."""
    out: list[Marking] = []
    lane = ROAD_LANE_M
    half = 0.06  # the lines are 0.12 m wide
    blocks = max(0, math.ceil((length_m - ROAD_WIDTH_M) / ROAD_BLOCK_M))
    for b in range(blocks):
        start = b * ROAD_BLOCK_M
        here, ahead = start + ROAD_WIDTH_M / 2, start + ROAD_BLOCK_M + ROAD_WIDTH_M / 2  # crossing centres
        lines = (start + ROAD_WIDTH_M, start + ROAD_BLOCK_M)
        for off in (-0.15, 0.15):  # the double centre line: two 0.12 m lines 0.18 m apart
            out.append(Marking(*lines, off - half, off + half, tuple(YELLOW)))
        for e in (-lane, lane):
            out.append(Marking(*lines, e - half, e + half, tuple(WHITE)))
        # a stop line 0.45 m wide (18 in) across each approach lane: the way the road runs
        # stops before the crossing ahead, the other way after this one's crossing
        out.append(Marking(ahead - ROAD_STOP_M - 0.225, ahead - ROAD_STOP_M + 0.225, 0.25, lane, tuple(WHITE)))
        out.append(Marking(here + ROAD_STOP_M - 0.225, here + ROAD_STOP_M + 0.225, -lane, -0.25, tuple(WHITE)))
    cut = []
    for mk in out:
        if mk.start < length_m:
            cut.append(Marking(mk.start, min(mk.end, length_m), mk.left, mk.right, mk.rgb))
    return cut


def _asphalt_strip(rng, base, h, w):
    img = _shade(base, 1.0 + 0.06 * _fbm(rng, h, w, 64, 3))
    grit = rng.random((h, w))
    img[grit < 0.05] *= 1.4
    img[grit > 0.96] *= 0.6
    return img


def _grass(rng, base):
    # grass: blades (short vertical streaks) of varied green over darker soil
    h = w = 256
    img = _shade(base, 0.85 + 0.15 * _fbm(rng, h, w, 8))
    blades = _noise(rng, h, w, 128) + 0.6 * _noise(rng, h, w, 64)
    streak = np.roll(blades, 1, axis=0) + blades + np.roll(blades, -1, axis=0)
    img *= (1.0 + 0.12 * streak)[..., None]
    img[..., 1] *= 1.0 + 0.06 * _fbm(rng, h, w, 4)
    return img


TEXTURES: dict[str, TextureKind] = {
    "osb": TextureKind((1.22, 1.22), 0.15, _osb),
    "plywood": TextureKind((1.22, 1.22), 0.2, _plywood),
    "painted_panel": TextureKind((1.22, 1.22), 0.25, _painted_panel),
    "concrete": TextureKind((2.0, 2.0), 0.1, _concrete),
    "tile": TextureKind((1.2, 1.2), 0.35, _tile),
    "cinder": TextureKind((0.814, 0.814), 0.05, _cinder),
    "brick": TextureKind((0.816, 0.536), 0.05, _brick),
    "paper": TextureKind((0.297, 0.297), 0.05, _paper),
    "pipe": TextureKind((0.5, 0.5), 0.6, _pipe),
    "rubble": TextureKind((1.5, 1.5), 0.05, _rubble),
    "gravel": TextureKind((1.5, 1.5), 0.05, _gravel),
    "asphalt": TextureKind((2.0, 2.0), 0.05, _asphalt),
    "road": TextureKind((ROAD_BLOCK_M, ROAD_WIDTH_M), 0.05, _road, fitted=True),
    "grass": TextureKind((1.0, 1.0), 0.05, _grass),
}
TEXTURE_NAMES = tuple(TEXTURES)


def cache_dir() -> Path:
    root = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(root) / "usarsim" / "textures"


_MEMORY: dict[tuple[str, tuple[int, ...]], np.ndarray] = {}  # (name, its colour's 3 levels) -> image


def texture_image(name: str, rgb) -> np.ndarray:
    """The texture ``name`` made around the colour ``rgb`` (each 0..1): an (h, w, 3) uint8
    image, rows from the image's top."""
    key = (name, tuple(int(round(float(c) * 255)) for c in rgb[:3]))
    img = _MEMORY.get(key)
    if img is not None:
        return img
    tag = f"{name}-{key[1][0]:02x}{key[1][1]:02x}{key[1][2]:02x}-v{VERSION}.npy"
    path = cache_dir() / tag
    try:
        img = np.load(path, allow_pickle=False)
        if img.dtype != np.uint8 or img.ndim != 3:
            img = None
    except (OSError, ValueError):
        img = None
    if img is None:
        kind = TEXTURES[name]
        seed = sum((i + 1) * ord(ch) for i, ch in enumerate(name)) + 7919 * sum(key[1])
        base = np.array(key[1], dtype=float) / 255.0
        img = (np.clip(kind.draw(np.random.default_rng(seed), base), 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(f".{os.getpid()}.tmp")
            with open(tmp, "wb") as f:
                np.save(f, img)
            os.replace(tmp, path)
        except OSError as exc:  # a read-only home: made again next time
            log.debug("texture cache %s not written: %s", path, exc)
    _MEMORY[key] = img
    return img
