"""World files: static geometry, materials and start poses (YAML).

Coordinates are in the USARSim frame (X forward/north, Y right/east, Z down),
metres and radians; the floor's top surface is the plane z = 0.

This module holds the format's classes and :func:`load_world`; the sections are read by
usarsim.config.world_objects (materials, floor, objects, element kinds' solids) and
usarsim.config.world_sections (the rest), the point-inside tests of
:meth:`WorldConfig.solid_at` are in usarsim.config.solids and the UTM conversions of the
geo reference in usarsim.config.utm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from usarsim.config.channel import ChannelConfig
from usarsim.config.elements import Landmark
from usarsim.config.solids import in_box, mesh_depth, to_local
from usarsim.config.utm import UTM_FALSE_EASTING_M as UTM_FALSE_EASTING_M
from usarsim.config.utm import UTM_FALSE_NORTHING_SOUTH_M as UTM_FALSE_NORTHING_SOUTH_M
from usarsim.config.utm import UTM_K0 as UTM_K0
from usarsim.config.utm import UTM_LETTERS as UTM_LETTERS
from usarsim.config.utm import WGS84_A_M as WGS84_A_M
from usarsim.config.utm import WGS84_F as WGS84_F
from usarsim.config.utm import UtmCoordinate as UtmCoordinate
from usarsim.config.utm import latlon_to_utm as latlon_to_utm
from usarsim.config.utm import utm_band_limits_deg as utm_band_limits_deg
from usarsim.config.utm import utm_central_meridian_deg as utm_central_meridian_deg
from usarsim.config.utm import utm_to_latlon as utm_to_latlon

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
# lying, sitting (the upper body upright), or trapped: lying with debris across the legs
VICTIM_POSTURES = ("lying", "sitting", "trapped")
VICTIM_BUILDS = ("average", "slim", "heavy", "child")  # body builds (usarsim.sim.victims.BUILDS)
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
    """An entry of a world file's ``materials``: the colour, friction and camera texture of the surfaces that name
    it, the sensor rays it lets through, and its special effects (a mirror, a porous grid fender; manual 3.2.1)."""

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
    # what a thermal camera sees of it (degrees Celsius; None: the room's, AMBIENT_C)
    temperature_c: float | None = None


@dataclass(frozen=True, kw_only=True)
class StaticObject:
    """An entry of a world file's ``objects``: a box, cylinder or mesh at ``center`` (USARSim frame, metres) with its
    rotation and material; ramps and stairs are expanded into boxes, and a mass above 0 makes it a movable object."""

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
class StartPose:
    """An entry of a world file's ``start_poses``: a named location and rotation where robots may be spawned, as
    ``GETSTARTPOSES`` lists them (protocol.md 5.2, 6.1); the world's ``path_nodes`` are written alike."""

    name: str
    location: Vec3
    rotation: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True, kw_only=True)
class Floor:
    """A world file's ``floor``: the rectangle of the plane z = 0 (centre and extents in metres) that range sensors
    see and robots may be spawned above, and its material."""

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
    build: str = "average"
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
    # what a thermal camera sees (degrees Celsius): warmer than the room, as a false alarm
    # placed to fool detectors of warm bodies is, and cooler than skin (an estimate)
    temperature_c: float = 28.0


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
    """An entry of a world file's ``rfid_tags``: an RFID tag lying in the world with its integer id, location and the
    memory text robots read and write (protocol.md 7.10)."""

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
    channel: ChannelConfig | None = None  # the channel beyond the path loss (usarsim.config.channel)


@dataclass(frozen=True, kw_only=True)
class WorldConfig:
    """A world as its world file describes it: the floor, materials, objects, start poses and path nodes, the
    victims, false alarms, RFID tags, water and lights, the physics timestep and gravity, the geo reference and the
    radio model."""

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
    # the ``variation`` section: how variants place things (usarsim.config.variation's
    # VariationRules; None: the defaults), and the variant this world is (None: as written)
    variation: Any = None
    variant: int | None = None
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
            local = to_local((x, y, z), obj.center, obj.rotation)
            if obj.shape == "box":
                inside = in_box(local, obj.size, margin_m)
            elif obj.shape == "cylinder":
                inside = (
                    math.hypot(local[0], local[1]) < obj.radius_m - margin_m
                    and abs(local[2]) < obj.length_m / 2.0 - margin_m
                )
            else:
                inside = mesh_depth(obj.mesh_file, obj.scale, local) > margin_m
            if inside:
                return _describe_object(obj)
        for a in self.false_alarms:
            if in_box(to_local((x, y, z), a.center, a.rotation), a.size, margin_m):
                return f"false alarm '{a.name}'"
        return None


def _describe_object(obj: StaticObject) -> str:
    if obj.part_of and obj.name != obj.part_of:  # a step of a flight of stairs
        return f"stairs '{obj.part_of}' (step {obj.name.rsplit('step', 1)[-1]})"
    if obj.part_of:
        return f"ramp '{obj.part_of}'"
    return f"{obj.shape} '{obj.name}'" + (" (movable)" if obj.mass_kg > 0 else "")


def bare_world(
    name: str, size_m: float = 10.0, rgba: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0)
) -> WorldConfig:
    """A world of a floor alone, ``size_m`` square and coloured ``rgba`` (robots checked or
    drawn on their own)."""
    return WorldConfig(
        name=name,
        description="",
        path="",
        floor=Floor(center=(0, 0), size=(size_m, size_m)),
        materials={"floor": Material(name="floor", rgba=rgba)},
        objects=(),
        start_poses=(),
    )
