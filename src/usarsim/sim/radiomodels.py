"""The radio propagation models of the wireless simulation (manual section 3.2.4; protocol.md 12).

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
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar

from usarsim.config.channel import ChannelConfig
from usarsim.config.reader import did_you_mean
from usarsim.config.world import WIRELESS_MODELS, WirelessConfig
from usarsim.errors import ConfigError
from usarsim.registry import Registry
from usarsim.sim.channel import check_channel

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
