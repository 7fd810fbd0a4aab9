"""World files: static geometry, materials and start poses (YAML).

Coordinates are in the USARSim frame (X forward/north, Y right/east, Z down),
metres and radians; the floor's top surface is the plane z = 0.
"""

from __future__ import annotations

import dataclasses
import math
import struct
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

from usarsim.config.elements import ELEMENT_KINDS, Landmark
from usarsim.config.reader import FieldDefaults, Section, did_you_mean, load_yaml, name_entries
from usarsim.errors import ConfigError

Vec3 = tuple[float, float, float]

# Shapes of the objects a world holds (a ramp and stairs are expanded into boxes at load time).
SHAPES = ("box", "cylinder", "mesh")
OBJECT_SHAPES = (*SHAPES, "ramp", "stairs")
# Mesh files MuJoCo reads: Wavefront OBJ and binary STL.
MESH_SUFFIXES = (".obj", ".stl")
# Sensor kinds a material can let rays through (glass: IR and cameras, manual 3.2.1).
SEE_THROUGH_KINDS = ("ir", "camera", "laser", "sonar")
# Textures a material can name (usarsim.sim.textures.TEXTURES, which draws them; listed here
# so that reading a world file loads no NumPy).
TEXTURE_NAMES = (
    "osb",
    "plywood",
    "painted_panel",
    "concrete",
    "tile",
    "cinder",
    "brick",
    "paper",
    "pipe",
    "rubble",
    "gravel",
    "asphalt",
    "road",
    "grass",
)
# Light types of the world's ``lights`` (MuJoCo's mjtLightType without image lights).
LIGHT_TYPES = ("point", "spot", "directional")
# The steepest ramp or flight of stairs a world may hold (degrees): steeper than this is a
# wall, not something a ground robot is expected to climb.
MAX_SLOPE_DEG = 60.0
# A ramp's plate reaches this far below the surface at its foot (metres), so that a wheel
# rolls onto it without meeting an edge.
RAMP_FOOT_SINK_M = 0.005
# Body parts a victim is made of (protocol.md 7.9: the UT2004 victim model's collision boxes).
VICTIM_PARTS = ("Head", "Chest", "Pelvis", "Arm", "Hand", "Leg", "Foot")
VICTIM_POSTURES = ("lying", "sitting")
# Radio propagation models of the wireless simulation (usarsim.sim.radio; manual 3.2.4,
# protocol.md 12.2): the Wall Attenuation Factor model with the manual's constants, the
# same with the later USARSim code's, distance only, a perfect link.
WIRELESS_MODELS = ("waf", "waf2009", "distance", "perfect")  # built in (usarsim.sim.radio); plugins add more
# How deep inside a solid a point must lie to be in it (metres, WorldConfig.solid_at): a
# start pose set on a floor or a platform, up to 1 cm into it, is on it, not inside.
SOLID_MARGIN_M = 0.01
# The ComConnection keys of USARSim's USARComServer.ini (manual 3.2.4.2), as the world's
# ``wireless`` section and ``--wireless-config`` take them, and the setting each gives.
WIRELESS_KEYS = {
    "ePdo": "pd0_dbm",
    "eDo": "d0_m",
    "eN": "path_loss_exponent",
    "eCutoff": "cutoff_dbm",
    "eMaxObs": "max_walls",
    "eAttenFac": "wall_db",
}


@dataclass(frozen=True, kw_only=True)
class Material:
    name: str
    rgba: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0)
    friction: float = 1.0
    see_through: tuple[str, ...] = ()  # sensor kinds whose rays pass through (SEE_THROUGH_KINDS)
    # special effects (manual 3.2.1): a mirror reflects laser and IR rays; a grid fender lets
    # the fraction ``porosity`` of laser, IR and camera rays through
    mirror: bool = False
    porosity: float = 0.0
    # what cameras see (usarsim.sim.textures): a procedural texture made around ``rgba``, and
    # how many of its tiles cover a metre along its width and height (None: its natural size)
    texture: str = ""
    texture_scale: tuple[float, float] | None = None


@dataclass(frozen=True, kw_only=True)
class StaticObject:
    name: str
    shape: str
    center: Vec3
    size: Vec3 = (0.0, 0.0, 0.0)  # full extents (box)
    radius_m: float = 0.0  # cylinder
    length_m: float = 0.0  # cylinder, along its own Z axis
    rotation: Vec3 = (0.0, 0.0, 0.0)
    material: str = "default"
    mass_kg: float = 0.0  # > 0: a movable object (a brick, a pipe) that robots can push and lift
    mesh_file: str = ""  # mesh: absolute path of the OBJ or STL file
    scale: Vec3 = (1.0, 1.0, 1.0)  # mesh: factors applied to its vertices (object frame)
    part_of: str = ""  # the ramp or stairs this box was expanded from


