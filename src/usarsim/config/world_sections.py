"""Reading a world file: :func:`read_world` turns a file's data into a WorldConfig, with the
readers of its sections beyond the solids (usarsim.config.world_objects): start poses and path
nodes, the geo reference, victims, false alarms, RFID tags, water, lights and the radio model.

Coordinates are in the USARSim frame (X forward/north, Y right/east, Z down), metres and
radians.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from usarsim.config.channel import read_channel
from usarsim.config.reader import FieldDefaults, Section
from usarsim.config.utm import UTM_LETTERS, UtmCoordinate, utm_band_limits_deg, utm_to_latlon
from usarsim.config.variation import read_variation
from usarsim.config.world import (
    LIGHT_TYPES,
    VICTIM_BUILDS,
    VICTIM_PARTS,
    VICTIM_POSTURES,
    WIRELESS_MODELS,
    FalseAlarm,
    GeoReference,
    Light,
    RfidTagConfig,
    StartPose,
    Vec3,
    Victim,
    WaterVolume,
    WirelessConfig,
    WorldConfig,
)
from usarsim.config.world_objects import (
    as_vec3,
    check_material,
    read_elements,
    read_floor,
    read_materials,
    read_objects,
    unique_name,
)


def read_world(data: dict[Any, Any], path: str) -> WorldConfig:
    """The world a file's data describes (``path``: where it was read, for errors and for
    the mesh files named relative to it)."""
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

    materials = read_materials(top)
    floor = read_floor(top, materials)
    names: set[str] = set()
    objects = read_objects(top, names, materials, Path(path).resolve().parent)
    elements, landmarks = read_elements(top, names, objects, materials)

    poses = _named_poses(top, "start_poses", "start pose")
    path_nodes = _named_poses(top, "path_nodes", "path node")
    geo = _geo_reference(top.section("geo_reference", {}))
    victims = _victims(top, names)
    alarms = _false_alarms(top, names, materials)
    tags = _rfid_tags(top)
    water = _water(top, names)

    lights: list[Light] = []
    lnames: set[str] = set()
    for s in top.entries("lights"):
        lights.append(_light(s, unique_name(s, lnames, "light name")))
    ambient: tuple[float, ...] | None = top.vec("ambient_light", 3, d.ambient_light)
    if ambient is not None and any(c < 0 or c > 1 for c in ambient):
        raise top.error("ambient_light", f"each colour component must be within [0, 1], got {list(ambient)}")

    wireless = read_wireless(top.section("wireless")) if top.has("wireless") else d.wireless
    variation = read_variation(top.section("variation"), names) if top.has("variation") else d.variation

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
        ambient_light=None if ambient is None else as_vec3(ambient),
        wireless=wireless,
        elements=elements,
        landmarks=landmarks,
        variation=variation,
    )


def _geo_reference(g: Section) -> GeoReference:
    """The ``geo_reference`` section: the origin as latitude and longitude, or in UTM."""
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
    return geo


def _victims(top: Section, names: set[str]) -> list[Victim]:
    victims: list[Victim] = []
    vd = FieldDefaults(Victim)
    for s in top.entries("victims"):
        vname = unique_name(s, names)
        sound = s.section("sound", {})  # sound.X fills sound_X
        victims.append(
            Victim(
                name=vname,
                location=as_vec3(s.vec("location")),
                rotation=as_vec3(s.vec("rotation", 3, vd.rotation)),
                posture=s.str("posture", vd.posture, choices=VICTIM_POSTURES),
                build=s.str("build", vd.build, choices=VICTIM_BUILDS),
                waving=s.bool("waving", vd.waving),
                sound_loudness_db=sound.float("loudness_db", vd.sound_loudness_db, min=0.0, max=200.0),
                sound_period_s=sound.float("period_s", vd.sound_period_s, min=0.1),
                sound_duration_s=sound.float("duration_s", vd.sound_duration_s, min=0.01),
            )
        )
        sound.finish()
    return victims


def _false_alarms(top: Section, names: set[str], materials: dict[str, Any]) -> list[FalseAlarm]:
    alarms: list[FalseAlarm] = []
    fd = FieldDefaults(FalseAlarm)
    for s in top.entries("false_alarms"):
        aname = unique_name(s, names)
        material = s.str("material", fd.material)
        check_material(s, "material", material, materials)
        alarms.append(
            FalseAlarm(
                name=aname,
                center=as_vec3(s.vec("center")),
                size=as_vec3(s.vec("size", 3, positive=True)),
                rotation=as_vec3(s.vec("rotation", 3, fd.rotation)),
                part=s.str("part", fd.part, choices=VICTIM_PARTS),
                material=material,
                temperature_c=s.float("temperature_c", fd.temperature_c, min=-50.0, max=500.0),
            )
        )
    return alarms


def _rfid_tags(top: Section) -> list[RfidTagConfig]:
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
        tags.append(RfidTagConfig(tag_id=tid, location=as_vec3(s.vec("location")), memory=mem))
    return tags


def _water(top: Section, names: set[str]) -> list[WaterVolume]:
    water: list[WaterVolume] = []
    wd = FieldDefaults(WaterVolume)
    for s in top.entries("water"):
        wname = unique_name(s, names)
        water.append(
            WaterVolume(
                name=wname,
                center=as_vec3(s.vec("center")),
                size=as_vec3(s.vec("size", 3, positive=True)),
                density_kg_m3=s.float("density_kg_m3", wd.density_kg_m3, min=1.0, max=20000.0),
            )
        )
    return water


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
        poses.append(
            StartPose(
                name=pname, location=as_vec3(s.vec("location")), rotation=as_vec3(s.vec("rotation", 3, pd.rotation))
            )
        )
    return tuple(poses)


def read_wireless(s: Section) -> WirelessConfig:
    """The ``wireless`` section: ``model`` (a radio model's name: the built-in WIRELESS_MODELS or
    a plugin's, checked against the registry of usarsim.sim.radio when the server starts), the
    ini keys of WIRELESS_KEYS, ``cache_distance_m`` and the ``channel``
    (:func:`usarsim.config.channel.read_channel`)."""
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
    channel = read_channel(s.section("channel")) if s.has("channel") else None
    cfg = WirelessConfig(
        model=model,
        pd0_dbm=s.float("ePdo", d.pd0_dbm, min=-300.0, max=100.0),
        d0_m=d0,
        path_loss_exponent=n,
        cutoff_dbm=s.float("eCutoff", d.cutoff_dbm, min=-300.0, max=100.0),
        max_walls=max_obs,
        wall_db=waf,
        cache_distance_m=cache,
        channel=channel,
    )
    s.finish()
    return cfg


def _light(s: Section, name: str) -> Light:
    d = FieldDefaults(Light)
    ltype = s.str("type", d.type, choices=LIGHT_TYPES)

    def rgb(key: str, default: Vec3) -> Vec3:
        v = s.vec(key, 3, default)
        if any(c < 0 or c > 1 for c in v):
            raise s.error(key, f"each colour component must be within [0, 1], got {list(v)}")
        return as_vec3(v)

    direction = as_vec3(s.vec("direction", 3, d.direction))
    norm = math.sqrt(sum(c * c for c in direction))
    if norm < 1e-9:
        raise s.error("direction", f"the direction must not be zero, got {list(direction)}")
    position = as_vec3(s.vec("position", 3, d.position))
    attenuation = s.vec("attenuation", 3, d.attenuation)
    if any(c < 0 for c in attenuation) or not any(c > 0 for c in attenuation):
        raise s.error(
            "attenuation", f"[constant, linear, quadratic] must be >= 0 and not all 0, got {list(attenuation)}"
        )
    return Light(
        name=name,
        type=ltype,
        position=position,
        direction=as_vec3(tuple(c / norm for c in direction)),
        color=rgb("color", d.color),
        intensity=s.float("intensity", d.intensity, min=0.0, max=100.0),
        ambient=rgb("ambient", d.ambient),
        specular=rgb("specular", d.specular),
        attenuation=as_vec3(attenuation),
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
