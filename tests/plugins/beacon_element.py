"""A kind of world element that is not built in, added from the test tree: radio beacons, posts
a robot's laser sees and the ground-truth service lists.  Importing this module registers it;
a world file then lists them under ``beacons:``::

    beacons:
      - {name: B1, location: [2.0, 0.0, 0.0], height: 1.0}
"""

from __future__ import annotations

from dataclasses import dataclass

from usarsim.config.elements import ELEMENT_KINDS, ElementKind, Landmark
from usarsim.config.world import StaticObject

POST_RADIUS_M = 0.1  # a post 20 cm across: a tripod-mounted beacon's mast with its case


@dataclass(frozen=True)
class Beacon:
    name: str
    location: tuple[float, float, float]  # where the post stands on the floor (USARSim frame, Z down)
    height_m: float


@ELEMENT_KINDS.register("beacons")
class Beacons(ElementKind):
    """Radio beacons: each a post of POST_RADIUS_M standing ``height`` metres tall (default 1 m)
    on the floor at ``location``, listed by the ground-truth service as class ``Beacon``."""

    @classmethod
    def parse(cls, s):
        beacon = Beacon(s.str("name"), s.vec("location"), s.float("height", 1.0, min=0.1, max=10.0))
        s.finish()
        return beacon

    @classmethod
    def solids(cls, b):
        x, y, z = b.location
        return (
            StaticObject(
                name="post",
                shape="cylinder",
                center=(x, y, z - b.height_m / 2.0),
                radius_m=POST_RADIUS_M,
                length_m=b.height_m,
            ),
        )

    @classmethod
    def landmarks(cls, b):
        return (Landmark(b.name, "Beacon", b.location),)
