"""Radio propagation of the wireless simulation (manual section 3.2.4; protocol.md 12).

A message between two robots gets through while the signal strength S at the receiver,
in dBm, is at least the cutoff.  Models (``--wireless-model``, a world's ``wireless``
section, ``--wireless-config``):

* ``waf``, the Wall Attenuation Factor model (Seidel and Rappaport) with the constants of
  the USARSim 3.1.3 manual (section 3.2.4, measured at International University Bremen):
  S = P(d0) - 10 n log10(d / d0) - min(n_w, C) WAF, with P(d0) = -49.67 dBm, d0 = 2 m,
  n = 1.09, C = 5 walls, WAF = 6.625 dB and a cutoff of -93 dBm; n_w is the number of walls
  crossed by the straight line between the two antennas.  The default.
* ``waf2009``: the same formula with the constants of the later USARSim code (the UDK
  ComServer's ini and the WSS obstacle model, protocol.md 12.1 and 12.2): n = 1,
  WAF = 6.325 dB and no cap on the walls.
* ``distance``: S = P(d0) - 10 n log10(d / d0), walls ignored (the WSS distance-only
  model), with the manual's P(d0), d0, n and cutoff.
* ``perfect``: 0 dBm, every link holds (the WSS's Noop model).

Every constant can be changed with the ComConnection keys of USARComServer.ini (manual
3.2.4.2): ``ePdo`` P(d0), ``eDo`` d0, ``eN`` n, ``eCutoff`` the cutoff, ``eMaxObs`` C (below
0: no cap), ``eAttenFac`` WAF.  Wall counts between two robots are kept per pair until
either robot has moved more than ``cache_distance_m`` (1 m, the WSS's ``maxcachedist``).

:class:`RadioNet` holds the links' state on the simulation thread: signals are computed
from the simulated poses, so in lock-step a link's fate depends on simulated time only.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from usarsim.config.channel import ChannelConfig
from usarsim.config.reader import did_you_mean
from usarsim.config.world import WIRELESS_MODELS, WirelessConfig
from usarsim.errors import ConfigError
from usarsim.registry import Registry
from usarsim.sim import frames
from usarsim.sim.channel import (
    SENSITIVITY_FRAME_BYTES,
    Channel,
    Delivery,
    Drop,
    LinkCounts,
    LinkView,
    Shadowing,
    check_channel,
    packet_error_rate,
)
from usarsim.sim.routing import best_route

if TYPE_CHECKING:
    from usarsim.sim.simulation import Simulation

Point = tuple[float, float, float]  # an antenna, MuJoCo frame

# Closer than this, two antennas count as this far apart (the formula has no value at 0).
MIN_DISTANCE_M = 0.01


def waf_signal_dbm(
    distance_m: float,
    walls: int,
    *,
    pd0_dbm: float,
    d0_m: float,
    path_loss_exponent: float,
    wall_db: float,
    max_walls: int | None,
) -> float:
    """The Wall Attenuation Factor model (manual 3.2.4): S = P(d0) - 10 n log10(d / d0) -
    min(walls, C) WAF, in dBm; ``max_walls`` None: no cap (C infinite)."""
    d = max(float(distance_m), MIN_DISTANCE_M)
    counted = walls if max_walls is None else min(walls, max_walls)
    return pd0_dbm - 10.0 * path_loss_exponent * math.log10(d / d0_m) - counted * wall_db


# The radio models by name (``--wireless-model``, a world's ``wireless`` section): a model is
# one class registered here (a plugin's own too: tests/plugins/freespace_radio.py).
RADIO_MODELS = Registry("radio model")


@RADIO_MODELS.register("waf")
@dataclass(frozen=True, kw_only=True)
class RadioModel:
    """A radio propagation model: the signal strength between two antennas ``distance_m``
    apart with ``walls`` walls between them, and whether a link of that strength holds.

    This base is the manual's WAF model (3.2.4); a model of another kind subclasses it,
    registers with :data:`RADIO_MODELS` and overrides :meth:`signal_dbm` (and :meth:`holds`
    or :meth:`describe` if it must).  Every model carries the ComConnection constants of
    USARComServer.ini (a world's ``wireless`` section and ``--wireless-config`` change them)
    and uses those it needs."""

    name: str = "waf"
    pd0_dbm: float = -49.67
    d0_m: float = 2.0
    path_loss_exponent: float = 1.09
    cutoff_dbm: float = -93.0
    max_walls: int | None = 5  # C; None: no cap
    wall_db: float = 6.625  # WAF
    cache_distance_m: float = 1.0
    COUNTS_WALLS: ClassVar[bool] = True  # whether signal_dbm uses the walls (they are counted by ray casts)

    def __post_init__(self) -> None:
        if not self.d0_m > 0 or self.path_loss_exponent < 0 or self.wall_db < 0 or self.cache_distance_m < 0:
            raise ValueError("need eDo > 0, eN >= 0, eAttenFac >= 0 and cache_distance_m >= 0")

    @property
    def counts_walls(self) -> bool:
        return self.COUNTS_WALLS

    def signal_dbm(self, distance_m: float, walls: int = 0) -> float:
        return waf_signal_dbm(
            distance_m,
            walls if self.counts_walls else 0,
            pd0_dbm=self.pd0_dbm,
            d0_m=self.d0_m,
            path_loss_exponent=self.path_loss_exponent,
            wall_db=self.wall_db,
            max_walls=self.max_walls,
        )

    def holds(self, dbm: float) -> bool:
        """Whether a link with this signal strength carries messages."""
        return dbm >= self.cutoff_dbm

    def describe(self) -> str:
        cap = "no cap" if self.max_walls is None else f"C {self.max_walls}"
        walls = f", WAF {self.wall_db:g} dB, {cap}" if self.counts_walls else ""
        return (
            f"{self.name} (P(d0) {self.pd0_dbm:g} dBm, d0 {self.d0_m:g} m, n {self.path_loss_exponent:g}"
            f"{walls}, cutoff {self.cutoff_dbm:g} dBm)"
        )


@RADIO_MODELS.register("waf2009")
@dataclass(frozen=True, kw_only=True)
class Waf2009Model(RadioModel):
    """The WAF formula with the later USARSim code's constants (the UDK ComServer's ini and the
    WSS obstacle model, protocol.md 12.1 and 12.2): n = 1, WAF = 6.325 dB, no cap on walls."""

    name: str = "waf2009"
    path_loss_exponent: float = 1.0
    wall_db: float = 6.325
    max_walls: int | None = None


@RADIO_MODELS.register("distance")
@dataclass(frozen=True, kw_only=True)
class DistanceModel(RadioModel):
    """The WSS distance-only model: the WAF formula with walls ignored."""

    name: str = "distance"
    COUNTS_WALLS: ClassVar[bool] = False


@RADIO_MODELS.register("perfect")
@dataclass(frozen=True, kw_only=True)
class PerfectModel(RadioModel):
    """The WSS's Noop model: 0 dBm, every link holds."""

    name: str = "perfect"
    COUNTS_WALLS: ClassVar[bool] = False

    def signal_dbm(self, distance_m: float, walls: int = 0) -> float:
        return 0.0

    def holds(self, dbm: float) -> bool:
        return True

    def describe(self) -> str:
        return "perfect (0 dBm, every link holds)"


