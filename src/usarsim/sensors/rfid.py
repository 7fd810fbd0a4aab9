"""RFID: the tag reader (``RFID``, protocol.md 7.10 and 5.4, manual section 10.9); the
tag dropper is an effecter (:mod:`usarsim.effecters.releaser`).

Tags are world entities (the world file's ``rfid_tags``, plus the ones robots drop),
each with an integer id and a memory that any robot's reader can read and write: the
tag keeps what was written, for everyone.

The reader's three sensing modes, after the UT2004 RFID sensor's ``SensingMode`` setting
(manual 10.9.3, "Choosing the right SensingMode"), whose values are named ``Radius``,
``Obstacle`` and ``Attenuation``; the robot file gives the number or the name, and GETCONF
reports the name:

* 0, ``Radius``: every tag within MaxRange is detected, walls or not;
* 1, ``Obstacle``: ... and no wall stands on the straight line to it;
* 2, ``Attenuation``: the tag's signal at the reader, P(d) = P(1 m) - 10 n log10(d) -
  ObstacleLoss x (walls crossed), must reach the Threshold (and d <= MaxRange).

Walls are the static solids of the world, counted as the wireless simulation counts them
(``RayCaster.count_walls``); robots and victims are not walls.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from usarsim.readings import FieldValue, ItemParams, OperationResult, RfidReading, RfidTag
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig
from usarsim.sim import frames

if TYPE_CHECKING:
    from usarsim.sim.view import WorldView

SENSING_MODES = ("Radius", "Obstacle", "Attenuation")
"""The names of sensing modes 0, 1 and 2: the values of the UT2004 RFID sensor's SensingMode
(manual 10.9.3)."""


@dataclass(frozen=True, kw_only=True)
class RfidConfig(SensorConfig):
    """An RFID reader's settings in a robot file (protocol.md 7.10, manual 10.9.3): its range in metres, its sensing
    mode, the signal model (dBm, dB) of the Attenuation mode, and its scan interval."""

    # The reader's range was not recovered from any USARSim source (protocol.md 7.10:
    # "a few metres"); 3 m is an estimate for a passive UHF tag reader.
    max_range_m: float = 3.0
    sensing_mode: int | str = 0  # 0, 1, 2 or its name (SENSING_MODES); a number once made
    # Signal-strength mode (estimates, no USARSim figures survive): -40 dBm at 1 m,
    # free-space exponent 2, 10 dB per wall, detection down to -75 dBm.
    signal_at_1m_dbm: float = -40.0
    path_loss_exponent: float = 2.0
    obstacle_loss_db: float = 10.0
    threshold_dbm: float = -75.0
    scan_interval_s: float = 0.2

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.max_range_m <= 0:
            raise ValueError(f"max_range_m must be > 0, got {self.max_range_m}")
        mode = self.sensing_mode
        if isinstance(mode, str):
            names = {n.lower(): i for i, n in enumerate(SENSING_MODES)}
            mode = names.get(mode.strip().lower(), mode)
        if isinstance(mode, bool) or not isinstance(mode, int) or mode not in (0, 1, 2):
            raise ValueError(
                f"sensing_mode must be 0 (Radius), 1 (Obstacle) or 2 (Attenuation), got {self.sensing_mode!r}"
            )
        object.__setattr__(self, "sensing_mode", mode)


def _tag_and_data(text: str | None) -> tuple[int | None, str]:
    """The tag id and the data of an RFID operation's Params, ``<tagID> <data...>``
    (protocol.md 5.4): the data is text and may hold blanks and commas."""
    words = (text or "").strip().split(None, 1)
    try:
        tag = int(words[0])
    except (ValueError, IndexError):
        return None, ""
    return tag, words[1] if len(words) > 1 else ""


@SENSORS.register("RFID", "RFIDSensor")
class RFID(Sensor[RfidConfig]):
    """An RFID reader (protocol.md 6.3, 7.10): the tags within range, by the sensing mode
    (every tag in the radius, only those with no wall between, or those whose attenuated
    signal is above the threshold), with their memory."""

    RAY_KIND = "laser"  # radio does not pass walls any better than light here; glass counts as a wall
    ALIASES = {
        "MaxRange": "max_range_m",
        "SensingMode": "sensing_mode",
        "ObstacleLoss": "obstacle_loss_db",
        "Threshold": "threshold_dbm",
    }

    def _detected(self, view: WorldView) -> list[tuple[int, tuple[float, float, float]]]:
        """(tag id, tag position in the sensor frame) of every tag the reader senses now."""
        ents = view.entities
        if ents is None or not ents.tags:
            return []
        c = self.config
        d = view.data
        pos, rot = self.handle.sensor_frame(d, self.item.location, self.item.orientation, self.item.mount)
        ids, world = ents.tag_positions()
        delta = world - pos
        dist = np.linalg.norm(delta, axis=1)
        near = np.flatnonzero(dist <= c.max_range_m)
        out = []
        mode = int(c.sensing_mode)  # a number once the config is made
        if len(near) and mode > 0:
            # walls on each line to a tag (a tag lying on a surface is not behind it)
            walls = view.caster.count_walls(
                np.broadcast_to(pos, (len(near), 3)),
                world[near],
                kind=self.RAY_KIND,
                end_margin=0.01,
                stop_at_first=mode == 1,
            )
        for k, i in enumerate(near.tolist()):
            if mode == 1 and walls[k] > 0:
                continue
            if mode == 2:
                r = max(float(dist[i]), 0.01)
                p = c.signal_at_1m_dbm - 10.0 * c.path_loss_exponent * math.log10(r) - c.obstacle_loss_db * walls[k]
                if p < c.threshold_dbm:
                    continue
            local = rot.T @ delta[i]
            out.append((ids[i], frames.from_mj_vec(local)))
        return out

    def measure(self, view: WorldView) -> RfidReading:
        ents = view.entities
        if ents is None:  # a world without entities has no tags
            return RfidReading(self.name, ())
        tags = []
        for tid, loc in self._detected(view):
            mem = ents.tags[tid].memory
            tags.append(RfidTag(tid, loc, mem if mem else None))  # a blank tag: no {Mem}
        return RfidReading(self.name, tuple(tags))

    def operate(self, view: WorldView, opcode: str, params: ItemParams) -> OperationResult | None:
        """Read, Write and Erase of a tag's memory (protocol.md 5.4; manual 10.9.5-10.9.7):
        the tag must be sensed now.  Read replies ``{ID id} {Mem data}``; a blank tag (never
        written, or erased) has the empty text as its data, printed ``{Mem }``, and its SEN
        pair carries no Mem (protocol.md 6.3: only tags written with data add one).  The
        Params are text, ``<tagID> <data...>``."""
        op = opcode.lower()
        if op not in ("read", "write", "erase"):
            return None
        tid, data = _tag_and_data(params.text)
        ents = view.entities
        if tid is None or ents is None or tid not in {t for t, _ in self._detected(view)}:
            return OperationResult(ok=False)
        tag = ents.tags[tid]
        if op == "read":
            return OperationResult(ok=True, extra=(("ID", tid), ("Mem", tag.memory)))
        if op == "erase":
            tag.memory = ""
            return OperationResult(ok=True)
        if any(ch in data for ch in "{}\r\n") or len(data) > 1024:
            return OperationResult(ok=False)
        tag.memory = data
        return OperationResult(ok=True)

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        c = self.config
        return (
            ("ScanInterval", c.scan_interval_s),
            ("MaxRange", c.max_range_m),
            ("SensingMode", SENSING_MODES[int(c.sensing_mode)]),
        )
