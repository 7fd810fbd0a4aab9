"""What a camera under water sees: its picture, rendered as in air with its depth, made over
for the water between the camera and what each pixel shows.

The model is the single-scattering picture of a camera in natural water (the form of
Koschmieder's law for haze, as used for water by Akkaynak and Treibitz, "A Revised Underwater
Image Formation Model", CVPR 2018): along a pixel's ray, what lies at distance ``t`` is dimmed
as ``exp(-K t)`` and the water in between adds light of its own, the veiling light, scattered
towards the camera from the daylight that reaches it.  Daylight fades with depth as
``exp(-K depth)`` (K: the diffuse attenuation coefficient of downward irradiance), so the
water near the surface is brighter than the water below; a picture is balanced for the light
at the camera's depth (as a camera's automatic exposure and white balance would be), so that
what is near the camera keeps its colours at any depth.  With one coefficient K per colour
channel for both the beam and the daylight, a ray going up at ``mu`` (the sine of its
elevation; negative looking down) shows

    C = X exp(-a t) + W K (1 - exp(-a t)) / a,        a = K (1 - mu),

where ``W`` is the colour of an endless horizontal stretch of water at the camera's depth and
``X`` what ends the ray: a thing in the water (its colour as rendered in air), or the water's
surface seen from below, or what lies beyond a side of the water volume where no wall closes it.
The surface from below (Fresnel's equations, water to air) passes what is above (the sky, the
quays: the picture rendered in air) within Snell's window, where a ray's incidence is below the
critical angle, and mirrors the water, ``W / (1 + mu)`` (an endless path of water looking
down), with the rest of the light; beyond the critical angle it is a mirror.  Refraction's bend
of the view through Snell's window is left out (the view above the water is not compressed into
the window), and so is the blur of forward scattering.

Nothing here runs for a camera above water: its picture is MuJoCo's own.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

# The diffuse attenuation coefficient of downward irradiance K (1/m) of Jerlov's coastal water
# type 3C (N. G. Jerlov, "Marine Optics", 2nd ed., Elsevier 1976, Table XXVII: 0.33 at 600 nm
# and 0.40 at 625 nm; 0.20 at 525 nm and 0.19 at 550 nm; 0.39 at 450 nm and 0.29 at 475 nm),
# read at the dominant wavelengths of the sRGB primaries of IEC 61966-2-1 (611, 549 and 464 nm),
# linearly between the table's columns: the red, green and blue channels.  Jerlov's coastal types run
# from 1C, the clearest, to 9C, the most turbid; 3C, the water of a harbour basin, is an
# estimate.  The same K dims the line of sight (the model's simplification: the beam
# attenuation coefficient is larger, but light scattered forward still reaches the camera,
# blurred): half the green is gone after 3.6 m, all but 2 % after 20 m, the red and the blue
# nearly twice as fast: murky water, green at a distance.
ATTENUATION_PER_M = np.array([0.36, 0.19, 0.334])
# The veiling light's colour: particles scatter light nearly alike at every wavelength in turbid
# coastal water (C. D. Mobley, "Light and Water", Academic Press 1994, ch. 3: scattering by
# particles large against the wavelength varies little with it), so the light an endless path of
# water sends back goes as 1/K from channel to channel (W = beta / K, beta the light scattered
# towards the camera per metre): olive green.  Its green, as a share of a white surface lit by
# the world's daylight, is an estimate for the renderer (the water about as bright as the
# basin's silt bottom seen close by).
VEIL_GREEN = 0.40
VEIL_SHARE = VEIL_GREEN * ATTENUATION_PER_M[1] / ATTENUATION_PER_M
# The refractive index of water, 1.333 at 589 nm and 20 degrees C (IAPWS, "Release on the
# Refractive Index of Ordinary Water Substance as a Function of Wavelength, Temperature and
# Pressure", 1997); air's, 1.000.
WATER_INDEX = 1.333


@dataclass(frozen=True)
class WaterBox:
    """A water volume in MuJoCo's frame (an axis-aligned box, config.world.WaterVolume): its
    lower and upper corners (metres); the top is the water's surface."""

    lo: np.ndarray
    hi: np.ndarray

    def holds(self, point) -> bool:
        p = np.asarray(point, dtype=float)
        return bool(np.all(p >= self.lo) and np.all(p <= self.hi))


@dataclass(frozen=True)
class Water:
    """A model's water volumes and the colour of its water (RGB 0..255, a horizontal stretch at
    the camera's depth, balanced for the light there)."""

    boxes: tuple[WaterBox, ...]
    colour: np.ndarray

    def around(self, point) -> WaterBox | None:
        """The water volume ``point`` (MuJoCo's frame) is in, or None."""
        for b in self.boxes:
            if b.holds(point):
                return b
        return None


def daylight(model: mujoco.MjModel) -> np.ndarray:
    """The light of the world's sky and lamps on a horizontal surface facing up, RGB, each at
    most 1 (as the renderer lights a white surface): the ambient light and, of each world
    light, its ambient part and its diffuse part times the cosine of its direction to the
    vertical (a point light counts as overhead).  Robots' headlights are not daylight."""
    e = np.array(model.vis.headlight.ambient, dtype=float)
    for i in range(model.nlight):
        if model.light(i).name.endswith("/headlight") or not model.light_active[i]:
            continue
        e += model.light_ambient[i]
        if int(model.light_type[i]) == int(mujoco.mjtLightType.mjLIGHT_POINT):
            e += model.light_diffuse[i]
        else:
            e += model.light_diffuse[i] * max(0.0, -float(model.light_dir[i][2]))
    return np.minimum(e, 1.0)


