"""Map files as ROS's map_server reads and writes them: a picture (PGM, or PNG) and a YAML
file beside it, and a PNG for people with victims, RFID tags and start poses drawn.

The YAML keys are map_server's (``image``, ``resolution``, ``origin`` [x, y, yaw], ``negate``,
``occupied_thresh``, ``free_thresh``, ``mode``); a pixel's occupancy probability is
``(255 - value) / 255`` (``value / 255`` with ``negate: 1``), above ``occupied_thresh``
occupied, below ``free_thresh`` free, unknown between.  Maps are written as map_saver writes
them: occupied 0, free 254, unknown 205.

A team's map may list the victims it found, in the map's frame, under a key map_server
ignores::

    victims:
      - {name: V1, position: [3.2, -1.5]}
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from usarsim.errors import ConfigError
from usarsim.maps.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap

# map_saver's pixel values and thresholds (nav2_map_server's defaults)
PIXEL_OCCUPIED, PIXEL_FREE, PIXEL_UNKNOWN = 0, 254, 205
OCCUPIED_THRESH, FREE_THRESH = 0.65, 0.25
MODES = ("trinary", "scale", "raw")


@dataclass
class MapFile:
    """A map read from its YAML file: the grid, and the victims it reports (map frame)."""

    grid: OccupancyMap
    victims: list[tuple[str, float, float]] = field(default_factory=list)
    path: str = ""


def write_map(path: str | Path, grid: OccupancyMap, *, victims=(), extra: dict[str, Any] | None = None) -> Path:
    """Write ``grid`` as ``path`` (a .yaml) and its picture beside it (the same name, .pgm);
    ``victims`` ((name, x, y) in the map frame) go under ``victims``.  Returns the YAML's path."""
    import yaml  # type: ignore[import-untyped]  # PyYAML ships no type information

    path = Path(path)
    if path.suffix not in (".yaml", ".yml"):
        path = path.with_suffix(".yaml")
    path.parent.mkdir(parents=True, exist_ok=True)
    image = path.with_suffix(".pgm")
    pixels = np.full(grid.shape, PIXEL_UNKNOWN, np.uint8)
    pixels[grid.data == FREE] = PIXEL_FREE
    pixels[grid.data == OCCUPIED] = PIXEL_OCCUPIED
    rows, cols = grid.shape
    # the picture's top row is the map's highest row (map_server's convention)
    image.write_bytes(f"P5\n# usarsim map\n{cols} {rows}\n255\n".encode() + np.flipud(pixels).tobytes())
    doc: dict[str, Any] = {
        "image": image.name,
        "mode": "trinary",
        "resolution": float(grid.resolution),
        "origin": [float(grid.origin[0]), float(grid.origin[1]), 0.0],
        "negate": 0,
        "occupied_thresh": OCCUPIED_THRESH,
        "free_thresh": FREE_THRESH,
    }
    if victims:
        doc["victims"] = [{"name": str(n), "position": [round(float(x), 4), round(float(y), 4)]} for n, x, y in victims]
    doc.update(extra or {})
    path.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return path