def model_names() -> list[str]:
    """The radio models registered (built in and plugins')."""
    return RADIO_MODELS.names()


def new_model(name: str) -> RadioModel:
    """The model ``name`` with its own default constants; ConfigError if none has that name."""
    if name not in RADIO_MODELS:
        raise ConfigError(f"unknown radio model {name!r}{did_you_mean(name, model_names())}")
    model: RadioModel = RADIO_MODELS.get(name)()
    return model


# The built-in models with their default constants.
PRESETS: dict[str, RadioModel] = {name: new_model(name) for name in WIRELESS_MODELS}


def resolve_model(*layers: WirelessConfig | None, model: str | None = None) -> RadioModel:
    """The radio model: the one ``model`` names (the command line), else the last layer
    naming one, else ``waf``; its preset's constants, then those each layer gives, in order
    (the world's, then the configuration file's)."""
    name = model or next((ly.model for ly in reversed(layers) if ly is not None and ly.model), None) or "waf"
    out = new_model(name)
    for ly in layers:
        if ly is None:
            continue
        given = {
            f.name: getattr(ly, f.name)
            for f in dataclasses.fields(ly)
            if f.name not in ("model", "channel") and getattr(ly, f.name) is not None
        }
        if "max_walls" in given and given["max_walls"] < 0:
            given["max_walls"] = None
        out = dataclasses.replace(out, **given)
    return out


