"""The compiled ray caster against MuJoCo's own ``mj_multiRay``: same hits, same
distances, same surfaces, for every shape the worlds use, with invisible geoms,
excluded groups and the excluded body skipped."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from usarsim.sim.raycaster import RayCaster

SHAPES = """<mujoco><worldbody>
<geom name="floor" type="plane" size="3 3 0.1"/>
<geom name="deep" type="plane" size="0 0 1" pos="0 0 -1"/>
<geom name="box" type="box" size="0.3 0.2 0.4" pos="1 0.5 0.5" euler="10 20 30"/>
<geom name="cyl" type="cylinder" size="0.2 0.3" pos="-1 0.5 0.4" euler="40 0 10"/>
<geom name="ball" type="sphere" size="0.25" pos="0 -1 0.5"/>
<geom name="cap" type="capsule" size="0.1 0.3" pos="1 -1 0.5" euler="0 60 0"/>
<geom name="egg" type="ellipsoid" size="0.3 0.1 0.2" pos="-1 -1 0.5" euler="30 30 0"/>
<geom name="ghost" type="box" size="0.3 0.3 0.3" pos="0 1.5 0.3" rgba="1 1 1 0"/>
<geom name="hidden" type="box" size="0.3 0.3 0.3" pos="0 -2 0.3" group="4"/>
<body name="me" pos="0 0 1"><freejoint/><geom name="self" type="box" size="0.1 0.1 0.1"/></body>
</worldbody></mujoco>"""


@pytest.fixture(scope="module")
def scene():
    m = mujoco.MjModel.from_xml_string(SHAPES)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    return m, d


def random_rays(n, seed):
    rng = np.random.default_rng(seed)
    orig = rng.uniform(-1.5, 1.5, (n, 3))
    orig[:, 2] = rng.uniform(0.0, 1.2, n)
    dirs = rng.normal(size=(n, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    return orig, dirs


def test_compiled_caster_matches_mj_multiray(scene):
    m, d = scene
    fast, ref = RayCaster(m, d, "compiled"), RayCaster(m, d, "mujoco")
    assert fast.backend == "compiled"
    orig, dirs = random_rays(5000, 1)
    me = m.body("me").id
    da, na, ga = fast.cast_from(orig, dirs, 4.0, me, normals=True)
    db, nb, gb = ref.cast_from(orig, dirs, 4.0, me, normals=True)
    hit = np.isfinite(da)
    assert hit.sum() > 1000  # plenty of hits on every kind of shape
    assert set(m.geom_type[ga[hit]]) >= {0, 2, 3, 4, 5, 6}
    np.testing.assert_array_equal(hit, np.isfinite(db))
    np.testing.assert_array_equal(ga, gb)
    np.testing.assert_allclose(da[hit], db[hit], rtol=0, atol=1e-9)
    # the surface seen: same angle of incidence
    cos_a = np.abs(np.einsum("ij,ij->i", na[hit], dirs[hit]))
    cos_b = np.abs(np.einsum("ij,ij->i", nb[hit], dirs[hit]))
    np.testing.assert_allclose(cos_a, cos_b, atol=1e-9)


def test_invisible_hidden_and_own_geoms_are_not_seen(scene):
    m, d = scene
    caster = RayCaster(m, d, "compiled")
    me = m.body("me").id
    down = np.array([[0.0, 0.0, -1.0]])
    # straight down through the invisible box onto the floor
    dist, _, gid = caster.cast(np.array([0.0, 1.5, 1.0]), down, 10.0, me)
    assert m.geom(int(gid[0])).name == "floor" and dist[0] == pytest.approx(1.0)
    # the group-4 box is not seen either
    dist, _, gid = caster.cast(np.array([0.0, -2.0, 1.0]), down, 10.0, me)
    assert m.geom(int(gid[0])).name == "floor"
    # from inside our own body, the body is skipped; without exclusion it is hit
    dist, _, gid = caster.cast(np.array([0.0, 0.0, 1.0]), down, 10.0, me)
    assert m.geom(int(gid[0])).name == "floor" and dist[0] == pytest.approx(1.0)
    dist, _, gid = caster.cast(np.array([0.0, 0.0, 1.0]), down, 10.0, -1)
    assert m.geom(int(gid[0])).name == "self" and dist[0] == pytest.approx(0.1)


def test_cutoff_and_misses_read_infinity(scene):
    m, d = scene
    caster = RayCaster(m, d, "compiled")
    up = np.array([[0.0, 0.0, 1.0]])
    dist, _, gid = caster.cast(np.array([2.0, 2.0, 0.5]), up, 10.0, -1)
    assert np.isinf(dist[0]) and gid[0] == -1  # nothing above
    # the floor plane is seen from above only, and only within its size
    dist, _, _ = caster.cast(np.array([2.0, 2.0, 0.5]), -up, 0.4, -1)
    assert np.isinf(dist[0])  # 0.5 m away, cutoff 0.4 m
    dist, _, gid = caster.cast(np.array([5.0, 0.0, 0.5]), -up, 10.0, -1)
    assert m.geom(int(gid[0])).name == "deep"  # outside the 3 m floor: falls to the infinite plane


def test_a_world_with_a_mesh_falls_back_to_mujoco():
    xml = """<mujoco><asset><mesh name="t" vertex="0 0 0 1 0 0 0 1 0 0 0 1"/></asset>
    <worldbody><geom type="mesh" mesh="t" pos="0 0 0"/></worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    caster = RayCaster(m, d)
    assert caster.backend == "mujoco"
    dist, _, _ = caster.cast(np.array([0.2, 0.2, 2.0]), np.array([[0.0, 0.0, -1.0]]), 5.0, -1)
    assert 1.0 < dist[0] < 2.0
