"""Sensor plugins; importing this package registers every built-in sensor."""

from usarsim.sensors import (  # noqa: F401  (registration)
    camera, effecters, gps, inertial, motion, range, rfid, scanner, sound, touch, victim)
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig, make_sensor

__all__ = ["SENSORS", "Sensor", "SensorConfig", "make_sensor"]
