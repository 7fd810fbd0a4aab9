"""The victims of a world in the model (manual 3.2.1): life-size human bodies lying or
sitting, some waving an arm (a kinematic shoulder moved by the victims system)."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from usarsim.sim import frames
from usarsim.sim.constants import GROUP_STATIC, SOLID_CONAFFINITY, SOLID_CONTYPE
from usarsim.sim.faces import FACE_SIZE_M, face_picture
from usarsim.sim.robotlook import cameras_only_geom

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
# Body builds, as (length, girth) factors of the adult above: a child of six is 1.15 m tall
# (the median stature at 6 years, CDC growth charts, 2000) against the adult's 1.75 m, and
# slighter (0.75, an estimate); a heavy adult as tall, 1.3 times as broad and deep (an
# estimate: the waist of a body mass index of 35 against 22); a slim one 0.85.
BUILDS = {"average": (1.0, 1.0), "slim": (1.0, 0.85), "heavy": (1.0, 1.3), "child": (0.66, 0.75)}
# What lies on a trapped victim (victim frame, lying): a slab of concrete across the legs and
# a board across the hips, resting on them, each (centre, full size, rotation), the heights
# above the body's top (estimates: a 0.9 x 0.6 m piece of a 8 cm floor slab, a 2 x 6 in
# board 1.2 m long)
DEBRIS = (
    ("slab", (-0.5, 0.0, -0.06), (0.6, 0.9, 0.08), (0.12, 0.0, 0.1), (0.62, 0.61, 0.58)),
    ("board", (0.0, 0.05, -0.03), (0.14, 1.2, 0.04), (0.0, 0.0, 0.35), (0.78, 0.64, 0.44)),
)


def victim_parts(build: str = "average") -> tuple:
    """VICTIM_LYING for a body build: part centres and sizes scaled along the body (length)
    and across it (girth)."""
    length, girth = BUILDS[build]
    out = []
    for part, shape, (x, y, z), raw in VICTIM_LYING:
        size: tuple[float, ...] = raw
        if shape == "sphere":
            scaled: tuple[float, ...] = (size[0] * girth,)
        elif shape == "capsule":
            scaled = (size[0] * girth, size[1] * length)
        else:
            scaled = (size[0] * length, size[1] * girth, size[2] * girth)
        out.append((part, shape, (x * length, y * girth, z * girth), scaled))
    return tuple(out)


def shoulder_of(victim) -> tuple[float, float, float]:
    """The right shoulder of ``victim`` (victim frame, its build)."""
    length, girth = BUILDS[getattr(victim, "build", "average")]
    return (SHOULDER[0] * length, SHOULDER[1] * girth, SHOULDER[2] * girth)


VICTIM_RGBA = [0.87, 0.68, 0.55, 1.0]

# What cameras see of a victim: skin on the head and hands, clothes on the body, shoes, and
# a face.  Skin tones span light to dark skin (sRGB, within the spread of skin colours
# measured by K. Xiao et al., "Characterising the variations in ethnic skin colours",
# Color Research & Application 42(2), 2017); every one has a hue of 18-21 degrees and a
# saturation of 0.30-0.52, the skin cluster of colour-based detectors (Kovac, Peer and
# Solina, "Human skin colour clustering for face detection", EUROCON 2003: R > G > B,
# R - G > 15 of 255), and away from wood and cardboard (hue 30-40 degrees).
SKIN_TONES = ((0.92, 0.72, 0.62), (0.80, 0.57, 0.45), (0.66, 0.44, 0.33), (0.47, 0.31, 0.23))
# Clothes: jeans blue, work-shirt colours, a grey hoodie, a green jacket (saturated or dark
# enough, hue outside 10-26 degrees, never to pass for skin).
SHIRTS = ((0.20, 0.35, 0.62), (0.25, 0.50, 0.30), (0.55, 0.55, 0.58), (0.70, 0.15, 0.40), (0.90, 0.90, 0.92))
TROUSERS = ((0.16, 0.22, 0.38), (0.22, 0.22, 0.24), (0.35, 0.38, 0.25))
SHOES = (0.12, 0.10, 0.09)
HAIR = ((0.10, 0.07, 0.05), (0.30, 0.20, 0.12), (0.05, 0.05, 0.05))
EYE = (0.08, 0.06, 0.05)
MOUTH = (0.55, 0.18, 0.18)
# Decorations (the face, the hair) are seen by cameras only: the ray groups and the victim
# sensor never see them (constants.GROUP_WATER is the camera-only group).
LOOK_GROUP = 4


def victim_colours(name: str) -> dict[str, tuple[float, float, float]]:
    """The colours of a victim, chosen from its name (the same victim looks the same in every
    run): skin, shirt, trousers, hair."""
    k = sum((i + 1) * ord(c) for i, c in enumerate(name))
    return {
        "skin": SKIN_TONES[k % len(SKIN_TONES)],
        "shirt": SHIRTS[(k // 4) % len(SHIRTS)],
        "trousers": TROUSERS[(k // 20) % len(TROUSERS)],
        "hair": HAIR[(k // 7) % len(HAIR)],
    }


def part_colour(part: str, colours: dict) -> list[float]:
    if part in ("Head", "Hand"):
        rgb = colours["skin"]
    elif part in ("Chest", "Arm"):
        rgb = colours["shirt"]
    elif part in ("Pelvis", "Leg"):
        rgb = colours["trousers"]
    else:
        rgb = SHOES
    return [*rgb, 1.0]


def _look(body, name: str, kind, pos, size, rgb) -> mujoco.MjsGeom:
    g = cameras_only_geom(body, name, rgb)
    g.type = kind
    g.pos = frames.to_mj_vec(pos).tolist()
    g.size = list(size)
    return g


def add_face(spec: mujoco.MjSpec, body, victim, colours) -> None:
    """A face and hair on the victim's head (victim frame; lying: the face up, sitting: the
    face forward): a thin plate just in front of the head showing the picture of a face
    (:mod:`usarsim.sim.faces`), and a cap of hair over the crown and the back of the head."""
    head = victim_parts(victim.build)[0]
    (hx, hy, hz), _ = victim_part_pose(victim.posture, head[2], None, None)
    r = head[3][0]
    scale = BUILDS[victim.build][1]
    if victim.posture == "sitting":

        def at(fwd, side, up):  # a point on the head: towards the face, the right, the crown
            return (hx + fwd, hy + side, hz - up)
    else:

        def at(fwd, side, up):
            return (hx + up, hy + side, hz - fwd)

    prefix = f"look/victim/{victim.name}"
    box, ellipsoid = mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_ELLIPSOID
    # the face: a plate 1 cm in front of the head's surface, its picture upright (the crown up)
    width, height = FACE_SIZE_M
    plate = (0.004, scale * width / 2.0, scale * height / 2.0)
    face = _look(body, f"{prefix}/face", box, at(r + 0.005, 0.0, 0.0), plate, (1.0, 1.0, 1.0))
    face.material = face_material(spec, colours["skin"], colours["hair"])
    if victim.posture != "sitting":  # lying: the plate's outside up, its picture's top towards the crown
        face.quat = [0.0, math.sqrt(0.5), 0.0, math.sqrt(0.5)]
    # hair: a cap over the crown and the back of the head
    _look(body, f"{prefix}/hair", ellipsoid, at(-0.02, 0.0, 0.02), (r * 1.02, r * 1.03, r * 0.98), colours["hair"])


def face_material(spec: mujoco.MjSpec, skin: tuple[float, float, float], hair: tuple[float, float, float]) -> str:
    """The material showing the face of a victim of ``skin`` and ``hair`` (made once a model)."""
    key = "%.2f,%.2f,%.2f/%.2f,%.2f,%.2f" % (*skin, *hair)
    name = f"material/face/{key}"
    if spec.material(name) is None:
        img = face_picture(skin, hair)
        t = spec.add_texture()
        t.name = f"texture/face/{key}"
        t.type = mujoco.mjtTexture.mjTEXTURE_2D
        t.height, t.width = img.shape[0], img.shape[1]
        t.nchannel = 3
        t.data = img.tobytes()
        m = spec.add_material()
        m.name = name
        m.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = t.name
        m.texrepeat = [1.0, 1.0]
        m.texuniform = False
        m.specular = 0.1  # skin is matt
    return name


def victim_part_pose(posture: str, centre, size, shape):
    """Centre and rotation (USARSim rpy) of a part for a posture: sitting raises the
    upper body (Head, Chest, Arms, Hands) upright above the pelvis."""
    x, y, z = centre
    if posture == "sitting" and x > 0.05:
        # rotate the upper body by -90 degrees of pitch about the pelvis: +X becomes -Z (up)
        return (0.0, y, z - x), (0.0, math.pi / 2, 0.0)
    return (x, y, z), (0.0, 0.0, 0.0)


def add_victim(spec: mujoco.MjSpec, victim) -> None:
    colours = victim_colours(victim.name)
    body = spec.worldbody.add_body()
    body.name = f"victim/{victim.name}"
    body.pos = frames.to_mj_vec(victim.location).tolist()
    body.quat = frames.usar_euler_to_mj_quat(victim.rotation).tolist()
    shoulder_at = shoulder_of(victim)
    for i, (part, shape, centre, size) in enumerate(victim_parts(victim.build)):
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
                sh = victim_part_pose(victim.posture, shoulder_at, None, None)[0]
                shoulder.pos = frames.to_mj_vec(loc + rot_v @ np.array(sh)).tolist()
                shoulder.quat = frames.usar_euler_to_mj_quat(victim.rotation).tolist()
            parent = shoulder
            sh = victim_part_pose(victim.posture, shoulder_at, None, None)[0]
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
        g.rgba = part_colour(part, colours)
        g.group = GROUP_STATIC
        g.contype, g.conaffinity = SOLID_CONTYPE, SOLID_CONAFFINITY
    add_face(spec, body, victim, colours)
    if victim.posture == "trapped":
        add_debris(spec, victim)


def add_debris(spec: mujoco.MjSpec, victim) -> None:
    """What lies on a trapped victim (DEBRIS): solid pieces of the world on its legs and hips,
    which lasers see and robots meet, named ``debris/<victim>/<piece>``."""
    length, girth = BUILDS[victim.build]
    top = 0.10 * girth  # the body's top, above its centre line (the chest's half depth)
    loc = np.array(victim.location, dtype=float)
    rot = frames.euler_to_mat(*victim.rotation)
    for piece, (x, y, z), size, rpy, rgb in DEBRIS:
        centre = loc + rot @ np.array([x * length, y, z - top - size[2] / 2.0])
        g = spec.worldbody.add_geom()
        g.name = f"debris/{victim.name}/{piece}"
        g.type = mujoco.mjtGeom.mjGEOM_BOX
        g.size = [size[0] / 2.0, size[1] / 2.0, size[2] / 2.0]
        g.pos = frames.to_mj_vec(tuple(centre)).tolist()
        turned = frames.mat_to_euler(rot @ frames.euler_to_mat(*rpy))  # the victim's turn, then the piece's
        g.quat = frames.usar_euler_to_mj_quat(turned).tolist()
        g.rgba = [*rgb, 1.0]
        g.group = GROUP_STATIC
        g.contype, g.conaffinity = SOLID_CONTYPE, SOLID_CONAFFINITY
