"""The world-file format's arena features: ramps and stairs expanded into boxes, mesh
objects, mirror and grid materials, lights, and the geographic reference given in UTM;
each with the errors that name the file, the key path and what is allowed."""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from usarsim.config import world as W
from usarsim.config.world import GeoReference, UtmCoordinate, latlon_to_utm, utm_to_latlon
from usarsim.config.world_file import load_world
from usarsim.errors import ConfigError
from usarsim.sim import builder, frames
from usarsim.sim.entities import Entities

DATA = Path(__file__).resolve().parent.parent / "data"

HEAD = """\
name: Format
floor: {center: [0.0, 0.0], size: [20.0, 20.0]}
materials:
  wall: {rgba: [0.9, 0.8, 0.4, 1.0]}
  mirror: {mirror: true}
  fence: {porosity: 0.3}
start_poses:
  - {name: A, location: [0.0, 0.0, -0.2]}
"""


def world(tmp_path: Path, body: str, name: str = "w.yaml"):
    p = tmp_path / name
    p.write_text(HEAD + body)
    return load_world(p)


def error(tmp_path: Path, body: str) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        world(tmp_path, body)
    return info.value


def top_face_ends(o: W.StaticObject):
    """The two ends of a box's top face's centre line (USARSim frame): local -Z is up."""
    r = frames.euler_to_mat(*o.rotation)
    c = np.array(o.center)
    top = c - r[:, 2] * o.size[2] / 2.0
    return top - r[:, 0] * o.size[0] / 2.0, top + r[:, 0] * o.size[0] / 2.0


# --------------------------------------------------------------------------- ramps


@pytest.mark.parametrize("heading", [0.0, 0.6, -2.0])
def test_a_ramp_is_one_plate_from_its_foot_to_its_top_edge(tmp_path, heading):
    w = world(
        tmp_path,
        f"""\
objects:
  - {{name: r1, shape: ramp, foot: [1.0, 2.0, -0.1], heading: {heading}, length: 2.0, width: 1.5, rise: 0.4,
     material: wall}}
""",
    )
    (o,) = w.objects
    assert (o.name, o.shape, o.material, o.part_of) == ("r1", "box", "wall", "r1")
    assert o.size[1] == 1.5 and o.size[2] == 0.05  # width, default thickness
    low, high = top_face_ends(o)
    u = np.array([math.cos(heading), math.sin(heading), 0.0])
    # the top edge: 2 m of run along the heading and 0.4 m up (Z down) from the foot
    np.testing.assert_allclose(high, np.array([1.0, 2.0, -0.1]) + 2.0 * u + [0, 0, -0.4], atol=1e-12)
    # the top face passes through the foot and ends RAMP_FOOT_SINK_M below the surface
    assert low[2] == pytest.approx(-0.1 + W.RAMP_FOOT_SINK_M, abs=1e-12)
    foot_side = np.array([1.0, 2.0, -0.1]) - low
    assert np.linalg.norm(np.cross(foot_side, high - low)) == pytest.approx(0.0, abs=1e-12)
    assert o.rotation[1] == pytest.approx(math.atan2(0.4, 2.0))  # pitched up by the slope


def test_a_ramp_can_be_thick(tmp_path):
    w = world(
        tmp_path,
        """\
objects:
  - {name: r1, shape: ramp, foot: [0.0, 0.0, 0.0], length: 1.0, width: 1.0, rise: 0.2, thickness: 0.2}
""",
    )
    (o,) = w.objects
    assert o.size[2] == 0.2
    _, high = top_face_ends(o)
    np.testing.assert_allclose(high, [1.0, 0.0, -0.2], atol=1e-12)