@dataclass(frozen=True, kw_only=True)
class Light:
    """A light of the world (USARSim frame): cameras render the scene with it."""

    name: str
    type: str = "spot"  # LIGHT_TYPES
    position: Vec3 = (0.0, 0.0, -3.0)
    direction: Vec3 = (0.0, 0.0, 1.0)  # unit vector (straight down by default); spot, directional
    color: tuple[float, float, float] = (0.7, 0.7, 0.7)  # diffuse colour at intensity 1
    intensity: float = 1.0  # multiplies the colour
    ambient: tuple[float, float, float] = (0.0, 0.0, 0.0)
    specular: tuple[float, float, float] = (0.3, 0.3, 0.3)
    attenuation: Vec3 = (1.0, 0.0, 0.0)  # constant, linear, quadratic (OpenGL)
    cutoff_deg: float = 45.0  # spot: half-angle of the cone
    exponent: float = 10.0  # spot: how fast the light falls off from the axis
    cast_shadows: bool = True


@dataclass(frozen=True, kw_only=True)
class UtmCoordinate:
    """A point in Universal Transverse Mercator coordinates (WGS84)."""

    easting_m: float
    northing_m: float
    zone: int  # 1..60
    letter: str  # latitude band, C..X without I and O; N and above is the northern hemisphere


@dataclass(frozen=True, kw_only=True)
class StartPose:
    name: str
    location: Vec3
    rotation: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True, kw_only=True)
class Floor:
    center: tuple[float, float]
    size: tuple[float, float]
    material: str = "floor"


@dataclass(frozen=True, kw_only=True)
class GeoReference:
    """Geographic coordinate of the world origin, for GPS (protocol.md 7.6): world +X is
    north, +Y east.  Defaults: USARSim's ZeroZeroLocation (NIST Gaithersburg,
    39 deg 8.0273' N, 77 deg 12.998' W) and its scales, 111200 m per degree of latitude
    and 71670 m per degree of longitude."""

    latitude_deg: float = 39.0 + 8.0273 / 60.0
    longitude_deg: float = -(77.0 + 12.998 / 60.0)
    scale_latitude_m: float = 111200.0
    scale_longitude_m: float = 71670.0
    utm: UtmCoordinate | None = None  # the origin as the world file gave it, when in UTM


@dataclass(frozen=True, kw_only=True)
class Victim:
    """A person to be found: body parts the victim sensor can see, optionally waving
    (its arm moves) and making sounds."""

    name: str
    location: Vec3  # the pelvis, on the floor: z is the height of the body's centre line
    rotation: Vec3 = (0.0, 0.0, 0.0)
    posture: str = "lying"
    waving: bool = False
    sound_loudness_db: float = 0.0  # 0: silent
    sound_period_s: float = 5.0
    sound_duration_s: float = 1.0


@dataclass(frozen=True, kw_only=True)
class FalseAlarm:
    """An object that fools the victim sensor: a box reported as a body part."""

    name: str
    center: Vec3
    size: Vec3
    rotation: Vec3 = (0.0, 0.0, 0.0)
    part: str = "Head"
    material: str = "default"


@dataclass(frozen=True, kw_only=True)
class WaterVolume:
    """A box of water (axis-aligned): robots in it float and are slowed down; robots not
    built for water lose their battery in it, as in UT2004 (protocol.md 5.3e)."""

    name: str
    center: Vec3
    size: Vec3
    density_kg_m3: float = 1000.0  # fresh water

    def depth_of(self, point) -> float:
        """How far below the surface ``point`` (USARSim frame, Z down) is; negative above
        it, -inf outside the box horizontally or below its bottom."""
        x, y, z = point
        cx, cy, cz = self.center
        sx, sy, sz = self.size
        if abs(x - cx) > sx / 2 or abs(y - cy) > sy / 2 or z > cz + sz / 2:
            return -math.inf
        return z - (cz - sz / 2)


@dataclass(frozen=True, kw_only=True)
class RfidTagConfig:
    tag_id: int
    location: Vec3
    memory: str = ""


@dataclass(frozen=True, kw_only=True)
class WirelessConfig:
    """A world's (or a configuration file's) choice of radio model and the constants it
    overrides; None: not given (the model's own value).  ``max_walls`` below 0: no cap."""

    model: str | None = None
    pd0_dbm: float | None = None
    d0_m: float | None = None
    path_loss_exponent: float | None = None
    cutoff_dbm: float | None = None
    max_walls: int | None = None
    wall_db: float | None = None
    cache_distance_m: float | None = None


