"""Frames of the world for observers that draw or record it (``usarsim serve --record``,
``--foxglove``): where every robot and movable object is at one simulated instant, and how
strong the radio link between robots is.

A frame is taken on the simulation thread each time the simulated clock reaches a multiple
of its period (:class:`FrameWatch`, registered with ``Simulation.every``): a read of the poses already
computed by the physics, a few microseconds per robot; the radio links (a ray cast per pair
that moved) only every ``links_period_s`` and for a bounded number of robots.  Nothing is
taken per sensor message: sensor data reach observers as the outputs the servers get.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from usarsim.sim import frames
from usarsim.sim.radio import RadioModel, RadioNet, pair_key
from usarsim.sim.worldframe import LinkFrame, LinkTraffic, ObjectFrame, RelayFrame, RobotFrame, WorldFrame

if TYPE_CHECKING:
    from usarsim.sim.simulation import Simulation

# Radio links are sampled for all pairs of at most this many robots (n (n - 1) / 2 pairs);
# beyond it a frame carries no links (the wireless servers still compute theirs).
MAX_LINK_ROBOTS = 32


def take_frame(sim: Simulation, radio: RadioNet | None = None, live: RadioNet | None = None) -> WorldFrame:
    """The poses of every robot and movable object now, and the relays dropped; with
    ``radio``, the links of every pair of robots (at most MAX_LINK_ROBOTS robots) and what the
    channel of ``live`` (the servers' radio) carried so far."""
    d, m = sim.data, sim.model
    forces = wall_forces(sim)
    robots = tuple(
        RobotFrame(
            r.uid,
            r.name,
            r.config,
            r.handle.location(d),
            tuple(frames.wrap_2pi(a) for a in r.handle.orientation(d)),  # type: ignore[arg-type]  # 3 angles
            r.battery_left(),
            r.spawn_time,
            forces.get(r.uid, 0.0),
        )
        for r in sim.robots.values()
        if not r.removed
    )
    objects = []
    for o in sim.world.objects:
        if o.mass_kg > 0:
            b = m.body(f"movable/{o.name}").id
            objects.append(
                ObjectFrame(
                    o.name,
                    frames.from_mj_vec(d.xpos[b]),
                    tuple(frames.wrap_2pi(a) for a in frames.mj_mat_to_usar_euler(d.xmat[b])),  # type: ignore[arg-type]  # 3 angles
                )
            )
    links: tuple[LinkFrame, ...] | None = None
    if radio is not None:
        found: list[LinkFrame] = []
        if len(robots) <= MAX_LINK_ROBOTS:
            antennas = RadioNet.antennas(sim)
            names = sorted(antennas)
            for i, a in enumerate(names):
                for b in names[i + 1 :]:
                    ln = radio.link(sim, a, b, antennas)
                    if ln is not None:
                        pa, pb = pair_key(a, b)
                        found.append(LinkFrame(pa, pb, ln.signal_dbm, ln.distance_m, ln.walls, ln.holds))
        links = tuple(found)
    traffic = None
    if radio is not None and live is not None and live.channel is not None:
        traffic = tuple(
            LinkTraffic(
                a,
                b,
                c.delivered,
                c.delivered_bytes,
                c.dropped["range"],
                c.dropped["loss"],
                c.dropped["capacity"],
                sum(c.dropped_bytes.values()),
                c.delay_s / c.delivered if c.delivered else 0.0,
            )
            for (a, b), c in live.counts().items()
        )
    relays = tuple(RelayFrame(r.name, r.owner, r.location) for r in sim.entities.relays)
    return WorldFrame(sim.time, robots, tuple(objects), links, traffic, relays)


# A contact counts as a push against a wall when its normal is within 60 degrees of the
# horizontal (|n_z| < sin 30 degrees = 0.5): driving on a floor, a ramp or a step is not one.
WALL_NORMAL_MAX_Z = 0.5


def wall_forces(sim: Simulation) -> dict[int, float]:
    """Robot id -> the largest normal force (N) of its contacts with static solids (geoms of
    the world body: walls, boxes, ramps) whose normal is near horizontal, now."""
    m, d = sim.model, sim.data
    n = d.ncon
    if n == 0 or not sim.robots:
        return {}
    geoms = d.contact.geom[:n]
    bodies = m.geom_bodyid[geoms]
    static = bodies == 0
    one = np.flatnonzero(static[:, 0] ^ static[:, 1])
    if one.size == 0:
        return {}
    normals_z = d.contact.frame[:n, 2]
    one = one[np.abs(normals_z[one]) < WALL_NORMAL_MAX_Z]
    if one.size == 0:
        return {}
    roots = {int(m.body_rootid[r.handle.body_id]): r.uid for r in sim.robots.values()}
    out: dict[int, float] = {}
    f6 = np.zeros(6)
    for i in one.tolist():
        other = bodies[i, 1] if static[i, 0] else bodies[i, 0]
        uid = roots.get(int(m.body_rootid[other]))
        if uid is None:
            continue
        mujoco.mj_contactForce(m, d, i, f6)
        f = abs(float(f6[0]))
        if f > out.get(uid, 0.0):
            out[uid] = f
    return out


class FrameWatch:
    """Hands a :class:`WorldFrame` to each of its observers (on the simulation thread) each
    time the simulated clock reaches a multiple of its period (:meth:`Simulation.every`): one
    frame taken for all of them.  Radio links are in the frames that fall ``links_period_s``
    after the last ones that had them, for the observers that asked for them (with a radio
    model); the others get those frames without links."""

    def __init__(self, links_period_s: float = 1.0, live: Callable[[], RadioNet | None] | None = None):
        self.links_period_s = links_period_s
        self.live = live or (lambda: None)  # the servers' radio, whose channel's counts frames carry
        self._observers: list[tuple[Callable[[WorldFrame], None], bool]] = []
        self._radio: RadioNet | None = None  # its own wall cache
        self._last_links = -math.inf

    def add(self, on_frame: Callable[[WorldFrame], None], radio_model: RadioModel | None = None) -> None:
        """Also hand frames to ``on_frame``; with ``radio_model``, with the links under it (the
        first model given is the one used)."""
        if radio_model is not None and self._radio is None:
            self._radio = RadioNet(radio_model)
        self._observers.append((on_frame, radio_model is not None))

    def __call__(self, sim: Simulation) -> None:
        now = sim.time
        radio = None
        if self._radio is not None and now - self._last_links >= self.links_period_s - 1e-9:
            radio, self._last_links = self._radio, now
        frame = take_frame(sim, radio, self.live())
        bare = None
        for on_frame, links in self._observers:
            if frame.links is not None and not links:
                bare = bare or WorldFrame(frame.time, frame.robots, frame.objects, None, None, frame.relays)
                on_frame(bare)
            else:
                on_frame(frame)
