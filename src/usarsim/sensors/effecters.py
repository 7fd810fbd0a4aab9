"""The effecters are plugins of their own kind, in :mod:`usarsim.effecters`; this module
keeps their former import path (the roller-table world system imports ``RollerTable`` from
here)."""

from usarsim.effecters.gripper import Gripper
from usarsim.effecters.roller_table import RollerTable

__all__ = ["Gripper", "RollerTable"]
