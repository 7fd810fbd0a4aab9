"""The grid ray caster against the same kernel with every geom in one cell (no walk): the same distance, geom and
normal for every ray, in crowded scenes of every shape, with rays that start outside
the grid, run along its lines, through its corners or straight up and down; and the
grid is filed again when something moves."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from usarsim.sim import raycast
from usarsim.sim.raycaster import RayCaster

SHAPES = ("box", "cylinder", "sphere", "capsule", "ellipsoid")


def crowded_scene(seed: int, n: int = 120, spread: float = 6.0) -> str:
    """Robot-like free bodies and static shapes of every kind, some touching and overlapping."""
    rng = np.random.default_rng(seed)
    parts = [
        '<geom name="floor" type="plane" size="0 0 1"/>',
        '<geom name="wall" type="box" size="8 0.1 1" pos="0 6.5 1"/>',
    ]
    for i in range(n):
        shape = SHAPES[i % len(SHAPES)]
        size = " ".join(f"{v:.3f}" for v in rng.uniform(0.05, 0.6, 3))
        pos = f"{rng.uniform(-spread, spread):.3f} {rng.uniform(-spread, spread):.3f} {rng.uniform(0, 1.5):.3f}"
        euler = " ".join(f"{v:.1f}" for v in rng.uniform(-90, 90, 3))
        geom = f'<geom type="{shape}" size="{size}" euler="{euler}"/>'
        if i % 3 == 0:
            parts.append(f'<body pos="{pos}"><freejoint/>{geom}</body>')
        else:
            parts.append(geom.replace("<geom ", f'<geom pos="{pos}" '))
    # two boxes with a face in common: hits at the very same distance
    parts.append('<geom name="twinA" type="box" size="0.5 0.5 0.5" pos="9 0 0.5"/>')
    parts.append('<geom name="twinB" type="box" size="0.5 0.5 0.5" pos="9 0 0.5"/>')
    return f"<mujoco><worldbody>{''.join(parts)}</worldbody></mujoco>"


def exhaustive(c: RayCaster, orig, dirs, cutoff, exclude=-1):
    """Every ray tested against every geom: the kernel with one cell that holds them all."""
    n = len(dirs)
    dist, gid, nrm = np.empty(n), np.empty(n, np.int32), np.zeros((n, 3))
    planes = np.flatnonzero(c._visible & (c._gtype == raycast.PLANE))
    others = np.flatnonzero(c._visible & (c._gtype != raycast.PLANE))
    one_cell = (
        -1e9,
        -1e9,
        2e9,
        1,
        1,
        np.array([0, len(others)]),
        others.astype(np.int64),
        planes.astype(np.int64),
        -1e9,
        1e9,
    )
    raycast.cast_grid_kernel(
        orig,
        dirs,
        cutoff,
        c._gtype,
        c.m.geom_size,
        c.m.geom_rbound,
        c._gbody,
        c._visible,
        c.d.geom_xpos,
        c.d.geom_xmat,
        exclude,
        True,
        dist,
        gid,
        nrm,
        *one_cell,
    )
    return dist, gid, nrm


def awkward_rays(rng, n):
    """Random rays, and rays along the grid's lines, through its corners, vertical, from far outside."""
    orig = rng.uniform(-12, 12, (n, 3))
    orig[:, 2] = rng.uniform(-0.5, 2.5, n)
    dirs = rng.normal(size=(n, 3))
    k = n // 6
    dirs[:k, 2] = 0.0  # level, like lasers and sonars
    dirs[k : 2 * k, 1:] = 0.0  # along x
    dirs[2 * k : 3 * k, [0, 2]] = 0.0  # along y
    dirs[3 * k : 4 * k, :2] = 0.0  # straight up or down
    orig[4 * k : 5 * k, :2] = np.round(orig[4 * k : 5 * k, :2])  # from grid corners (cells of 1 m at whole metres)
    dirs[4 * k : 5 * k] = [1.0, 1.0, 0.0]
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    return np.ascontiguousarray(orig), np.ascontiguousarray(dirs)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_grid_gives_the_exhaustive_kernels_hits(seed):
    m = mujoco.MjModel.from_xml_string(crowded_scene(seed))
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    c = RayCaster(m, d, "compiled")
    rng = np.random.default_rng(seed)
    orig, dirs = awkward_rays(rng, 6000)
    for cutoff in (1.0, 5.0, 30.0):
        got_d, got_n, got_g = c.cast_from(orig, dirs, cutoff, -1, normals=True)
        want_d, want_g, want_n = exhaustive(c, orig, dirs, cutoff)
        np.testing.assert_array_equal(got_g, want_g)
        np.testing.assert_array_equal(got_d, want_d)
        np.testing.assert_array_equal(got_n, want_n)
        if cutoff == 30.0:
            assert np.isfinite(got_d).sum() > 1500  # a third of the rays hit something
    # exact ties between two coincident boxes go to the lower id, as in the exhaustive kernel
    o = np.array([[12.0, 0.0, 0.5]])
    v = np.array([[-1.0, 0.0, 0.0]])
    _, _, g = c.cast_from(o, v, 10.0, -1)
    assert g[0] == m.geom("twinA").id


