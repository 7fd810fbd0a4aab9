"""Things in a world that sensors look for, beyond plain geometry: victims and their
body parts, false alarms, RFID tags (with writable memory, shared by every robot),
which geoms each kind of sensor sees through (glass), and the special effects of
materials on rays: mirrors and grid fenders (porosity).

Geoms are found by the names the builder gives them (``victim/<name>/<Part>/<i>``,
``falsealarm/<name>/<Part>``, ``world/<object>``), again after every model build.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import cast

import mujoco
import numpy as np

from usarsim.config.world import SEE_THROUGH_KINDS, WorldConfig
from usarsim.sim import frames
from usarsim.sim.constants import WAVE_AMPLITUDE_RAD, WAVE_PERIOD_S

# Tag ids handed to tags dropped by an RFIDReleaser start here (world tags keep theirs).
RELEASED_TAG_FIRST_ID = 20000


def _waving_terms(rotations: list[tuple[float, float, float]]) -> tuple[np.ndarray, np.ndarray]:
    """For arms at rest at ``rotations`` (roll, pitch, yaw in the USARSim frame), the
    quaternions A and B (rows, MuJoCo frame) with which an arm raised by ``lift`` (its pitch
    ``pitch - lift``) is turned by ``cos(lift/2) A + sin(lift/2) B``.

    In the MuJoCo frame the arm turns by Rz(-yaw) Ry(-pitch + lift) Rx(roll)
    (:func:`usarsim.sim.frames.usar_euler_to_mj_mat`), and the lift about the same axis as
    the pitch splits off: q = P Ry(lift) R with P = qz(-yaw) qy(-pitch), R = qx(roll), and
    Ry(lift) = cos(lift/2) + sin(lift/2) j.  So A = P R and B = P j R, made once; a
    stretch of physics steps then turns every arm with two multiplications."""
    at_rest, lifting = np.zeros((len(rotations), 4)), np.zeros((len(rotations), 4))
    j = np.array([0.0, 0.0, 1.0, 0.0])
    for i, (roll, pitch, yaw) in enumerate(rotations):
        qz = np.array([math.cos(-0.5 * yaw), 0.0, 0.0, math.sin(-0.5 * yaw)])
        qy = np.array([math.cos(-0.5 * pitch), 0.0, math.sin(-0.5 * pitch), 0.0])
        qx = np.array([math.cos(0.5 * roll), math.sin(0.5 * roll), 0.0, 0.0])
        p, pj = np.zeros(4), np.zeros(4)
        mujoco.mju_mulQuat(p, qz, qy)
        mujoco.mju_mulQuat(at_rest[i], p, qx)
        mujoco.mju_mulQuat(pj, p, j)
        mujoco.mju_mulQuat(lifting[i], pj, qx)
    return at_rest, lifting


@dataclass
class Tag:
    """An RFID tag: integer id, world position (USARSim frame) and memory."""

    tag_id: int
    location: tuple[float, float, float]
    memory: str = ""


@dataclass(frozen=True)
class RelayNode:
    """A radio relay a robot dropped (a ``RelayDropper``'s breadcrumb): its name on the radio
    (``<robot>-Relay<k>``), the robot that dropped it, where its antenna is (USARSim frame) and
    when it was dropped (simulated seconds)."""

    name: str
    owner: str
    location: tuple[float, float, float]
    time: float


@dataclass(frozen=True)
class PartHit:
    """What a geom of a victim or a false alarm is to the victim sensor: whose part it is, which body part, and
    whether it is a false alarm."""

    owner: str  # victim or false-alarm name
    part: str  # Head, Chest, ...
    false_alarm: bool


class Entities:
    """A world's victims, false alarms and RFID tags as the sensors meet them in the model: which geom is which body
    part, what each kind of sensor's rays pass through (glass, mirrors, grid fenders), the waving arms, and the tags
    with their memory, shared by every robot."""

    def __init__(self, world: WorldConfig):
        self.world = world
        self.tags: dict[int, Tag] = {
            t.tag_id: Tag(t.tag_id, cast("tuple[float, float, float]", tuple(t.location)), t.memory)
            for t in world.rfid_tags
        }
        self._next_id = max([RELEASED_TAG_FIRST_ID - 1, *self.tags]) + 1
        self.relays: list[RelayNode] = []  # dropped by robots (RelayDropper), in the order dropped
        self._tag_rows: tuple[list[int], np.ndarray] | None = None  # see tag_positions
        self.parts: dict[int, PartHit] = {}
        self._part_ids: np.ndarray | None = None
        self._part_rbound = np.empty(0)
        # per sensor kind: the geoms its rays pass through; plus "mirror" (bool per geom) and
        # "porosity" (fraction of rays let through, per geom) when the world has such materials
        self.see_through: dict[str, np.ndarray] = {}
        # per waving arm: its mocap body, and the quaternions A and B of _waving_terms
        self._wave_terms: list[tuple[int, tuple, tuple]] = []
        self._victims = {v.name: v for v in world.victims}

    # After each build ---------------------------------------------------------------
    def resolve(self, m: mujoco.MjModel) -> None:
        self.parts.clear()
        self._part_ids = None
        mats = {f"world/{o.name}": self.world.materials[o.material] for o in self.world.objects}
        mats["floor"] = self.world.materials[self.world.floor.material]
        for a in self.world.false_alarms:
            mats[f"falsealarm/{a.name}/{a.part}"] = self.world.materials[a.material]
        see = {k: np.zeros(m.ngeom, dtype=bool) for k in SEE_THROUGH_KINDS}
        mirror = np.zeros(m.ngeom, dtype=bool)
        porosity = np.zeros(m.ngeom)
        for g in range(m.ngeom):
            name = m.geom(g).name
            if name.startswith("victim/"):
                _, owner, part, _ = name.split("/", 3)
                self.parts[g] = PartHit(owner, part, False)
            elif name.startswith("falsealarm/"):
                _, owner, part = name.split("/", 2)
                self.parts[g] = PartHit(owner, part, True)
            mat = mats.get(name)
            if mat is not None:
                for k in mat.see_through:
                    see[k][g] = True
                mirror[g] = mat.mirror
                porosity[g] = mat.porosity
        # the ray caster takes the effects along with the see-through masks (RayCaster's
        # reserved entries "mirror" and "porosity"), present only when a material has them
        if mirror.any():
            see["mirror"] = mirror
        if porosity.any():
            see["porosity"] = porosity
        self.see_through = see
        self._part_ids = np.array(sorted(self.parts), dtype=np.intp)
        self._part_rbound = m.geom_rbound[self._part_ids] if len(self._part_ids) else np.empty(0)
        wavers = [v for v in self.world.victims if v.waving]
        at_rest, lifting = _waving_terms([v.rotation for v in wavers])
        self._wave_terms = [
            (int(m.body_mocapid[m.body(f"victim/{v.name}/shoulder").id]), tuple(a.tolist()), tuple(b.tolist()))
            for v, a, b in zip(wavers, at_rest, lifting)
        ]

    def parts_within(
        self,
        d: mujoco.MjData,
        pos: np.ndarray,
        reach: float,
        forward: np.ndarray | None = None,
        half_angle: float = math.pi,
    ) -> bool:
        """Whether any victim or false-alarm part is within ``reach`` of ``pos`` (MuJoCo
        frame) and, with ``forward`` (a unit vector), inside the cone of ``half_angle``
        about it (a part counts if any of its bounding sphere is)."""
        if self._part_ids is None or len(self._part_ids) != len(self.parts):
            self._part_ids = np.array(sorted(self.parts), dtype=np.intp)
        if not len(self._part_ids):
            return False
        delta = d.geom_xpos[self._part_ids] - pos
        dist = np.linalg.norm(delta, axis=1)
        near = dist - self._part_rbound <= reach
        if forward is None or half_angle >= math.pi or not near.any():
            return bool(near.any())
        cos_to = (delta[near] @ forward) / np.maximum(dist[near], 1e-9)
        spread = np.arcsin(np.clip(self._part_rbound[near] / np.maximum(dist[near], 1e-9), 0.0, 1.0))
        return bool((np.arccos(np.clip(cos_to, -1.0, 1.0)) <= half_angle + spread).any())

    # Each stretch of physics steps ------------------------------------------------------
    def update(self, d: mujoco.MjData, time: float) -> None:
        """Move the waving victims' arms to their angle at ``time``: raised (a negative pitch, about
        the shoulder's left-right axis) from 0 at whole periods to twice the amplitude half a
        period later."""
        if not self._wave_terms:
            return
        lift = WAVE_AMPLITUDE_RAD * (1.0 - math.cos(2.0 * math.pi * time / WAVE_PERIOD_S))
        # the arm's orientation (roll, pitch - lift, yaw), as cos(lift/2) A + sin(lift/2) B
        # (in Python floats: a few arms cost less so than with numpy's calls)
        c, s = math.cos(0.5 * lift), math.sin(0.5 * lift)
        quat = d.mocap_quat
        for mocap, a, b in self._wave_terms:
            quat[mocap] = (c * a[0] + s * b[0], c * a[1] + s * b[1], c * a[2] + s * b[2], c * a[3] + s * b[3])

    @property
    def has_motion(self) -> bool:
        return bool(self._wave_terms)

    def victim(self, name: str):
        return self._victims.get(name)

    # RFID --------------------------------------------------------------------------------
    def tag_positions(self) -> tuple[list[int], np.ndarray]:
        """The id and position (MuJoCo frame, one row each) of every tag, in the order of
        ``tags``.  Tags are only ever added and never move, so the rows are made again only
        when their number changes (every RFID reading of every robot used to make them)."""
        rows = self._tag_rows
        if rows is None or len(rows[0]) != len(self.tags):
            ids = list(self.tags)
            rows = (ids, np.array([frames.to_mj_vec(self.tags[i].location) for i in ids], dtype=float).reshape(-1, 3))
            self._tag_rows = rows
        return rows

    def drop_relay(self, owner: str, location: tuple[float, float, float], time: float) -> RelayNode:
        """A relay node of ``owner``'s, its antenna at ``location`` (USARSim frame), from now on
        a radio of the wireless simulation (usarsim.sim.radio)."""
        k = sum(1 for r in self.relays if r.owner == owner) + 1
        loc = cast("tuple[float, float, float]", tuple(float(v) for v in location))
        node = RelayNode(f"{owner}-Relay{k}", owner, loc, float(time))
        self.relays.append(node)
        return node

    def release_tag(self, location: tuple[float, float, float]) -> Tag:
        tag = Tag(self._next_id, cast("tuple[float, float, float]", tuple(float(v) for v in location)), "")
        self._next_id += 1
        self.tags[tag.tag_id] = tag
        return tag
