"""The radio channel beyond the path loss (docs/wireless.md, "The channel"): what happens to
each message a robot sends another while their link holds.

* **Shadowing** (:class:`Shadowing`): a link's signal is offset by a log-normal draw (normal in
  dB) of ``shadowing_db`` plus ``shadowing_wall_db`` per wall on the line, drawn again when either
  end has moved ``shadowing_distance_m`` (a decorrelation distance: M. Gudmundson, "Correlation
  model for shadow fading in mobile radio systems", Electronics Letters 27(23), 1991).  It is
  part of the link's signal: GETSS reports it and a link is down while it is below the cutoff.
* **Fading** (``rayleigh``): each message's own fast fade on top, its power an exponential draw
  of mean 1 (Rayleigh fading; T. S. Rappaport, "Wireless Communications", 2nd ed., 2002, 5.6).
* **Loss** (:data:`LOSS_MODELS`, each model one class registered there): ``none``;
  ``independent`` (each message lost with ``rate``); ``gilbert_elliott`` (a two-state Markov chain
  of good and bad spells: E. N. Gilbert, "Capacity of a burst-noise channel", Bell System
  Technical Journal 39, 1960; E. O. Elliott, "Estimates of error rates for codes on burst-noise
  channels", BSTJ 42, 1963); ``signal`` (the packet error rate of the message's signal margin over
  the cutoff, faded: :func:`packet_error_rate`).
* **Capacity and queueing**: a radio sends one message at a time, at the link's capacity
  (``link_bytes_per_s``) and never faster than its own (``radio_bytes_per_s``): its budget of a
  slice of time is that rate times the slice, spent as the slice passes.  Messages wait their
  turn at the sending radio; one that would make more than ``queue_bytes`` wait is dropped.
* **Delay**: a message is delivered when its last byte is sent (serialisation), plus the
  distance over the speed of light, ``latency_s`` and a uniform draw of up to ``jitter_s``;
  the messages of one link arrive in the order they were sent.

Every random draw comes from a generator of the link's own (the seed, the two robots' names
and the draw's purpose), so that a link's fate does not depend on what other links carry, and
the same seed with the same messages at the same simulated times gives the same deliveries.
:class:`Channel` is sans-IO: servers hand it messages and ask it what is due at each instant.
"""

from __future__ import annotations

import collections
import dataclasses
import heapq
import math
import random
import threading
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from usarsim.config.channel import ChannelConfig
from usarsim.sim.lossmodels import (
    EB_N0_AT_CUTOFF_DB,
    LOSS_MODELS,
    SENSITIVITY_FRAME_BYTES,
    SENSITIVITY_PER,
    GilbertElliottLoss,
    IndependentLoss,
    LossModel,
    NoLoss,
    SignalLoss,
    check_channel,
    describe_channel,
    loss_model_class,
    packet_error_rate,
)

# the loss models, where they have always been imported from
__all__ = [
    "DROP_CAUSES",
    "EB_N0_AT_CUTOFF_DB",
    "LATER",
    "LOSS_MODELS",
    "SENSITIVITY_FRAME_BYTES",
    "SENSITIVITY_PER",
    "Channel",
    "Delivery",
    "Drop",
    "GilbertElliottLoss",
    "IndependentLoss",
    "LinkCounts",
    "LinkView",
    "LossModel",
    "NoLoss",
    "Shadowing",
    "SignalLoss",
    "check_channel",
    "describe_channel",
    "link_rng",
    "loss_model_class",
    "packet_error_rate",
]

SPEED_OF_LIGHT_M_S = 299_792_458.0
DROP_CAUSES = ("range", "loss", "capacity")  # out of reach, lost on the way, no room in the queue


def link_rng(seed: int, src: str, dst: str, purpose: str) -> random.Random:
    """The generator of one purpose (``fade``, ``loss``, ``jitter``, ``shadow``) of the link from
    ``src`` to ``dst`` (names in any case): Python's Mersenne Twister, seeded from the seed and a
    CRC of the names and purpose, the same in every run (a draw costs a tenth of a NumPy
    generator's single draw, and a channel draws a few for every message)."""
    key = zlib.crc32(f"{src.lower()}>{dst.lower()}/{purpose}".encode())
    return random.Random(int(seed) * 4_294_967_296 + key)


# --------------------------------------------------------------------------- shadowing


