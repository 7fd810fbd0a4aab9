"""A robot's part of the MuJoCo model: its chassis, wheels and treads, links and joint
servos, cameras and touch probes, added to a world's ``MjSpec`` (:mod:`usarsim.sim.builder`)
while the simulation runs and removed again when its client leaves."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from usarsim.config.robot import MountedItem, RobotConfig
from usarsim.sim import frames
from usarsim.sim.constants import (
    GROUP_ROBOT,
    GROUP_WHEEL,
    ROLL_FRICTION,
    SOLID_CONAFFINITY,
    SOLID_CONTYPE,
    SPIN_FRICTION,
    TREAD_WHEEL_CONAFFINITY,
    TREAD_WHEEL_CONTYPE,
    WHEEL_CONAFFINITY,
    WHEEL_CONTYPE,
)
from usarsim.sim.plugins import PluginSet, builtin_plugins
from usarsim.sim.robotlook import add_look, cameras_only_geom, set_shape, wheel_rgba

if TYPE_CHECKING:
    from usarsim.robots.base import DriveModel
    from usarsim.sensors.base import Item


def add_robot(
    spec: mujoco.MjSpec,
    robot: RobotConfig,
    prefix: str,
    location,
    rotation,
    drive: DriveModel[Any, Any],
    items: Sequence[Item[Any]] = (),
) -> mujoco.MjsBody:
    """Add a robot's bodies, joints and actuators under ``prefix``; its chassis origin at
    ``location`` (USARSim frame) with ``rotation`` (roll, pitch, yaw).  ``drive``, the
    robot's drive model (:mod:`usarsim.robots`), adds what its kind needs on the chassis (an
    aerial robot's rotors); each of ``items``, its mounted items, adds what it needs
    (:meth:`usarsim.sensors.base.Item.build`)."""
    body = spec.worldbody.add_body()
    body.name = prefix
    body.pos = frames.to_mj_vec(location).tolist()
    body.quat = frames.usar_euler_to_mj_quat(rotation).tolist()
    root = body.add_freejoint()
    root.name = f"{prefix}/root"
    for i, piece in enumerate(robot.chassis):
        _add_piece(body, f"{prefix}/chassis{i}", piece, robot)
    drive.build(spec, body, robot, prefix)
    # the headlight (every robot has one, protocol.md 8): a spotlight at the front of the
    # body, looking forward, off until DRIVE {Light True}
    lamp = body.add_light()
    lamp.name = f"{prefix}/headlight"
    lamp.pos = frames.to_mj_vec((robot.geometry.dimensions[0] / 2.0, 0.0, 0.0)).tolist()
    lamp.dir = [1.0, 0.0, 0.0]
    lamp.cutoff = 35.0
    lamp.exponent = 10.0
    lamp.diffuse = [0.9, 0.9, 0.8]
    lamp.castshadow = False
    lamp.active = False
    bodies = {"chassis": body}
    treads = drive.treads(robot)
    for w in robot.wheels:
        if w.parent == "chassis":
            _add_wheel(spec, body, w, robot, prefix, treads)
    for ln in robot.links:
        lb = bodies[ln.parent].add_body()
        lb.name = f"{prefix}/{ln.name}"
        lb.pos = frames.to_mj_vec(ln.location).tolist()
        lb.quat = frames.usar_euler_to_mj_quat(ln.orientation).tolist()
        if drive.GRAVITY_COMPENSATED:
            lb.gravcomp = 1.0
        j = lb.add_joint()
        j.name = f"{prefix}/{ln.name}"
        j.type = mujoco.mjtJoint.mjJNT_HINGE if ln.joint == "revolute" else mujoco.mjtJoint.mjJNT_SLIDE
        j.axis = frames.to_mj_vec(ln.axis).tolist()
        j.armature = ln.armature
        if ln.limited:
            j.limited = mujoco.mjtLimited.mjLIMITED_TRUE
            # MinRange == MaxRange locks the joint; MuJoCo wants a range of some width
            j.range = [ln.min_range, max(ln.max_range, ln.min_range + LOCKED_WIDTH)]
        if ln.shapes:
            for k, piece in enumerate(ln.shapes):
                g = _add_piece(lb, f"{prefix}/{ln.name}/{k}", piece, robot)
                if not ln.collide:
                    g.contype = g.conaffinity = 0
        else:  # a massless link would make the joint singular: a small point mass
            lb.mass = 0.01
            lb.inertia = [1e-5, 1e-5, 1e-5]
            lb.explicitinertial = True
        a = spec.add_actuator()
        a.name = f"{prefix}/{ln.name}"
        a.target = f"{prefix}/{ln.name}"
        a.trntype = mujoco.mjtTrn.mjTRN_JOINT
        a.forcelimited = 1
        a.forcerange = [-ln.max_torque, ln.max_torque]
        # a position servo that follows a set point moving at the commanded speed: the set
        # point is the actuator's activation, integrated from ctrl (rad/s or m/s) and held
        # within actrange, which the simulation narrows to stop it at a target angle
        kp, kv = joint_servo_gains(ln)
        a.dyntype = mujoco.mjtDyn.mjDYN_INTEGRATOR
        a.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        a.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        a.gainprm[0] = kp
        a.biasprm[0], a.biasprm[1], a.biasprm[2] = 0.0, -kp, -kv
        a.actlimited = 1
        a.actrange = joint_travel(ln)
        bodies[ln.name] = lb
    for w in robot.wheels:
        if w.parent != "chassis":
            _add_wheel(spec, bodies[w.parent], w, robot, prefix, treads)
    add_look(spec, bodies, robot, prefix)
    # a robot's parts do not collide with each other (MuJoCo filters parent and child only)
    # parent -> child pairs are filtered by MuJoCo already; every other pair of the robot's
    # jointed bodies (chassis, links, wheels on links) is excluded
    parent_of = {
        f"{prefix}/{ln.name}": (prefix if ln.parent == "chassis" else f"{prefix}/{ln.parent}") for ln in robot.links
    }
    parent_of.update(
        {
            f"{prefix}/{w.name}": (prefix if w.parent == "chassis" else f"{prefix}/{w.parent}")
            for w in robot.wheels
            if w.parent != "chassis"
        }
    )
    # a steered wheel hangs on its knuckle: exclude it from the chassis (wheel wells)
    parent_of.update({f"{prefix}/{w.name}": f"{prefix}/{w.name}/knuckle" for w in robot.wheels if w.steer != "none"})
    names = [prefix, *parent_of]
    for i, a_name in enumerate(names):
        for b_name in names[i + 1 :]:
            if parent_of.get(b_name) == a_name or parent_of.get(a_name) == b_name:
                continue
            ex = spec.add_exclude()
            ex.bodyname1, ex.bodyname2 = a_name, b_name
    for part in items:  # what each mounted item adds (a camera, a touch probe, a grasp's weld), in the file's order
        part.build(spec, body, prefix)
    _add_chase_camera(body, robot, prefix)
    return body


# Items the image server renders (cameras), and the MuJoCo camera each becomes (add_camera): it
# looks along the item's X axis with its Z axis (down in USARSim's frame) at the bottom of the
# picture.
# a MuJoCo camera looks along its -Z with +Y up and +X to the right; in an item's own
# MuJoCo-frame axes (forward, left, up) those are: right = -left, up, -forward
_CAMERA_AXES = np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def camera_name(prefix: str, item_name: str) -> str:
    return f"{prefix}/camera/{item_name}"


def camera_fovy_deg(hfov_rad: float, width: int, height: int) -> float:
    """MuJoCo's vertical field of view for a horizontal one at a picture's aspect."""
    return math.degrees(2.0 * math.atan(math.tan(min(hfov_rad, math.radians(179.0)) / 2.0) * height / width))


def mount_body(spec: mujoco.MjSpec, chassis: mujoco.MjsBody, item: MountedItem, prefix: str) -> mujoco.MjsBody:
    """The body an item rides on: the chassis when it is mounted ``HARD``, else its robot's part."""
    if item.mount == "HARD":
        return chassis
    return spec.body(f"{prefix}/{item.mount}") or chassis


