"""The victims of a world in the model (manual 3.2.1): life-size human bodies lying or
sitting, some waving an arm (a kinematic shoulder moved by the victims system)."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from usarsim.sim import frames
from usarsim.sim.constants import GROUP_STATIC, SOLID_CONAFFINITY, SOLID_CONTYPE

# A victim's body, lying on its back along its own +X axis (head forward), in its own
# USARSim frame (X forward, Y right, Z down) with the origin at the pelvis centre.
# Rounded adult body dimensions (estimates for a 1.75 m adult; the manual's victims,
# section 3.2.1, are life-size human models): (part, shape, centre, size) where a box
# size is its full extents, a sphere size its radius and a capsule (along X) its
# radius and half-length.
VICTIM_LYING = (
    ("Head", "sphere", (0.78, 0.0, 0.0), (0.10,)),
    ("Chest", "box", (0.40, 0.0, 0.0), (0.46, 0.36, 0.20)),
    ("Pelvis", "box", (0.0, 0.0, 0.0), (0.26, 0.34, 0.20)),
    ("Arm", "capsule", (0.40, -0.24, 0.0), (0.05, 0.22)),
    ("Arm", "capsule", (0.40, 0.24, 0.0), (0.05, 0.22)),
    ("Hand", "sphere", (0.08, -0.25, 0.0), (0.05,)),
    ("Hand", "sphere", (0.08, 0.25, 0.0), (0.05,)),
    ("Leg", "capsule", (-0.45, -0.10, 0.0), (0.07, 0.30)),
    ("Leg", "capsule", (-0.45, 0.10, 0.0), (0.07, 0.30)),
    ("Foot", "box", (-0.86, -0.10, -0.05), (0.08, 0.09, 0.22)),
    ("Foot", "box", (-0.86, 0.10, -0.05), (0.08, 0.09, 0.22)),
)
# The waving arm (the right one) swings about the shoulder (constants.WAVE_AMPLITUDE_RAD,
# WAVE_PERIOD_S).
SHOULDER = (0.62, 0.24, 0.0)  # the right shoulder, victim frame
VICTIM_RGBA = [0.87, 0.68, 0.55, 1.0]


def victim_part_pose(posture: str, centre, size, shape):
    """Centre and rotation (USARSim rpy) of a part for a posture: sitting raises the
    upper body (Head, Chest, Arms, Hands) upright above the pelvis."""
    x, y, z = centre
    if posture == "sitting" and x > 0.05:
        # rotate the upper body by -90 degrees of pitch about the pelvis: +X becomes -Z (up)
        return (0.0, y, z - x), (0.0, math.pi / 2, 0.0)
    return (x, y, z), (0.0, 0.0, 0.0)


def add_victim(spec: mujoco.MjSpec, victim) -> None:
    body = spec.worldbody.add_body()
    body.name = f"victim/{victim.name}"
    body.pos = frames.to_mj_vec(victim.location).tolist()
    body.quat = frames.usar_euler_to_mj_quat(victim.rotation).tolist()
    for i, (part, shape, centre, size) in enumerate(VICTIM_LYING):
        waving = victim.waving and part in ("Arm", "Hand") and centre[1] > 0
        parent = body
        c, rot = victim_part_pose(victim.posture, centre, size, shape)
        if waving:
            # the right arm and hand hang from a shoulder body that is moved kinematically
            shoulder = spec.body(f"victim/{victim.name}/shoulder")
            if shoulder is None:
                shoulder = spec.worldbody.add_body()
                shoulder.name = f"victim/{victim.name}/shoulder"
                shoulder.mocap = True
                loc = np.array(victim.location, dtype=float)
                rot_v = frames.euler_to_mat(*victim.rotation)
                sh = victim_part_pose(victim.posture, SHOULDER, None, None)[0]
                shoulder.pos = frames.to_mj_vec(loc + rot_v @ np.array(sh)).tolist()
                shoulder.quat = frames.usar_euler_to_mj_quat(victim.rotation).tolist()
            parent = shoulder
            sh = victim_part_pose(victim.posture, SHOULDER, None, None)[0]
            c = tuple(np.array(c) - np.array(sh))
        g = parent.add_geom()
        g.name = f"victim/{victim.name}/{part}/{i}"
        g.pos = frames.to_mj_vec(c).tolist()
        if shape == "sphere":
            g.type = mujoco.mjtGeom.mjGEOM_SPHERE
            g.size = [size[0], 0.0, 0.0]
        elif shape == "capsule":
            g.type = mujoco.mjtGeom.mjGEOM_CAPSULE
            g.size = [size[0], size[1], 0.0]
            # MuJoCo capsules lie along their own Z; the part lies along the victim's X
            r = np.array(rot, dtype=float) + np.array([0.0, math.pi / 2, 0.0])
            g.quat = frames.usar_euler_to_mj_quat(tuple(r)).tolist()
        else:
            g.type = mujoco.mjtGeom.mjGEOM_BOX
            g.size = [size[0] / 2.0, size[1] / 2.0, size[2] / 2.0]
            g.quat = frames.usar_euler_to_mj_quat(rot).tolist()
        g.rgba = VICTIM_RGBA
        g.group = GROUP_STATIC
        g.contype, g.conaffinity = SOLID_CONTYPE, SOLID_CONAFFINITY