class Shadowing:
    """The shadowing of each pair of robots (both directions alike): a normal draw in dB, kept
    until either end has moved ``shadowing_distance_m`` from where it was drawn."""

    def __init__(self, cfg: ChannelConfig, seed: int):
        self.cfg = cfg
        self.seed = seed
        self._drawn: dict[tuple[str, str], tuple[tuple[float, ...], tuple[float, ...], float]] = {}
        self._rngs: dict[tuple[str, str], random.Random] = {}
        self.active = cfg.shadowing_db > 0.0 or cfg.shadowing_wall_db > 0.0
        self._lim = cfg.shadowing_distance_m

    def offset_db(self, pair: tuple[str, str], pa, pb, walls: int) -> float:
        if not self.active:
            return 0.0
        hit = self._drawn.get(pair)
        if hit is not None:
            lim, dist = self._lim, math.dist
            if dist(pa, hit[0]) <= lim and dist(pb, hit[1]) <= lim:
                return hit[2]
        rng = self._rngs.get(pair)
        if rng is None:
            rng = self._rngs[pair] = link_rng(self.seed, pair[0], pair[1], "shadow")
        sigma = self.cfg.shadowing_db + self.cfg.shadowing_wall_db * walls
        value = rng.gauss(0.0, sigma)
        self._drawn[pair] = (tuple(pa), tuple(pb), value)
        return value

    def forget(self, pair: tuple[str, str]) -> None:
        self._drawn.pop(pair, None)


# --------------------------------------------------------------------------- the channel


@dataclass(slots=True)
class LinkView:
    """What the channel needs of a link at one instant: its signal (shadowing included), the
    cutoff, and the distance between the antennas."""

    signal_dbm: float
    cutoff_dbm: float
    distance_m: float
    holds: bool


@dataclass(slots=True)
class Delivery:
    """A message that arrived: ``payload`` from ``src`` to ``dst``, sent at ``sent_at`` and
    delivered at ``at`` (simulated seconds); ``token`` is the sender's own mark."""

    token: Any
    src: str
    dst: str
    payload: bytes
    sent_at: float
    at: float


@dataclass(slots=True)
class Drop:
    """A message that did not arrive, and why (``cause``: one of DROP_CAUSES)."""

    token: Any
    src: str
    dst: str
    nbytes: int
    sent_at: float
    at: float
    cause: str


@dataclass
class LinkCounts:
    """What one link (one direction) carried: messages and bytes delivered, dropped by cause,
    and the sum of the delivered messages' delays (s)."""

    delivered: int = 0
    delivered_bytes: int = 0
    dropped: dict[str, int] = field(default_factory=lambda: dict.fromkeys(DROP_CAUSES, 0))
    dropped_bytes: dict[str, int] = field(default_factory=lambda: dict.fromkeys(DROP_CAUSES, 0))
    delay_s: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        return {
            "delivered": self.delivered,
            "delivered_bytes": self.delivered_bytes,
            "dropped": dict(self.dropped),
            "dropped_bytes": dict(self.dropped_bytes),
            "mean_delay_s": self.delay_s / self.delivered if self.delivered else 0.0,
        }


class _Link:
    """One direction of one link: its generators, loss model, last delivery time and counts, and
    the sending radio's state (shared by every link from that radio)."""

    __slots__ = ("counts", "fade", "jitter", "last_at", "loss", "pair", "radio")

    def __init__(self, loss: type[LossModel], settings: dict[str, float], seed: int, src: str, dst: str, radio: _Radio):
        self.fade = link_rng(seed, src, dst, "fade")
        self.jitter = link_rng(seed, src, dst, "jitter")
        self.loss = loss(settings, link_rng(seed, src, dst, "loss"))
        self.last_at = -math.inf
        self.counts = LinkCounts()
        self.radio = radio
        self.pair = (src, dst) if src <= dst else (dst, src)  # the two radios, lower case, in order


class _Radio:
    """One sending radio: when its last queued byte leaves (``free``), the (time its last byte
    leaves, bytes) of what it has still to send (``backlog``, ``waiting`` bytes), and the
    messages not judged yet, in the order their last bytes leave (``sending``: tuples of finish,
    sequence number, src, dst, payload, sent_at, token and _Link)."""

    __slots__ = ("backlog", "free", "sending", "waiting")

    def __init__(self) -> None:
        self.free = -math.inf
        self.backlog: collections.deque[tuple[float, int]] = collections.deque()
        self.waiting = 0
        self.sending: collections.deque[tuple] = collections.deque()