def add_housing(
    spec: mujoco.MjSpec,
    chassis: mujoco.MjsBody,
    item: MountedItem,
    prefix: str,
    *,
    box: tuple[float, float, float] | None = None,
    disc: tuple[float, float] | None = None,
    rgb: tuple[float, float, float],
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> None:
    """What cameras see of a mounted item's own body (a laser's housing, a camera's case): a
    ``box`` (full extents along the item's X, Y, Z) or a ``disc`` (radius, thickness, facing
    along the item's X) at the item's place and turned as it is, its centre ``offset`` in the
    item's frame (USARSim, metres), on the item's mount.  Cameras only: it has no mass and no
    contacts, and range sensors' rays and the victim sensor pass through it."""
    parent = mount_body(spec, chassis, item, prefix)
    rot = frames.usar_euler_to_mj_mat(item.orientation)
    g = cameras_only_geom(parent, f"{prefix}/housing/{item.name}", rgb)
    g.pos = (frames.to_mj_vec(item.location) + rot @ frames.to_mj_vec(offset)).tolist()
    if box is not None:
        g.type = mujoco.mjtGeom.mjGEOM_BOX
        g.size = [box[0] / 2.0, box[1] / 2.0, box[2] / 2.0]
        g.quat = frames.mat_to_quat(rot).tolist()
    elif disc is not None:
        g.type = mujoco.mjtGeom.mjGEOM_CYLINDER  # along its own Z: turned onto the item's X
        g.size = [disc[0], disc[1] / 2.0, 0.0]
        along_x = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
        g.quat = frames.mat_to_quat(rot @ along_x).tolist()


def add_camera(spec: mujoco.MjSpec, chassis: mujoco.MjsBody, item: MountedItem, prefix: str) -> None:
    """A camera item's MuJoCo camera at its mount, looking along the item's X axis."""
    parent = mount_body(spec, chassis, item, prefix)
    cam = parent.add_camera()
    cam.name = camera_name(prefix, item.name)
    cam.pos = frames.to_mj_vec(item.location).tolist()
    cam.quat = frames.mat_to_quat(frames.usar_euler_to_mj_mat(item.orientation) @ _CAMERA_AXES).tolist()
    cam.fovy = camera_fovy_deg(math.radians(50.0), 4, 3)  # set from the camera's zoom at each picture


# The chase view (the spectator's view over a robot, manual 5.1: key C): a camera on the
# chassis, behind and above the robot, looking down at it.  Viewers bind to it under the
# reserved camera name CHASE_CAMERA, like to any camera the robot carries.
CHASE_CAMERA = "Chase"
CHASE_FOV_RAD = math.radians(70.0)  # horizontal field of view
CHASE_MIN_BACK_M, CHASE_MIN_UP_M = 1.2, 0.7  # how far behind and above the chassis origin, at least


def chase_camera_name(prefix: str) -> str:
    return f"{prefix}/chase"


def chase_camera_pose(robot: RobotConfig) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Where the chase camera sits on the chassis (USARSim robot frame) and its orientation:
    2.5 robot lengths behind and 2 heights above the origin (at least 1.2 m and 0.7 m),
    pitched down to look at a point half a length ahead of the origin."""
    length, _, height = robot.geometry.dimensions
    back = max(CHASE_MIN_BACK_M, 2.5 * length)
    up = max(CHASE_MIN_UP_M, 2.0 * height)
    pitch = -math.atan2(up, back + 0.5 * length)
    return (-back, 0.0, -up), (0.0, pitch, 0.0)


def _add_chase_camera(chassis, robot: RobotConfig, prefix: str) -> None:
    location, orientation = chase_camera_pose(robot)
    cam = chassis.add_camera()
    cam.name = chase_camera_name(prefix)
    cam.pos = frames.to_mj_vec(location).tolist()
    cam.quat = frames.mat_to_quat(frames.usar_euler_to_mj_mat(orientation) @ _CAMERA_AXES).tolist()
    cam.fovy = camera_fovy_deg(CHASE_FOV_RAD, 4, 3)


# Joint servo (manual 3.2.3: a joint is driven at its speed towards a target angle, with
# up to its torque): a stiff position servo follows a set point that moves at the link's
# MaxSpeed; it reaches full torque POSITION_BAND_RAD away from the set point, and is
# critically damped on the link's reflected inertia (its armature).
POSITION_BAND_RAD = 0.02
UNLIMITED = 1.0e6  # set-point range of a continuous joint
LOCKED_WIDTH = 1.0e-6  # the width given to the range of a locked joint (MinRange == MaxRange)


def joint_servo_gains(ln) -> tuple[float, float]:
    """(kp, kv) of a link's position servo."""
    kp = ln.max_torque / POSITION_BAND_RAD
    return kp, 2.0 * math.sqrt(kp * max(ln.armature, 1e-3))


def joint_travel(ln) -> tuple[float, float]:
    if not ln.limited:
        return -UNLIMITED, UNLIMITED
    return ln.min_range, max(ln.max_range, ln.min_range + LOCKED_WIDTH)


# Steering knuckles: a stiff position servo turns a steered wheel about the vertical
# (positive = to the right, as yaw) with up to the robot's steer_torque_nm, reached
# STEER_BAND_RAD away from the commanded angle.
STEER_BAND_RAD = 0.05


def _add_wheel(spec, parent, w, robot, prefix: str, treads=None) -> None:
    """A wheel on its parent body, with a steering knuckle in between when it is steered;
    with ``treads`` (usarsim.robots.base.Treads) it meets the floor through its tread."""
    # wheel cylinders lie along MuJoCo's Y axis (the axle)
    axle_quat = [math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0]
    holder = parent
    pos = frames.to_mj_vec(w.position).tolist()
    if w.steer != "none":
        knuckle = parent.add_body()
        knuckle.name = f"{prefix}/{w.name}/knuckle"
        knuckle.pos = pos
        knuckle.mass = 0.05
        knuckle.inertia = [1e-4, 1e-4, 1e-4]
        knuckle.explicitinertial = True
        sj = knuckle.add_joint()
        sj.name = f"{prefix}/{w.name}/steer"
        sj.type = mujoco.mjtJoint.mjJNT_HINGE
        sj.axis = [0.0, 0.0, -1.0]  # USARSim Z is down: positive steers right
        sj.armature = 0.01
        limit = robot.max_front_steer_rad if w.steer == "front" else robot.max_rear_steer_rad
        if w.steer in ("front", "rear") and limit > 0:
            sj.limited = mujoco.mjtLimited.mjLIMITED_TRUE
            sj.range = [-limit - 0.01, limit + 0.01]
        sa = spec.add_actuator()
        sa.name = f"{prefix}/{w.name}/steer"
        sa.target = f"{prefix}/{w.name}/steer"
        sa.trntype = mujoco.mjtTrn.mjTRN_JOINT
        kp = robot.steer_torque_nm / STEER_BAND_RAD
        sa.set_to_position(kp=kp, kv=0.1 * kp)
        sa.forcelimited = 1
        sa.forcerange = [-robot.steer_torque_nm, robot.steer_torque_nm]
        holder, pos = knuckle, [0.0, 0.0, 0.0]
    wb = holder.add_body()
    wb.name = f"{prefix}/{w.name}"
    wb.pos = pos
    j = wb.add_joint()
    j.name = f"{prefix}/{w.name}"
    j.type = mujoco.mjtJoint.mjJNT_HINGE
    j.axis = [0.0, 1.0, 0.0]  # MuJoCo +Y is the robot's left: positive spin rolls forward
    j.armature = 0.01
    g = wb.add_geom()
    g.name = f"{prefix}/{w.name}"
    g.type = mujoco.mjtGeom.mjGEOM_CYLINDER
    g.size = [w.radius_m, w.width_m / 2.0, 0.0]
    g.quat = axle_quat
    g.mass = w.mass_kg
    g.friction = [robot.wheel_friction, SPIN_FRICTION, ROLL_FRICTION]
    g.rgba = wheel_rgba(robot)
    g.group = GROUP_WHEEL
    g.contype, g.conaffinity = WHEEL_CONTYPE, WHEEL_CONAFFINITY
    if treads is not None:
        g.contype, g.conaffinity = TREAD_WHEEL_CONTYPE, TREAD_WHEEL_CONAFFINITY
        _add_tread(spec, wb, w, robot, prefix, treads)
        if w.driven:
            j.armature = max(j.armature, treads.drive_inertia_kg * w.radius_m**2)
    if w.driven:
        a = spec.add_actuator()
        a.name = f"{prefix}/{w.name}"
        a.target = f"{prefix}/{w.name}"
        a.trntype = mujoco.mjtTrn.mjTRN_JOINT
        a.set_to_velocity(kv=robot.wheel_gain)
        a.forcelimited = 1
        a.forcerange = [-robot.wheel_torque_limit_nm, robot.wheel_torque_limit_nm]


def tread_name(prefix: str, wheel_name: str) -> str:
    return f"{prefix}/{wheel_name}/tread"


def _add_tread(spec, wheel_body, w, robot, prefix: str, treads) -> None:
    """The wheel's tread contact with the floor: an invisible capsule of the wheel's radius
    along the axle, as wide as the wheel (it touches the floor at the two edges of the
    tread, as the cylinder does), in an explicit contact pair with the floor whose friction
    is the contact's usual one (the larger of the two, or the slippery floor's) along the
    rolling direction and ``treads.lateral_ratio`` of it across."""
    g = wheel_body.add_geom()
    g.name = tread_name(prefix, w.name)
    g.type = mujoco.mjtGeom.mjGEOM_CAPSULE
    g.size = [w.radius_m, w.width_m / 2.0, 0.0]
    g.quat = [math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0]  # along the axle (Y)
    g.mass = 0.0
    g.density = 0.0
    g.contype = g.conaffinity = 0  # it meets the floor through its pair only
    g.group = GROUP_WHEEL
    g.rgba = [0.0, 0.0, 0.0, 0.0]
    floor = spec.geom("floor")
    mu = float(floor.friction[0]) if floor.priority > 0 else max(float(floor.friction[0]), robot.wheel_friction)
    p = spec.add_pair()
    p.name = g.name
    p.geomname1 = "floor"
    p.geomname2 = g.name
    p.condim = 3
    p.solref = list(treads.solref)
    # the capsule's contact frame: first tangent along its axis (across the tread)
    p.friction = [mu * treads.lateral_ratio, mu, SPIN_FRICTION, ROLL_FRICTION, ROLL_FRICTION]


def _add_piece(body, name: str, piece, robot) -> mujoco.MjsGeom:
    g = body.add_geom()
    g.name = name
    set_shape(g, piece)
    g.mass = piece.mass_kg
    if piece.friction is not None:
        # its own friction wins over the surface's (MuJoCo otherwise takes the larger one):
        # a caster ball stays slippery on any floor
        g.friction = [piece.friction, SPIN_FRICTION, ROLL_FRICTION]
        g.priority = 1
    g.rgba = list(robot_rgba(robot))
    g.group = GROUP_ROBOT
    g.contype, g.conaffinity = SOLID_CONTYPE, SOLID_CONAFFINITY
    return g


def robot_rgba(robot: RobotConfig) -> tuple[float, float, float, float]:
    """The body's colour in pictures: the robot file's ``color`` (opaque)."""
    return (*robot.color, 1.0)


def remove_robot(spec: mujoco.MjSpec, prefix: str) -> None:
    for a in list(spec.actuators):
        if a.name.startswith(prefix + "/"):
            spec.delete(a)
    for p in list(spec.pairs):
        if p.name.startswith(prefix + "/"):
            spec.delete(p)
    for e in list(spec.equalities):
        if e.name.startswith(prefix + "/"):
            spec.delete(e)
    for ex in list(spec.excludes):
        if ex.bodyname1 == prefix or ex.bodyname1.startswith(prefix + "/"):
            spec.delete(ex)
    body = spec.body(prefix)
    if body is not None:
        spec.delete(body)


def robot_model_summary(robot: RobotConfig, plugins: PluginSet | None = None) -> str:
    """Compile a robot alone on a plane: checks that its drive model has what it needs and that
    MuJoCo accepts it (``plugins``: the drives and items to build it from; the built-in ones
    by default)."""
    from usarsim.config.world import bare_world
    from usarsim.sim.builder import world_spec

    plugins = plugins or builtin_plugins()
    world = bare_world("check")
    spec = world_spec(world)
    items = [plugins.make_item(item, robot, 0, "check") for item in robot.items]
    add_robot(spec, robot, "r", (0.0, 0.0, -1.0), (0.0, 0.0, 0.0), plugins.make_drive(robot), items)
    m = spec.compile()
    return f"{m.nbody - 1} bodies, {m.njnt} joints, {m.nu} actuators, {m.ngeom - 1} geoms"
