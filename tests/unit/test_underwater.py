"""The picture of a camera under water (usarsim.sim.underwater), pixel by pixel, without a
renderer: what is near keeps its colour, what is far is the water's, the water near the
surface is brighter than the water below, and the surface seen from below lets the sky through
within Snell's window and mirrors the water beyond it."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from usarsim.sim import underwater as uw

NEAR, FAR = 0.02, 5000.0
WATER = np.array([52.0, 99.0, 56.0])


def camera(forward, up=(0.0, 0.0, 1.0), pos=(0.0, 0.0, -2.0), half_height=0.004):
    """An OpenGL camera as MuJoCo's scene holds it (a narrow view: its pixels look almost
    along ``forward``)."""
    return SimpleNamespace(
        pos=np.array(pos, float),
        forward=np.array(forward, float),
        up=np.array(up, float),
        frustum_center=0.0,
        frustum_width=0.0,
        frustum_bottom=-half_height * NEAR,
        frustum_top=half_height * NEAR,
        frustum_near=NEAR,
        frustum_far=FAR,
    )


def raw_depth(glcam, distance, width=4, height=4) -> np.ndarray:
    """The depth buffer (reverse Z) of a picture whose every pixel shows something ``distance``
    metres away along its ray."""
    _, length = uw.rays(glcam, width, height)
    along = distance / length
    n, f = NEAR, FAR
    c = -0.5 * (-(f + n) / (f - n)) - 0.5
    d = -0.5 * (-(2 * f * n) / (f - n))
    return (d / along - c).astype(np.float32)


# a basin 40 m square, 3.5 m deep, the surface at z = 0
BASIN = uw.WaterBox(lo=np.array([-20.0, -20.0, -3.5]), hi=np.array([20.0, 20.0, 0.0]))


def seen(colour, distance, glcam) -> np.ndarray:
    rgb = np.full((4, 4, 3), colour, dtype=np.uint8)
    return uw.through_water(rgb, raw_depth(glcam, distance), glcam, BASIN, WATER).reshape(-1, 3).mean(axis=0)


def test_near_things_keep_their_colour_and_far_ones_take_the_waters():
    level = camera((1.0, 0.0, 0.0))
    red = (200, 40, 40)
    assert np.allclose(seen(red, 0.03, level), red, atol=2)
    assert np.allclose(seen(red, 60.0, level), WATER, atol=2)
    # in between, each channel fades as exp(-K t) (a level ray: the light is the same all along)
    kept = (seen(red, 2.0, level) - WATER) / (np.array(red) - WATER)
    assert np.allclose(kept, np.exp(-uw.ATTENUATION_PER_M * 2.0), atol=0.02)


def test_the_water_is_brighter_looking_up_than_looking_down():
    up = seen((0, 0, 0), 1.9, camera((math.cos(0.5), 0.0, math.sin(0.5)), up=(-math.sin(0.5), 0.0, math.cos(0.5))))
    down = seen((0, 0, 0), 1.9, camera((math.cos(0.5), 0.0, -math.sin(0.5)), up=(math.sin(0.5), 0.0, math.cos(0.5))))
    assert up.mean() > 1.15 * down.mean(), (up, down)


def test_the_surface_lets_the_sky_through_above_and_mirrors_the_water_at_a_slant():
    sky = (150, 190, 240)
    straight_up = camera((0.0, 0.0, 1.0), up=(1.0, 0.0, 0.0))
    # the sky (drawn far away) through the 2 m of water above: not dimmed (the picture is
    # balanced for the daylight that came down the same way), and the water's own light added
    through = seen(sky, 4000.0, straight_up)
    assert np.all(through >= np.array(sky) - 1) and np.all(through <= np.minimum(np.array(sky) + WATER, 255)), through
    # 60 degrees from the vertical, past the critical angle (48.6 degrees): a mirror of the water
    slant = math.radians(60.0)
    beyond = camera((math.sin(slant), 0.0, math.cos(slant)), up=(-math.cos(slant), 0.0, math.sin(slant)))
    mirrored = seen(sky, 4000.0, beyond)
    assert mirrored[2] < mirrored[1] and abs(mirrored - WATER).max() < 0.4 * WATER.max(), mirrored


def test_fresnel_reflectance_of_the_surface_from_below():
    normal = uw.fresnel_reflectance(np.array([1.0]))[0]
    assert normal == pytest.approx(((1.333 - 1.0) / (1.333 + 1.0)) ** 2, rel=1e-3)
    critical = math.asin(1.0 / uw.WATER_INDEX)  # 48.6 degrees
    assert math.degrees(critical) == pytest.approx(48.6, abs=0.1)
    inside, outside = np.cos([critical - 0.05, critical + 0.01])
    assert uw.fresnel_reflectance(np.array([inside]))[0] < 0.5
    assert uw.fresnel_reflectance(np.array([outside]))[0] == 1.0


def test_a_camera_finds_the_water_it_is_in():
    water = uw.Water(boxes=(BASIN,), colour=WATER)
    assert water.around((0.0, 0.0, -1.0)) is BASIN
    assert water.around((0.0, 0.0, 0.5)) is None  # above the surface
    assert water.around((30.0, 0.0, -1.0)) is None  # beside the basin
