"""Where each camera's picture lies in an image server picture (manual 3.2.6's MultiView):
plain values, shared by the render thread and the image server."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Tile:
    """One camera's place in a picture: its robot, its name, and the rectangle it fills."""

    uid: int
    camera: str
    x: int
    y: int
    width: int
    height: int


def grid_tiles(cameras, count: int, wide_mode: int, tile_w: int, tile_h: int) -> tuple[list[Tile], int, int]:
    """The MultiView layout (manual 3.2.6): ``count`` tiles of ``tile_w`` x ``tile_h``;
    ``wide_mode`` 0 lays them in a box (as many columns as rows, or one more), n > 0 puts
    n in a row before starting the next; tiles fill rows left to right, top to bottom.
    ``cameras`` lists (robot id, camera name) for the first tiles.  Returns the tiles and
    the picture's width and height."""
    count = max(1, count)
    cols = wide_mode if wide_mode > 0 else math.ceil(math.sqrt(count))
    cols = max(1, min(cols, count))
    rows = math.ceil(count / cols)
    tiles = [
        Tile(uid, name, (i % cols) * tile_w, (i // cols) * tile_h, tile_w, tile_h)
        for i, (uid, name) in enumerate(list(cameras)[:count])
    ]
    return tiles, cols * tile_w, rows * tile_h
