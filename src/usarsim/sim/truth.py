"""The ground truth (protocol.md 12.4, the UDK's USARTruth): where every robot, victim, RFID
tag, false alarm and movable object is, now."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usarsim.sim import frames

if TYPE_CHECKING:
    from usarsim.sim.simulation import Simulation


def truth_rows(sim: Simulation, class_name: str | None = None, name: str | None = None) -> list[tuple]:
    """Everything the ground-truth service knows, now: (name, class, time, location,
    rotation) of every robot (its class and INIT name; the class ``Robot`` asks for every
    robot), victim (``Victim``), RFID tag
    (``RFIDTag``, named by its id), false alarm (``FalseAlarm``) and movable object
    (``MovableObject``), the landmarks of the world's element kinds (their own classes) and the
    radio relays robots dropped (``RadioRelay``, at their antennas);
    world frame, rotations in [0, 2 pi).  Filtered by class and
    name (any case) when given."""
    now = sim.time
    m, d = sim.model, sim.data
    rows: list[tuple[str, str, tuple[float, ...], tuple[float, ...]]] = []
    loc: tuple[float, ...]
    rot: tuple[float, ...]
    for r in sim.robots.values():
        loc, rot = r.handle.location(d), r.handle.orientation(d)
        rows.append((r.name, r.config.class_name, loc, rot))
    for v in sim.world.victims:
        b = m.body(f"victim/{v.name}").id
        rows.append((v.name, "Victim", frames.from_mj_vec(d.xpos[b]), frames.mj_mat_to_usar_euler(d.xmat[b])))
    for tag in sim.entities.tags.values():
        rows.append((str(tag.tag_id), "RFIDTag", tuple(tag.location), (0.0, 0.0, 0.0)))
    for a in sim.world.false_alarms:
        rows.append((a.name, "FalseAlarm", tuple(a.center), tuple(a.rotation)))
    for o in sim.world.objects:
        if o.mass_kg > 0:
            b = m.body(f"movable/{o.name}").id
            rows.append(
                (o.name, "MovableObject", frames.from_mj_vec(d.xpos[b]), frames.mj_mat_to_usar_euler(d.xmat[b]))
            )
    for lm in sim.world.landmarks:  # what the world's element kinds list (usarsim.config.elements)
        rows.append((lm.name, lm.class_name, lm.location, lm.rotation))
    for relay in sim.entities.relays:  # the radio relays robots dropped (RelayDropper)
        rows.append((relay.name, "RadioRelay", relay.location, (0.0, 0.0, 0.0)))
    robots = len(sim.robots)  # the first rows: ``{Class Robot}`` asks for every one of them
    out = []
    for i, (n, c, loc, rot) in enumerate(rows):
        if (
            class_name is None or c.lower() == class_name.lower() or (i < robots and class_name.lower() == "robot")
        ) and (name is None or n.lower() == name.lower()):
            out.append((n, c, now, tuple(float(x) for x in loc), tuple(frames.wrap_2pi(float(a)) for a in rot)))
    return out
