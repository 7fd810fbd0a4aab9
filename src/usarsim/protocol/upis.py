"""The image server's protocol (UPIS, protocol.md 10), both ends, without I/O.

A client asks with ``OK`` for one whole picture or with ``U`` and four 32-bit big-endian numbers
(x, y, width, height) for a rectangle of it; any other byte is ignored.  Each picture comes back
as a frame: a type byte (0 raw, 1..5 JPEG from "superb" to "bad"), a 4-byte big-endian length
and the payload, a JPEG file or, for a raw picture, its width and height (16-bit big-endian)
and its pixels as B, G, R, rows top to bottom.

The image server reads requests with :class:`RequestReader` and writes :func:`frame`; the
operator console and the benchmark ask with :func:`ask_whole` and read frames with
:class:`FrameReader`.
"""

from __future__ import annotations

import struct

Rect = tuple[int, int, int, int]  # x, y, width, height
HEADER = struct.Struct(">BI")  # a frame's type byte and payload length
RAW_SIZE = struct.Struct(">HH")  # a raw picture's width and height
_RECT = struct.Struct(">IIII")
RAW = 0  # the type byte of a raw picture; 1..5 are JPEG levels
# (an extension) a PNG file: the pictures of depth, thermal and label cameras, which JPEG would
# spoil (docs/protocol.md, "Pictures beyond colour")
PNG = 6
MAX_FRAME_BYTES = 64 << 20  # a frame longer than this is not a picture of this server


def ask_whole() -> bytes:
    """The request for one whole picture."""
    return b"OK"


def ask_rect(x: int, y: int, width: int, height: int) -> bytes:
    """The request for a rectangle of the picture."""
    return b"U" + _RECT.pack(x, y, width, height)


class RequestReader:
    """The server's end: bytes in, requests out, in order (None: the whole picture; else the
    rectangle), however the bytes were cut; what is no request is skipped."""

    def __init__(self) -> None:
        self._buf = bytearray()

    def feed(self, data: bytes) -> list[Rect | None]:
        self._buf += data
        b = self._buf
        out: list[Rect | None] = []
        while b:
            if b[0] == ord("O"):
                if len(b) < 2:
                    break
                if b[1] == ord("K"):
                    out.append(None)
                    del b[:2]
                else:
                    del b[:1]
            elif b[0] == ord("U"):
                if len(b) < 1 + _RECT.size:
                    break
                x, y, w, h = _RECT.unpack(bytes(b[1 : 1 + _RECT.size]))
                out.append((x, y, w, h))
                del b[: 1 + _RECT.size]
            else:
                del b[:1]  # CR, LF and anything else: ignored
        return out


def frame(image_type: int, payload: bytes) -> bytes:
    """One picture as it goes on the wire."""
    return HEADER.pack(image_type, len(payload)) + payload


def raw_payload(width: int, height: int, bgr: bytes) -> bytes:
    """A raw picture's payload: its size, then its B, G, R rows top to bottom."""
    return RAW_SIZE.pack(width, height) + bgr


def parse_raw(payload: bytes) -> tuple[int, int, bytes]:
    """(width, height, B, G, R pixels) of a raw picture's payload."""
    w, h = RAW_SIZE.unpack_from(payload)
    return w, h, payload[RAW_SIZE.size : RAW_SIZE.size + 3 * w * h]


class FrameReader:
    """The client's end: bytes in, whole pictures (type byte, payload) out, however the bytes
    were cut.  ValueError on a length no picture has (the peer speaks another protocol)."""

    def __init__(self) -> None:
        self._buf = bytearray()

    def feed(self, data: bytes) -> list[tuple[int, bytes]]:
        self._buf += data
        out = []
        while len(self._buf) >= HEADER.size:
            kind, length = HEADER.unpack_from(self._buf)
            if length > MAX_FRAME_BYTES:
                raise ValueError(f"a picture of {length} bytes announced: not an image server")
            end = HEADER.size + length
            if len(self._buf) < end:
                break
            out.append((kind, bytes(self._buf[HEADER.size : end])))
            del self._buf[:end]
        return out

    def wanted(self) -> int:
        """How many more bytes complete the picture under way (the header's, before it)."""
        if len(self._buf) < HEADER.size:
            return HEADER.size - len(self._buf)
        length: int = HEADER.unpack_from(self._buf)[1]
        return HEADER.size + length - len(self._buf)


__all__ = [
    "HEADER",
    "PNG",
    "RAW",
    "FrameReader",
    "Rect",
    "RequestReader",
    "ask_rect",
    "ask_whole",
    "frame",
    "parse_raw",
    "raw_payload",
]
