"""Sensor plugins; importing this package registers every built-in sensor."""

from usarsim.sensors import camera, effecters, gps, inertial, motion, range, rfid, scanner, sound, touch, victim  # noqa: F401  (registration)
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig, make_sensor

__all__ = ["SENSORS", "Sensor", "SensorConfig", "make_sensor"]