_UNSEEN = object()
# what a view answers for a link it knows nothing of yet: its messages wait for a later call
LATER: Any = object()


def _arrival_order(entry: tuple) -> tuple[float, int]:
    return entry[0], entry[1]


class Channel:
    """The messages under way between robots (see the module's text).  ``submit`` hands one
    over at the simulated instant ``now``; ``due`` returns what arrived and what was dropped by
    ``now``, each link judged by ``view(src, dst)`` when a message's last byte leaves.

    A radio sends in order, so each radio's messages wait in a queue of their own, in the order
    they finish; a message's fate is drawn from its link's generators only, so that the order in
    which the radios' queues are judged changes nothing.  A message is judged at the first call
    of ``due`` after the instant it was handed over, never at that instant, so that whether it
    was handed over before or after the call at that instant changes nothing either.

    Its methods may be called from any thread (they hold :attr:`lock`)."""

    def __init__(self, cfg: ChannelConfig, seed: int):
        self.cfg = cfg
        self.seed = cfg.seed if cfg.seed is not None else seed
        self._loss = loss_model_class(cfg.loss)
        self._settings = self._loss.read(cfg.loss_settings)
        self._links: dict[tuple[str, str], _Link] = {}  # by lower-case names
        self._named: dict[tuple[str, str], _Link] = {}  # by the names as given
        self.lock = threading.Lock()
        self._unjudged_by_pair: dict[tuple[str, str], int] = {}
        self._radios: dict[str, _Radio] = {}  # by lower-case name
        self._arriving: list[tuple[float, int, Delivery, _Link]] = []  # judged and delivered, by time
        self._unjudged = 0
        self._seq = 0
        rates = [r for r in (cfg.link_bytes_per_s, cfg.radio_bytes_per_s) if r is not None]
        self.rate = min(rates) if rates else math.inf
        self._capped = math.isfinite(self.rate)
        self._rayleigh = cfg.fading == "rayleigh"
        self._fade_loses = cfg.loss in ("none", "signal")  # a message faded below the cutoff is lost

    def link(self, src: str, dst: str) -> _Link:
        ln = self._named.get((src, dst))
        if ln is None:
            key = (src.lower(), dst.lower())
            ln = self._links.get(key)
            if ln is None:
                radio = self._radios.setdefault(key[0], _Radio())
                ln = self._links[key] = _Link(self._loss, self._settings, self.seed, *key, radio)
            self._named[(src, dst)] = ln
        return ln

    def counts(self) -> dict[tuple[str, str], LinkCounts]:
        """Each link's counts (by sender and receiver, lower case), a copy of how they stand."""
        with self.lock:
            return {
                k: dataclasses.replace(
                    ln.counts, dropped=dict(ln.counts.dropped), dropped_bytes=dict(ln.counts.dropped_bytes)
                )
                for k, ln in sorted(self._links.items())
            }

    def waiting_pairs(self) -> frozenset[tuple[str, str]]:
        """The pairs of radios (lower case, in order) with messages not judged yet: those whose
        links a view must give."""
        with self.lock:
            return frozenset(self._unjudged_by_pair)

    @property
    def pending(self) -> int:
        """Messages handed over and neither delivered nor dropped yet."""
        return self._unjudged + len(self._arriving)

    def under_way_bytes(self) -> int:
        """The bytes of the messages handed over and neither delivered nor dropped yet."""
        with self.lock:
            waiting = sum(len(m[4]) for r in self._radios.values() for m in r.sending)
            return waiting + sum(len(d.payload) for _, _, d, _ in self._arriving)

    def submit(self, now: float, src: str, dst: str, payload: bytes, token: Any = None) -> Drop | None:
        """Hand over a message from ``src`` to ``dst``; a Drop when its radio's queue has no
        room for it (counted), else None (it is under way)."""
        with self.lock:
            return self._put(now, src, dst, payload, token)

    def _put(self, now: float, src: str, dst: str, payload: bytes, token: Any) -> Drop | None:
        ln = self._named.get((src, dst)) or self.link(src, dst)
        radio = ln.radio
        finish = now
        if self._capped:  # it waits its turn at the radio
            n = len(payload)
            backlog = radio.backlog
            while backlog and backlog[0][0] <= now:
                radio.waiting -= backlog.popleft()[1]
            if radio.waiting and radio.waiting + n > self.cfg.queue_bytes:
                return self._drop(ln, (now, 0, src, dst, payload, now, token), now, "capacity")
            finish = (now if now > radio.free else radio.free) + n / self.rate
            radio.free = finish
            backlog.append((finish, n))
            radio.waiting += n
        self._seq += 1
        radio.sending.append((finish, self._seq, src, dst, payload, now, token, ln))
        self._unjudged += 1
        by_pair = self._unjudged_by_pair
        by_pair[ln.pair] = by_pair.get(ln.pair, 0) + 1
        return None

    def due(self, now: float, view: Callable[[str, str], LinkView | None]) -> tuple[list[Delivery], list[Drop]]:
        """What arrived (in order of arrival) and what was dropped by ``now`` (``view`` may answer
        :data:`LATER` for a link: its messages are judged at a later call)."""
        with self.lock:
            return self._due(now, view)

    def _due(self, now: float, view: Callable[[str, str], LinkView | None]) -> tuple[list[Delivery], list[Drop]]:
        drops: list[Drop] = []
        ready: list[tuple[float, int, Delivery, _Link]] = []  # judged now and arrived already
        if self._unjudged:
            self._judge_due(now, view, drops, ready)
        arriving = self._arriving
        while arriving and arriving[0][0] <= now:
            ready.append(heapq.heappop(arriving))
        ready.sort(key=_arrival_order)
        out: list[Delivery] = []
        for _, _, d, ln in ready:
            c = ln.counts
            c.delivered += 1
            c.delivered_bytes += len(d.payload)
            c.delay_s += d.at - d.sent_at
            out.append(d)
        return out, drops

    def _judge_due(
        self, now: float, view: Callable[[str, str], LinkView | None], drops: list[Drop], ready: list
    ) -> None:
        """Judge every message whose last byte has left by ``now``, by its link's view: a drop
        goes to ``drops``; a delivery to ``ready`` when it has arrived by ``now``, else it waits."""
        views: dict[_Link, Any] = {}  # each link asked once a call
        log10, expo = math.log10, random.Random.expovariate
        cfg = self.cfg
        latency, jitter = cfg.latency_s, cfg.jitter_s
        rayleigh, fade_loses = self._rayleigh, self._fade_loses
        arriving = self._arriving
        by_pair = self._unjudged_by_pair
        judged = 0
        for radio in self._radios.values():
            sending = radio.sending
            while sending and sending[0][0] <= now and sending[0][5] < now:
                m = sending[0]
                finish, seq, src, dst, payload, sent_at, token, ln = m
                lv = views.get(ln, _UNSEEN)
                if lv is _UNSEEN:
                    lv = views[ln] = view(src, dst)
                if lv is LATER:
                    break  # this radio's queue waits for its link to be known
                sending.popleft()
                judged += 1
                left = by_pair[ln.pair] - 1
                if left:
                    by_pair[ln.pair] = left
                else:
                    del by_pair[ln.pair]
                if lv is None or not lv.holds:
                    drops.append(self._drop(ln, m, finish, "range"))
                    continue
                signal = lv.signal_dbm
                if rayleigh:
                    signal += 10.0 * log10(max(expo(ln.fade, 1.0), 1e-12))
                    if signal < lv.cutoff_dbm and fade_loses:
                        drops.append(self._drop(ln, m, finish, "loss"))  # faded below the cutoff
                        continue
                if ln.loss.lost(signal - lv.cutoff_dbm, len(payload)):
                    drops.append(self._drop(ln, m, finish, "loss"))
                    continue
                at = finish + lv.distance_m / SPEED_OF_LIGHT_M_S + latency
                if jitter > 0.0:
                    at += ln.jitter.uniform(0.0, jitter)
                if at < ln.last_at:  # a link's messages arrive in the order they were sent
                    at = ln.last_at
                ln.last_at = at
                entry = (at, seq, Delivery(token, src, dst, payload, sent_at, at), ln)
                if at <= now:
                    ready.append(entry)
                else:
                    heapq.heappush(arriving, entry)
        self._unjudged -= judged

    @staticmethod
    def _drop(ln: _Link, m: tuple, at: float, cause: str) -> Drop:
        n = len(m[4])
        c = ln.counts
        c.dropped[cause] += 1
        c.dropped_bytes[cause] += n
        return Drop(m[6], m[2], m[3], n, m[5], at, cause)
