"""GPS receiver (protocol.md 6.3 and 7.6): latitude and longitude of the sensor,
a fix flag and the number of satellites in view.

Model (UDK ``GPSSensor``, protocol.md 7.6):

* Position: the sensor's own world position (the robot's pose plus the item's mount),
  world +X (north) adds latitude and world +Y (east) adds longitude, converted with the
  world's :class:`~usarsim.config.world.GeoReference` (origin coordinate and metres per
  degree).  Degrees are whole, minutes fractional, hemisphere N/S and E/W.
* Satellites: one is in view when it is more than 5 degrees above the horizon and a
  line-of-sight ray from the sensor towards it hits nothing (walls, roofs, other robots;
  the sensor's own chassis is ignored).  A fix needs at least 4 in view; without a fix the
  reading carries only the satellite count.
* Noise (:class:`SatelliteNoise`, the sensor's ``NOISE``, applied by the framework to what
  it senses): with a fix, x and y (metres) each get a Gaussian error with
  sigma = (slope * n + b) / 3, slope = (maxNoise - minNoise) / -8, b = maxNoise - 4 * slope,
  n the satellites in view, before the conversion to degrees: sigma falls from maxNoise/3
  with 4 satellites to minNoise/3 with 12.  n is held within [4, 12] for the noise (beyond
  12 the UDK line would go below minNoise and then negative).  Without a fix nothing is
  drawn.

The constellation (our design; UDK read recorded satellite positions from
``USARSatelliteTracker.ini``): 24 satellites, the size of the GPS baseline
constellation, at directions spread evenly over the whole sphere (a Fibonacci lattice
turned by a rotation drawn once from a generator with the fixed seed
:data:`CONSTELLATION_SEED`), so about 11 are above the 5 degree mask under a clear sky,
within the 8 to 12 a real receiver sees.  The whole shell turns slowly about the
celestial pole (tilted from the vertical by the world's latitude) with the GPS orbital
period, half a sidereal day: a satellite rises or sets every few minutes of simulated
time, as in reality, while a reading over a few seconds sees a steady sky.

The sky belongs to the world, not to one receiver: every GPS, on every robot and with
every seed, sees the same satellites at the same simulated time.  Only the position noise
comes from the sensor's own seeded generator, so another seed changes the noise and not
the satellite count.

The geographic reference is ``view.geo`` when the world view carries one, else the
default :class:`GeoReference` (USARSim's ``ZeroZeroLocation``, NIST Gaithersburg).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from usarsim.config.world import GeoReference
from usarsim.readings import FieldValue, GpsReading
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig
from usarsim.sensors.noise import Noise

if TYPE_CHECKING:
    from usarsim.sim.view import WorldView

# A satellite counts when it is more than 5 degrees above the horizon (protocol.md 7.6;
# UDK GPSSensor.GetGPS: Elevation(...) > 5).
ELEVATION_MASK_DEG = 5.0
# A fix needs at least 4 satellites in view (protocol.md 7.6; UDK GPSSensor.GetData).
MIN_SATELLITES_FOR_FIX = 4
# The noise line runs from maxNoise at 4 satellites to minNoise at 12 (protocol.md 7.6:
# slope = (maxNoise - minNoise) / -8, b = maxNoise - 4 * slope).
NOISE_MIN_SATELLITES = 4
NOISE_MAX_SATELLITES = 12

# Constellation (our design, see the module docstring): 24 satellites, the number of
# orbital slots of the GPS baseline constellation (6 planes x 4).
NUM_SATELLITES = 24
# The fixed seed of the constellation's orientation ("GPS" in ASCII): the same sky in
# every run, world and robot.
CONSTELLATION_SEED = 0x475053
# GPS orbital period: half a sidereal day, 11 h 58 min 2 s.
ORBIT_PERIOD_S = 43082.0
# Length of the line-of-sight rays: anything farther than 1 km does not shade a receiver
# in a USARSim arena.
LINE_OF_SIGHT_RANGE_M = 1000.0

_DEFAULT_GEO = GeoReference()


# --------------------------------------------------------------------------- geography


def world_to_geographic(x_m: float, y_m: float, geo: GeoReference) -> tuple[float, float]:
    """Latitude and longitude (degrees, north and east positive) of the world point
    (x north, y east, metres) for the reference ``geo`` (protocol.md 7.6)."""
    return (geo.latitude_deg + x_m / geo.scale_latitude_m, geo.longitude_deg + y_m / geo.scale_longitude_m)


def degrees_minutes(value_deg: float, positive: str, negative: str) -> tuple[int, float, str]:
    """``value_deg`` as (whole degrees, minutes, hemisphere), e.g. -77.2166 ->
    (77, 12.9960, 'W') with ``positive='E', negative='W'``.

    Minutes that would print as 60.0000 (4 decimals, protocol.md 6.3) carry into the
    degrees instead.
    """
    hemisphere = negative if value_deg < 0 else positive
    a = abs(float(value_deg))
    degrees = int(math.floor(a))
    minutes = (a - degrees) * 60.0
    if round(minutes, 4) >= 60.0:
        degrees, minutes = degrees + 1, 0.0
    return degrees, minutes, hemisphere


def geographic_to_degrees(coordinate: tuple[int, float, str]) -> float:
    """Inverse of :func:`degrees_minutes`: signed degrees (south and west negative)."""
    degrees, minutes, hemisphere = coordinate
    value = degrees + minutes / 60.0
    return -value if hemisphere in ("S", "W") else value


# --------------------------------------------------------------------------- noise


def noise_sigma_m(satellites: int, max_noise_m: float, min_noise_m: float) -> float:
    """Standard deviation (m) of the x and y error with ``satellites`` in view
    (protocol.md 7.6, UDK GPSSensor.Noise), the count held within [4, 12]."""
    n = min(max(satellites, NOISE_MIN_SATELLITES), NOISE_MAX_SATELLITES)
    slope = (max_noise_m - min_noise_m) / -8.0
    b = max_noise_m - 4.0 * slope
    return (slope * n + b) / 3.0


@dataclass(frozen=True, slots=True)
class GpsPosition:
    """What a receiver senses: the satellites in view and its position in USARSim world metres
    (``x_m`` north, ``y_m`` east), with the geographic reference that turns it into degrees."""

    satellites: int
    x_m: float
    y_m: float
    geo: GeoReference


class SatelliteNoise(Noise):
    """The GPS position error of UDK ``GPSSensor.Noise`` (protocol.md 7.6): with a fix (at least
    4 satellites in view, UDK ``GPSSensor.GetData``), x and y each get a Gaussian error, mean 0
    and sigma :func:`noise_sigma_m` of the satellites in view and the sensor's ``maxNoise`` and
    ``minNoise``, drawn (x then y) from the sensor's generator; without a fix there is no
    position to corrupt and nothing is drawn.  ``true``: a :class:`GpsPosition`."""

    def apply(self, sensor: Sensor[Any], true: GpsPosition) -> GpsPosition:
        n = true.satellites
        if n < MIN_SATELLITES_FOR_FIX:
            return true
        c: GpsConfig = sensor.config
        ex, ey = (float(e) for e in sensor.rng.normal(0.0, noise_sigma_m(n, c.max_noise_m, c.min_noise_m), size=2))
        return GpsPosition(n, true.x_m + ex, true.y_m + ey, true.geo)


# --------------------------------------------------------------------------- constellation


def _rotation_about(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix by ``angle`` (right-handed) about the unit vector ``axis``."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    rot: np.ndarray = np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)
    return rot


class Constellation:
    """Directions to the satellites in the local east-north-up frame, at a simulated time.

    ``n`` nearly evenly spread directions (Fibonacci lattice), turned once by a random
    rotation from ``seed``, and then turning about the celestial pole with ``period_s``.
    """

    def __init__(
        self, n: int = NUM_SATELLITES, seed: int = CONSTELLATION_SEED, period_s: float = ORBIT_PERIOD_S
    ) -> None:
        k = np.arange(n) + 0.5
        up = 1.0 - 2.0 * k / n
        ring = np.sqrt(1.0 - up * up)
        azimuth = math.pi * (1.0 + math.sqrt(5.0)) * k
        lattice = np.stack([ring * np.cos(azimuth), ring * np.sin(azimuth), up], axis=-1)
        # a uniformly random rotation: a normalised 4-d Gaussian is a uniform unit quaternion
        w, x, y, z = (q := np.random.default_rng(seed).normal(size=4)) / np.linalg.norm(q)
        rot = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ]
        )
        self.directions0 = lattice @ rot.T
        self.period_s = float(period_s)
        self._cache_key: tuple[float, float] | None = None
        self._cache = np.empty((0, 3))

    def directions_enu(self, time_s: float, latitude_deg: float) -> np.ndarray:
        """Unit vectors (n x 3: east, north, up) towards every satellite at ``time_s``
        seen from ``latitude_deg``."""
        lat = math.radians(latitude_deg)
        pole = np.array([0.0, math.cos(lat), math.sin(lat)])  # the celestial pole, due north
        # the sky turns westwards: clockwise seen from above the pole
        turn = _rotation_about(pole, -2.0 * math.pi * time_s / self.period_s)
        dirs: np.ndarray = self.directions0 @ turn.T
        return dirs

    def directions_mj(self, time_s: float, latitude_deg: float) -> np.ndarray:
        """The same directions in the MuJoCo world frame: east-north-up (e, n, u) is
        (n, e, -u) in the USARSim frame (X north, Y east, Z down), which is (n, -e, u)
        in MuJoCo's (frames.py).  The sky is taken at whole simulated seconds (it turns
        by 0.15 mrad a second) and kept for the next calls."""
        key = (math.floor(time_s), latitude_deg)
        if self._cache_key != key:
            enu = self.directions_enu(float(key[0]), latitude_deg)
            self._cache = np.stack([enu[:, 1], -enu[:, 0], enu[:, 2]], axis=-1)
            self._cache_key = key
        return self._cache


SKY = Constellation()


# --------------------------------------------------------------------------- the sensor


@dataclass(frozen=True, kw_only=True)
class GpsConfig(SensorConfig):
    """A GPS sensor's settings in a robot file (protocol.md 7.6): its scan interval and the position noise, in
    metres, at many satellites in view (``minNoise``) and at few (``maxNoise``)."""

    # UDK GPSSensor defaults (protocol.md 7.6): ScanInterval 0.2 s, maxNoise 2.5 m,
    # minNoise 0.75 m.
    scan_interval_s: float = 0.2
    max_noise_m: float = 2.5
    min_noise_m: float = 0.75

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (
            math.isfinite(self.max_noise_m)
            and math.isfinite(self.min_noise_m)
            and 0.0 <= self.min_noise_m <= self.max_noise_m
        ):
            raise ValueError(f"need 0 <= min_noise_m <= max_noise_m, got {self.min_noise_m} and {self.max_noise_m}")


@SENSORS.register("GPS")
class GPS(Sensor[GpsConfig]):
    """Latitude/longitude of the sensor with satellite-dependent Gaussian noise; no fix
    with fewer than 4 satellites in view (see the module docstring)."""

    NOISE = SatelliteNoise()
    ALIASES = {"maxNoise": "max_noise_m", "minNoise": "min_noise_m"}

    def visible_satellites(self, view: WorldView) -> tuple[int, np.ndarray]:
        """The number of satellites in view and the sensor's world position (MuJoCo frame)."""
        geo = getattr(view, "geo", None) or _DEFAULT_GEO
        pos, _ = self.handle.sensor_frame(view.data, self.item.location, self.item.orientation, self.item.mount)
        dirs = SKY.directions_mj(view.time, geo.latitude_deg)
        above = dirs[dirs[:, 2] > math.sin(math.radians(ELEVATION_MASK_DEG))]
        if len(above) == 0:
            return 0, pos
        # one ray per satellite above the mask, all in one call
        dist, _, _ = view.caster.cast(pos, above, LINE_OF_SIGHT_RANGE_M, self.handle.body_id)
        return int(np.count_nonzero(np.isinf(dist))), pos

    def sense(self, view: WorldView) -> GpsPosition:
        n, pos = self.visible_satellites(view)
        geo = getattr(view, "geo", None) or _DEFAULT_GEO
        # USARSim world x (north) and y (east) of the sensor: MuJoCo (x, -y)
        return GpsPosition(n, float(pos[0]), -float(pos[1]), geo)

    def reading(self, values: GpsPosition) -> GpsReading:
        n = values.satellites
        if n < MIN_SATELLITES_FOR_FIX:
            return GpsReading(self.name, False, n)
        lat, lon = world_to_geographic(values.x_m, values.y_m, values.geo)
        return GpsReading(self.name, True, n, degrees_minutes(lat, "N", "S"), degrees_minutes(lon, "E", "W"))

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        # CONF {Type GPS} {Name GPS} {ScanInterval 0.2000} (UDK GPSSensor.GetConfData)
        return (("ScanInterval", self.config.scan_interval_s),)
