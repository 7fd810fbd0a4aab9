"""The types the servers use with the simulation facade (:mod:`usarsim.sim.facade`).

The servers (``usarsim.server``, ``usarsim.web``) import from the simulation layer only
the facade and this module: every value that crosses between them is one of these (and ``euler_to_mat``, the
rotation of a USARSim roll, pitch and yaw, for drawing the world).
"""

from __future__ import annotations

from usarsim.sim.channel import LATER, Channel, Delivery, Drop, LinkCounts, LinkView, describe_channel
from usarsim.sim.frames import euler_to_mat
from usarsim.sim.outputs import ItemDescription, Output, RobotNumbers, VelocityLimits
from usarsim.sim.radio import Link, Pair, RadioModel, pair_key, resolve_channel, resolve_model
from usarsim.sim.tiles import Tile, grid_tiles
from usarsim.sim.worldframe import LinkFrame, LinkTraffic, ObjectFrame, RelayFrame, RobotFrame, WorldFrame

__all__ = [
    "LATER",
    "Channel",
    "Delivery",
    "Drop",
    "ItemDescription",
    "Link",
    "LinkCounts",
    "LinkView",
    "LinkFrame",
    "LinkTraffic",
    "ObjectFrame",
    "Output",
    "Pair",
    "RadioModel",
    "RelayFrame",
    "RobotFrame",
    "RobotNumbers",
    "Tile",
    "VelocityLimits",
    "WorldFrame",
    "describe_channel",
    "euler_to_mat",
    "grid_tiles",
    "pair_key",
    "resolve_channel",
    "resolve_model",
]
