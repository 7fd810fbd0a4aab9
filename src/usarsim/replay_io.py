"""What ``usarsim replay`` (:mod:`usarsim.replay`) reads and what it reports: a recording read
back from its first byte on (:func:`read_recording`: the transcript and run information; one
the server did not close is read up to where it ends), the first difference between the
recorded and the replayed server lines (:class:`Difference`) and the report of a replay
(:class:`Report`, :func:`format_report`).
"""

from __future__ import annotations

import math
import os
import shlex
from dataclasses import dataclass, field

from usarsim.errors import UsarsimError
from usarsim.server.recording.transcript import (
    METADATA_NAME,
    TOPIC,
    Chunk,
    RunInfo,
    decode_chunk,
    parse_run_info,
)


class ReplayError(UsarsimError):
    """A recording that cannot be replayed (missing, not MCAP, damaged, no transcript, an
    unknown world)."""


@dataclass
class Recording:
    """A recording (MCAP, ``usarsim serve --record``) read back: its run information and the transcript's chunks in
    order, and, for one the server did not close, where its readable part ends."""

    path: str
    info: RunInfo
    chunks: list[Chunk]
    complete: bool = True  # False: the server stopped without closing the file (killed, crashed)
    end_time: float = 0.0  # simulated time of the last message it holds, s
    end_byte: int = 0  # where its readable part ends
    size: int = 0  # bytes in the file

    def ending(self) -> str | None:
        """A recording the server did not close: where it ends, in words (None when closed)."""
        if self.complete:
            return None
        return (
            f"the recording ends at t={self.end_time:.3f} s, byte {self.end_byte} of {self.size} (it was not "
            "closed: the server stopped without closing it, killed or crashed, or the file was cut short); "
            "what it holds is replayed"
        )


def read_recording(path: str | os.PathLike) -> Recording:
    """The transcript and run information of a recording, read from its first byte on
    (:func:`usarsim.server.recording.reading.read_mcap`): a recording the server did not close
    is read up to where it ends.  ReplayError says in one line what is wrong with the file."""
    from usarsim.server.recording.reading import DamagedRecording, RecordingError, read_mcap

    name = str(path)
    try:
        contents = read_mcap(path, topics=[TOPIC])
    except DamagedRecording as exc:
        raise ReplayError(
            f"{exc}: the file was changed after it was written (a disk or copy error); what comes "
            f"before that byte replays: head -c {exc.offset} {shlex.quote(name)} > part.mcap && "
            "usarsim replay part.mcap"
        ) from exc
    except RecordingError as exc:
        raise ReplayError(f"{exc}; give a recording made with usarsim serve --record") from exc
    except OSError as exc:
        raise ReplayError(f"{name} cannot be read ({exc.strerror or exc})") from exc
    meta = contents.metadata.get(METADATA_NAME)
    if meta is None:
        if not contents.complete:
            raise ReplayError(
                f"{name} ends at byte {contents.end} before its run information (the server stopped "
                "as it started): nothing to replay"
            )
        raise ReplayError(f"{name}: no '{METADATA_NAME}' metadata: not recorded by usarsim serve --record")
    chunks: list[Chunk] = []
    try:
        info = parse_run_info(meta)
        for _, _, data in contents.messages:
            chunks.append(decode_chunk(data))
    except (ValueError, KeyError, TypeError) as exc:
        raise ReplayError(
            f"{name}: its transcript does not decode ({type(exc).__name__}: {exc}): not a usarsim "
            "recording, or one changed after it was written"
        ) from exc
    chunks.sort(key=lambda c: c.seq)
    return Recording(
        name,
        info,
        chunks,
        complete=contents.complete,
        end_time=contents.end_ns / 1e9,
        end_byte=contents.end,
        size=contents.size,
    )


@dataclass
class Difference:
    """The first server line where a replay differs from its recording: the connection, the line's number on it and
    its simulated time (s), and the recorded and replayed lines (None where one side has no line)."""

    conn: int
    port: str
    peer: str
    line_no: int  # 1-based, among the server lines of this connection
    sim_time: float
    recorded: str | None  # None: the server sent a line the recording does not have
    replayed: str | None  # None: the server did not send the recorded line

    def describe(self) -> str:
        head = (
            f"first difference: connection {self.conn} ({self.port}, recorded from {self.peer}), "
            f"server line {self.line_no}, at t={self.sim_time:.3f} s"
        )
        rec = "(nothing)" if self.recorded is None else self.recorded
        rep = "(nothing within the timeout)" if self.replayed is None else self.replayed
        return f"{head}\n  recorded: {_clip(rec)}\n  replayed: {_clip(rep)}"


def _clip(s: str, n: int = 400) -> str:
    return s if len(s) <= n else s[:n] + f"... ({len(s)} characters)"


@dataclass
class Report:
    """What a replay found: the connections replayed and skipped, by port, the client lines sent, how many server
    lines were compared and how many came out identical, the first difference and, in real time, the largest
    difference of the numbers by kind of line."""

    info: RunInfo
    connections: dict[str, int] = field(default_factory=dict)  # replayed, by port
    skipped: dict[str, int] = field(default_factory=dict)  # not replayed, by port
    client_lines: int = 0
    compared: int = 0
    identical: int = 0
    first: Difference | None = None
    last_time: float = 0.0
    numbers: dict[str, float] = field(default_factory=dict)  # real time: kind -> largest difference
    wall_s: float = 0.0

    @property
    def ok(self) -> bool:
        return self.first is None and self.compared == self.identical


def format_report(path: str, rep: Report) -> str:
    info = rep.info
    clock = "lock-step" if info.lockstep else ("max speed" if info.speed is None else f"speed {info.speed:g}x")
    conns = ", ".join(f"{n} {p}" for p, n in sorted(rep.connections.items())) or "none"
    out = [
        f"{path}: {info.world}, seed {info.seed}, {clock}, recorded by usarsim {info.version}",
        f"replayed {sum(rep.connections.values())} connections ({conns}), {rep.client_lines} client lines up to "
        f"t={rep.last_time:.3f} s, in {rep.wall_s:.1f} s",
    ]
    if rep.skipped:
        out.append(
            "not replayed: "
            + ", ".join(f"{n} {p} connection{'s' if n != 1 else ''}" for p, n in sorted(rep.skipped.items()))
        )
    if rep.ok:
        out.append(f"identical: all {rep.compared} server lines are the recorded ones")
        return "\n".join(out)
    out.append(f"{rep.identical} of {rep.compared} server lines compared are identical")
    if not info.lockstep and rep.numbers:
        worst = sorted(rep.numbers.items(), key=lambda kv: -kv[1])[:8]
        out.append(
            "largest differences of the numbers, by kind of line: "
            + "; ".join(f"{k}: {'different fields' if math.isinf(v) else f'{v:.4g}'}" for k, v in worst)
        )
    if rep.first is not None:
        out.append(rep.first.describe())
    return "\n".join(out)
