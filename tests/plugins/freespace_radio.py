"""A radio model that is not built in, added from the test tree: free-space propagation (Friis)
with walls ignored.  Importing this module registers it as ``freespace``; ``serve
--wireless-model freespace`` or a world's ``wireless: {model: freespace}`` chooses it."""

from __future__ import annotations

import math
from dataclasses import dataclass

from usarsim.sim.radio import RADIO_MODELS, RadioModel

SPEED_OF_LIGHT_M_S = 299_792_458.0  # exact, by the definition of the metre (SI, 1983)


@RADIO_MODELS.register("freespace")
@dataclass(frozen=True, kw_only=True)
class FreeSpace(RadioModel):
    """S = P_tx - FSPL, FSPL = 20 log10(4 pi d f / c) (Friis, Proc. IRE 34, 1946), in dBm:
    a 2.4 GHz radio (IEEE 802.11b/g) sending 20 dBm (100 mW, the EIRP limit of ETSI EN 300 328
    for the 2.4 GHz band) with isotropic antennas, walls ignored."""

    name: str = "freespace"
    tx_power_dbm: float = 20.0
    frequency_hz: float = 2.4e9
    COUNTS_WALLS = False

    def signal_dbm(self, distance_m: float, walls: int = 0) -> float:
        d = max(distance_m, 0.01)
        return self.tx_power_dbm - 20.0 * math.log10(4.0 * math.pi * d * self.frequency_hz / SPEED_OF_LIGHT_M_S)

    def describe(self) -> str:
        return (
            f"freespace ({self.tx_power_dbm:g} dBm at {self.frequency_hz / 1e9:g} GHz, cutoff {self.cutoff_dbm:g} dBm)"
        )
