"""Building the MuJoCo model of a world: a world file becomes an ``MjSpec`` (its floor,
materials and textures, objects, victims, false alarms, water and lights).  Robots are added
to and removed from that spec while the simulation runs (:mod:`usarsim.sim.robotspec`;
``MjSpec.recompile`` carries the state of everything else over)."""

from __future__ import annotations

import mujoco
import numpy as np

from usarsim.config.world import WorldConfig
from usarsim.sim import frames, markings, textures
from usarsim.sim.constants import (
    FLOOR_CONTYPE,
    GROUP_MOVABLE,
    GROUP_STATIC,
    ROLL_FRICTION,
    SOLID_CONAFFINITY,
    SOLID_CONTYPE,
    SPIN_FRICTION,
)
from usarsim.sim.victims import add_victim

# A surface more slippery than the default 1.0 (paper, polished metal, ice) decides the
# friction of whatever touches it: MuJoCo otherwise takes the larger of the two
# coefficients, and a wheel's 1.0 would grip paper as well as concrete.  A robot part with
# a friction of its own (priority 1) still wins on ordinary surfaces.
SLIPPERY_PRIORITY = 2


# The largest picture the image server renders (the offscreen buffer the model reserves).
MAX_PICTURE_WIDTH, MAX_PICTURE_HEIGHT = 1920, 1080

# Textures on the world's surfaces (usarsim.sim.textures): on unless SimSettings.textures says
# otherwise (serve --no-textures: plain colours, the quickest pictures on a machine that renders
# in software).  What is seen only: no geom's size, contact or friction changes.
# The side of each light's shadow map (pixels).  A software renderer (Mesa llvmpipe) draws
# the scene once more into it for every light that casts shadows; 1024 pixels over an
# arena's 20 m gives shadows about 2 cm sharp, and costs a third of MuJoCo's 4096 default.
SHADOW_MAP_PX = 1024
# A fitted texture (a road's markings) is laid on boxes at least this many times as long as
# they are wide; a squarer box of its material (a parking lot) shows plain asphalt.
FITTED_MIN_RATIO = 4.0


def _dress(spec: mujoco.MjSpec, g, mat, box_size=None, textured: bool = True) -> None:
    """The look of a world geom of material ``mat``: its colour, and its texture when the
    material names one (a MuJoCo material whose texture is made around the colour; the
    colour then comes from the texture, the geom keeps the material's opacity).  A fitted
    texture (a road's markings) runs along the longer horizontal side of the box of full
    extents ``box_size``, once across its width."""
    g.rgba = list(mat.rgba)
    if not mat.texture or not textured:
        return
    kind = textures.TEXTURES[mat.texture]
    texture = mat.texture
    if kind.fitted and (
        box_size is None or max(box_size[0], box_size[1]) < FITTED_MIN_RATIO * min(box_size[0], box_size[1])
    ):
        # not a strip (a parking lot, a cylinder): the surface without its markings
        texture, kind = "asphalt", textures.TEXTURES["asphalt"]
    rgb = tuple(int(round(float(c) * 255)) for c in mat.rgba[:3])
    colour = "".join(f"{c:02x}" for c in rgb)
    scale = mat.texture_scale or (1.0 / kind.size_m[0], 1.0 / kind.size_m[1])
    if kind.fitted:
        along_x = box_size[0] >= box_size[1]
        tex_name = f"texture/{texture}/{colour}/{'x' if along_x else 'y'}"
        mat_name = f"material/{mat.name}/{g.name}"
        length, width = (box_size[0], box_size[1]) if along_x else (box_size[1], box_size[0])
        repeat = [length * scale[0], width * scale[1]] if along_x else [width * scale[1], length * scale[0]]
        uniform = False
    else:
        along_x = True
        tex_name = f"texture/{texture}/{colour}"
        mat_name = f"material/{mat.name}/{texture}"
        repeat, uniform = [scale[0], scale[1]], True
    if spec.texture(tex_name) is None:
        img = textures.texture_image(texture, mat.rgba)
        if not along_x:
            # a box along Y shows the image's rows along the box, its first column at the
            # right-hand kerb of the way the rows run (the same side as along X)
            img = np.ascontiguousarray(img[::-1, :].transpose(1, 0, 2))
        t = spec.add_texture()
        t.name = tex_name
        t.type = mujoco.mjtTexture.mjTEXTURE_2D
        t.height, t.width = img.shape[0], img.shape[1]
        t.nchannel = 3
        t.data = img.tobytes()
    if spec.material(mat_name) is None:
        m = spec.add_material()
        m.name = mat_name
        m.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = tex_name
        m.texrepeat = repeat
        m.texuniform = uniform
        m.rgba = [1.0, 1.0, 1.0, float(mat.rgba[3])]
        m.specular = kind.specular
        m.shininess = 0.2
    g.material = mat_name
    g.rgba = [1.0, 1.0, 1.0, float(mat.rgba[3])]
    if texture == "road":  # its markings, laid on it (textures.road_markings)
        markings.add_road_markings(spec, g, along_x, kind.specular)