def resolve_channel(*layers: WirelessConfig | None) -> ChannelConfig:
    """The channel beyond the path loss: that of the last layer giving one (the world's, then
    the configuration file's), else the ideal channel (USARSim's)."""
    chosen = next((ly.channel for ly in reversed(layers) if ly is not None and ly.channel is not None), None)
    out = chosen if chosen is not None else ChannelConfig()
    check_channel(out)
    return out


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
        # what arrived and what was dropped, after each advance: on_deliver(time, deliveries, drops)
        self.on_deliver: Callable[[float, list[Delivery], list[Drop]], None] | None = None
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
    def send(self, sim: Simulation, src: str, dst: str, payload: bytes, token: object = None) -> Drop | None:
        """Hand a message from robot ``src`` to robot ``dst`` to the channel now; a Drop when
        the sending radio's queue has no room for it, else None (what becomes of it is told to
        ``on_deliver`` after the advance at which it arrives or is lost)."""
        if self.channel is None:
            raise RuntimeError("the ideal channel carries no messages: servers relay them at once")
        return self.channel.submit(sim.time, src, dst, payload, token)

    def send_many(self, sim: Simulation, messages: list[tuple[str, str, bytes, object]]) -> list[Drop]:
        """:meth:`send` for each (src, dst, payload, token) in order; the drops (full queues)."""
        out = []
        for src, dst, payload, token in messages:
            drop = self.send(sim, src, dst, payload, token)
            if drop is not None:
                out.append(drop)
        return out

    def counts(self) -> dict[tuple[str, str], LinkCounts]:
        """What each link (sender, receiver) carried through the channel so far."""
        return self.channel.counts() if self.channel is not None else {}

    def _deliver(self, sim: Simulation) -> None:
        ch = self.channel
        if ch is None or not ch.pending:
            return
        antennas = self.antennas(sim)
        cutoff = self.model.cutoff_dbm

        seen: dict[Pair, LinkView | None] = {}  # each link once an advance, however many messages it carries

        def view(src: str, dst: str) -> LinkView | None:
            pair = pair_key(src, dst)
            if pair not in seen:
                ln = self.link(sim, src, dst, antennas)
                seen[pair] = None if ln is None else LinkView(ln.signal_dbm, cutoff, ln.distance_m, ln.holds)
            return seen[pair]

        deliveries, drops = ch.due(sim.time, view)
        if (deliveries or drops) and self.on_deliver is not None:
            self.on_deliver(sim.time, deliveries, drops)

    def evaluate(self, sim: Simulation) -> None:
        """Run after every advance of the clock (``Simulation.on_advance``): what the channel
        delivers by now, then every watched pair's link, changes reported."""
        self._deliver(sim)
        watched = self.watched
        if not watched and not self._reported:
            return
        now = sim.time
        if now - self._last < self.min_interval_s - 1e-9:
            return
        self._last = now
        antennas = self.antennas(sim)
        holds = self.model.holds
        routed = bool(sim.entities.relays)
        changes = []
        for pair in sorted(watched):
            pa, pb = antennas.get(pair[0]), antennas.get(pair[1])
            if pa is None or pb is None:
                up = False
            elif routed:  # direct, or through relays and robots
                up = (ln := self.link(sim, *pair, antennas)) is not None and ln.holds
            else:
                up = holds(self._signal(sim, pair, pa, pb)[0])
            if self._reported.get(pair) is not up:
                self._reported[pair] = up
                changes.append((pair, up))
        for pair in [p for p in self._reported if p not in watched]:
            del self._reported[pair]
        if len(self._walls) > 2 * len(watched) + 256:  # forget pairs nobody asks about
            self._walls = {p: w for p, w in self._walls.items() if p in watched}
        if changes and self.on_change is not None:
            self.on_change(now, changes)
