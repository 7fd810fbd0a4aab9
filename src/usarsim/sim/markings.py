"""A road's painted markings (textures.road_markings) laid on its box as thin boxes that
cameras see and nothing else touches: they neither collide nor stop a ray."""

from __future__ import annotations

import mujoco
import numpy as np

from usarsim.sim import textures
from usarsim.sim.constants import GROUP_WATER

# Paint lies this far above the road's top face (m), its boxes this thick: far below what a
# robot's camera can tell, enough for the depth buffer to keep it in front of the road.
LIFT_M, THICKNESS_M = 0.0015, 0.001
CAMERAS_ONLY = GROUP_WATER  # the camera-only geom group


def paint_material(spec: mujoco.MjSpec, rgb, specular: float) -> str:
    """The (shared) material of paint of colour ``rgb``: flat, as shiny as the road."""
    name = "material/paint/" + "".join(f"{round(c * 255):02x}" for c in rgb)
    if spec.material(name) is None:
        m = spec.add_material()
        m.name = name
        m.rgba = [*rgb, 1.0]
        m.specular = specular
        m.shininess = 0.2
    return name


def add_road_markings(spec: mujoco.MjSpec, g, along_x: bool, specular: float) -> int:
    """Lay the markings of a street on the box geom ``g`` (a road of material ``road``): along
    its longer horizontal side (its local X when ``along_x``, else Y), the way the road runs
    towards +X (+Y), in the geom's own body.  Returns how many boxes were added."""
    hx, hy, hz = (float(v) for v in g.size[:3])
    length, width = (2 * hx, 2 * hy) if along_x else (2 * hy, 2 * hx)
    fwd = np.array([1.0, 0.0, 0.0]) if along_x else np.array([0.0, 1.0, 0.0])
    right = np.cross(fwd, [0.0, 0.0, 1.0])  # on the right of the way the road runs
    quat = np.array(g.quat, dtype=float)
    quat = quat / np.linalg.norm(quat) if np.linalg.norm(quat) > 0 else np.array([1.0, 0.0, 0.0, 0.0])
    body = g.parent
    n = 0
    for k, mk in enumerate(textures.road_markings(length)):
        left, right_edge = max(mk.left, -width / 2), min(mk.right, width / 2)
        if right_edge <= left:
            continue
        along = (mk.start + mk.end) / 2 - length / 2
        across = (left + right_edge) / 2
        local = fwd * along + right * across + np.array([0.0, 0.0, hz + LIFT_M + THICKNESS_M / 2])
        offset = np.zeros(3)
        mujoco.mju_rotVecQuat(offset, local, quat)
        d = body.add_geom()
        d.name = f"paint/{g.name}/{k}"
        d.type = mujoco.mjtGeom.mjGEOM_BOX
        half = np.abs(fwd * (mk.end - mk.start) / 2 + right * (right_edge - left) / 2)
        half[2] = THICKNESS_M / 2
        d.size = half.tolist()
        d.pos = (np.array(g.pos, dtype=float) + offset).tolist()
        d.quat = quat.tolist()
        d.material = paint_material(spec, mk.rgb, specular)
        d.rgba = [*mk.rgb, 1.0]
        d.group = CAMERAS_ONLY
        d.contype = d.conaffinity = 0
        d.castshadow = False
        n += 1
    return n
