"""The types the servers use with the simulation facade (:mod:`usarsim.sim.facade`).

The servers (``usarsim.server``, ``usarsim.web``) import from the simulation layer only
the facade and this module: every value that crosses between them is one of these.
"""

from __future__ import annotations

from usarsim.sim.outputs import ItemDescription, Output
from usarsim.sim.radio import Link, Pair, RadioModel, pair_key, resolve_model
from usarsim.sim.render import Tile, grid_tiles

__all__ = ["ItemDescription", "Link", "Output", "Pair", "RadioModel", "Tile", "grid_tiles", "pair_key",
           "resolve_model"]