@pytest.mark.parametrize(
    "fields, key, words",
    [
        ("length: 1.0, width: 1.0, rise: 2.0", "objects[0].rise", ["63.4 degrees", "below 60 degrees"]),
        ("length: 0.0, width: 1.0, rise: 0.2", "objects[0].length", ["must be > 0.0"]),
        ("length: 1.0, width: -1.0, rise: 0.2", "objects[0].width", ["must be > 0.0"]),
        ("length: 1.0, width: 1.0, rise: 0.2, thickness: 0", "objects[0].thickness", ["must be > 0.0"]),
        ("length: 1.0, width: 1.0", "objects[0].rise", ["required key is missing"]),
        ("length: 1.0, width: 1.0, rise: 0.2, center: [0, 0, 0]", "objects[0].center", ["unknown key 'center'"]),
        ("length: 1.0, width: 1.0, rise: 0.2, mass_kg: 3", "objects[0].mass_kg", ["unknown key 'mass_kg'"]),
        ("length: 1.0, width: 1.0, rise: 0.2, heading: east", "objects[0].heading", ["expected a number"]),
    ],
)
def test_ramp_errors_name_the_key_and_what_is_allowed(tmp_path, fields, key, words):
    err = error(tmp_path, f"objects:\n  - {{name: r1, shape: ramp, foot: [0.0, 0.0, 0.0], {fields}}}\n")
    assert err.key == key and str(tmp_path / "w.yaml") in str(err)
    for w in words:
        assert w in str(err)


# --------------------------------------------------------------------------- stairs


def test_stairs_are_one_solid_box_per_step(tmp_path):
    w = world(
        tmp_path,
        """\
objects:
  - {name: st, shape: stairs, foot: [1.0, 0.0, 0.0], heading: 1.5707963267948966, width: 1.2, steps: 3,
     step_rise: 0.2, step_run: 0.3, material: wall}
""",
    )
    assert [o.name for o in w.objects] == ["st/step1", "st/step2", "st/step3"]
    for k, o in enumerate(w.objects, start=1):
        assert o.shape == "box" and o.material == "wall" and o.part_of == "st"
        assert o.size == pytest.approx((0.3, 1.2, 0.2 * k))
        # along +Y (heading 90 degrees), from the foot; solid down to the surface (z = 0)
        assert o.center == pytest.approx((1.0, (k - 0.5) * 0.3, -0.1 * k))
        assert o.center[2] + o.size[2] / 2 == pytest.approx(0.0)


@pytest.mark.parametrize(
    "fields, key, words",
    [
        ("steps: 0, step_rise: 0.2, step_run: 0.3", "objects[0].steps", ["must be >= 1"]),
        ("steps: 2.5, step_rise: 0.2, step_run: 0.3", "objects[0].steps", ["expected an integer"]),
        ("steps: 3, step_rise: 0.6, step_run: 0.3", "objects[0].step_rise", ["63.4 degrees", "below 60 degrees"]),
        ("steps: 3, step_rise: 0.2, step_run: 0", "objects[0].step_run", ["must be > 0.0"]),
        ("steps: 3, step_rise: 0.2, step_run: 0.3, rise: 0.2", "objects[0].rise", ["did you mean 'step_rise'"]),
    ],
)
def test_stairs_errors_name_the_key_and_what_is_allowed(tmp_path, fields, key, words):
    err = error(tmp_path, f"objects:\n  - {{name: st, shape: stairs, foot: [0, 0, 0], width: 1.0, {fields}}}\n")
    assert err.key == key
    for w in words:
        assert w in str(err)


def test_a_step_name_must_not_clash(tmp_path):
    err = error(
        tmp_path,
        """\
objects:
  - {name: st/step2, shape: box, center: [5, 5, -0.5], size: [1, 1, 1]}
  - {name: st, shape: stairs, foot: [0, 0, 0], width: 1.0, steps: 3, step_rise: 0.2, step_run: 0.3}
""",
    )
    assert err.key == "objects[1].name" and "st/step2" in str(err)


def test_the_shape_error_lists_the_new_shapes(tmp_path):
    err = error(tmp_path, "objects:\n  - {name: x, shape: ramps, center: [0, 0, 0]}\n")
    assert err.key == "objects[0].shape" and "did you mean 'ramp'" in str(err)
    allowed = str(err).split("allowed:", 1)[1]
    for shape in ("box", "cylinder", "mesh", "ramp", "stairs"):
        assert shape in allowed


