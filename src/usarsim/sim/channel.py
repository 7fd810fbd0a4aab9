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
import heapq
import math
import random
import zlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

from usarsim.config.channel import ChannelConfig
from usarsim.config.reader import did_you_mean
from usarsim.errors import ConfigError
from usarsim.registry import Registry

SPEED_OF_LIGHT_M_S = 299_792_458.0
DROP_CAUSES = ("range", "loss", "capacity")  # out of reach, lost on the way, no room in the queue


def link_rng(seed: int, src: str, dst: str, purpose: str) -> random.Random:
    """The generator of one purpose (``fade``, ``loss``, ``jitter``, ``shadow``) of the link from
    ``src`` to ``dst`` (names in any case): Python's Mersenne Twister, seeded from the seed and a
    CRC of the names and purpose, the same in every run (a draw costs a tenth of a NumPy
    generator's single draw, and a channel draws a few for every message)."""
    key = zlib.crc32(f"{src.lower()}>{dst.lower()}/{purpose}".encode())
    return random.Random(int(seed) * 4_294_967_296 + key)


# --------------------------------------------------------------------------- loss models

# IEEE 802.11b-1999, 18.4.8.2: a receiver's sensitivity is the signal at which 8 % of 1,024-byte
# frames are lost.  The cutoff is taken as that sensitivity: at the cutoff the signal model
# loses 8 % of 1,024-byte messages.
SENSITIVITY_PER = 0.08
SENSITIVITY_FRAME_BYTES = 1024


def _ber_at_sensitivity() -> float:
    return 1.0 - (1.0 - SENSITIVITY_PER) ** (1.0 / (8 * SENSITIVITY_FRAME_BYTES))


# Eb/N0 at the cutoff (about 10.3 dB) for differential BPSK, whose bit error rate is
# 0.5 exp(-Eb/N0) (J. G. Proakis, "Digital Communications", 4th ed., 2001, 5.2.8), the
# modulation of 802.11's 1 Mb/s rate
EB_N0_AT_CUTOFF_DB = 10.0 * math.log10(math.log(0.5 / _ber_at_sensitivity()))


def packet_error_rate(margin_db: float, nbytes: int) -> float:
    """The chance that a message of ``nbytes`` is lost at ``margin_db`` above the cutoff: each
    bit in error with DBPSK's rate 0.5 exp(-Eb/N0), Eb/N0 rising dB for dB with the margin from
    EB_N0_AT_CUTOFF_DB at the cutoff (8 % of 1,024-byte messages lost there)."""
    eb_n0 = 10.0 ** ((margin_db + EB_N0_AT_CUTOFF_DB) / 10.0)
    ber = 0.5 * math.exp(-eb_n0)
    return 1.0 - (1.0 - ber) ** (8 * max(1, nbytes))


LOSS_MODELS = Registry("loss model")


class LossModel:
    """Whether each message of one link (one direction) is lost, with the link's own generator;
    a model is a subclass registered with :data:`LOSS_MODELS`, its settings (``SETTINGS``: name
    -> default) read from the ``loss`` mapping of the channel."""

    SETTINGS: ClassVar[dict[str, float]] = {}

    def __init__(self, settings: Mapping[str, float], rng: random.Random):
        self.settings = dict(settings)
        self.rng = rng

    @classmethod
    def read(cls, raw: Mapping[str, Any]) -> dict[str, float]:
        """The model's settings from the ``loss`` mapping (``raw``), defaults filled in; a key
        it does not know, or a value that is not a probability, is refused by name."""
        out = dict(cls.SETTINGS)
        for key, value in raw.items():
            if key not in cls.SETTINGS:
                raise ConfigError(
                    f"the {cls.TYPE} loss model has no setting '{key}'{did_you_mean(key, cls.SETTINGS)}"  # type: ignore[attr-defined]
                )
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= value <= 1.0:
                raise ConfigError(f"loss setting '{key}' is a probability from 0 to 1, got {value!r}")
            out[key] = float(value)
        return out

    def lost(self, margin_db: float, nbytes: int) -> bool:
        """Whether the next message (``nbytes`` long, its signal ``margin_db`` above the
        cutoff, faded) is lost."""
        return False


