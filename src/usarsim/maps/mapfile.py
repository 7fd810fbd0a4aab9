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

# map_saver's pixel values and the thresholds it writes into the YAML (ROS's map_server
# documentation, wiki.ros.org/map_server: occupied_thresh 0.65, free_thresh 0.196): an unknown
# cell's 205 reads back as (255 - 205) / 255 = 0.196..., not below free_thresh, so unknown
PIXEL_OCCUPIED, PIXEL_FREE, PIXEL_UNKNOWN = 0, 254, 205
OCCUPIED_THRESH, FREE_THRESH = 0.65, 0.196
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
    values = np.flipud(pixels).astype(np.float64)
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


def draw_map(path: str | Path, grid: OccupancyMap, markers=(), *, scale: int = 2) -> Path:
    """A PNG of ``grid`` for people (usarsim.maps.picture: north up, victims, tags and start
    poses drawn)."""
    from usarsim.maps.picture import draw_grid

    return draw_grid(path, grid, markers, scale=scale)