# --------------------------------------------------------------------------- meshes


def test_a_mesh_object_reads_its_file_relative_to_the_world(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "wedge.obj").write_bytes((DATA / "wedge.obj").read_bytes())
    w = world(
        tmp_path,
        """\
objects:
  - {name: m, shape: mesh, file: parts/wedge.obj, center: [2.0, 0.0, 0.0], rotation: [0, 0, 1.0],
     scale: [2.0, 1.0, 0.5], material: wall, mass_kg: 4.0}
  - {name: n, shape: mesh, file: parts/wedge.obj, center: [4.0, 0.0, 0.0]}
""",
    )
    m, n = w.objects
    assert m.mesh_file == str((tmp_path / "parts" / "wedge.obj").resolve())
    assert (m.shape, m.scale, m.mass_kg, m.rotation) == ("mesh", (2.0, 1.0, 0.5), 4.0, (0.0, 0.0, 1.0))
    assert n.scale == (1.0, 1.0, 1.0) and n.mass_kg == 0.0
    model = builder.world_spec(w).compile()
    assert model.geom("world/n").type == mujoco.mjtGeom.mjGEOM_MESH
    assert model.body("movable/m").id > 0  # a movable mesh: a free body of its own
    d = mujoco.MjData(model)
    mujoco.mj_forward(model, d)
    # the static wedge's vertical back face (0.5 m tall, USARSim z 0..-0.5) at x = 3.5
    geom = np.array([-1], np.int32)
    dist = mujoco.mj_ray(model, d, np.array([0.0, 0.0, 0.3]), np.array([1.0, 0.0, 0.0]), None, 1, -1, geom)
    assert dist == pytest.approx(3.5) and geom[0] == model.geom("world/n").id


def test_a_binary_stl_mesh_loads(tmp_path):
    # the wedge's 8 triangles written as binary STL (80-byte header, count, 50 bytes each)
    verts = [
        tuple(map(float, ln.split()[1:])) for ln in (DATA / "wedge.obj").read_text().splitlines() if ln.startswith("v ")
    ]
    faces = [
        tuple(int(i) - 1 for i in ln.split()[1:])
        for ln in (DATA / "wedge.obj").read_text().splitlines()
        if ln.startswith("f ")
    ]
    out = bytearray(b"wedge".ljust(80, b" ")) + len(faces).to_bytes(4, "little")
    for f in faces:
        out += np.zeros(3, "<f4").tobytes() + np.array([verts[i] for i in f], "<f4").tobytes() + b"\0\0"
    (tmp_path / "wedge.stl").write_bytes(bytes(out))
    w = world(tmp_path, "objects:\n  - {name: s, shape: mesh, file: wedge.stl, center: [2, 0, 0]}\n")
    model = builder.world_spec(w).compile()
    assert model.geom("world/s").type == mujoco.mjtGeom.mjGEOM_MESH


@pytest.mark.parametrize(
    "file, words",
    [
        ("nowhere.obj", ["mesh file 'nowhere.obj' not found", "relative to the world file"]),
        ("wedge.ply", ["not a mesh file MuJoCo reads", ".obj, .stl"]),
        ("ascii.stl", ["not a binary STL file"]),
    ],
)
def test_mesh_file_errors(tmp_path, file, words):
    (tmp_path / "wedge.ply").write_text("ply\n")
    (tmp_path / "ascii.stl").write_text("solid x\nendsolid x\n")
    err = error(tmp_path, f"objects:\n  - {{name: m, shape: mesh, file: {file}, center: [0, 0, 0]}}\n")
    assert err.key == "objects[0].file"
    for w in words:
        assert w in str(err)


def test_mesh_scale_must_be_positive(tmp_path):
    (tmp_path / "wedge.obj").write_bytes((DATA / "wedge.obj").read_bytes())
    err = error(
        tmp_path, "objects:\n  - {name: m, shape: mesh, file: wedge.obj, center: [0, 0, 0], scale: [1, 0, 1]}\n"
    )
    assert err.key == "objects[0].scale" and "> 0" in str(err)