@LOSS_MODELS.register("none")
class NoLoss(LossModel):
    """Nothing is lost while the link holds (USARSim's channel)."""


@LOSS_MODELS.register("independent")
class IndependentLoss(LossModel):
    """Each message lost with probability ``rate``, whatever befell the one before."""

    SETTINGS: ClassVar[dict[str, float]] = {"rate": 0.0}

    def lost(self, margin_db: float, nbytes: int) -> bool:
        return self.rng.random() < self.settings["rate"]


@LOSS_MODELS.register("gilbert_elliott")
class GilbertElliottLoss(LossModel):
    """Bursts of loss: before each message the link passes from its good state to its bad one
    with ``p_good_bad`` and back with ``p_bad_good``, and loses the message with ``loss_good`` or
    ``loss_bad`` of the state it is in.  A bad spell lasts 1 / ``p_bad_good`` messages on average
    (geometrically distributed), a good one 1 / ``p_good_bad``; the long-run loss is
    (p_bad_good loss_good + p_good_bad loss_bad) / (p_good_bad + p_bad_good)."""

    SETTINGS: ClassVar[dict[str, float]] = {"p_good_bad": 0.01, "p_bad_good": 0.25, "loss_good": 0.0, "loss_bad": 1.0}

    def __init__(self, settings: Mapping[str, float], rng: random.Random):
        super().__init__(settings, rng)
        self.bad = False

    def lost(self, margin_db: float, nbytes: int) -> bool:
        s = self.settings
        self.bad = self.rng.random() < (1.0 - s["p_bad_good"] if self.bad else s["p_good_bad"])
        return self.rng.random() < (s["loss_bad"] if self.bad else s["loss_good"])


@LOSS_MODELS.register("signal")
class SignalLoss(LossModel):
    """Each message lost with the packet error rate of its faded signal's margin over the
    cutoff and its length (:func:`packet_error_rate`)."""

    def lost(self, margin_db: float, nbytes: int) -> bool:
        return self.rng.random() < packet_error_rate(margin_db, nbytes)


def loss_model_class(name: str) -> type[LossModel]:
    if name not in LOSS_MODELS:
        raise ConfigError(f"unknown loss model {name!r}{did_you_mean(name, LOSS_MODELS.names())}")
    cls: type[LossModel] = LOSS_MODELS.get(name)
    return cls


def check_channel(cfg: ChannelConfig) -> None:
    """Refuse a channel whose loss model or loss settings are unknown (ConfigError)."""
    loss_model_class(cfg.loss).read(cfg.loss_settings)


def describe_channel(cfg: ChannelConfig) -> str:
    """The channel in a few words, for the server's log."""
    parts = []
    if cfg.shadowing_db or cfg.shadowing_wall_db:
        parts.append(f"shadowing {cfg.shadowing_db:g} dB + {cfg.shadowing_wall_db:g} dB a wall")
    if cfg.fading != "none":
        parts.append(f"{cfg.fading} fading")
    if cfg.loss != "none":
        settings = ", ".join(f"{k} {v:g}" for k, v in loss_model_class(cfg.loss).read(cfg.loss_settings).items())
        parts.append(f"{cfg.loss} loss ({settings})" if settings else f"{cfg.loss} loss")
    for what, rate in (("link", cfg.link_bytes_per_s), ("radio", cfg.radio_bytes_per_s)):
        if rate is not None:
            parts.append(f"{rate:g} bytes/s a {what}")
    if cfg.latency_s or cfg.jitter_s:
        parts.append(f"latency {cfg.latency_s:g} s + up to {cfg.jitter_s:g} s")
    return "; ".join(parts) or "ideal"


# --------------------------------------------------------------------------- shadowing


