"""The loss models of the radio channel (:mod:`usarsim.sim.channel`): whether each message of a
link is lost, one class registered in :data:`LOSS_MODELS` per model, and the packet error rate
of a signal margin that the ``signal`` model and a link's quality use."""

from __future__ import annotations

import math
import random
from collections.abc import Mapping
from typing import Any, ClassVar

from usarsim.config.channel import ChannelConfig
from usarsim.config.reader import did_you_mean
from usarsim.errors import ConfigError
from usarsim.registry import Registry

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
        jitter = f" + up to {cfg.jitter_s:g} s" if cfg.jitter_s else ""
        parts.append(f"latency {cfg.latency_s:g} s{jitter}")
    return "; ".join(parts) or "ideal"