def world_spec(world: WorldConfig, *, textures: bool = True, antialias: int = 4) -> mujoco.MjSpec:
    s = mujoco.MjSpec()
    s.modelname = world.name
    s.compiler.degree = False  # joint ranges are in radians, as everywhere in usarsim
    o = s.option
    o.timestep = world.timestep_s
    # implicitfast: explicit Euler goes unstable with stiff wheel velocity servos
    o.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    o.cone = mujoco.mjtCone.mjCONE_PYRAMIDAL
    o.gravity = [0.0, 0.0, -world.gravity_m_s2]
    # A blow-up must not reset the whole world: the simulation resets only the robot
    # concerned (usarsim.sim.health.BlowUpGuard).
    o.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
    s.visual.global_.offwidth = MAX_PICTURE_WIDTH
    s.visual.global_.offheight = MAX_PICTURE_HEIGHT
    s.visual.quality.shadowsize = SHADOW_MAP_PX
    s.visual.quality.offsamples = antialias  # multisampling of pictures (SimSettings.antialias)
    # a sky for the cameras (a pale gradient, lighter at the horizon) instead of black
    sky = s.add_texture()
    sky.name = "sky"
    sky.type = mujoco.mjtTexture.mjTEXTURE_SKYBOX
    sky.builtin = mujoco.mjtBuiltin.mjBUILTIN_GRADIENT
    sky.rgb1 = [0.78, 0.84, 0.90]
    sky.rgb2 = [0.36, 0.46, 0.58]
    sky.width = sky.height = 64

    fl = world.floor
    floor_mat = world.materials[fl.material]
    g = s.worldbody.add_geom()
    g.name = "floor"
    # a plane at z = 0: contacts with it are analytic (cheap) and nothing tunnels
    # through it; ray casts see it within the floor's rectangle only
    g.type = mujoco.mjtGeom.mjGEOM_PLANE
    g.size = [fl.size[0] / 2.0, fl.size[1] / 2.0, 0.1]
    g.pos = [fl.center[0], -fl.center[1], 0.0]
    _dress(s, g, floor_mat, textured=textures)
    g.friction = [floor_mat.friction, SPIN_FRICTION, ROLL_FRICTION]
    if floor_mat.friction < 1.0:
        g.priority = SLIPPERY_PRIORITY
    g.group = GROUP_STATIC
    g.contype, g.conaffinity = FLOOR_CONTYPE, SOLID_CONAFFINITY

    for obj in world.objects:
        mat = world.materials[obj.material]
        if obj.mass_kg > 0:  # a movable object: a free body of its own
            holder = s.worldbody.add_body()
            holder.name = f"movable/{obj.name}"
            holder.pos = frames.to_mj_vec(obj.center).tolist()
            holder.quat = frames.usar_euler_to_mj_quat(obj.rotation).tolist()
            fj = holder.add_freejoint()
            fj.name = f"movable/{obj.name}"
            g = holder.add_geom()
            g.mass = obj.mass_kg
            g.group = GROUP_MOVABLE
        else:
            g = s.worldbody.add_geom()
            g.pos = frames.to_mj_vec(obj.center).tolist()
            g.quat = frames.usar_euler_to_mj_quat(obj.rotation).tolist()
            g.group = GROUP_STATIC
        g.name = f"world/{obj.name}"
        if obj.shape == "box":
            g.type = mujoco.mjtGeom.mjGEOM_BOX
            g.size = [obj.size[0] / 2.0, obj.size[1] / 2.0, obj.size[2] / 2.0]
        elif obj.shape == "mesh":
            mesh = s.add_mesh()
            mesh.name = f"world/{obj.name}"
            mesh.file = obj.mesh_file
            mesh.scale = list(obj.scale)
            g.type = mujoco.mjtGeom.mjGEOM_MESH
            g.meshname = mesh.name
            # the file's vertices are in the object's USARSim frame (X forward, Y right, Z
            # down): a half turn about X turns them into MuJoCo's axes
            # (a movable mesh's body carries the object's rotation; a static one, the geom)
            own = np.array([1.0, 0.0, 0.0, 0.0]) if obj.mass_kg > 0 else frames.usar_euler_to_mj_quat(obj.rotation)
            turned = np.zeros(4)
            mujoco.mju_mulQuat(turned, own, MESH_FRAME_QUAT)
            g.quat = turned.tolist()
        else:
            g.type = mujoco.mjtGeom.mjGEOM_CYLINDER
            g.size = [obj.radius_m, obj.length_m / 2.0, 0.0]
        _dress(s, g, mat, obj.size if obj.shape == "box" else None, textured=textures)
        g.friction = [mat.friction, SPIN_FRICTION, ROLL_FRICTION]
        if mat.friction < 1.0:
            g.priority = SLIPPERY_PRIORITY
        g.contype, g.conaffinity = SOLID_CONTYPE, SOLID_CONAFFINITY

    for v in world.victims:
        add_victim(s, v)
    for a in world.false_alarms:
        mat = world.materials[a.material]
        g = s.worldbody.add_geom()
        g.name = f"falsealarm/{a.name}/{a.part}"
        g.type = mujoco.mjtGeom.mjGEOM_BOX
        g.size = [a.size[0] / 2.0, a.size[1] / 2.0, a.size[2] / 2.0]
        g.pos = frames.to_mj_vec(a.center).tolist()
        g.quat = frames.usar_euler_to_mj_quat(a.rotation).tolist()
        _dress(s, g, mat, textured=textures)
        if a.material == "default":
            add_false_alarm_look(s, g, a)
        g.group = GROUP_STATIC
        g.contype, g.conaffinity = SOLID_CONTYPE, SOLID_CONAFFINITY

    for wv in world.water:  # seen by cameras only: it neither collides nor stops a ray
        g = s.worldbody.add_geom()
        g.name = f"water/{wv.name}"
        g.type = mujoco.mjtGeom.mjGEOM_BOX
        g.size = [wv.size[0] / 2.0, wv.size[1] / 2.0, wv.size[2] / 2.0]
        g.pos = frames.to_mj_vec(wv.center).tolist()
        g.rgba = [0.2, 0.4, 0.8, 0.35]
        g.group = 4
        g.contype = g.conaffinity = 0

    if world.ambient_light is not None:
        s.visual.headlight.ambient = list(world.ambient_light)
    if not world.lights:
        # the default lighting: a spotlight 10 m above the floor's centre, looking down, and
        # MuJoCo's headlight (ambient 0.1, diffuse 0.4, which follows the rendering camera)
        light = s.worldbody.add_light()
        light.name = "sun"
        light.pos = [fl.center[0], -fl.center[1], 10.0]
        light.dir = [0.0, 0.0, -1.0]
    for lt in world.lights:
        add_world_light(s, lt)
    return s


