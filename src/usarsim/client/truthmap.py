"""The ground-truth map as the ground-truth service hands it out (``{Map}``, our extension)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from usarsim.protocol.truth import MapHeader


@dataclass(frozen=True)
class GroundTruthGrid:
    """A world's ground-truth occupancy grid: ``data[row, col]`` (NumPy int8; 0 free, 100
    occupied, -1 unknown) is the cell whose lower-left corner lies at ``origin`` + (col, row)
    times ``resolution`` in ROS's map frame (x north, y west: a USARSim point (x, y) is at
    (x, -y)), row 0 the lowest, as nav_msgs/OccupancyGrid lays it out."""

    header: MapHeader
    data: Any

    @property
    def world(self) -> str:
        return self.header.world

    @property
    def variant(self) -> int | None:
        return None if self.header.variant < 0 else self.header.variant

    @property
    def resolution(self) -> float:
        return self.header.resolution

    @property
    def origin(self) -> tuple[float, float]:
        return self.header.origin

    @property
    def sensing_height(self) -> float:
        return self.header.sensing_height