# --------------------------------------------------------------------------- mirrors and grids


def test_mirror_and_porosity_materials(tmp_path):
    w = world(
        tmp_path,
        """\
objects:
  - {name: m, shape: box, center: [2, 0, -0.5], size: [0.02, 1, 1], material: mirror}
  - {name: g, shape: cylinder, center: [4, 0, -0.5], radius: 0.5, length: 1, material: fence}
  - {name: st, shape: stairs, foot: [6, 0, 0], width: 1.0, steps: 2, step_rise: 0.2, step_run: 0.3, material: mirror}
""",
    )
    assert w.materials["mirror"].mirror and w.materials["mirror"].porosity == 0.0
    assert w.materials["fence"].porosity == 0.3 and not w.materials["fence"].mirror
    assert not w.materials["default"].mirror and w.materials["default"].porosity == 0.0
    # the ray caster gets them with the see-through masks
    m = builder.world_spec(w).compile()
    ents = Entities(w)
    ents.resolve(m)
    mirror, porosity = ents.see_through["mirror"], ents.see_through["porosity"]
    assert {m.geom(g).name for g in np.flatnonzero(mirror)} == {"world/m", "world/st/step1", "world/st/step2"}
    assert porosity[m.geom("world/g").id] == 0.3 and porosity.sum() == pytest.approx(0.3)


def test_a_world_without_effects_gives_the_caster_none(tmp_path):
    w = world(tmp_path, "objects:\n  - {name: b, shape: box, center: [2, 0, -0.5], size: [1, 1, 1]}\n")
    ents = Entities(w)
    ents.resolve(builder.world_spec(w).compile())
    assert "mirror" not in ents.see_through and "porosity" not in ents.see_through


@pytest.mark.parametrize(
    "body, key, words",
    [
        (
            "objects:\n  - {name: c, shape: cylinder, center: [0, 0, 0], radius: 1, length: 1, material: mirror}\n",
            "objects[0].material",
            ["is a mirror", "only box objects", "cylinder"],
        ),
        ("materials:\n  glassy: {porosity: 1.5}\n", "materials.glassy.porosity", ["must be <= 1.0"]),
        ("materials:\n  glassy: {porosity: -0.1}\n", "materials.glassy.porosity", ["must be >= 0.0"]),
        ("materials:\n  glassy: {mirror: true, porosity: 0.5}\n", "materials.glassy.porosity", ["cannot be porous"]),
        ("materials:\n  glassy: {mirror: yes please}\n", "materials.glassy.mirror", ["expected true or false"]),
        ("materials:\n  glassy: {mirrors: true}\n", "materials.glassy.mirrors", ["did you mean 'mirror'"]),
    ],
)
def test_material_effect_errors(tmp_path, body, key, words):
    text = HEAD + body
    if body.startswith("materials:"):
        text = HEAD.replace("materials:\n", body)
    p = tmp_path / "w.yaml"
    p.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_world(p)
    assert info.value.key == key
    for w in words:
        assert w in str(info.value)


def test_a_mirror_floor_is_refused(tmp_path):
    p = tmp_path / "w.yaml"
    p.write_text(HEAD.replace("size: [20.0, 20.0]}", "size: [20.0, 20.0], material: mirror}"))
    with pytest.raises(ConfigError) as info:
        load_world(p)
    assert info.value.key == "floor.material" and "plane" in str(info.value)


# --------------------------------------------------------------------------- lights