def read_map(path: str | Path) -> MapFile:
    """A map_server map (its YAML file); ConfigError naming the file and the key when wrong."""
    from usarsim.config.reader import load_yaml

    path = Path(path)
    if not path.exists():
        raise ConfigError("no such map file", path=str(path))
    doc = load_yaml(str(path))

    def bad(key: str, why: str) -> ConfigError:
        return ConfigError(why, path=str(path), key=key)

    if not isinstance(doc.get("image"), str):
        raise bad("image", "a map file names its picture (a PGM or PNG file beside it)")
    try:
        resolution = float(doc["resolution"])
    except (KeyError, TypeError, ValueError):
        raise bad("resolution", "the cell size in metres (a number > 0)") from None
    if not resolution > 0 or not math.isfinite(resolution):
        raise bad("resolution", f"the cell size must be > 0 m, got {doc.get('resolution')!r}")
    origin = doc.get("origin", [0.0, 0.0, 0.0])
    if not (isinstance(origin, list) and len(origin) in (2, 3) and all(isinstance(v, (int, float)) for v in origin)):
        raise bad("origin", f"[x, y, yaw] of the picture's lower-left corner, got {origin!r}")
    if len(origin) == 3 and abs(float(origin[2])) > 1e-9:
        raise bad("origin", "a turned map origin (yaw other than 0) is not supported; map_server ignores it too")
    mode = str(doc.get("mode", "trinary"))
    if mode not in MODES:
        raise bad("mode", f"one of {', '.join(MODES)}, got {mode!r}")
    occ_t = float(doc.get("occupied_thresh", OCCUPIED_THRESH))
    free_t = float(doc.get("free_thresh", FREE_THRESH))
    negate = bool(doc.get("negate", 0))
    image = path.parent / doc["image"]
    pixels = _read_picture(image, bad)
    grid = OccupancyMap(
        resolution, (float(origin[0]), float(origin[1])), _occupancy(pixels, mode, negate, occ_t, free_t)
    )
    victims = []
    for i, v in enumerate(doc.get("victims") or []):
        pos = v.get("position") if isinstance(v, dict) else None
        if not (isinstance(pos, list) and len(pos) >= 2 and all(isinstance(c, (int, float)) for c in pos[:2])):
            raise bad(f"victims[{i}].position", f"[x, y] in the map's frame (metres), got {pos!r}")
        victims.append((str(v.get("name", f"victim{i + 1}")), float(pos[0]), float(pos[1])))
    return MapFile(grid, victims, str(path))


def _read_picture(image: Path, bad) -> np.ndarray:
    from PIL import Image

    if not image.exists():
        raise bad("image", f"the map's picture {image} is not there")
    try:
        with Image.open(image) as im:
            return np.asarray(im.convert("L"), np.uint8)
    except OSError as exc:
        raise bad("image", f"cannot read the map's picture {image}: {exc}") from None


def _occupancy(pixels: np.ndarray, mode: str, negate: bool, occ_t: float, free_t: float) -> np.ndarray:
    """map_server's reading of the picture, bottom row first."""
    values = np.flipud(pixels).astype(float)
    data = np.full(values.shape, UNKNOWN, np.int8)
    if mode == "raw":
        known = values <= 100
        data[known] = values[known].astype(np.int8)
        data[(data > 0) & (data < 100)] = np.where(data[(data > 0) & (data < 100)] >= 50, OCCUPIED, FREE)
        return data
    p = values / 255.0 if negate else (255.0 - values) / 255.0
    data[p > occ_t] = OCCUPIED
    data[p < free_t] = FREE
    return data


# colours of the picture for people (RGB)
COLOURS = {
    FREE: (255, 255, 255),
    OCCUPIED: (30, 30, 30),
    UNKNOWN: (190, 190, 200),
    "victim": (220, 40, 40),
    "tag": (40, 120, 220),
    "start": (30, 160, 60),
}


def draw_map(path: str | Path, grid: OccupancyMap, markers=(), *, scale: int = 2) -> Path:
    """A PNG of ``grid`` for people (north up: the map's X points up the page, its Y to the
    left), with ``markers`` (usarsim.maps.truth.Marker) drawn: victims as red discs, RFID tags
    as blue squares, start poses as green triangles."""
    from PIL import Image, ImageDraw

    rows, cols = grid.shape
    rgb = np.zeros((rows, cols, 3), np.uint8)
    for value in (FREE, OCCUPIED, UNKNOWN):
        rgb[grid.data == value] = COLOURS[value]
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
        elif m.kind == "tag":
            s = r * 0.6
            draw.rectangle((u - s, v - s, u + s, v + s), fill=COLOURS["tag"])
        else:
            draw.polygon([(u, v - r), (u - r, v + r), (u + r, v + r)], fill=COLOURS["start"])
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    im.save(path)
    return path
