"""What cameras see of a robot beyond its solid pieces (:class:`usarsim.config.robot.Look`):
tracks drawn round the wheels of a tracked robot, tyres with hubs on a wheeled one, and the
robot file's own pieces (bumpers, decks, masts), in the real robot's colours.

Every geom added here is seen by cameras only (``GROUP_LOOK``): no mass, no contacts, and
range sensors' rays and the victim sensor pass through it, so a robot's physics and every
reading but its pictures are those of its solid pieces alone."""

from __future__ import annotations

import math
from collections.abc import Mapping

import mujoco
import numpy as np

from usarsim.config.robot import RobotConfig
from usarsim.config.robot_parts import ChassisBox, Wheel
from usarsim.sim import frames
from usarsim.sim.constants import GROUP_LOOK

# A track's belt: rubber this thick round the wheels, this much wider than the widest of them
# (estimates from photographs of tracked rescue robots: a 1-2 cm thick rubber belt)
BELT_THICKNESS_M = 0.012
BELT_MARGIN_M = 0.004
# A hub stands this far out of the wheel's outer face, and its spoke this far out of the hub
HUB_THICKNESS_M = 0.006
SPOKE_THICKNESS_M = 0.004
SPOKE_SHADE = 0.6  # a spoke's colour: the hub's, darker
HUB_SIDES = 16  # a hub's disc is a prism of this many sides


def look_name(prefix: str, *parts: object) -> str:
    return "/".join([prefix, "look", *(str(p) for p in parts)])


def cameras_only_geom(body: mujoco.MjsBody, name: str, rgb) -> mujoco.MjsGeom:
    """A geom on ``body`` that cameras alone see, in colour ``rgb``: no mass, no contacts, in
    the group rays and the victim sensor pass through (a robot's look, a sensor's housing, a
    victim's face and hair)."""
    g = body.add_geom()
    g.name = name
    g.rgba = [*rgb, 1.0]
    g.group = GROUP_LOOK
    g.contype = g.conaffinity = 0
    g.mass = 0.0
    g.density = 0.0
    return g


def add_look(spec: mujoco.MjSpec, bodies: Mapping[str, mujoco.MjsBody], robot: RobotConfig, prefix: str) -> None:
    """Add ``robot``'s look to its bodies (``bodies``: the chassis and each link by name)."""
    look = robot.look
    if look.tracks:
        groups: dict[tuple[str, str], list[Wheel]] = {}
        for w in robot.wheels:
            groups.setdefault((w.parent, w.side), []).append(w)
        for (parent, side), wheels in groups.items():
            add_belt(bodies[parent], look_name(prefix, "track", parent, side), wheels, look.track_color)
            width = max(w.width_m for w in wheels) + BELT_MARGIN_M
            y = sum(w.position[1] for w in wheels) / len(wheels)
            for w in wheels:
                wheel_body = spec.body(f"{prefix}/{w.name}")
                if wheel_body is not None:
                    add_drum(wheel_body, f"{prefix}/{w.name}/drum", w, width, y - w.position[1], look.track_color)
    elif look.hub_color is not None:
        for w in robot.wheels:
            wheel_body = spec.body(f"{prefix}/{w.name}")
            if wheel_body is not None:
                add_hub(spec, wheel_body, f"{prefix}/{w.name}/hub", w, look.hub_ratio, look.hub_color)
    for i, piece in enumerate(look.pieces):
        set_shape(cameras_only_geom(bodies[piece.body], look_name(prefix, i), piece.color), piece.shape)


def wheel_rgba(robot: RobotConfig) -> list[float]:
    """How a wheel itself is drawn: its tyre's colour, or not at all on a tracked robot, whose
    belt's drum stands in its place (MuJoCo skips geoms of no opacity)."""
    return [0.0, 0.0, 0.0, 0.0] if robot.look.tracks else [*robot.look.tyre_color, 1.0]


