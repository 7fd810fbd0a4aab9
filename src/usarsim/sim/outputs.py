"""What leaves the simulation for the servers: outputs for a robot's client, and the
description of a robot's mounted items (GETGEO/GETCONF)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True, slots=True)
class Output:
    """One message-worth of data for the client that owns robot ``uid``.

    ``key`` identifies the periodic stream (``STA``, ``SEN:Sonar``, ``SEN:RangeScanner:Scanner1``)
    for latest-wins dropping; ``periodic`` is False for replies that must not be dropped.
    """

    uid: int
    time: float | None
    value: Any
    key: str
    periodic: bool = True


@dataclass(frozen=True)
class ItemDescription:
    """What GETGEO/GETCONF report for one mounted item."""

    item_type: str
    name: str
    location: tuple[float, float, float]
    orientation: tuple[float, float, float]
    mount: str
    conf: tuple[tuple[str, Any], ...]