class Shadowing:
    """The shadowing of each pair of robots (both directions alike): a normal draw in dB, kept
    until either end has moved ``shadowing_distance_m`` from where it was drawn."""

    def __init__(self, cfg: ChannelConfig, seed: int):
        self.cfg = cfg
        self.seed = seed
        self._drawn: dict[tuple[str, str], tuple[tuple[float, ...], tuple[float, ...], float]] = {}
        self._rngs: dict[tuple[str, str], random.Random] = {}

    @property
    def active(self) -> bool:
        return self.cfg.shadowing_db > 0.0 or self.cfg.shadowing_wall_db > 0.0

    def offset_db(self, pair: tuple[str, str], pa, pb, walls: int) -> float:
        if not self.active:
            return 0.0
        hit = self._drawn.get(pair)
        lim = self.cfg.shadowing_distance_m
        if hit is not None and math.dist(pa, hit[0]) <= lim and math.dist(pb, hit[1]) <= lim:
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


@dataclass(frozen=True)
class LinkView:
    """What the channel needs of a link at one instant: its signal (shadowing included), the
    cutoff, and the distance between the antennas."""

    signal_dbm: float
    cutoff_dbm: float
    distance_m: float
    holds: bool


@dataclass(frozen=True)
class Delivery:
    """A message that arrived: ``payload`` from ``src`` to ``dst``, sent at ``sent_at`` and
    delivered at ``at`` (simulated seconds); ``token`` is the sender's own mark."""

    token: Any
    src: str
    dst: str
    payload: bytes
    sent_at: float
    at: float


@dataclass(frozen=True)
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


@dataclass(slots=True)
class _Sending:
    finish: float
    seq: int
    src: str
    dst: str
    payload: bytes
    sent_at: float
    token: Any
    link: _Link


class _Link:
    """One direction of one link: its generators, loss model, last delivery time and counts."""

    def __init__(self, loss: type[LossModel], settings: dict[str, float], seed: int, src: str, dst: str):
        self.fade = link_rng(seed, src, dst, "fade")
        self.jitter = link_rng(seed, src, dst, "jitter")
        self.loss = loss(settings, link_rng(seed, src, dst, "loss"))
        self.last_at = -math.inf
        self.counts = LinkCounts()