def add_drum(body: mujoco.MjsBody, name: str, w: Wheel, width: float, offset_y: float, rgb) -> None:
    """The belt round wheel ``w``: a drum on the wheel's body, ``width`` wide, its middle
    ``offset_y`` along the axle from the wheel's (USARSim Y), the belt's thickness out."""
    drum = cameras_only_geom(body, name, rgb)
    drum.type = mujoco.mjtGeom.mjGEOM_CYLINDER
    drum.size = [w.radius_m + BELT_THICKNESS_M, width / 2.0, 0.0]
    drum.pos = [0.0, -offset_y, 0.0]  # MuJoCo's +Y is USARSim's -Y
    drum.quat = [math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0]  # along the axle (Y)


def disc_mesh(spec: mujoco.MjSpec, radius: float, thickness: float) -> str:
    """The name of a flat disc mesh of ``radius`` and ``thickness`` (a prism of HUB_SIDES
    sides, its axis along Y), made once a model: a hub costs the renderer a few dozen
    triangles, where MuJoCo's own cylinder costs hundreds."""
    name = f"look/disc/{radius:.4f}x{thickness:.4f}"
    if spec.mesh(name) is None:
        a = np.linspace(0.0, 2.0 * math.pi, HUB_SIDES, endpoint=False)
        ring = np.stack([radius * np.cos(a), np.zeros_like(a), radius * np.sin(a)], axis=1)
        half = np.array([0.0, thickness / 2.0, 0.0])
        mesh = spec.add_mesh()
        mesh.name = name
        mesh.uservert = np.concatenate([ring - half, ring + half]).ravel().tolist()
    return name


def add_hub(spec: mujoco.MjSpec, body: mujoco.MjsBody, name: str, w: Wheel, ratio: float, rgb) -> None:
    """A hub on the outer face of wheel ``w`` (on its body, turning with it) and a spoke
    across it that shows the wheel turning."""
    outward = 1.0 if w.side == "left" else -1.0  # MuJoCo +Y is the robot's left
    face = w.width_m / 2.0
    hub = cameras_only_geom(body, name, rgb)
    hub.type = mujoco.mjtGeom.mjGEOM_MESH
    hub.meshname = disc_mesh(spec, ratio * w.radius_m, HUB_THICKNESS_M)
    hub.pos = [0.0, outward * (face + HUB_THICKNESS_M / 2.0), 0.0]
    spoke = cameras_only_geom(body, f"{name}/spoke", [c * SPOKE_SHADE for c in rgb])
    spoke.type = mujoco.mjtGeom.mjGEOM_BOX
    spoke.size = [ratio * w.radius_m * 0.95, SPOKE_THICKNESS_M / 2.0, 0.15 * ratio * w.radius_m]
    spoke.pos = [0.0, outward * (face + HUB_THICKNESS_M + SPOKE_THICKNESS_M / 2.0), 0.0]


def _upper_chain(circles: list[tuple[np.ndarray, float]]) -> list[int]:
    """The circles (centre in the X-Z plane, radius; sorted along X) a belt's upper run touches,
    first to last: from each, the farthest circle whose tangent leaves every circle between
    below it (USARSim's Z is down: below is +Z)."""
    chain = [0]
    i = 0
    while i < len(circles) - 1:
        for j in range(len(circles) - 1, i, -1):
            p1, p2 = _tangent(circles[i], circles[j], 1.0)
            if p1 is None:
                continue
            e = p2 - p1
            n = np.array([e[1], -e[0]]) / float(np.hypot(*e))  # towards -Z (up)
            if all(float(np.dot(circles[k][0] - p1, n)) <= -circles[k][1] + 1e-9 for k in range(i + 1, j)):
                break
        chain.append(j)
        i = j
    return chain