# What a false alarm of the default material looks like: the thing it imitates (a doll's
# head of pink plastic with painted eyes, a tan leather work glove, a black rubber boot, a
# mannequin's leg), colours estimated from product photographs.
FALSE_ALARM_LOOKS = {
    "Head": (0.93, 0.74, 0.66),
    "Hand": (0.72, 0.55, 0.30),
    "Foot": (0.10, 0.10, 0.10),
    "Leg": (0.88, 0.72, 0.60),
    "Arm": (0.88, 0.72, 0.60),
    "Chest": (0.88, 0.72, 0.60),
    "Pelvis": (0.88, 0.72, 0.60),
}


def add_false_alarm_look(spec: mujoco.MjSpec, g, alarm) -> None:
    """Colours a false alarm's box as what it imitates; a doll's head gets eyes and a mouth
    on its +X face (decorations seen by cameras only)."""
    from usarsim.sim.victims import EYE, LOOK_GROUP, MOUTH

    g.rgba = [*FALSE_ALARM_LOOKS.get(alarm.part, (0.88, 0.72, 0.60)), 1.0]
    if alarm.part != "Head":
        return
    hx, hy, hz = (c / 2.0 for c in alarm.size)
    for name, local, size, rgb in (
        (f"look/falsealarm/{alarm.name}/eye0", (hx, -0.3 * hy, -0.2 * hz), (0.004, 0.015, 0.015), EYE),
        (f"look/falsealarm/{alarm.name}/eye1", (hx, 0.3 * hy, -0.2 * hz), (0.004, 0.015, 0.015), EYE),
        (f"look/falsealarm/{alarm.name}/mouth", (hx, 0.0, 0.35 * hz), (0.004, 0.03, 0.008), MOUTH),
    ):
        d = spec.worldbody.add_geom()
        d.name = name
        d.type = mujoco.mjtGeom.mjGEOM_BOX
        rot = frames.euler_to_mat(*alarm.rotation)
        d.pos = frames.to_mj_vec(np.array(alarm.center) + rot @ np.array(local)).tolist()
        d.quat = g.quat
        d.size = list(size)
        d.rgba = [*rgb, 1.0]
        d.group = LOOK_GROUP
        d.contype = d.conaffinity = 0


