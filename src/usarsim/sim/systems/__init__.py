"""World systems (see :mod:`usarsim.sim.systems.base`); importing this package registers
every built-in one."""

from usarsim.sim.systems import gaits, grasps, levelling, righting, rollers, victims, water  # noqa: F401  (registration)
from usarsim.sim.systems.base import EXTERNAL_FORCE_STEPS, SYSTEMS, System, collect

__all__ = ["EXTERNAL_FORCE_STEPS", "SYSTEMS", "System", "collect"]
