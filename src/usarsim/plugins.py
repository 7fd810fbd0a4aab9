"""Every built-in plugin, as one :class:`~usarsim.sim.plugins.PluginSet`: importing this
module registers every drive (:mod:`usarsim.robots`), sensor and camera
(:mod:`usarsim.sensors`), effecter and the world systems effecters need
(:mod:`usarsim.effecters`), and every world system of :mod:`usarsim.sim.systems`.

The composition root (:class:`usarsim.server.app.Application`) hands :data:`BUILTIN` to the
simulation; a simulation built without a set finds this module by name.
"""

from __future__ import annotations

from usarsim.robots import drive_class, make_drive
from usarsim.sensors import ITEMS, make_item
from usarsim.sim.plugins import PluginSet

BUILTIN = PluginSet(
    drive_class=drive_class,
    make_drive=make_drive,
    make_item=make_item,
    canonical_item_type=ITEMS.canonical,
)