# MuJoCo light types of the world file's light types.
LIGHT_TYPES = {
    "point": mujoco.mjtLightType.mjLIGHT_POINT,
    "spot": mujoco.mjtLightType.mjLIGHT_SPOT,
    "directional": mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
}
# A half turn about X: a mesh's vertices (USARSim axes) into the geom's own (MuJoCo) axes.
MESH_FRAME_QUAT = np.array([0.0, 1.0, 0.0, 0.0])


def add_world_light(spec: mujoco.MjSpec, lt) -> mujoco.MjsLight:
    """A light of the world file (config.world.Light) in the MuJoCo model, named
    ``light/<name>``; the diffuse colour is its colour times its intensity."""
    light = spec.worldbody.add_light()
    light.name = f"light/{lt.name}"
    light.type = LIGHT_TYPES[lt.type]
    light.pos = frames.to_mj_vec(lt.position).tolist()
    light.dir = frames.to_mj_vec(lt.direction).tolist()
    light.diffuse = [c * lt.intensity for c in lt.color]
    light.ambient = list(lt.ambient)
    light.specular = list(lt.specular)
    light.attenuation = list(lt.attenuation)
    # a point light shines all around: OpenGL's special cut-off angle of 180 degrees
    light.cutoff = 180.0 if lt.type == "point" else lt.cutoff_deg
    light.exponent = 0.0 if lt.type == "point" else lt.exponent
    light.castshadow = bool(lt.cast_shadows)
    return light