def test_lights_with_their_defaults(tmp_path):
    w = world(
        tmp_path,
        """\
ambient_light: [0.2, 0.2, 0.25]
lights:
  - {name: a}
  - {name: b, type: point, position: [1, 2, -3], color: [1, 0.5, 0], intensity: 2}
  - {name: c, type: directional, direction: [0, 3, 4], cast_shadows: false}
""",
    )
    a, b, c = w.lights
    assert (a.type, a.position, a.direction, a.cast_shadows, a.cutoff_deg) == (
        "spot",
        (0.0, 0.0, -3.0),
        (0.0, 0.0, 1.0),
        True,
        45.0,
    )
    assert b.type == "point" and not b.cast_shadows and b.intensity == 2.0
    assert c.direction == pytest.approx((0.0, 0.6, 0.8))  # made a unit vector
    m = builder.world_spec(w).compile()
    assert m.nlight == 3
    np.testing.assert_allclose(m.light_diffuse[m.light("light/b").id], [2.0, 1.0, 0.0])  # colour x intensity
    np.testing.assert_allclose(m.light_pos[m.light("light/b").id], [1.0, -2.0, 3.0])
    assert m.light_cutoff[m.light("light/b").id] == 180.0  # all around
    np.testing.assert_allclose(m.vis.headlight.ambient, [0.2, 0.2, 0.25], atol=1e-6)


@pytest.mark.parametrize(
    "light, key, words",
    [
        ("{name: a, type: neon}", "lights[0].type", ["'neon' is not allowed", "directional, point, spot"]),
        ("{name: a, direction: [0, 0, 0]}", "lights[0].direction", ["must not be zero"]),
        ("{name: a, color: [1, 2, 0]}", "lights[0].color", ["within [0, 1]"]),
        ("{name: a, cutoff_deg: 120}", "lights[0].cutoff_deg", ["must be <= 90.0"]),
        ("{name: a, attenuation: [0, 0, 0]}", "lights[0].attenuation", ["not all 0"]),
        ("{name: a, colour: [1, 1, 1]}", "lights[0].colour", ["did you mean 'color'"]),
        ("{type: spot}", "lights[0].name", ["required key is missing"]),
    ],
)
def test_light_errors(tmp_path, light, key, words):
    err = error(tmp_path, f"lights:\n  - {light}\n")
    assert err.key == key
    for w in words:
        assert w in str(err)


def test_duplicate_light_names(tmp_path):
    err = error(tmp_path, "lights:\n  - {name: a}\n  - {name: a}\n")
    assert err.key == "lights[1].name" and "duplicate light name 'a'" in str(err)


# --------------------------------------------------------------------------- UTM

# Reference values from PROJ's transverse Mercator (EPSG:32618 and EPSG:32756, WGS84 UTM
# zones 18N and 56S).
NIST = (39.0 + 8.0273 / 60.0, -(77.0 + 12.998 / 60.0))  # USARSim's ZeroZeroLocation
NIST_UTM = (308410.0013, 4333963.0639)  # zone 18, band S
SYDNEY = (-33.8688, 151.2093)
SYDNEY_UTM = (334368.6336, 6250948.3454)  # zone 56, band H


def test_the_forward_transform_of_known_points():
    u = latlon_to_utm(*NIST)
    assert (u.zone, u.letter) == (18, "S")
    assert u.easting_m == pytest.approx(NIST_UTM[0], abs=0.005)
    assert u.northing_m == pytest.approx(NIST_UTM[1], abs=0.005)
    s = latlon_to_utm(*SYDNEY)
    assert (s.zone, s.letter) == (56, "H")
    assert s.easting_m == pytest.approx(SYDNEY_UTM[0], abs=0.005)
    assert s.northing_m == pytest.approx(SYDNEY_UTM[1], abs=0.005)


def test_the_inverse_transform_of_known_points():
    lat, lon = utm_to_latlon(UtmCoordinate(easting_m=NIST_UTM[0], northing_m=NIST_UTM[1], zone=18, letter="S"))
    assert lat == pytest.approx(NIST[0], abs=1e-7) and lon == pytest.approx(NIST[1], abs=1e-7)
    lat, lon = utm_to_latlon(UtmCoordinate(easting_m=SYDNEY_UTM[0], northing_m=SYDNEY_UTM[1], zone=56, letter="H"))
    assert lat == pytest.approx(SYDNEY[0], abs=1e-7) and lon == pytest.approx(SYDNEY[1], abs=1e-7)