def _tangent(a: tuple[np.ndarray, float], b: tuple[np.ndarray, float], side: float):
    """The points where the outer tangent above (``side`` 1) or below (-1) circles ``a`` and
    ``b`` (``a`` before ``b`` along X) touches them; (None, None) if one lies within the other."""
    (c1, r1), (c2, r2) = a, b
    d = c2 - c1
    dist = float(np.hypot(*d))
    if dist <= abs(r1 - r2) + 1e-6:
        return None, None
    u = d / dist
    n = np.array([u[1], -u[0]])  # u turned towards -Z (up, USARSim's Z is down)
    along = (r1 - r2) / dist
    m = along * u + side * math.sqrt(1.0 - along * along) * n
    return c1 + r1 * m, c2 + r2 * m


def belt_segments(wheels: list[Wheel], thickness: float) -> list[tuple[np.ndarray, float, float]]:
    """The straight runs of a belt round ``wheels`` (USARSim frame, in the X-Z plane of their
    body), on the lines tangent to the wheels' belt circles (radius plus half the belt's
    thickness) that pass over the top of them all and under the bottom: each run as (centre,
    length, pitch angle about MuJoCo's +Y); upper runs first."""
    ws = sorted(wheels, key=lambda w: w.position[0])
    circles = [(np.array([w.position[0], w.position[2]]), w.radius_m + thickness / 2.0) for w in ws]
    out = []
    for side in (1.0, -1.0):  # the upper runs, then the lower (the same chain, mirrored in Z)
        mirrored = [(c * np.array([1.0, side]), r) for c, r in circles]
        chain = _upper_chain(mirrored)
        for i, j in zip(chain, chain[1:], strict=False):
            p1, p2 = _tangent(circles[i], circles[j], side)
            if p1 is None:
                continue
            e = p2 - p1
            # the box's X along the run: MuJoCo's pitch taking +X onto (e_x, -e_z) there
            out.append(((p1 + p2) / 2.0, float(np.hypot(*e)), math.atan2(e[1], e[0])))
    return out


def add_belt(body: mujoco.MjsBody, name: str, wheels: list[Wheel], rgb) -> None:
    """A track's rubber belt round ``wheels`` (one side of one body): the straight runs
    (:func:`belt_segments`) on ``body``; round each wheel, a drum on the wheel's own body named
    after the wheel (the wheel itself is not drawn: :func:`wheel_rgba`)."""
    width = max(w.width_m for w in wheels) + BELT_MARGIN_M
    y = sum(w.position[1] for w in wheels) / len(wheels)
    for k, (centre, length, pitch) in enumerate(belt_segments(wheels, BELT_THICKNESS_M)):
        run = cameras_only_geom(body, f"{name}/run{k}", rgb)
        run.type = mujoco.mjtGeom.mjGEOM_BOX
        run.size = [length / 2.0, width / 2.0, BELT_THICKNESS_M / 2.0]
        run.pos = frames.to_mj_vec((centre[0], y, centre[1])).tolist()
        run.quat = [math.cos(pitch / 2.0), 0.0, math.sin(pitch / 2.0), 0.0]


def set_shape(g: mujoco.MjsGeom, piece: ChassisBox) -> None:
    """Give geom ``g`` the shape, place and rotation of ``piece`` (a robot file's shape)."""
    g.pos = frames.to_mj_vec(piece.center).tolist()
    if piece.shape == "box":
        g.type = mujoco.mjtGeom.mjGEOM_BOX
        g.size = [piece.size[0] / 2.0, piece.size[1] / 2.0, piece.size[2] / 2.0]
    elif piece.shape == "sphere":
        g.type = mujoco.mjtGeom.mjGEOM_SPHERE
        g.size = [piece.radius_m, 0.0, 0.0]
    else:
        g.type = mujoco.mjtGeom.mjGEOM_CYLINDER if piece.shape == "cylinder" else mujoco.mjtGeom.mjGEOM_CAPSULE
        g.size = [piece.radius_m, piece.length_m / 2.0, 0.0]
    g.quat = frames.usar_euler_to_mj_quat(piece.rotation).tolist()