@dataclass(frozen=True, kw_only=True)
class WorldConfig:
    name: str
    description: str = ""
    path: str
    floor: Floor
    materials: dict[str, Material]
    objects: tuple[StaticObject, ...]
    start_poses: tuple[StartPose, ...]
    # named places of the world (the UDK's path nodes: GETPATHNODES, GETCLOSESTPATHNODE)
    path_nodes: tuple[StartPose, ...] = ()
    time_limit_min: int = 0
    timestep_s: float = 0.004
    gravity_m_s2: float = 9.81
    geo: GeoReference = field(default_factory=GeoReference)
    victims: tuple[Victim, ...] = ()
    false_alarms: tuple[FalseAlarm, ...] = ()
    rfid_tags: tuple[RfidTagConfig, ...] = ()
    water: tuple[WaterVolume, ...] = ()
    lights: tuple[Light, ...] = ()  # none: the default lighting (builder.world_spec)
    ambient_light: tuple[float, float, float] | None = None  # None: MuJoCo's default (0.1 grey)
    wireless: WirelessConfig | None = None  # None: the default radio model
    # the entries of sections read by registered element kinds (usarsim.config.elements), by
    # kind; their solids are among ``objects``, their landmarks here
    elements: tuple[tuple[str, tuple[Any, ...]], ...] = ()
    landmarks: tuple[Landmark, ...] = ()
    extra: dict = field(default_factory=dict)

    def start_pose(self, name: str) -> StartPose | None:
        """Look a start pose up by name, case-insensitively (protocol.md 5.1)."""
        low = name.lower()
        for p in self.start_poses:
            if p.name.lower() == low:
                return p
        return None

    def solid_at(self, point, *, margin_m: float = SOLID_MARGIN_M, movable: bool = True) -> str | None:
        """What solid of the world holds ``point`` (USARSim frame, metres) more than
        ``margin_m`` deep, or None when the point is free: ``"box 'wall_north'"``,
        ``"cylinder 'pipe'"``, ``"ramp 'r1'"``, ``"stairs 'st' (step 2)"``, ``"false alarm
        'fa'"``, ``"the floor"`` (below its top surface, z > 0).  A point on a surface, or
        less than ``margin_m`` into it, is free: a start pose resting on the floor or on a
        platform is fine.  Boxes and cylinders count with their rotation; a mesh counts as
        the closed surface its file draws.  Movable objects count where the file puts them
        unless ``movable`` is False (they may have been pushed away since)."""
        x, y, z = (float(c) for c in point)
        if z > margin_m:
            return "the floor"
        for obj in self.objects:
            if obj.mass_kg > 0 and not movable:
                continue
            local = _to_local((x, y, z), obj.center, obj.rotation)
            if obj.shape == "box":
                inside = _in_box(local, obj.size, margin_m)
            elif obj.shape == "cylinder":
                inside = (
                    math.hypot(local[0], local[1]) < obj.radius_m - margin_m
                    and abs(local[2]) < obj.length_m / 2.0 - margin_m
                )
            else:
                inside = _mesh_depth(obj.mesh_file, obj.scale, local) > margin_m
            if inside:
                return _describe_object(obj)
        for a in self.false_alarms:
            if _in_box(_to_local((x, y, z), a.center, a.rotation), a.size, margin_m):
                return f"false alarm '{a.name}'"
        return None


# --------------------------------------------------------------------------- UTM
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