def test_the_grid_is_filed_again_when_something_moves():
    m = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><geom type="plane" size="0 0 1"/>'
        '<body name="b" pos="3 0 0.5"><freejoint/><geom type="box" size="0.2 0.2 0.2"/></body>'
        '<geom type="box" size="0.2 0.2 0.2" pos="-5 -5 0.5"/></worldbody></mujoco>'
    )
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    c = RayCaster(m, d, "compiled")
    level = np.array([[1.0, 0.0, 0.0]])
    at = np.array([0.0, 0.0, 0.5])
    assert c.cast(at, level, 20.0, -1)[0][0] == pytest.approx(2.8)
    builds = c.grid_builds
    c.cast(at, level, 20.0, -1)
    assert c.grid_builds == builds  # nothing moved: the same grid
    # moved at the same instant (a robot put somewhere else): filed again
    d.qpos[0] = 7.0
    mujoco.mj_forward(m, d)
    assert c.cast(at, level, 20.0, -1)[0][0] == pytest.approx(6.8)
    assert c.grid_builds == builds + 1
    # moved by a step of time
    d.qvel[0] = -100.0
    mujoco.mj_step(m, d)
    mujoco.mj_forward(m, d)
    want = exhaustive(c, at[None, :].copy(), level, 20.0)[0][0]
    assert c.cast(at, level, 20.0, -1)[0][0] == want


def test_a_ray_from_inside_a_body_far_outside_the_grid_and_only_planes():
    m = mujoco.MjModel.from_xml_string('<mujoco><worldbody><geom type="plane" size="0 0 1"/></worldbody></mujoco>')
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    c = RayCaster(m, d, "compiled")
    dist, _, g = c.cast(np.array([100.0, -40.0, 2.0]), np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0]]), 10.0, -1)
    assert dist[0] == pytest.approx(2.0) and g[0] == 0
    assert np.isinf(dist[1])


def test_a_turned_mocap_body_is_filed_again():
    """A waving victim's arm is a mocap body turned at the same instant: its geom moves."""
    m = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><body name="arm" mocap="true" pos="0 0 0.5">'
        '<geom type="box" size="0.1 0.1 0.1" pos="2 0 0"/></body></worldbody></mujoco>'
    )
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    c = RayCaster(m, d, "compiled")
    at = np.array([0.0, 0.0, 0.5])
    along_x, along_y = np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]])
    assert c.cast(at, along_x, 5.0, -1)[0][0] == pytest.approx(1.9)
    assert np.isinf(c.cast(at, along_y, 5.0, -1)[0][0])
    d.mocap_quat[0] = [np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)]  # a quarter turn about z
    mujoco.mj_forward(m, d)
    assert c.cast(at, along_y, 5.0, -1)[0][0] == pytest.approx(1.9)
    assert np.isinf(c.cast(at, along_x, 5.0, -1)[0][0])