class Channel:
    """The messages under way between robots (see the module's text).  ``submit`` hands one
    over at the simulated instant ``now``; ``due`` returns what arrived and what was dropped by
    ``now``, each link judged by ``view(src, dst)`` when a message's last byte leaves."""

    def __init__(self, cfg: ChannelConfig, seed: int):
        self.cfg = cfg
        self.seed = cfg.seed if cfg.seed is not None else seed
        self._loss = loss_model_class(cfg.loss)
        self._settings = self._loss.read(cfg.loss_settings)
        self._links: dict[tuple[str, str], _Link] = {}
        self._sending: list[tuple[float, int, _Sending]] = []  # by the time the last byte leaves
        self._arriving: list[tuple[float, int, Delivery, _Link]] = []  # by delivery time
        self._radio_free: dict[str, float] = {}  # when each radio's last queued message is sent
        self._backlog: dict[str, collections.deque[tuple[float, int]]] = {}  # (finish, bytes) at each radio
        self._waiting: dict[str, int] = {}  # the bytes of each radio's backlog
        self._seq = 0
        rates = [r for r in (cfg.link_bytes_per_s, cfg.radio_bytes_per_s) if r is not None]
        self.rate = min(rates) if rates else math.inf
        self._rayleigh = cfg.fading == "rayleigh"
        self._fade_loses = cfg.loss in ("none", "signal")  # a message faded below the cutoff is lost

    def link(self, src: str, dst: str) -> _Link:
        key = (src.lower(), dst.lower())
        ln = self._links.get(key)
        if ln is None:
            ln = self._links[key] = _Link(self._loss, self._settings, self.seed, *key)
        return ln

    def counts(self) -> dict[tuple[str, str], LinkCounts]:
        """Each link's counts (by sender and receiver, lower case), as they stand."""
        return {k: ln.counts for k, ln in sorted(self._links.items())}

    @property
    def pending(self) -> int:
        """Messages handed over and neither delivered nor dropped yet."""
        return len(self._sending) + len(self._arriving)

    def submit(self, now: float, src: str, dst: str, payload: bytes, token: Any = None) -> Drop | None:
        """Hand over a message from ``src`` to ``dst``; a Drop when its radio's queue has no
        room for it (counted), else None (it is under way)."""
        n = len(payload)
        radio = src.lower()
        ln = self.link(src, dst)
        finish = now
        if math.isfinite(self.rate):  # it waits its turn at the radio
            backlog = self._backlog.setdefault(radio, collections.deque())
            waiting = self._waiting.get(radio, 0)
            while backlog and backlog[0][0] <= now:
                waiting -= backlog.popleft()[1]
            if waiting and waiting + n > self.cfg.queue_bytes:
                self._waiting[radio] = waiting
                return self._drop(_Sending(now, 0, src, dst, payload, now, token, ln), now, "capacity")
            finish = max(now, self._radio_free.get(radio, -math.inf)) + n / self.rate
            self._radio_free[radio] = finish
            backlog.append((finish, n))
            self._waiting[radio] = waiting + n
        self._seq += 1
        heapq.heappush(
            self._sending, (finish, self._seq, _Sending(finish, self._seq, src, dst, payload, now, token, ln))
        )
        return None

    def due(self, now: float, view: Callable[[str, str], LinkView | None]) -> tuple[list[Delivery], list[Drop]]:
        """What arrived (in order of arrival) and what was dropped by ``now``."""
        drops: list[Drop] = []
        views: dict[int, LinkView | None] = {}  # each link asked once a call
        sending = self._sending
        while sending and sending[0][0] <= now:
            m = heapq.heappop(sending)[2]
            key = id(m.link)
            if key not in views:
                views[key] = view(m.src, m.dst)
            drop = self._judge(m, views[key])
            if drop is not None:
                drops.append(drop)
        out: list[Delivery] = []
        arriving = self._arriving
        while arriving and arriving[0][0] <= now:
            _, _, d, ln = heapq.heappop(arriving)
            c = ln.counts
            c.delivered += 1
            c.delivered_bytes += len(d.payload)
            c.delay_s += d.at - d.sent_at
            out.append(d)
        return out, drops

    def _judge(self, m: _Sending, lv: LinkView | None) -> Drop | None:
        ln = m.link
        if lv is None or not lv.holds:
            return self._drop(m, m.finish, "range")
        signal = lv.signal_dbm
        if self._rayleigh:
            signal += 10.0 * math.log10(max(ln.fade.expovariate(1.0), 1e-12))
            if signal < lv.cutoff_dbm and self._fade_loses:
                return self._drop(m, m.finish, "loss")  # faded below the cutoff
        if ln.loss.lost(signal - lv.cutoff_dbm, len(m.payload)):
            return self._drop(m, m.finish, "loss")
        at = m.finish + lv.distance_m / SPEED_OF_LIGHT_M_S + self.cfg.latency_s
        if self.cfg.jitter_s > 0.0:
            at += ln.jitter.uniform(0.0, self.cfg.jitter_s)
        if at < ln.last_at:  # a link's messages arrive in the order they were sent
            at = ln.last_at
        ln.last_at = at
        heapq.heappush(self._arriving, (at, m.seq, Delivery(m.token, m.src, m.dst, m.payload, m.sent_at, at), ln))
        return None

    def _drop(self, m: _Sending, at: float, cause: str) -> Drop:
        c = m.link.counts
        c.dropped[cause] += 1
        c.dropped_bytes[cause] += len(m.payload)
        return Drop(m.token, m.src, m.dst, len(m.payload), m.sent_at, at, cause)
