"""Effecter plugins (protocol.md 8); importing this package registers every built-in one,
and the world systems they need (grasps, roller tables).

The :class:`Effecter` base and the :data:`EFFECTERS` registry are in :mod:`.base`; a robot
file's item is looked up among sensors, effecters and cameras by
:func:`usarsim.sensors.make_item`.
"""

from usarsim.effecters import grasps, rollers  # noqa: F401,E402  (registration: their world systems)
from usarsim.effecters.base import EFFECTERS, Effecter
from usarsim.effecters.gripper import Gripper
from usarsim.effecters.relay_dropper import RelayDropper
from usarsim.effecters.releaser import RFIDReleaser
from usarsim.effecters.roller_table import RollerTable

__all__ = ["EFFECTERS", "Effecter", "Gripper", "RFIDReleaser", "RelayDropper", "RollerTable"]