@pytest.mark.parametrize("lat, lon", [NIST, SYDNEY, (0.5, 3.1), (-45.0, -70.4), (71.0, 25.0), (60.0, 5.9)])
def test_utm_round_trip(lat, lon):
    back = utm_to_latlon(latlon_to_utm(lat, lon))
    assert back[0] == pytest.approx(lat, abs=1e-6) and back[1] == pytest.approx(lon, abs=1e-6)


def test_a_world_origin_given_in_utm(tmp_path):
    w = world(
        tmp_path,
        f"""\
geo_reference:
  utm: {{easting: {NIST_UTM[0]}, northing: {NIST_UTM[1]}, zone: 18, letter: S}}
""",
    )
    default = GeoReference()
    assert w.geo.latitude_deg == pytest.approx(default.latitude_deg, abs=1e-6)
    assert w.geo.longitude_deg == pytest.approx(default.longitude_deg, abs=1e-6)
    assert (w.geo.scale_latitude_m, w.geo.scale_longitude_m) == (111200.0, 71670.0)
    assert w.geo.utm == UtmCoordinate(easting_m=NIST_UTM[0], northing_m=NIST_UTM[1], zone=18, letter="S")
    # the GPS reads the origin's coordinate there
    from usarsim.sensors.gps import degrees_minutes, world_to_geographic

    lat, lon = world_to_geographic(0.0, 0.0, w.geo)
    assert degrees_minutes(lat, "N", "S") == (39, pytest.approx(8.0273, abs=1e-4), "N")
    assert degrees_minutes(lon, "E", "W") == (77, pytest.approx(12.998, abs=1e-4), "W")


def test_a_southern_utm_origin(tmp_path):
    w = world(
        tmp_path,
        f"""\
geo_reference:
  utm: {{easting: {SYDNEY_UTM[0]}, northing: {SYDNEY_UTM[1]}, zone: 56, letter: h}}
  scale_longitude_m: 92500
""",
    )
    assert w.geo.latitude_deg == pytest.approx(SYDNEY[0], abs=1e-6)
    assert w.geo.longitude_deg == pytest.approx(SYDNEY[1], abs=1e-6)
    assert w.geo.scale_longitude_m == 92500.0 and w.geo.utm.letter == "H"


@pytest.mark.parametrize(
    "geo, key, words",
    [
        (
            "{latitude_deg: 39.0, utm: {easting: 308410, northing: 4333963, zone: 18, letter: S}}",
            "geo_reference.latitude_deg",
            ["either as latitude_deg/longitude_deg or as utm"],
        ),
        (
            "{utm: {easting: 308410, northing: 4333963, zone: 61, letter: S}}",
            "geo_reference.utm.zone",
            ["zones are 1 to 60"],
        ),
        (
            "{utm: {easting: 308410, northing: 4333963, zone: 18, letter: I}}",
            "geo_reference.utm.letter",
            ["not a UTM latitude band", "C D E F G H J K L M N P Q R S T U V W X"],
        ),
        (
            "{utm: {easting: 308410, northing: 4333963, zone: 18, letter: T}}",
            "geo_reference.utm",
            ["outside band T", "40 to 48 degrees"],
        ),
        (
            "{utm: {easting: 50000, northing: 4333963, zone: 18, letter: S}}",
            "geo_reference.utm.easting",
            ["must be >= 100000.0"],
        ),
        (
            "{utm: {easting: 308410, northing: 4333963, zone: 18}}",
            "geo_reference.utm.letter",
            ["required key is missing"],
        ),
        (
            "{utm: {easting: 308410, northing: 4333963, zone: 18, letter: S, datum: NAD27}}",
            "geo_reference.utm.datum",
            ["unknown key 'datum'"],
        ),
    ],
)
def test_utm_errors(tmp_path, geo, key, words):
    err = error(tmp_path, f"geo_reference: {geo}\n")
    assert err.key == key
    for w in words:
        assert w in str(err)
