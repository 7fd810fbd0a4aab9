"""Mounted-item plugins; importing this package registers every built-in sensor, camera and
effecter (the effecters are in :mod:`usarsim.effecters`, with their base and registry).

:func:`make_item` makes the plugin of a robot file's item, its type looked up among the
three kinds (:data:`ITEMS`): :data:`SENSORS`, :data:`CAMERAS` and ``EFFECTERS``.
"""

import usarsim.effecters  # noqa: F401  (registration; it imports this package's base only)
from usarsim.sensors import (  # noqa: F401  (registration)
    camera,
    gps,
    imager,
    inertial,
    motion,
    range,
    rfid,
    scanner,
    sound,
    touch,
    victim,
)
from usarsim.sensors.base import ITEMS, SENSORS, Item, ItemConfig, Sensor, SensorConfig, make_item
from usarsim.sensors.camera import CAMERAS, CameraItem

__all__ = ["CAMERAS", "ITEMS", "SENSORS", "CameraItem", "Item", "ItemConfig", "Sensor", "SensorConfig", "make_item"]
