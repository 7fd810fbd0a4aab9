"""The radio channel beyond the path loss, as a world's ``wireless: {channel: ...}`` section or a
wireless configuration file gives it (docs/wireless.md, "The channel"): shadowing and fading,
the loss model, capacity, queueing and delay.

Every default leaves the channel ideal, as USARSim's was: a message is delivered at once, whole,
while the link's signal holds (``ChannelConfig().ideal``).  A loss model's own settings are kept
as written here and read by the model (:mod:`usarsim.sim.channel`), as a drive reads its own
section of a robot file.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from usarsim.config.reader import FieldDefaults, Section

FADING = ("none", "rayleigh")


@dataclass(frozen=True, kw_only=True)
class ChannelConfig:
    """The channel of every link (docs/wireless.md, "The channel")."""

    # log-normal shadowing: a link's signal is offset by a normal draw of this standard
    # deviation (dB), plus ``shadowing_wall_db`` for each wall on the line (signals worsen round
    # corners), drawn again when either end has moved ``shadowing_distance_m``
    shadowing_db: float = 0.0
    shadowing_wall_db: float = 0.0
    shadowing_distance_m: float = 2.0
    fading: str = "none"  # FADING: each message's own fast fade on top (rayleigh)
    loss: str = "none"  # the loss model's name (usarsim.sim.channel.LOSS_MODELS)
    loss_settings: dict[str, Any] = field(default_factory=dict)  # its own keys, as written
    link_bytes_per_s: float | None = None  # a link's capacity; None: unlimited
    radio_bytes_per_s: float | None = None  # what a radio sends at most, over all its links
    queue_bytes: int = 1_000_000  # waiting at a radio at most; a message beyond is dropped
    latency_s: float = 0.0  # added to every message's delay
    jitter_s: float = 0.0  # and a uniform draw from 0 to this
    seed: int | None = None  # None: the server's --seed

    @property
    def ideal(self) -> bool:
        """Whether messages go through at once and whole while a link holds (the channel
        changes nothing: USARSim's behaviour)."""
        return (
            self.shadowing_db == 0.0
            and self.shadowing_wall_db == 0.0
            and self.fading == "none"
            and self.loss == "none"
            and self.link_bytes_per_s is None
            and self.radio_bytes_per_s is None
            and self.latency_s == 0.0
            and self.jitter_s == 0.0
        )


def read_channel(s: Section) -> ChannelConfig:
    """The ``channel`` mapping: the fields of :class:`ChannelConfig`; ``loss`` is a loss model's
    name or a mapping ``{model: name, ...its own settings}``."""
    d = FieldDefaults(ChannelConfig)
    if isinstance(s.data.get("loss"), dict):
        ls = s.section("loss")
        loss = ls.str("model")
        settings = {str(k): v for k, v in ls.data.items() if k != "model"}
    else:
        settings = {}
        loss = s.str("loss", d.loss)
    if not loss.isidentifier() or loss != loss.lower():
        raise s.error("loss", f"a loss model's name is a lower-case word (none, independent, ...), got {loss!r}")
    cfg = ChannelConfig(
        shadowing_db=s.float("shadowing_db", d.shadowing_db, min=0.0, max=30.0),
        shadowing_wall_db=s.float("shadowing_wall_db", d.shadowing_wall_db, min=0.0, max=30.0),
        shadowing_distance_m=s.float("shadowing_distance_m", d.shadowing_distance_m, min=0.0),
        fading=s.str("fading", d.fading, choices=FADING),
        loss=loss,
        loss_settings=settings,
        link_bytes_per_s=_rate(s, "link_bytes_per_s"),
        radio_bytes_per_s=_rate(s, "radio_bytes_per_s"),
        queue_bytes=s.int("queue_bytes", d.queue_bytes, min=0),
        latency_s=s.float("latency_s", d.latency_s, min=0.0, max=60.0),
        jitter_s=s.float("jitter_s", d.jitter_s, min=0.0, max=60.0),
        seed=s.int("seed", d.seed, min=0),
    )
    s.finish()
    return cfg


def _rate(s: Section, name: str) -> float | None:
    v = s.raw(name, None)
    return None if v is None else s.float(name, min=1.0)
