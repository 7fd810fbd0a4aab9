"""Robots that do not move (a ComStation, protocol.md 9): DRIVE changes only the headlight."""

from __future__ import annotations

from usarsim.controls import DrivePart
from usarsim.robots.base import DRIVES, DriveModel


@DRIVES.register("static")
class Static(DriveModel[DrivePart, None]):
    """No drive part applies; Light, Flip and joint orders still do."""
