"""Universal Transverse Mercator coordinates on the WGS84 ellipsoid: the ``utm`` form of a
world's geo reference, and the conversions between it and latitude/longitude (GPS).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True, kw_only=True)
class UtmCoordinate:
    """A point in Universal Transverse Mercator coordinates (WGS84)."""

    easting_m: float
    northing_m: float
    zone: int  # 1..60
    letter: str  # latitude band, C..X without I and O; N and above is the northern hemisphere


# Universal Transverse Mercator on the WGS84 ellipsoid, with the series of J. P. Snyder,
# "Map Projections - A Working Manual", U.S. Geological Survey Professional Paper 1395,
# 1987, pp. 57-64 (transverse Mercator, ellipsoid: forward equations 8-9, 8-10, 3-21;
# inverse equations 8-17 to 8-25, 3-24 to 3-26, 7-19).  Within a UTM zone they agree with
# the exact projection to about a millimetre.  WGS84: semi-major axis 6378137 m, flattening
# 1/298.257223563 (NIMA TR8350.2, 2000, table 3.1); UTM scale factor 0.9996 on the central
# meridian, false easting 500 km, false northing 10000 km south of the equator
# (DMA TM 8358.2, 1989, section 2-6).
WGS84_A_M = 6378137.0
WGS84_F = 1.0 / 298.257223563
UTM_K0 = 0.9996
UTM_FALSE_EASTING_M = 500000.0
UTM_FALSE_NORTHING_SOUTH_M = 10000000.0
# Latitude bands, 8 degrees each from 80 S (X, the last, spans 72 N to 84 N); I and O are
# not used (DMA TM 8358.2, section 2-7).
UTM_LETTERS = "CDEFGHJKLMNPQRSTUVWX"

_E2 = WGS84_F * (2.0 - WGS84_F)  # first eccentricity squared
_EP2 = _E2 / (1.0 - _E2)  # second eccentricity squared


def utm_central_meridian_deg(zone: int) -> float:
    return zone * 6.0 - 183.0


def utm_band_limits_deg(letter: str) -> tuple[float, float]:
    """Southern and northern latitude of a UTM latitude band."""
    i = UTM_LETTERS.index(letter)
    south = -80.0 + 8.0 * i
    return south, (84.0 if letter == "X" else south + 8.0)


def _meridian_arc_m(phi: float) -> float:
    """Distance along the meridian from the equator to latitude ``phi`` (Snyder 3-21)."""
    e2, e4, e6 = _E2, _E2 * _E2, _E2**3
    return WGS84_A_M * (
        (1 - e2 / 4 - 3 * e4 / 64 - 5 * e6 / 256) * phi
        - (3 * e2 / 8 + 3 * e4 / 32 + 45 * e6 / 1024) * math.sin(2 * phi)
        + (15 * e4 / 256 + 45 * e6 / 1024) * math.sin(4 * phi)
        - (35 * e6 / 3072) * math.sin(6 * phi)
    )


def latlon_to_utm(latitude_deg: float, longitude_deg: float, zone: int | None = None) -> UtmCoordinate:
    """WGS84 latitude/longitude -> UTM (Snyder 1987, equations 8-9, 8-10, 3-21), in the
    point's own zone unless ``zone`` is given."""
    if zone is None:
        zone = int((longitude_deg + 180.0) // 6.0) % 60 + 1
    phi = math.radians(latitude_deg)
    dlam = math.radians((longitude_deg - utm_central_meridian_deg(zone) + 180.0) % 360.0 - 180.0)
    sin_p, cos_p, tan_p = math.sin(phi), math.cos(phi), math.tan(phi)
    n = WGS84_A_M / math.sqrt(1.0 - _E2 * sin_p * sin_p)
    t = tan_p * tan_p
    c = _EP2 * cos_p * cos_p
    a = dlam * cos_p
    x = UTM_K0 * n * (a + (1 - t + c) * a**3 / 6 + (5 - 18 * t + t * t + 72 * c - 58 * _EP2) * a**5 / 120)
    y = UTM_K0 * (
        _meridian_arc_m(phi)
        + n
        * tan_p
        * (
            a * a / 2
            + (5 - t + 9 * c + 4 * c * c) * a**4 / 24
            + (61 - 58 * t + t * t + 600 * c - 330 * _EP2) * a**6 / 720
        )
    )
    band = min(max(int((latitude_deg + 80.0) // 8.0), 0), len(UTM_LETTERS) - 1)
    return UtmCoordinate(
        easting_m=x + UTM_FALSE_EASTING_M,
        northing_m=y + (UTM_FALSE_NORTHING_SOUTH_M if latitude_deg < 0 else 0.0),
        zone=zone,
        letter=UTM_LETTERS[band],
    )


def utm_to_latlon(utm: UtmCoordinate) -> tuple[float, float]:
    """UTM (WGS84) -> latitude and longitude in degrees, north and east positive (Snyder
    1987, equations 8-17 to 8-25 with the footpoint latitude of 3-24 to 3-26 and 7-19)."""
    x = utm.easting_m - UTM_FALSE_EASTING_M
    y = utm.northing_m - (UTM_FALSE_NORTHING_SOUTH_M if utm.letter < "N" else 0.0)
    e2 = _E2
    mu = (y / UTM_K0) / (WGS84_A_M * (1 - e2 / 4 - 3 * e2 * e2 / 64 - 5 * e2**3 / 256))
    r = math.sqrt(1.0 - e2)
    e1 = (1.0 - r) / (1.0 + r)
    phi1 = (
        mu
        + (3 * e1 / 2 - 27 * e1**3 / 32) * math.sin(2 * mu)
        + (21 * e1**2 / 16 - 55 * e1**4 / 32) * math.sin(4 * mu)
        + (151 * e1**3 / 96) * math.sin(6 * mu)
        + (1097 * e1**4 / 512) * math.sin(8 * mu)
    )
    sin1, cos1, tan1 = math.sin(phi1), math.cos(phi1), math.tan(phi1)
    c1 = _EP2 * cos1 * cos1
    t1 = tan1 * tan1
    w = 1.0 - e2 * sin1 * sin1
    n1 = WGS84_A_M / math.sqrt(w)
    r1 = WGS84_A_M * (1.0 - e2) / w**1.5
    d = x / (n1 * UTM_K0)
    phi = phi1 - (n1 * tan1 / r1) * (
        d * d / 2
        - (5 + 3 * t1 + 10 * c1 - 4 * c1 * c1 - 9 * _EP2) * d**4 / 24
        + (61 + 90 * t1 + 298 * c1 + 45 * t1 * t1 - 252 * _EP2 - 3 * c1 * c1) * d**6 / 720
    )
    lam = (
        d - (1 + 2 * t1 + c1) * d**3 / 6 + (5 - 2 * c1 + 28 * t1 - 3 * c1 * c1 + 8 * _EP2 + 24 * t1 * t1) * d**5 / 120
    ) / cos1
    lon = utm_central_meridian_deg(utm.zone) + math.degrees(lam)
    return math.degrees(phi), (lon + 180.0) % 360.0 - 180.0