def water_of(model: mujoco.MjModel, data: mujoco.MjData) -> Water:
    """The water volumes of a model (its geoms named ``water/...``, builder.world_spec) and its
    water's colour."""
    boxes = []
    for g in range(model.ngeom):
        if model.geom(g).name.startswith("water/") and int(model.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_BOX):
            c, h = np.array(data.geom_xpos[g], dtype=float), np.array(model.geom_size[g], dtype=float)
            boxes.append(WaterBox(lo=c - h, hi=c + h))
    return Water(boxes=tuple(boxes), colour=255.0 * daylight(model) * VEIL_SHARE)


def fresnel_reflectance(cos_incidence: np.ndarray, n1: float = WATER_INDEX, n2: float = 1.0) -> np.ndarray:
    """The share of unpolarised light reflected where a ray in a medium of index ``n1`` meets
    one of index ``n2`` at an incidence whose cosine is given (Fresnel's equations: the mean of
    the s and p reflectances; E. Hecht, "Optics", 4th ed., sec. 4.6); 1 beyond the critical
    angle (total internal reflection)."""
    ci = np.clip(cos_incidence, 0.0, 1.0)
    st = n1 / n2 * np.sqrt(1.0 - ci * ci)
    inside = st < 1.0
    ct = np.sqrt(np.maximum(0.0, 1.0 - st * st))
    rs = ((n1 * ci - n2 * ct) / (n1 * ci + n2 * ct + 1e-12)) ** 2
    rp = ((n1 * ct - n2 * ci) / (n1 * ct + n2 * ci + 1e-12)) ** 2
    return np.where(inside, 0.5 * (rs + rp), 1.0)


def linear_depth(raw: np.ndarray, near: float, far: float) -> np.ndarray:
    """Distances along the view axis (m) from MuJoCo's depth buffer (reverse Z: 1 at the near
    clipping plane, 0 at the far one), as mujoco.Renderer converts them."""
    n, f = np.float32(near), np.float32(far)
    c = np.float32(-0.5) * (-(f + n) / (f - n)) - np.float32(0.5)
    d = np.float32(-0.5) * (-(np.float32(2) * f * n) / (f - n))
    return (d / (raw.astype(np.float64) + c)).astype(np.float32)


def rays(glcam, width: int, height: int) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], np.ndarray]:
    """The unit direction of each pixel's ray of an OpenGL camera of MuJoCo's scene: its X, Y
    and Z components in MuJoCo's frame (each height x width, rows top to bottom), and the
    length of the ray per metre along the view axis (height x width)."""
    near = float(glcam.frustum_near)
    bottom, top = float(glcam.frustum_bottom), float(glcam.frustum_top)
    half = float(glcam.frustum_width) or 0.5 * width / height * (top - bottom)  # mjr_render's rule
    centre = float(glcam.frustum_center)
    fwd = np.array(glcam.forward, dtype=np.float32)
    up = np.array(glcam.up, dtype=np.float32)
    right = np.cross(fwd, up)
    x = ((centre - half + 2.0 * half * (np.arange(width) + 0.5) / width) / near).astype(np.float32)[None, :]
    y = ((top - (top - bottom) * (np.arange(height) + 0.5) / height) / near).astype(np.float32)[:, None]
    d = [fwd[k] + x * right[k] + y * up[k] for k in range(3)]
    length = np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    return (d[0] / length, d[1] / length, d[2] / length), length


def through_water(rgb: np.ndarray, raw_depth: np.ndarray, glcam, box: WaterBox, colour: np.ndarray) -> np.ndarray:
    """The picture ``rgb`` (rendered in air, rows top to bottom) with its depth buffer, seen by
    ``glcam`` (mjvGLCamera) from inside the water volume ``box``: the water's effect on every
    pixel (see the module's docstring).  ``colour`` is the water's (W, RGB 0..255)."""
    h, w = raw_depth.shape
    pos = np.array(glcam.pos, dtype=np.float32)
    direction, length = rays(glcam, w, h)
    # how far each ray goes to what it shows (the sky is drawn far beyond any water volume)
    t_hit = linear_depth(raw_depth, float(glcam.frustum_near), float(glcam.frustum_far)) * length
    # where the ray leaves the water volume, and whether through the surface (the top face)
    t_exit = np.full((h, w), np.inf, dtype=np.float32)
    with np.errstate(divide="ignore", invalid="ignore"):
        for k, dk in enumerate(direction):
            tk = np.where(dk >= 0, (np.float32(box.hi[k]) - pos[k]) / dk, (np.float32(box.lo[k]) - pos[k]) / dk)
            if k == 2:
                through_top = (tk < t_exit) & (dk > 0)
            np.minimum(t_exit, tk, out=t_exit)
    surface = through_top & (t_exit < t_hit)
    t = np.minimum(t_hit, t_exit)
    mu = direction[2]
    rising = np.maximum(np.float32(1.0) - mu, np.float32(1e-6))  # 1 - mu
    k_rgb = ATTENUATION_PER_M.astype(np.float32)  # K, per colour channel
    e = np.expm1(-(rising * t)[..., None] * k_rgb)  # exp(-a t) - 1, a = K (1 - mu)
    veil = -e / rising[..., None]  # K (1 - exp(-a t)) / a: W's share along the path
    water = colour.astype(np.float32)
    x = rgb.astype(np.float32)
    if surface.any():  # mix what is above with the mirrored water, by Fresnel's reflectance
        r = np.where(surface, fresnel_reflectance(mu).astype(np.float32), np.float32(0.0))[..., None]
        mirrored = water / (np.float32(1.0) + np.maximum(mu, np.float32(0.0)))[..., None]
        x += r * (mirrored - x)
    out = x * (e + np.float32(1.0))
    out += veil * water
    out += np.float32(0.5)
    np.clip(out, 0.0, 255.0, out=out)
    return out.astype(np.uint8)
