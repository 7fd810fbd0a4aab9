"""The radio links of the wireless simulation (manual section 3.2.4; protocol.md 12) between
robots and the relays they drop: a link holds while the signal its model
(:mod:`usarsim.sim.radiomodels`) gives is at least the cutoff.

:class:`RadioNet` holds the links' state on the simulation thread: signals are computed
from the simulated poses, so in lock-step a link's fate depends on simulated time only.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from usarsim.config.channel import ChannelConfig
from usarsim.sim import frames
from usarsim.sim.channel import (
    SENSITIVITY_FRAME_BYTES,
    Channel,
    LinkCounts,
    LinkView,
    Shadowing,
    packet_error_rate,
)
from usarsim.sim.radiomodels import (
    MIN_DISTANCE_M,
    PRESETS,
    RADIO_MODELS,
    DistanceModel,
    PerfectModel,
    RadioModel,
    Waf2009Model,
    model_names,
    new_model,
    resolve_channel,
    resolve_model,
    waf_signal_dbm,
)
from usarsim.sim.routing import best_route

if TYPE_CHECKING:
    from usarsim.sim.simulation import Simulation

Point = tuple[float, float, float]  # an antenna, MuJoCo frame

# the models, where they were always imported from
__all__ = [
    "MIN_DISTANCE_M",
    "PRESETS",
    "RADIO_MODELS",
    "DistanceModel",
    "Link",
    "PerfectModel",
    "RadioModel",
    "RadioNet",
    "Waf2009Model",
    "link_quality",
    "model_names",
    "new_model",
    "pair_key",
    "resolve_channel",
    "resolve_model",
    "waf_signal_dbm",
]

# --------------------------------------------------------------------------- links


Pair = tuple[str, str]


def link_quality(margin_db: float) -> float:
    """A link's quality: the share of 1,024-byte messages a signal ``margin_db`` above the
    cutoff lets through (:func:`usarsim.sim.channel.packet_error_rate`, before fading and the
    loss model), 0 to 1."""
    return 1.0 - packet_error_rate(margin_db, SENSITIVITY_FRAME_BYTES)


def pair_key(a: str, b: str) -> Pair:
    """Two robot names as one key, whatever their order and letter case."""
    a, b = a.lower(), b.lower()
    return (a, b) if a <= b else (b, a)


@dataclass(frozen=True)
class Link:
    """The radio link between two robots at one simulated instant."""

    signal_dbm: float
    distance_m: float
    walls: int
    holds: bool
    # the radios a routed link goes through (relays and robots, in order); () for a direct one.
    # A routed link's signal is its weakest hop's, its distance and walls its hops' sums
    via: tuple[str, ...] = ()


class RadioNet:
    """The radio links between robots, computed on the simulation thread from their
    simulated poses (antenna: the chassis origin).

    The servers name the pairs they depend on in ``watched`` (a frozenset, replaced as a
    whole from their thread); at the end of every advance of the clock the link of each
    watched pair is computed and ``on_change(time, [(pair, holds), ...])`` is called
    (on the simulation thread) with those whose state changed since it was last reported,
    or that are new.  ``check`` computes one link at once (and reports it likewise).
    ``min_interval_s`` spaces the evaluations out (0 in lock-step: every STEP).
    """

    def __init__(self, model: RadioModel, channel: ChannelConfig | None = None, seed: int = 0):
        self.model = model
        cfg = channel if channel is not None else ChannelConfig()
        self.shadowing = Shadowing(cfg, cfg.seed if cfg.seed is not None else seed)
        # the messages under way (None: the ideal channel, servers relay at once)
        self.channel: Channel | None = None if cfg.ideal else Channel(cfg, seed)
        self.watched: frozenset[Pair] = frozenset()
        self.on_change: Callable[[float, list[tuple[Pair, bool]]], None] | None = None
        # with a channel, after each evaluation: on_views(time, {pair: LinkView | None}), what the
        # channel's messages are judged by (by whoever drives it, on its own thread)
        self.on_views: Callable[[float, dict[Pair, LinkView | None]], None] | None = None
        self.min_interval_s = 0.0
        self._reported: dict[Pair, bool] = {}
        self._walls: dict[Pair, tuple[Point, Point, int]] = {}
        self._last = -math.inf

    # robots ---------------------------------------------------------------------------
    @staticmethod
    def positions(sim: Simulation) -> list[tuple[str, tuple[float, float, float], bool]]:
        """(name, location in the world frame, battery empty) of every robot."""
        d = sim.data
        return [(r.name, r.handle.location(d), r.battery_empty) for r in sim.robots.values()]

    # walls ----------------------------------------------------------------------------
    @staticmethod
    def _count(sim: Simulation, pa: Sequence[float] | np.ndarray, pb: Sequence[float] | np.ndarray) -> int:
        """Walls crossed between two points (MuJoCo frame)."""
        return int(sim.caster.count_walls(np.array([pa], dtype=float), np.array([pb], dtype=float))[0])

    @classmethod
    def walls_between(cls, sim: Simulation, start: Sequence[float], end: Sequence[float]) -> int:
        """Walls crossed between two points of the world (USARSim frame)."""
        return cls._count(sim, frames.to_mj_vec(start), frames.to_mj_vec(end))

    @classmethod
    def walls_between_robots(cls, sim: Simulation, a: str, b: str) -> int:
        """Walls between two robots' antennas now (not the links' cached count); -1: no such robot."""
        antennas = cls.antennas(sim)
        pa, pb = antennas.get(a.lower()), antennas.get(b.lower())
        if pa is None or pb is None:
            return -1
        return cls._count(sim, pa, pb)

    def _cached_walls(self, sim: Simulation, pair: Pair, pa: Point, pb: Point) -> int:
        hit = self._walls.get(pair)
        lim = self.model.cache_distance_m
        if hit is not None and math.dist(pa, hit[0]) <= lim and math.dist(pb, hit[1]) <= lim:
            return hit[2]
        n = self._count(sim, pa, pb)
        self._walls[pair] = (pa, pb, n)
        return n

    # links ----------------------------------------------------------------------------
    @staticmethod
    def antennas(sim: Simulation) -> dict[str, tuple[float, float, float]]:
        """Where each robot's antenna is (its chassis origin, MuJoCo frame), by lower-case
        name (the first spawned wins a name used twice)."""
        d = sim.data
        out: dict[str, tuple[float, float, float]] = {}
        for r in sim.robots.values():
            key = r.name.lower()
            if key not in out:
                out[key] = tuple(d.xpos[r.handle.body_id].tolist())
        for relay in sim.entities.relays:  # the relays robots dropped (RelayDropper)
            out.setdefault(relay.name.lower(), tuple(frames.to_mj_vec(relay.location).tolist()))
        return out

    def _signal(self, sim: Simulation, pair: Pair, pa: Point, pb: Point) -> tuple[float, int]:
        m = self.model
        shadow = self.shadowing
        walls = self._cached_walls(sim, pair, pa, pb) if m.counts_walls or shadow.cfg.shadowing_wall_db else 0
        s = m.signal_dbm(math.dist(pa, pb), walls)
        if shadow.active:
            s += shadow.offset_db(pair, pa, pb, walls)
        return s, walls

    def link(self, sim: Simulation, a: str, b: str, antennas: dict[str, Point] | None = None) -> Link | None:
        """The link between the robots named ``a`` and ``b`` now; None when either is not
        in the simulation."""
        antennas = antennas if antennas is not None else self.antennas(sim)
        pair = pair_key(a, b)
        pa, pb = antennas.get(pair[0]), antennas.get(pair[1])
        if pa is None or pb is None:
            self._walls.pop(pair, None)
            return None
        s, walls = self._signal(sim, pair, pa, pb)
        direct = Link(s, math.dist(pa, pb), walls, self.model.holds(s))
        if direct.holds or not sim.entities.relays:
            return direct
        return self._routed(sim, pair, antennas) or direct

    def _routed(self, sim: Simulation, pair: Pair, antennas: dict[str, Point]) -> Link | None:
        """The best route between the two radios of ``pair`` through the others
        (:func:`usarsim.sim.routing.best_route`), as one link; None when there is none."""
        hops: dict[Pair, Link] = {}

        def hop(a: str, b: str) -> Link:
            key = pair_key(a, b)
            ln = hops.get(key)
            if ln is None:
                pa, pb = antennas[key[0]], antennas[key[1]]
                s, walls = self._signal(sim, key, pa, pb)
                ln = hops[key] = Link(s, math.dist(pa, pb), walls, self.model.holds(s))
            return ln

        def quality(a: str, b: str) -> float | None:
            ln = hop(a, b)
            return link_quality(ln.signal_dbm - self.model.cutoff_dbm) if ln.holds else None

        path = best_route(pair[0], pair[1], sorted(antennas), quality)
        if path is None:
            return None
        legs = [hop(a, b) for a, b in zip(path, path[1:], strict=False)]
        return Link(
            min(ln.signal_dbm for ln in legs),
            sum(ln.distance_m for ln in legs),
            sum(ln.walls for ln in legs),
            True,
            tuple(path[1:-1]),
        )

    def neighbours(self, sim: Simulation, a: str) -> list[tuple[str, Link, float]]:
        """Every radio (robot or relay) whose direct link with ``a`` holds now, by name, with the
        link and its quality (:func:`link_quality`); empty when ``a`` is not in the simulation."""
        antennas = self.antennas(sim)
        if a.lower() not in antennas:
            return []
        names = [r.name for r in sim.robots.values()] + [relay.name for relay in sim.entities.relays]
        out = []
        for b in sorted({n for n in names if n.lower() != a.lower()}, key=str.lower):
            pair = pair_key(a, b)
            pa, pb = antennas[pair[0]], antennas[pair[1]]
            signal, walls = self._signal(sim, pair, pa, pb)  # in reach: the direct link only
            ln = Link(signal, math.dist(pa, pb), walls, self.model.holds(signal))
            if ln.holds:
                out.append((b, ln, link_quality(ln.signal_dbm - self.model.cutoff_dbm)))
        return out

    def check(self, sim: Simulation, a: str, b: str) -> Link | None:
        """``link``, for a link about to be opened on it: a state that differs from the one
        last reported is reported at once, so that every server sees the same."""
        ln = self.link(sim, a, b)
        pair = pair_key(a, b)
        up = ln is not None and ln.holds
        if self._reported.get(pair) is not up:
            self._reported[pair] = up
            if self.on_change is not None:
                self.on_change(sim.time, [(pair, up)])
        return ln

    # messages ---------------------------------------------------------------------------
    def counts(self) -> dict[tuple[str, str], LinkCounts]:
        """What each link (sender, receiver) carried through the channel so far."""
        return self.channel.counts() if self.channel is not None else {}

    def evaluate(self, sim: Simulation) -> None:
        """Run after every advance of the clock (``Simulation.on_advance``): every watched
        pair's link (at most every ``min_interval_s``), changes reported; with a channel, the
        links of the watched pairs and of those that carried messages go to ``on_views``."""
        busy = self.channel is not None
        if (self.watched or self._reported or busy) and sim.time - self._last >= self.min_interval_s - 1e-9:
            self._evaluate_links(sim)

    def _evaluate_links(self, sim: Simulation) -> None:
        watched = self.watched
        carried = self.channel.waiting_pairs() if self.channel is not None else frozenset()
        now = self._last = sim.time
        antennas = self.antennas(sim)
        holds = self.model.holds
        routed = bool(sim.entities.relays)
        keep = self.channel is not None  # the channel judges messages by these links
        cutoff = self.model.cutoff_dbm
        views: dict[Pair, LinkView | None] = {}
        changes = []
        for pair in sorted(watched | carried):
            pa, pb = antennas.get(pair[0]), antennas.get(pair[1])
            if pa is None or pb is None:
                up = False
                views[pair] = None
            elif routed:  # direct, or through relays and robots
                ln = self.link(sim, *pair, antennas)
                up = ln is not None and ln.holds
                if keep:
                    views[pair] = None if ln is None else LinkView(ln.signal_dbm, cutoff, ln.distance_m, ln.holds)
            else:
                signal = self._signal(sim, pair, pa, pb)[0]
                up = holds(signal)
                if keep:
                    views[pair] = LinkView(signal, cutoff, math.dist(pa, pb), up)
            if pair in watched and self._reported.get(pair) is not up:
                self._reported[pair] = up
                changes.append((pair, up))
        for pair in [p for p in self._reported if p not in watched]:
            del self._reported[pair]
        if len(self._walls) > 2 * len(watched) + 256:  # forget pairs nobody asks about
            self._walls = {p: w for p, w in self._walls.items() if p in watched}
        if changes and self.on_change is not None:
            self.on_change(now, changes)
        if keep and self.on_views is not None:
            self.on_views(now, views)
