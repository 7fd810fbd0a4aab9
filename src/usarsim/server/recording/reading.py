"""Reading a recording back from its first byte on, whether the server closed it or not.

A recording (:mod:`.recorder`) is an MCAP file: a header, the run's metadata, then chunks of
messages (zstd-compressed), and, once the server closes it, a summary and a footer.  The
``mcap`` package's reader starts from the footer; this one reads the records in their order
(the MCAP specification's records, https://mcap.dev/spec), so that it also reads

* a file the server never closed (killed, or the machine stopped): no summary, no footer,
  perhaps a last record cut short or a chunk still being written, whose complete zstd blocks
  are read too.  :attr:`Contents.complete` is False and :attr:`Contents.end_ns` says up to
  which simulated instant it holds messages;

and refuses, with :class:`DamagedRecording` naming the byte and what is wrong there,

* a file changed after it was written: a chunk that does not decompress or whose checksum
  (CRC-32 of its uncompressed records) does not match, a record that does not parse, a record
  of no MCAP kind;
* a file that is not MCAP at all.
"""

from __future__ import annotations

import io
import os
import struct
import zlib
from collections.abc import Collection
from dataclasses import dataclass, field
from pathlib import Path

from usarsim.errors import UsarsimError

MAGIC = b"\x89MCAP0\r\n"
# record opcodes (MCAP specification, "Records")
HEADER, FOOTER, SCHEMA, CHANNEL, MESSAGE, CHUNK = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06
METADATA = 0x0C
KNOWN_OPCODES = frozenset(range(0x01, 0x10))  # 0x01 Header .. 0x0F DataEnd
UNFINISHED = (1 << 64) - 1  # the length of a chunk still being written (foxglove-sdk writes it last)
# A record longer than this cannot be a recording's: its length field is garbage (the mcap
# reader's own limit, mcap.stream_reader.StreamReader's record_size_limit).
MAX_RECORD = 4 << 30
_HEAD = struct.Struct("<BQ")
_MESSAGE = struct.Struct("<HIQQ")  # channel id, sequence, log time, publish time
_CHUNK = struct.Struct("<QQQI")  # start time, end time, uncompressed size, uncompressed CRC-32


class RecordingError(UsarsimError):
    """A file that cannot be read as a recording (missing, not MCAP)."""


class DamagedRecording(RecordingError):
    """A recording changed after it was written: ``offset`` is the byte where the damage is,
    ``what`` says what is wrong there, ``messages`` how many messages come before it."""

    def __init__(self, path: str, offset: int, what: str, messages: int):
        self.path, self.offset, self.what, self.messages = path, offset, what, messages
        super().__init__(f"{path} is damaged at byte {offset} ({what})")


@dataclass
class Contents:
    """What a recording holds, read from its first byte on."""

    path: str
    size: int  # bytes in the file
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)  # metadata records by name
    messages: list[tuple[str, int, bytes]] = field(default_factory=list)  # (topic, log time ns, data) asked for
    count: int = 0  # messages read, every topic
    complete: bool = False  # the footer was read: the server closed the file
    end: int = 0  # byte where the readable part ends
    end_ns: int = 0  # the latest log time of any message read
    salvaged: int = 0  # messages read from a chunk the server had not finished


class _Truncated(Exception):
    """The file ends inside a record: what comes before is whole."""


def read_mcap(path: str | os.PathLike, topics: Collection[str] | None = None) -> Contents:
    """Every message on ``topics`` (None: all) and every metadata record of the MCAP file at
    ``path``, in the order written.  RecordingError when it is missing or not MCAP,
    DamagedRecording when it is damaged; a file cut short is read up to the cut."""
    p = Path(path)
    name = str(path)
    if not p.exists():
        raise RecordingError(f"{name}: no such file")
    if p.is_dir():
        raise RecordingError(f"{name} is a folder, not a recording")
    try:
        f = p.open("rb")
    except OSError as exc:
        raise RecordingError(f"{name} cannot be opened ({exc.strerror})") from exc
    with f:
        size = os.fstat(f.fileno()).st_size
        return _Reader(f, name, size, None if topics is None else frozenset(topics)).read()


