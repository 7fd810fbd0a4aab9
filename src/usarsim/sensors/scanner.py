"""Scanning range finders (protocol.md 7.3): RangeScanner with SICK LMS200 and
Hokuyo URG-04LX presets, IRScanner, RangeScanner3D.  All beams of one sweep are cast at one instant in one
batched ray cast; the first value is the rightmost beam."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeVar

import mujoco
import numpy as np

from usarsim.errors import ConfigError
from usarsim.readings import FieldValue, ItemParams, OperationResult, RangeScan3DReading, RangeScanReading
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig, check_range
from usarsim.sensors.noise import RANGES
from usarsim.sim.robotspec import add_housing
from usarsim.sim.view import unit_dirs_yaw_pitch

if TYPE_CHECKING:
    from usarsim.config.robot import MountedItem, RobotConfig
    from usarsim.sim.view import WorldView


LMS200_BLUE = (0.16, 0.33, 0.62)  # the SICK blue of an LMS200's housing


def trunc4(x: float) -> float:
    """USARSim printed scanner Resolution and FOV truncated to 4 decimals (0.0174, 3.1415);
    a value already written with 4 decimals (0.087) keeps them despite binary rounding."""
    scaled = x * 10000.0
    nearest = round(scaled)
    return (nearest if abs(scaled - nearest) < 1e-6 else math.trunc(scaled)) / 10000.0


@dataclass(frozen=True, kw_only=True)
class RangeScannerConfig(SensorConfig):
    """A scanning range finder's settings in a robot file (protocol.md 7.3): its range in metres, the angle between
    beams and the field of view of a sweep (rad), whether it sweeps in pan or tilt, and its relative noise."""

    # UDK RangeScanner base (protocol.md 7.3): MaxRange 4, MinRange 0.1, ScanInterval 0.2,
    # Resolution 0.157 rad, ScanFov 3.14, pan scan.
    max_range_m: float = 4.0
    min_range_m: float = 0.1
    resolution_rad: float = 0.157
    fov_rad: float = 3.14
    panning: bool = True
    tilting: bool = False
    noise: float = 0.001

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range(self.min_range_m, self.max_range_m)
        if not (0.0 < self.resolution_rad <= self.fov_rad <= 2 * math.pi):
            raise ValueError(f"need 0 < resolution_rad <= fov_rad <= 2 pi, got {self.resolution_rad}, {self.fov_rad}")

    @property
    def beam_count(self) -> int:
        # floor(FOV / Resolution) + 1 (181 for 1 degree over 180 degrees); the small
        # tolerance keeps exact multiples from losing a beam to rounding.
        return int(math.floor(self.fov_rad / self.resolution_rad + 1e-6)) + 1


RSC = TypeVar("RSC", bound=RangeScannerConfig)


@SENSORS.register("RangeScanner")
class RangeScanner(Sensor[RSC]):
    """A scanning laser range finder (protocol.md 6.3, 7.3): one sweep of beams across its
    field of view, rightmost first, each the distance to what it hits (MaxRange when nothing),
    with the relative noise of its settings."""

    SCANNABLE = True
    Config = RangeScannerConfig
    NOISE = RANGES
    RAY_KIND = "laser"  # which materials the beams pass through (world materials' see_through)
    ALIASES = {
        "MaxRange": "max_range_m",
        "MinRange": "min_range_m",
        "Resolution": "resolution_rad",
        "ScanFov": "fov_rad",
        "Fov": "fov_rad",
        "bYaw": "panning",
        "bPitch": "tilting",
        "Paning": "panning",
        "Panning": "panning",
        "Tilting": "tilting",
    }
    PRESETS = {
        # SICK LMS200 as USARSim configured it (protocol.md 7.3): 180 degrees, 1 degree,
        # 20 m.  The data sheet (SICK LMS200 Technical Description, 2003) gives 0.25/0.5/1
        # degree angular resolution over 180 degrees and a 10 mm range resolution.
        "SICK": {
            "max_range_m": 20.0,
            "min_range_m": 0.1,
            "resolution_rad": math.pi / 180.0,
            "fov_rad": math.pi,
            "scan_interval_s": 0.2,
        },
        # Hokuyo URG-04LX (protocol.md 7.3; Hokuyo URG-04LX specification: 240 degrees,
        # 0.36 degree steps, 4 m, 100 ms scan).  USARSim used 0.0184 rad steps and 0.3 s.
        "HokuyoURG04LX": {
            "max_range_m": 4.0,
            "min_range_m": 0.02,
            "resolution_rad": 0.0184,
            "fov_rad": 4.189,
            "scan_interval_s": 0.3,
        },
    }

    def build(self, spec: mujoco.MjSpec, chassis: mujoco.MjsBody, prefix: str) -> None:
        """What cameras see of a laser: a SICK LMS200's housing (155 x 156 x 210 mm, SICK's blue;
        LMS200 Technical Description, 2003) for one that reaches beyond 6 m, else a Hokuyo
        URG-04LX's (50 x 50 x 70 mm, black; Hokuyo URG-04LX specification); the scan plane in
        its upper part (an estimate, from photographs).  An IR scanner shows none."""
        if self.TYPE != "RangeScanner":
            return
        if self.config.max_range_m > 6.0:
            add_housing(
                spec, chassis, self.item, prefix, box=(0.156, 0.155, 0.21), rgb=LMS200_BLUE, offset=(-0.04, 0, 0.045)
            )
        else:
            add_housing(
                spec,
                chassis,
                self.item,
                prefix,
                box=(0.05, 0.05, 0.07),
                rgb=(0.08, 0.08, 0.08),
                offset=(-0.01, 0, 0.015),
            )

    def __init__(self, item: MountedItem, config: RSC, robot: RobotConfig, seed: int) -> None:
        super().__init__(item, config, robot, seed)
        cfg = self.config
        n = cfg.beam_count
        offsets = cfg.fov_rad / 2.0 - cfg.resolution_rad * np.arange(n)  # rightmost (+yaw) first
        if cfg.tilting and not cfg.panning:
            self._dirs = unit_dirs_yaw_pitch(np.zeros(n), offsets)
        else:
            self._dirs = unit_dirs_yaw_pitch(offsets, np.zeros(n))

    def sense(self, view: WorldView) -> np.ndarray:
        cfg = self.config
        pos, rot = self.handle.sensor_frame(view.data, self.item.location, self.item.orientation, self.item.mount)
        dist, _, _ = view.caster.cast(pos, self._dirs @ rot.T, cfg.max_range_m, self.handle.body_id, kind=self.RAY_KIND)
        return dist

    def reading(self, values: np.ndarray) -> RangeScanReading:
        cfg = self.config
        return RangeScanReading(
            self.TYPE, self.name, trunc4(cfg.resolution_rad), trunc4(cfg.fov_rad), tuple(values.tolist())
        )

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        c = self.config
        return (
            ("MaxRange", c.max_range_m),
            ("MinRange", c.min_range_m),
            ("Resolution", trunc4(c.resolution_rad)),
            ("Fov", trunc4(c.fov_rad)),
            ("Paning", c.panning),
            ("Tilting", c.tilting),
        )


@dataclass(frozen=True, kw_only=True)
class IRScannerConfig(RangeScannerConfig):
    """An IRScanner's settings in a robot file (protocol.md 7.3): a longer range and coarser resolution than the
    RangeScanner base."""

    # IRScanner (protocol.md 7.3): MaxRange 10, Resolution 0.087, ScanFov 3.14.
    max_range_m: float = 10.0
    resolution_rad: float = 0.087
    fov_rad: float = 3.14


@SENSORS.register("IRScanner")
class IRScanner(RangeScanner[IRScannerConfig]):
    """A scanning infrared range finder: its beams pass through what IR sees through (glass)."""

    RAY_KIND = "ir"
    PRESETS = {}


# Lines are kept shorter than this many bytes, CR LF included, so that the clients written
# for USARSim read each whole (protocol.md 1: "keep single lines below 4096 bytes"): Player's
# usarsim driver reads a line into a USBOT_MAX_MSG_LEN + 1 = 4097-byte buffer up to its LF
# (us_bot.h: USBOT_MAX_MSG_LEN 4096; us_bot.cc, UsBot::Main) and takes a segment's value only
# when it ends before byte 4096 (us_parser.cc, us_get_value2), the Range of a 3D sweep into a
# US_MAX_MSG_LEN = 4096-byte buffer (us_parser.h; us_get_laser3d); the SPQR RDK's USARSim
# client reads its lines the same way (usarsimclientmodule.h: USBOT_MAX_MSG_LEN 4096;
# us_getData).  The protocol layer keeps the same bound (usarsim.protocol.messages.LINE_LIMIT).
LINE_LIMIT = 4096

# The widest Time a SEN line's length is reckoned with: 4 decimals (protocol.md 2.4) and
# 9 digits before the point, 31 years of simulated time.
_LONGEST_TIME = "999999999.9999"


@dataclass(frozen=True, kw_only=True)
class RangeScanner3DConfig(SensorConfig):
    """A RangeScanner3D's settings in a robot file (protocol.md 7.3): its range in metres, its horizontal and
    vertical field of view and resolution (rad), which make its grid of beams, and whether a sweep goes out as one
    SEN line or one line per row."""

    # RangeScanner3D (protocol.md 7.3, UT Tarantula/Ardabot configs: USARBot.ini
    # [USARBot.RangeScanner3D], as the Ardabot4j project page gives it): MaxRange 1000
    # (effectively unlimited), ScanInterval 0.4, HorizontalFOV 1.0472 (60 degrees),
    # VerticalFOV 0.4363 (25 degrees).  USARSim's resolutions there, 0.0209 and 0.0145 rad,
    # make 51 x 31 = 1581 beams, up to 16 kB a sweep at this MaxRange: nearly four times the
    # line Player's driver and the SPQR RDK read (LINE_LIMIT), so neither could take such a
    # sweep whole.  Here the same field of view at 0.0436 rad (2.5 degrees) both ways:
    # 25 x 11 = 275 beams, a beam straight ahead in the middle of the middle row, and a sweep
    # of at most 2.9 kB with these ranges, within LINE_LIMIT.  USARSim's own grid is had with
    # its two resolutions and ``split_rows: true``.
    max_range_m: float = 1000.0
    min_range_m: float = 0.1
    scan_interval_s: float = 0.4
    horizontal_fov_rad: float = 1.0472
    horizontal_resolution_rad: float = 0.0436
    vertical_fov_rad: float = 0.4363
    vertical_resolution_rad: float = 0.0436
    panning: bool = False
    tilting: bool = True
    noise: float = 0.001
    # False: each sweep is one SEN line, the form of protocol.md 6.3 that Player's laser3d
    # driver and UvA parse; True: one line per row with {Frames rows} {Frame k}, the form
    # of the UDK RangeImager (protocol.md 6.3), for a sweep too long for one line.
    split_rows: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range(self.min_range_m, self.max_range_m)
        for res, fov, what in (
            (self.horizontal_resolution_rad, self.horizontal_fov_rad, "horizontal"),
            (self.vertical_resolution_rad, self.vertical_fov_rad, "vertical"),
        ):
            if not (0.0 < res <= fov <= 2 * math.pi):
                raise ValueError(f"need 0 < {what} resolution <= {what} fov <= 2 pi, got {res}, {fov}")
        rows, cols = self.counts
        if rows * cols > 100_000:
            raise ValueError(f"{rows} x {cols} beams is more than 100000 per scan")

    @property
    def counts(self) -> tuple[int, int]:
        """(rows, columns): vertical steps, horizontal steps."""
        return (
            int(math.floor(self.vertical_fov_rad / self.vertical_resolution_rad + 1e-6)) + 1,
            int(math.floor(self.horizontal_fov_rad / self.horizontal_resolution_rad + 1e-6)) + 1,
        )

    def _line_parts(self, name: str, split: bool) -> tuple[int, int, int]:
        """(bytes of the line but its ranges, CR LF included; ranges in it; bytes of a range
        with its comma) of the longest SEN line of the scanner ``name`` in the one-line form
        (``split`` False) or the split form: Time at its widest, every range at MaxRange, the
        widest it prints."""
        rows, cols = self.counts
        head = "SEN {Time %s} {Type RangeScanner3D} {Name %s} %s{Resolution %.4f,%.4f} {FOV %.4f,%.4f} {Range }\r\n" % (
            _LONGEST_TIME,
            name,
            "{Frames %d} {Frame %d} " % (rows, rows - 1) if split else "",
            trunc4(self.vertical_resolution_rad),
            trunc4(self.horizontal_resolution_rad),
            trunc4(self.vertical_fov_rad),
            trunc4(self.horizontal_fov_rad),
        )
        return len(head.encode()), cols if split else rows * cols, len("%.4f" % self.max_range_m) + 1

    def longest_line(self, name: str, split: bool) -> int:
        """The bytes, CR LF included, of the longest SEN line the scanner ``name`` can send in
        the one-line form (``split`` False) or the split form (one fewer comma than ranges)."""
        head, beams, value = self._line_parts(name, split)
        return head + beams * value - 1

    def line_problem(self, name: str, split: bool) -> str | None:
        """Why the scanner ``name`` cannot send its sweeps within LINE_LIMIT in the one-line
        form (``split`` False) or the split form (None: it can): what to change, and how
        many beams would fit."""
        longest = self.longest_line(name, split)
        if longest < LINE_LIMIT:
            return None
        rows, cols = self.counts
        head, _, value = self._line_parts(name, split)
        fit = (LINE_LIMIT - head) // value  # head + fit * value - 1 < LINE_LIMIT
        if split:
            return (
                f"a row of {cols} beams up to {self.max_range_m:g} m makes SEN lines of up to {longest} bytes, "
                f"more than the {LINE_LIMIT - 1} old clients read in one line, even in the split form (at most "
                f"{fit} beams a row at this MaxRange): choose a coarser horizontal_resolution_rad, a narrower "
                f"horizontal_fov_rad or a shorter max_range_m"
            )
        return (
            f"a sweep of {rows} x {cols} beams up to {self.max_range_m:g} m makes SEN lines of up to {longest} "
            f"bytes, more than the {LINE_LIMIT - 1} old clients read in one line (at most {fit} beams a sweep at "
            f"this MaxRange): choose a coarser vertical_resolution_rad or horizontal_resolution_rad, a narrower "
            f"field of view or a shorter max_range_m, or set split_rows: true to send one line per row"
        )


@SENSORS.register("RangeScanner3D", "3DRangeScanner")
class RangeScanner3D(Sensor[RangeScanner3DConfig]):
    """A 3D laser (a tilting or panning 2D scanner, as on Kurt3D): all beams of a sweep
    at one instant, every ScanInterval of simulated time, row-major -- one horizontal line
    per vertical step, the top row first, each row from its rightmost beam to its leftmost,
    as the 2D scanner.

    On the wire (protocol.md 6.3) a sweep is one SEN line::

        SEN {Time t} {Type RangeScanner3D} {Name n} {Resolution vres,hres} {FOV vfov,hfov} {Range r1,r2,...}

    with rows x columns values; the configuration is refused when that line would reach the
    4096 bytes old clients read (:data:`LINE_LIMIT`, protocol.md 1).

    Opt-in, by ``split_rows: true`` in the robot file or ``SET {Type RangeScanner3D} {Name n}
    {Opcode Split} {Params 1}`` (``{Params 0}`` goes back), a sweep is sent as one line per
    row instead, all with the sweep's Time, the top row first, each naming its row the way the
    UDK RangeImager names its frames (protocol.md 6.3)::

        SEN {Time t} {Type RangeScanner3D} {Name n} {Frames rows} {Frame k}
            {Resolution vres,hres} {FOV vfov,hfov} {Range r1,...,r_cols}

    (one line on the wire, broken here for reading).

    ``Frames`` is the number of rows (= lines) of the sweep and ``Frame`` the row this line
    holds, 0 for the top row up to rows - 1; Resolution and FOV are the whole sweep's, so
    row k looks ``vfov / 2 - k * vres`` up.  A SET to the one-line form fails (RES Failed)
    when the sweep would not fit in one line.
    """

    NOISE = RANGES

    SCANNABLE = True
    RAY_KIND = "laser"
    ALIASES = {
        "MaxRange": "max_range_m",
        "MinRange": "min_range_m",
        "HorizontalFOV": "horizontal_fov_rad",
        "HorizontalResolution": "horizontal_resolution_rad",
        "VerticalFOV": "vertical_fov_rad",
        "VerticalResolution": "vertical_resolution_rad",
        "bYaw": "panning",
        "bPitch": "tilting",
        "Paning": "panning",
        "Panning": "panning",
        "Tilting": "tilting",
    }

    def __init__(self, item: MountedItem, config: RangeScanner3DConfig, robot: RobotConfig, seed: int) -> None:
        super().__init__(item, config, robot, seed)
        c = self.config
        problem = c.line_problem(self.name, c.split_rows)
        if problem is not None:
            raise ConfigError(
                f"invalid {self.TYPE} settings: {problem}", path=robot.path, key=item.key_path or item.name
            )
        self.split = c.split_rows  # the form sweeps go out in; SET {Opcode Split} changes it
        rows, cols = c.counts
        pitches = c.vertical_fov_rad / 2.0 - c.vertical_resolution_rad * np.arange(rows)  # top row first
        yaws = c.horizontal_fov_rad / 2.0 - c.horizontal_resolution_rad * np.arange(cols)  # rightmost first
        pp, yy = np.meshgrid(pitches, yaws, indexing="ij")
        self._dirs = unit_dirs_yaw_pitch(yy.reshape(-1), pp.reshape(-1))

    def sense(self, view: WorldView) -> np.ndarray:
        c = self.config
        pos, rot = self.handle.sensor_frame(view.data, self.item.location, self.item.orientation, self.item.mount)
        dist, _, _ = view.caster.cast(pos, self._dirs @ rot.T, c.max_range_m, self.handle.body_id, kind=self.RAY_KIND)
        return dist

    def reading(self, values: np.ndarray) -> RangeScan3DReading:
        c = self.config
        return RangeScan3DReading(
            self.name,
            (trunc4(c.vertical_resolution_rad), trunc4(c.horizontal_resolution_rad)),
            (trunc4(c.vertical_fov_rad), trunc4(c.horizontal_fov_rad)),
            tuple(values.tolist()),
            sensor_type=self.TYPE,
            frames=c.counts[0],
            split=self.split,
        )

    def operate(self, view: WorldView, opcode: str, params: ItemParams) -> OperationResult | None:
        """``{Opcode SCAN}`` (a sweep at once, in the form chosen) and ``{Opcode Split}
        {Params 1|0}`` (also ``True``/``False``): one line per row from now on, or one line per
        sweep again; Failed when Params is neither or the sweep would not fit in one line."""
        if opcode.upper() != "SPLIT":
            return super().operate(view, opcode, params)
        text = (params.text or "").strip().lower()
        if params.values is not None and len(params.values) == 1 and params.values[0] in (0.0, 1.0):
            split = params.values[0] == 1.0
        elif text in ("true", "false"):
            split = text == "true"
        else:
            return OperationResult(ok=False)
        if self.config.line_problem(self.name, split) is not None:
            return OperationResult(ok=False)
        self.split = split
        return OperationResult(ok=True)

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        c = self.config
        return (
            ("MaxRange", c.max_range_m),
            ("MinRange", c.min_range_m),
            ("Resolution", (trunc4(c.vertical_resolution_rad), trunc4(c.horizontal_resolution_rad))),
            ("Fov", (trunc4(c.vertical_fov_rad), trunc4(c.horizontal_fov_rad))),
            ("Paning", c.panning),
            ("Tilting", c.tilting),
        )
