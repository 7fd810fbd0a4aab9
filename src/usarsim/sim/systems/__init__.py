"""World systems (see :mod:`usarsim.sim.systems.base`); importing this package registers
every built-in one that serves the world itself.  Systems that serve one kind of plugin live
with it and are registered with it (the grasps of :mod:`usarsim.effecters.grasps`, the roller
tables of :mod:`usarsim.effecters.rollers`, the aerial robots' levelling in
:mod:`usarsim.robots.aerial`, the walking robots' gaits in :mod:`usarsim.robots.legged`)."""

from usarsim.sim.systems import righting, victims, water  # noqa: F401  (registration)
from usarsim.sim.systems.base import EXTERNAL_FORCE_STEPS, SYSTEMS, System, collect

__all__ = ["EXTERNAL_FORCE_STEPS", "SYSTEMS", "System", "collect"]