class _Reader:
    def __init__(self, f: io.BufferedReader, path: str, size: int, topics: frozenset[str] | None):
        self.f = f
        self.out = Contents(path, size)
        self.topics = topics
        self.channels: dict[int, str] = {}

    def damaged(self, offset: int, what: str) -> DamagedRecording:
        return DamagedRecording(self.out.path, offset, what, self.out.count)

    def read(self) -> Contents:
        out = self.out
        magic = self.f.read(len(MAGIC))
        if magic != MAGIC:
            if not magic:
                raise RecordingError(f"{out.path} is empty, not a recording")
            if MAGIC.startswith(magic):
                raise RecordingError(f"{out.path} ends within MCAP's first {len(MAGIC)} bytes: it holds nothing")
            raise RecordingError(f"{out.path} is not an MCAP file (it does not start with MCAP's magic bytes)")
        pos = len(MAGIC)
        try:
            while True:
                out.end = pos
                head = self.f.read(_HEAD.size)
                if len(head) < _HEAD.size:
                    raise _Truncated
                opcode, length = _HEAD.unpack(head)
                if opcode == 0 and not (head + self.f.read()).strip(b"\0"):
                    raise _Truncated  # zeros to the end: blocks the file system had not filled when it stopped
                if opcode not in KNOWN_OPCODES:
                    raise self.damaged(pos, f"a record of no MCAP kind, opcode {opcode:#04x}")
                if opcode == CHUNK and length == UNFINISHED:
                    self._salvage(pos, self.f.read())  # the chunk being written when the server stopped
                    raise _Truncated
                if length > MAX_RECORD:
                    raise self.damaged(pos, f"a record of {length} bytes")
                body = self.f.read(length)
                if len(body) < length:
                    if opcode == CHUNK:
                        self._salvage(pos, body)
                    raise _Truncated
                if opcode == FOOTER:
                    out.complete = True
                    out.end = pos + _HEAD.size + length + len(self.f.read(len(MAGIC)))
                    return out
                self._record(pos, opcode, body)
                pos += _HEAD.size + length
        except _Truncated:
            return out

    def _record(self, pos: int, opcode: int, body: bytes) -> None:
        try:
            if opcode == CHUNK:
                self._chunk(pos, body)
            elif opcode == CHANNEL:
                self._channel(body)
            elif opcode == MESSAGE:
                self._message(pos, body)
            elif opcode == METADATA:
                name, pairs = _metadata(body)
                self.out.metadata[name] = pairs
        except (struct.error, UnicodeDecodeError, IndexError, ValueError) as exc:
            raise self.damaged(pos, f"a record that does not parse: {type(exc).__name__}: {exc}") from exc

    def _channel(self, body: bytes) -> None:
        cid, _, n = struct.unpack_from("<HHI", body, 0)  # channel id, schema id, topic's length
        raw = body[8 : 8 + n]
        if len(raw) != n:
            raise ValueError("the topic runs past the record's end")
        self.channels[cid] = raw.decode("utf-8")

    def _message(self, pos: int, body: bytes) -> None:
        cid, _, log_time, _ = _MESSAGE.unpack_from(body, 0)
        topic = self.channels.get(cid)
        if topic is None:
            raise self.damaged(pos, f"a message of channel {cid}, which no channel record defines")
        out = self.out
        out.count += 1
        out.end_ns = max(out.end_ns, log_time)
        if self.topics is None or topic in self.topics:
            out.messages.append((topic, log_time, body[_MESSAGE.size :]))

    def _records(self, pos: int, data: bytes, whole: bool) -> None:
        """The records of a chunk's uncompressed data; ``whole``: it must end with a record (a
        salvaged chunk's last record may be cut short)."""
        k = 0
        while k < len(data):
            if len(data) - k < _HEAD.size:
                break
            opcode, length = _HEAD.unpack_from(data, k)
            if k + _HEAD.size + length > len(data):
                break
            body = data[k + _HEAD.size : k + _HEAD.size + length]
            if opcode == CHANNEL:
                self._channel(body)
            elif opcode == MESSAGE:
                self._message(pos, body)
                if not whole:
                    self.out.salvaged += 1
            elif opcode != SCHEMA:
                raise ValueError(f"a record of opcode {opcode:#04x} inside a chunk")
            k += _HEAD.size + length
        if whole and k != len(data):
            raise ValueError("the chunk's last record runs past the chunk's end")

    def _chunk(self, pos: int, body: bytes) -> None:
        _, _, usize, crc = _CHUNK.unpack_from(body, 0)
        (n,) = struct.unpack_from("<I", body, _CHUNK.size)
        k = _CHUNK.size + 4
        compression = body[k : k + n].decode("utf-8")
        k += n
        (rlen,) = struct.unpack_from("<Q", body, k)
        k += 8
        records = body[k : k + rlen]
        if len(records) != rlen:
            raise ValueError("the chunk's records run past the record's end")
        if compression == "zstd":
            import zstandard

            # as a stream: the memory it takes is what the data holds, whatever its size field says
            stream = zstandard.ZstdDecompressor().decompressobj()
            try:
                data = stream.decompress(records)
            except zstandard.ZstdError as exc:
                raise self.damaged(pos, f"a compressed chunk does not decompress: {exc}") from exc
            if not stream.eof:
                raise self.damaged(pos, "a compressed chunk does not decompress: its data ends within it")
        elif compression == "lz4":
            try:
                import lz4.frame
            except ImportError as exc:
                raise self.damaged(pos, "a chunk compressed with lz4, which needs the lz4 package") from exc
            try:
                data = lz4.frame.decompress(records)
            except RuntimeError as exc:
                raise self.damaged(pos, f"a compressed chunk does not decompress: {exc}") from exc
        elif compression == "":
            data = records
        else:
            raise self.damaged(pos, f"a chunk compressed with {compression!r}, which MCAP does not define")
        if len(data) != usize:
            raise self.damaged(pos, f"a chunk of {len(data)} bytes where it says {usize}")
        if crc != 0 and zlib.crc32(data) != crc:
            raise self.damaged(pos, "a chunk whose checksum does not match its contents")
        self._records(pos, data, whole=True)

    def _salvage(self, pos: int, body: bytes) -> None:
        """The records of a chunk cut short: its complete zstd blocks (a block is written
        whole or not at all; its messages are taken as they are, with no checksum to check)."""
        try:
            (n,) = struct.unpack_from("<I", body, _CHUNK.size)
            k = _CHUNK.size + 4
            compression = body[k : k + n].decode("utf-8")
            records = body[k + n + 8 :]
            if compression == "zstd":
                import zstandard

                data = zstandard.ZstdDecompressor().decompressobj().decompress(records)
            elif compression == "":
                data = records
            else:
                return
            self._records(pos, data, whole=False)
        except Exception:  # noqa: BLE001 (whatever the cut leaves: the messages before it are kept)
            return


def _metadata(body: bytes) -> tuple[str, dict[str, str]]:
    k = 0

    def string() -> str:
        nonlocal k
        (n,) = struct.unpack_from("<I", body, k)
        s = body[k + 4 : k + 4 + n]
        if len(s) != n:
            raise ValueError("a string runs past the record's end")
        k += 4 + n
        return s.decode("utf-8")

    name = string()
    (size,) = struct.unpack_from("<I", body, k)
    k += 4
    end = k + size
    pairs = {}
    while k < end:
        key = string()
        pairs[key] = string()
    if k != end:
        raise ValueError("the metadata's pairs run past their end")
    return name, pairs
