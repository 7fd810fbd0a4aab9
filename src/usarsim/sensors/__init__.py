"""Sensor plugins; importing this package registers every built-in sensor."""

from usarsim.sensors import camera, gps, inertial, motion, range, rfid, scanner, touch, victim  # noqa: F401  (registration)
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig, make_sensor

__all__ = ["SENSORS", "Sensor", "SensorConfig", "make_sensor"]