# --------------------------------------------------------------------------- solids
def _rotation(rpy) -> tuple[tuple[float, float, float], ...]:
    """The rotation matrix of (roll, pitch, yaw) applied yaw, then pitch, then roll (the
    USARSim frame's convention, docs/world-files.md): object axes -> world axes."""
    cr, sr = math.cos(rpy[0]), math.sin(rpy[0])
    cp, sp = math.cos(rpy[1]), math.sin(rpy[1])
    cy, sy = math.cos(rpy[2]), math.sin(rpy[2])
    return (
        (cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
        (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
        (-sp, cp * sr, cp * cr),
    )


def _to_local(point, center, rotation) -> Vec3:
    """``point`` (world) in the frame of an object at ``center`` turned by ``rotation``."""
    d = (point[0] - center[0], point[1] - center[1], point[2] - center[2])
    m = _rotation(rotation)
    return (
        m[0][0] * d[0] + m[1][0] * d[1] + m[2][0] * d[2],
        m[0][1] * d[0] + m[1][1] * d[1] + m[2][1] * d[2],
        m[0][2] * d[0] + m[1][2] * d[1] + m[2][2] * d[2],
    )


def _in_box(local, size, margin: float) -> bool:
    return all(abs(c) < e / 2.0 - margin for c, e in zip(local, size))


def _describe_object(obj: StaticObject) -> str:
    if obj.part_of and obj.name != obj.part_of:  # a step of a flight of stairs
        return f"stairs '{obj.part_of}' (step {obj.name.rsplit('step', 1)[-1]})"
    if obj.part_of:
        return f"ramp '{obj.part_of}'"
    return f"{obj.shape} '{obj.name}'" + (" (movable)" if obj.mass_kg > 0 else "")


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _dot(a, b) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@cache
def _mesh_triangles(mesh_file: str, scale: Vec3, mtime: float) -> tuple:
    """The triangles of an OBJ (its faces, fanned) or binary STL file, scaled, in the
    object's frame; empty when the file cannot be read.  (``mtime``: read again when the
    file changes.)"""
    p = Path(mesh_file)
    tris = []
    try:
        if p.suffix.lower() == ".obj":
            verts: list[Vec3] = []
            for line in p.read_text(errors="replace").splitlines():
                parts = line.split()
                if parts[:1] == ["v"] and len(parts) >= 4:
                    verts.append(tuple(float(v) * k for v, k in zip(parts[1:4], scale)))
                elif parts[:1] == ["f"] and len(parts) >= 4:
                    idx = [int(t.split("/")[0]) for t in parts[1:]]
                    idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                    tris += [(verts[idx[0]], verts[idx[k]], verts[idx[k + 1]]) for k in range(1, len(idx) - 1)]
        else:
            data = p.read_bytes()
            (count,) = struct.unpack_from("<I", data, 80)
            for t in range(count):
                v = struct.unpack_from("<9f", data, 84 + 50 * t + 12)
                tris.append(tuple(tuple(v[3 * i + j] * scale[j] for j in range(3)) for i in range(3)))
    except (OSError, ValueError, IndexError, struct.error):
        return ()
    return tuple(tris)


def _closest_on_triangle(p, a, b, c):
    """The point of triangle abc closest to p (C. Ericson, Real-Time Collision Detection,
    2005, section 5.1.5)."""
    ab, ac, ap = _sub(b, a), _sub(c, a), _sub(p, a)
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    if d1 <= 0 and d2 <= 0:
        return a
    bp = _sub(p, b)
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    if d3 >= 0 and d4 <= d3:
        return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        v = d1 / (d1 - d3)
        return (a[0] + v * ab[0], a[1] + v * ab[1], a[2] + v * ab[2])
    cp = _sub(p, c)
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    if d6 >= 0 and d5 <= d6:
        return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        w = d2 / (d2 - d6)
        return (a[0] + w * ac[0], a[1] + w * ac[1], a[2] + w * ac[2])
    va = d3 * d6 - d5 * d4
    if va <= 0 and (d4 - d3) >= 0 and (d5 - d6) >= 0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return (b[0] + w * (c[0] - b[0]), b[1] + w * (c[1] - b[1]), b[2] + w * (c[2] - b[2]))
    denom = 1.0 / (va + vb + vc)
    v, w = vb * denom, vc * denom
    return (a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w)


# A direction no mesh edge or face of a hand-made file is likely to be parallel to, for the
# inside test's ray.
_RAY = (0.5773, 0.5781, 0.5766)


def _mesh_depth(mesh_file: str, scale: Vec3, local) -> float:
    """How deep ``local`` (the object's frame) lies inside the closed surface of a mesh file:
    the distance to its nearest triangle when a ray from it crosses the surface an odd
    number of times (Moeller and Trumbore's ray-triangle test), else negative."""
    try:
        mtime = Path(mesh_file).stat().st_mtime
    except OSError:
        return -1.0
    tris = _mesh_triangles(mesh_file, tuple(scale), mtime)
    if not tris:
        return -1.0
    crossings, nearest = 0, math.inf
    for a, b, c in tris:
        q = _closest_on_triangle(local, a, b, c)
        nearest = min(nearest, math.dist(local, q))
        e1, e2 = _sub(b, a), _sub(c, a)
        h = _cross(_RAY, e2)
        det = _dot(e1, h)
        if abs(det) < 1e-12:
            continue
        sv = _sub(local, a)
        u = _dot(sv, h) / det
        qv = _cross(sv, e1)
        v = _dot(_RAY, qv) / det
        if u < 0 or v < 0 or u + v > 1:
            continue
        if _dot(e2, qv) / det > 0:
            crossings += 1
    return nearest if crossings % 2 else -nearest


def _unique_name(s: Section, taken: set[str], what: str = "name") -> str:
    """The entry's ``name``, refused when ``taken`` has it already (then it has it)."""
    name = s.str("name")
    if name in taken:
        raise s.error("name", f"duplicate {what} '{name}'")
    taken.add(name)
    return name


def load_world(path: str | Path) -> WorldConfig:
    path = str(path)
    data = load_yaml(path)
    try:
        return _world(data, path)
    except ConfigError as exc:
        name_entries(exc, data)
        raise


def _world(data: dict, path: str) -> WorldConfig:
    d = FieldDefaults(WorldConfig)
    top = Section(data, path=path)
    name = top.str("name")
    if any(c in name for c in "{} \t"):
        raise top.error("name", f"a world name may not contain spaces or braces, got {name!r}")
    description = top.str("description", d.description)
    time_limit = top.int("time_limit_min", d.time_limit_min, min=0)
    physics = top.section("physics", {})
    timestep = physics.float("timestep_s", d.timestep_s, min=0.0005, max=0.02)
    gravity = physics.float("gravity_m_s2", d.gravity_m_s2, min=0.0, max=100.0)
    physics.finish()

    mats_sec = top.section("materials", {})
    materials: dict[str, Material] = {"default": Material(name="default")}
    md = FieldDefaults(Material)
    for mname in list(mats_sec.data):
        ms = mats_sec.section(str(mname))
        rgba = ms.vec("rgba", 4, md.rgba)
        if any(c < 0 or c > 1 for c in rgba):
            raise ms.error("rgba", f"each colour component must be within [0, 1], got {list(rgba)}")
        see = ms.list("see_through", [])
        for k in see:
            if k not in SEE_THROUGH_KINDS:
                raise ms.error(
                    "see_through",
                    f"unknown sensor kind {k!r}{did_you_mean(str(k), SEE_THROUGH_KINDS)}; "
                    f"allowed: {', '.join(SEE_THROUGH_KINDS)}",
                )
        mirror = ms.bool("mirror", md.mirror)
        porosity = ms.float("porosity", md.porosity, min=0.0, max=1.0)
        if mirror and porosity > 0:
            raise ms.error("porosity", "a mirror cannot be porous: give either mirror: true or a porosity")
        texture = ms.str("texture", md.texture)
        if texture and texture not in TEXTURE_NAMES:
            raise ms.error("texture", f"unknown texture '{texture}'{did_you_mean(texture, TEXTURE_NAMES)}")
        scale = md.texture_scale
        if ms.has("texture_scale"):
            if not texture:
                raise ms.error("texture_scale", "a texture_scale needs a texture")
            raw = ms.raw("texture_scale")
            scale = ms.vec("texture_scale", 2) if isinstance(raw, list) else (ms.float("texture_scale"),) * 2
            if not all(0.001 <= c <= 1000.0 for c in scale):
                raise ms.error("texture_scale", f"tiles per metre must be within [0.001, 1000], got {raw!r}")
        materials[str(mname)] = Material(
            name=str(mname),
            rgba=rgba,
            friction=ms.float("friction", md.friction, min=0.0, max=10.0),
            see_through=tuple(see),
            mirror=mirror,
            porosity=porosity,
            texture=texture,
            texture_scale=scale,
        )
        ms.finish()

    def check_material(sec: Section, key: str, value: str) -> None:
        if value not in materials:
            raise sec.error(key, f"unknown material '{value}'{did_you_mean(value, materials)}")

    def check_flat(sec: Section, key: str, value: str, shape: str) -> None:
        # a mirror reflects about the face it is hit on: only boxes have flat faces here
        if materials[value].mirror and shape != "box":
            raise sec.error(
                key,
                f"material '{value}' is a mirror, which only box objects (and ramps and "
                f"stairs) may use; this object is a {shape}",
            )

    fl = top.section("floor")
    floor = Floor(
        center=fl.vec("center", 2),
        size=fl.vec("size", 2, positive=True),
        material=fl.str("material", FieldDefaults(Floor).material),
    )
    if floor.material not in materials:
        materials[floor.material] = Material(name=floor.material)
    check_flat(fl, "material", floor.material, "plane")
    fl.finish()

    objects: list[StaticObject] = []
    names: set[str] = set()
    world_dir = Path(path).resolve().parent
    od = FieldDefaults(StaticObject)
    for s in top.entries("objects"):
        oname = _unique_name(s, names, "object name")
        shape = s.str("shape", choices=OBJECT_SHAPES)
        material = s.str("material", od.material)
        check_material(s, "material", material)
        if shape in ("ramp", "stairs"):
            parts = _ramp(s, oname, material) if shape == "ramp" else _stairs(s, oname, material)
            for part in parts:
                if part.name != oname and part.name in names:
                    raise s.error("name", f"object '{part.name}' (a part of '{oname}') has the name of another object")
                names.add(part.name)
            objects.extend(parts)
            continue
        check_flat(s, "material", material, shape)
        center = s.vec("center")
        rotation = s.vec("rotation", 3, od.rotation)
        mass = s.float("mass_kg", od.mass_kg, min=0.0)
        if shape == "box":
            obj = StaticObject(
                name=oname,
                shape=shape,
                center=center,
                size=s.vec("size", 3, positive=True),
                rotation=rotation,
                material=material,
                mass_kg=mass,
            )
        elif shape == "cylinder":
            obj = StaticObject(
                name=oname,
                shape=shape,
                center=center,
                radius_m=s.float("radius", min=0.001),
                length_m=s.float("length", min=0.001),
                rotation=rotation,
                material=material,
                mass_kg=mass,
            )
        else:
            obj = StaticObject(
                name=oname,
                shape=shape,
                center=center,
                rotation=rotation,
                material=material,
                mass_kg=mass,
                mesh_file=_mesh_file(s, world_dir),
                scale=s.vec("scale", 3, od.scale, positive=True),
            )
        objects.append(obj)
    elements, landmarks = _elements(top, names, objects, materials)

    poses = _named_poses(top, "start_poses", "start pose")
    path_nodes = _named_poses(top, "path_nodes", "path node")

    g = top.section("geo_reference", {})
    gd = FieldDefaults(GeoReference)
    utm = gd.utm
    if g.has("utm"):
        both = [k for k in ("latitude_deg", "longitude_deg") if g.has(k)]
        if both:
            raise g.error(both[0], "give the origin either as latitude_deg/longitude_deg or as utm, not both")
        utm = _utm(g.section("utm"))
        lat, lon = utm_to_latlon(utm)
        south, north = utm_band_limits_deg(utm.letter)
        if not south - 1e-6 <= lat <= north + 1e-6:
            raise g.error(
                "utm",
                f"northing {utm.northing_m:g} m in zone {utm.zone}{utm.letter} is latitude "
                f"{lat:.4f} degrees, outside band {utm.letter} ({south:g} to {north:g} degrees); "
                f"check the northing and the letter",
            )
        if not -89.0 <= lat <= 89.0:
            raise g.error("utm", f"the origin must lie within 89 degrees of the equator, got latitude {lat:.4f}")
    else:
        lat = g.float("latitude_deg", gd.latitude_deg, min=-89.0, max=89.0)
        lon = g.float("longitude_deg", gd.longitude_deg, min=-180.0, max=180.0)
    geo = GeoReference(
        latitude_deg=lat,
        longitude_deg=lon,
        scale_latitude_m=g.float("scale_latitude_m", gd.scale_latitude_m, min=1.0),
        scale_longitude_m=g.float("scale_longitude_m", gd.scale_longitude_m, min=1.0),
        utm=utm,
    )
    g.finish()

    victims: list[Victim] = []
    vd = FieldDefaults(Victim)
    for s in top.entries("victims"):
        vname = _unique_name(s, names)
        sound = s.section("sound", {})  # sound.X fills sound_X
        victims.append(
            Victim(
                name=vname,
                location=s.vec("location"),
                rotation=s.vec("rotation", 3, vd.rotation),
                posture=s.str("posture", vd.posture, choices=VICTIM_POSTURES),
                waving=s.bool("waving", vd.waving),
                sound_loudness_db=sound.float("loudness_db", vd.sound_loudness_db, min=0.0, max=200.0),
                sound_period_s=sound.float("period_s", vd.sound_period_s, min=0.1),
                sound_duration_s=sound.float("duration_s", vd.sound_duration_s, min=0.01),
            )
        )
        sound.finish()

    alarms: list[FalseAlarm] = []
    fd = FieldDefaults(FalseAlarm)
    for s in top.entries("false_alarms"):
        aname = _unique_name(s, names)
        material = s.str("material", fd.material)
        check_material(s, "material", material)
        alarms.append(
            FalseAlarm(
                name=aname,
                center=s.vec("center"),
                size=s.vec("size", 3, positive=True),
                rotation=s.vec("rotation", 3, fd.rotation),
                part=s.str("part", fd.part, choices=VICTIM_PARTS),
                material=material,
            )
        )

    tags: list[RfidTagConfig] = []
    ids: set[int] = set()
    for s in top.entries("rfid_tags"):
        tid = s.int("id", min=0)
        if tid in ids:
            raise s.error("id", f"duplicate RFID tag id {tid}")
        ids.add(tid)
        mem = s.str("memory", FieldDefaults(RfidTagConfig).memory)
        if any(c in mem for c in "{}\r\n"):
            raise s.error("memory", "tag memory may not contain braces or line breaks")
        tags.append(RfidTagConfig(tag_id=tid, location=s.vec("location"), memory=mem))

    water: list[WaterVolume] = []
    wd = FieldDefaults(WaterVolume)
    for s in top.entries("water"):
        wname = _unique_name(s, names)
        water.append(
            WaterVolume(
                name=wname,
                center=s.vec("center"),
                size=s.vec("size", 3, positive=True),
                density_kg_m3=s.float("density_kg_m3", wd.density_kg_m3, min=1.0, max=20000.0),
            )
        )

    lights: list[Light] = []
    lnames: set[str] = set()
    for s in top.entries("lights"):
        lights.append(_light(s, _unique_name(s, lnames, "light name")))
    ambient = top.vec("ambient_light", 3, d.ambient_light)
    if ambient is not None and any(c < 0 or c > 1 for c in ambient):
        raise top.error("ambient_light", f"each colour component must be within [0, 1], got {list(ambient)}")

    wireless = _wireless(top.section("wireless")) if top.has("wireless") else d.wireless

    top.finish()
    return WorldConfig(
        name=name,
        description=description,
        path=path,
        floor=floor,
        materials=materials,
        objects=tuple(objects),
        start_poses=poses,
        path_nodes=path_nodes,
        time_limit_min=time_limit,
        timestep_s=timestep,
        gravity_m_s2=gravity,
        geo=geo,
        victims=tuple(victims),
        false_alarms=tuple(alarms),
        rfid_tags=tuple(tags),
        water=tuple(water),
        lights=tuple(lights),
        ambient_light=ambient,
        wireless=wireless,
        elements=elements,
        landmarks=landmarks,
    )


def _elements(
    top: Section, names: set[str], objects: list[StaticObject], materials: dict[str, Material]
) -> tuple[tuple[tuple[str, tuple[Any, ...]], ...], tuple[Landmark, ...]]:
    """The sections of the registered element kinds (usarsim.config.elements): each entry
    parsed by its kind, its solids added to ``objects`` (named ``<kind>/<entry>/<solid>``), its
    landmarks collected."""
    elements = []
    landmarks: list[Landmark] = []
    for kind_name in ELEMENT_KINDS.names():
        if not top.has(kind_name):
            continue
        kind = ELEMENT_KINDS.get(kind_name)
        entries = []
        taken: set[str] = set()
        for s in top.entries(kind_name):
            element = kind.parse(s)
            if element.name in taken:
                raise s.error("name", f"two {kind_name} entries are called '{element.name}'")
            taken.add(element.name)
            for solid in kind.solids(element):
                solid = dataclasses.replace(solid, name=f"{kind_name}/{element.name}/{solid.name}")
                if solid.name in names:
                    raise s.error("name", f"object '{solid.name}' has the name of another object")
                if solid.material not in materials:
                    raise s.error(
                        "name",
                        f"{kind_name} '{element.name}': its solid names no material of the "
                        f"world: '{solid.material}'{did_you_mean(solid.material, materials)}",
                    )
                names.add(solid.name)
                objects.append(solid)
            landmarks.extend(kind.landmarks(element))
            entries.append(element)
        elements.append((kind_name, tuple(entries)))
    return tuple(elements), tuple(landmarks)


def _named_poses(top: Section, key: str, what: str) -> tuple[StartPose, ...]:
    """The ``start_poses`` or ``path_nodes`` of a world: named poses, names unique (any case)
    and without the characters that separate them on the wire."""
    poses: list[StartPose] = []
    names: set[str] = set()
    pd = FieldDefaults(StartPose)
    for s in top.entries(key):
        pname = s.str("name")
        if any(c in pname for c in "{} \t,"):
            raise s.error("name", f"a {what} name may not contain spaces, commas or braces, got {pname!r}")
        if pname.lower() in names:
            raise s.error("name", f"duplicate {what} name '{pname}'")
        names.add(pname.lower())
        poses.append(StartPose(name=pname, location=s.vec("location"), rotation=s.vec("rotation", 3, pd.rotation)))
    return tuple(poses)


def _wireless(s: Section) -> WirelessConfig:
    """The ``wireless`` section: ``model`` (a radio model's name: the built-in WIRELESS_MODELS or
    a plugin's, checked against the registry of usarsim.sim.radio when the server starts), the
    ini keys of WIRELESS_KEYS and ``cache_distance_m``."""
    d = FieldDefaults(WirelessConfig)
    model = s.str("model", d.model)
    if model is not None and (not model.isidentifier() or model != model.lower()):
        raise s.error(
            "model",
            f"a radio model's name is a lower-case word (built in: {', '.join(WIRELESS_MODELS)}), got {model!r}",
        )
    d0 = s.float("eDo", d.d0_m, min=0.0, min_exclusive=True)
    n = s.float("eN", d.path_loss_exponent, min=0.0, max=10.0)
    waf = s.float("eAttenFac", d.wall_db, min=0.0, max=200.0)
    max_obs = s.int("eMaxObs", d.max_walls)
    if max_obs is None and s.data.get("eMaxObs", 0) is None:
        max_obs = -1  # eMaxObs: null, no cap
    cache = s.float("cache_distance_m", d.cache_distance_m, min=0.0)
    cfg = WirelessConfig(
        model=model,
        pd0_dbm=s.float("ePdo", d.pd0_dbm, min=-300.0, max=100.0),
        d0_m=d0,
        path_loss_exponent=n,
        cutoff_dbm=s.float("eCutoff", d.cutoff_dbm, min=-300.0, max=100.0),
        max_walls=max_obs,
        wall_db=waf,
        cache_distance_m=cache,
    )
    s.finish()
    return cfg


def _slope_check(s: Section, key: str, rise: float, run: float, what: str) -> None:
    slope = math.degrees(math.atan2(rise, run))
    if slope >= MAX_SLOPE_DEG:
        raise s.error(
            key,
            f"{what} is {slope:.1f} degrees steep; allowed: below {MAX_SLOPE_DEG:g} degrees "
            f"(rise < {math.tan(math.radians(MAX_SLOPE_DEG)):.3f} x run)",
        )


def _ramp(s: Section, name: str, material: str) -> list[StaticObject]:
    """A ramp: one plate (a box) whose top face runs from the foot (the middle of its bottom
    edge, on the surface it stands on) up ``length`` m of run and ``rise`` m of height along
    ``heading``, reaching RAMP_FOOT_SINK_M below the surface at its foot."""
    foot = s.vec("foot")
    heading = s.float("heading", 0.0)
    length = s.float("length", min=0.0, min_exclusive=True)
    width = s.float("width", min=0.0, min_exclusive=True)
    rise = s.float("rise", min=0.0, min_exclusive=True)
    thickness = s.float("thickness", 0.05, min=0.0, min_exclusive=True)
    _slope_check(s, "rise", rise, length, f"the ramp (rise {rise:g} m over a run of {length:g} m)")
    theta = math.atan2(rise, length)
    # the top face's line, extended past the foot until it is RAMP_FOOT_SINK_M below the surface
    ext = RAMP_FOOT_SINK_M / math.sin(theta)
    slope_len = math.hypot(length, rise) + ext
    ux, uy = math.cos(heading), math.sin(heading)
    su, sz = math.cos(theta), -math.sin(theta)  # along the slope, upwards (Z down)
    top_mid = (math.hypot(length, rise) - ext) / 2.0  # the top face's middle, from the foot along the slope
    # the plate's centre is half its thickness below the top face (normal up: (-sin u, -cos))
    nu, nz = -math.sin(theta), -math.cos(theta)
    center = (
        foot[0] + ux * (top_mid * su - thickness / 2.0 * nu),
        foot[1] + uy * (top_mid * su - thickness / 2.0 * nu),
        foot[2] + top_mid * sz - thickness / 2.0 * nz,
    )
    # the box's own X along the slope: pitch up by theta (positive pitch raises X), then yaw
    return [
        StaticObject(
            name=name,
            shape="box",
            center=center,
            size=(slope_len, width, thickness),
            rotation=(0.0, theta, heading),
            material=material,
            part_of=name,
        )
    ]


def _stairs(s: Section, name: str, material: str) -> list[StaticObject]:
    """A flight of stairs: ``steps`` boxes along ``heading`` from the foot (the middle of the
    bottom step's front edge, on the surface it stands on); step k (1 = the lowest) is
    ``k * step_rise`` high and solid down to that surface."""
    foot = s.vec("foot")
    heading = s.float("heading", 0.0)
    width = s.float("width", min=0.0, min_exclusive=True)
    steps = s.int("steps", min=1)
    if steps > 200:
        raise s.error("steps", f"at most 200 steps, got {steps}")
    rise = s.float("step_rise", min=0.0, min_exclusive=True)
    run = s.float("step_run", min=0.0, min_exclusive=True)
    _slope_check(s, "step_rise", rise, run, f"the flight (step rise {rise:g} m over a run of {run:g} m)")
    ux, uy = math.cos(heading), math.sin(heading)
    out = []
    for k in range(1, steps + 1):
        along = (k - 0.5) * run
        out.append(
            StaticObject(
                name=f"{name}/step{k}",
                shape="box",
                center=(foot[0] + ux * along, foot[1] + uy * along, foot[2] - k * rise / 2.0),
                size=(run, width, k * rise),
                rotation=(0.0, 0.0, heading),
                material=material,
                part_of=name,
            )
        )
    return out


def _mesh_file(s: Section, world_dir: Path) -> str:
    rel = s.str("file")
    p = Path(rel)
    p = p if p.is_absolute() else world_dir / p
    if p.suffix.lower() not in MESH_SUFFIXES:
        raise s.error("file", f"'{rel}' is not a mesh file MuJoCo reads; allowed: {', '.join(MESH_SUFFIXES)} files")
    if not p.is_file():
        raise s.error("file", f"mesh file '{rel}' not found (looked for {p}; paths are relative to the world file)")
    if p.suffix.lower() == ".stl":
        size = p.stat().st_size
        with p.open("rb") as f:
            head = f.read(84)
        count = int.from_bytes(head[80:84], "little") if len(head) == 84 else -1
        if count < 0 or size != 84 + 50 * count:
            raise s.error(
                "file",
                f"'{rel}' is not a binary STL file (MuJoCo reads binary STL only); convert it or use an OBJ file",
            )
    return str(p.resolve())


def _light(s: Section, name: str) -> Light:
    d = FieldDefaults(Light)
    ltype = s.str("type", d.type, choices=LIGHT_TYPES)

    def rgb(key: str, default):
        v = s.vec(key, 3, default)
        if any(c < 0 or c > 1 for c in v):
            raise s.error(key, f"each colour component must be within [0, 1], got {list(v)}")
        return v

    direction = s.vec("direction", 3, d.direction)
    norm = math.sqrt(sum(c * c for c in direction))
    if norm < 1e-9:
        raise s.error("direction", f"the direction must not be zero, got {list(direction)}")
    position = s.vec("position", 3, d.position)
    attenuation = s.vec("attenuation", 3, d.attenuation)
    if any(c < 0 for c in attenuation) or not any(c > 0 for c in attenuation):
        raise s.error(
            "attenuation", f"[constant, linear, quadratic] must be >= 0 and not all 0, got {list(attenuation)}"
        )
    return Light(
        name=name,
        type=ltype,
        position=position,
        direction=tuple(c / norm for c in direction),
        color=rgb("color", d.color),
        intensity=s.float("intensity", d.intensity, min=0.0, max=100.0),
        ambient=rgb("ambient", d.ambient),
        specular=rgb("specular", d.specular),
        attenuation=attenuation,
        cutoff_deg=s.float("cutoff_deg", d.cutoff_deg, min=0.0, max=90.0, min_exclusive=True),
        exponent=s.float("exponent", d.exponent, min=0.0, max=128.0),
        # a point light casts none unless asked (docs/world-files.md)
        cast_shadows=s.bool("cast_shadows", d.cast_shadows and ltype != "point"),
    )


def _utm(u: Section) -> UtmCoordinate:
    zone = u.int("zone", min=1)
    if zone > 60:
        raise u.error("zone", f"UTM zones are 1 to 60, got {zone}")
    letter = u.str("letter")
    if len(letter) != 1 or letter.upper() not in UTM_LETTERS:
        raise u.error(
            "letter",
            f"'{letter}' is not a UTM latitude band; allowed: one of {' '.join(UTM_LETTERS)} "
            f"(N and after: northern hemisphere)",
        )
    out = UtmCoordinate(
        easting_m=u.float("easting", min=100000.0, max=900000.0),
        northing_m=u.float("northing", min=0.0, max=10000000.0),
        zone=zone,
        letter=letter.upper(),
    )
    u.finish()
    return out


def check_world_file(path: str | Path) -> WorldConfig:
    """Load a world file and check what a world must have to be served (``usarsim
    validate``): at least one start pose, none inside a solid (WorldConfig.solid_at)."""
    cfg = load_world(path)
    if not cfg.start_poses:
        raise ConfigError("a world needs at least one start pose", path=str(path), key="start_poses")
    for i, pose in enumerate(cfg.start_poses):
        solid = cfg.solid_at(pose.location)
        if solid is not None:
            where = ", ".join(f"{c:g}" for c in pose.location)
            err = ConfigError(
                f"start pose '{pose.name}' at [{where}] lies inside {solid} (more than "
                f"{SOLID_MARGIN_M * 100:g} cm deep): move it into free space or onto a surface (z is "
                f"down; the floor is z = 0)",
                path=str(path),
                key=f"start_poses[{i}].location",
            )
            raise name_entries(err, load_yaml(path))
    return cfg
