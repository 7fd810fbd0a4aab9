"""The protocol transcript of a recording: every chunk of bytes each connection of the
simulator's ports received and sent, in the order the server saw them (sans-IO: encoding
and decoding only).

A chunk is one MCAP message on :data:`TOPIC`, JSON encoded (:data:`SCHEMA`)::

    {"seq": 12, "conn": 3, "port": "control", "peer": "127.0.0.1:50312", "kind": "in",
     "sim_time": 1.2, "wall_time": 1764000000.123, "text": "DRIVE {Left 1} {Right 1}\\r\\n"}

``kind`` is ``open`` (a connection accepted), ``in`` (bytes from the client), ``out`` (bytes
to it) or ``close``.  ``text`` holds the bytes exactly, one character per byte (Latin-1), so
that any byte a client sends survives the round trip; a binary output (the image server's
pictures) carries its size in ``bytes`` and no text.  ``seq`` numbers the chunks of a
recording from 0 without gaps; ``conn`` numbers the connections in the order they were
accepted, over every port.

The recording's metadata record :data:`METADATA_NAME` holds what a replay needs to start the
same server (:func:`run_info` and :func:`parse_run_info`).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

TOPIC = "/usarsim/transcript"
SCHEMA_NAME = "usarsim.TranscriptChunk"
METADATA_NAME = "usarsim"
KINDS = ("open", "in", "out", "close")

SCHEMA = {
    "title": SCHEMA_NAME,
    "description": "Bytes one connection of the simulator received (in) or sent (out), or its opening or "
    "closing, in the order the server saw them.",
    "type": "object",
    "properties": {
        "seq": {"type": "integer", "description": "order of the chunk in the recording, from 0"},
        "conn": {"type": "integer", "description": "connection number, in the order accepted over all ports"},
        "port": {"type": "string", "description": "control, truth, image, comserver, wss or cominterface"},
        "peer": {"type": "string", "description": "the client's address, ip:port"},
        "kind": {"type": "string", "enum": list(KINDS)},
        "sim_time": {"type": "number", "description": "simulated time when the server saw it, s"},
        "wall_time": {"type": "number", "description": "wall-clock time when the server saw it, s since 1970"},
        "text": {"type": "string", "description": "the bytes, one character per byte (Latin-1)"},
        "bytes": {"type": "integer", "description": "size of a binary output whose bytes are not kept"},
    },
    "required": ["seq", "conn", "port", "peer", "kind", "sim_time", "wall_time"],
}


@dataclass(frozen=True, slots=True)
class Chunk:
    """One chunk of a recording's transcript (an MCAP message on :data:`TOPIC`): the bytes a connection received or
    sent, or its opening or closing, with the simulated and wall-clock time (s) at which the server saw them."""

    seq: int
    conn: int
    port: str
    peer: str
    kind: str
    sim_time: float
    wall_time: float
    text: str = ""
    size: int | None = None  # a binary output: its size; its bytes are not kept

    @property
    def data(self) -> bytes:
        return self.text.encode("latin-1")


def encode_chunk(c: Chunk) -> bytes:
    d = {
        "seq": c.seq,
        "conn": c.conn,
        "port": c.port,
        "peer": c.peer,
        "kind": c.kind,
        "sim_time": round(c.sim_time, 9),
        "wall_time": round(c.wall_time, 6),
    }
    if c.size is not None:
        d["bytes"] = c.size
    else:
        d["text"] = c.text
    return json.dumps(d, separators=(",", ":")).encode("ascii")


def decode_chunk(data: bytes) -> Chunk:
    d = json.loads(data)
    return Chunk(
        seq=int(d["seq"]),
        conn=int(d["conn"]),
        port=str(d["port"]),
        peer=str(d["peer"]),
        kind=str(d["kind"]),
        sim_time=float(d["sim_time"]),
        wall_time=float(d["wall_time"]),
        text=str(d.get("text", "")),
        size=d.get("bytes"),
    )


def split_lines(chunks: Iterable[Chunk]) -> Iterator[tuple[Chunk, str]]:
    """(chunk, line) for every whole line in a stream of chunks of one connection and one
    direction, CRLF or LF kept off; a chunk is the one in which its line ended.  A last line
    without its end is given at the end of the stream."""
    pending = ""
    last = None
    for c in chunks:
        last = c
        pending += c.text
        while True:
            i = pending.find("\n")
            if i < 0:
                break
            line, pending = pending[:i], pending[i + 1 :]
            yield c, line[:-1] if line.endswith("\r") else line
    if pending and last is not None:
        yield last, pending


def run_info(
    *, version: str, world: str, world_path: str, seed: int, lockstep: bool, speed: float | None, options: dict
) -> dict[str, str]:
    """The metadata record of a recording: strings only, as MCAP stores them."""
    return {
        "version": version,
        "world": world,
        "world_path": world_path,
        "seed": str(seed),
        "clock": "lockstep" if lockstep else ("max" if speed is None else f"speed {speed:g}"),
        "options": json.dumps(options, sort_keys=True),
    }


@dataclass(frozen=True)
class RunInfo:
    """A recording's run information (its :data:`METADATA_NAME` metadata record), parsed: the usarsim version and
    world that made it, the seed, the clock (lock-step, or the speed; None: as fast as it can) and the server's
    options, what a replay starts the same server with."""

    version: str
    world: str
    world_path: str
    seed: int
    lockstep: bool
    speed: float | None
    options: dict


def parse_run_info(meta: dict[str, str]) -> RunInfo:
    clock = meta.get("clock", "lockstep")
    speed: float | None = 1.0
    if clock == "max":
        speed = None
    elif clock.startswith("speed "):
        speed = float(clock.split()[1])
    return RunInfo(
        version=meta.get("version", "?"),
        world=meta.get("world", ""),
        world_path=meta.get("world_path", ""),
        seed=int(meta.get("seed", "0")),
        lockstep=clock == "lockstep",
        speed=speed,
        options=json.loads(meta.get("options", "{}")),
    )
