"""The framing of a link the ComServer relays (protocol.md 12.1, manual 3.2.4.3): what a robot
writes on it is ``SEND <n> <n bytes>;`` (binary-safe) and ``CLOSE;``.

* :class:`SendParser` cuts the bytes a robot writes into messages, CLOSE and dropped frames.
* :func:`format_send` frames a message.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Self

from .comserver import MAX_SEND_BYTES

__all__ = ["CLOSE_FRAME", "SendClose", "SendEvent", "SendParser", "SendProblem", "format_send"]


@dataclass(frozen=True, slots=True)
class SendClose:
    """``CLOSE;`` on a relayed link: the robot ends the link."""


class SendProblem(str):
    """A frame of a relayed link that was dropped: the text says why; ``kind`` is one of
    ``unknown`` (not SEND or CLOSE), ``no-length``, ``too-long``, ``wrong-length`` (the
    bytes are not followed by ``;``) and ``close`` (CLOSE not followed by ``;``), what a
    server logs once each."""

    kind: str

    def __new__(cls, kind: str, text: str) -> Self:
        self = super().__new__(cls, text)
        self.kind = kind
        return self


SendEvent = bytes | SendClose | SendProblem

CLOSE_FRAME = b"CLOSE;"
"""What a robot sends to end a relayed link."""

_BLANKS = b" \t\r\n"


def format_send(payload: bytes) -> bytes:
    """The frame that relays ``payload`` (any bytes, ``;`` and line breaks included)."""
    return b"SEND %d %s;" % (len(payload), payload)


def _skip_blanks(buf: bytearray) -> None:
    """Drop the blanks and line breaks at the start of ``buf``."""
    i = 0
    while i < len(buf) and buf[i] in _BLANKS:
        i += 1
    del buf[:i]


class SendParser:
    """The framing of a relayed ComServer link (manual 3.2.4.3): ``SEND <n> <n bytes>;``
    (binary-safe) and ``CLOSE;``, both words case-sensitive; blanks and line breaks between
    frames are skipped.

    ``feed`` returns the events the bytes complete, in order: a message (``bytes``), ``CLOSE``
    (a :class:`SendClose`), or a :class:`SendProblem` for a frame that was dropped, after
    which the parser skips to the next ``;``.  A SEND is delivered only once its ``n`` bytes
    and its ``;`` have arrived: one whose length does not end at a ``;`` is dropped whole,
    never delivered in part, and one cut off by the end of the connection shows as
    ``partial``.  The result does not depend on how the bytes are split between calls, and
    ``feed`` never raises.
    """

    CLOSE: ClassVar[SendClose] = SendClose()

    def __init__(self, max_bytes: int = MAX_SEND_BYTES):
        self.max_bytes = max_bytes
        self._buf = bytearray()
        self._state = "head"
        self._digits = b""
        self._need = 0
        self._body = bytearray()

    def feed(self, data: bytes) -> list[SendEvent]:
        """The events completed by ``data``: payload bytes, CLOSE, or the problem of a dropped frame."""
        buf = self._buf
        buf += data
        out: list[SendEvent] = []
        while True:
            st = self._state
            if st == "head":
                _skip_blanks(buf)
                if not buf:
                    break
                head = bytes(buf[:5])
                if head == b"SEND ":
                    del buf[:5]
                    self._state, self._digits = "length", b""
                elif head == b"CLOSE":
                    del buf[:5]
                    self._state = "close"
                elif len(head) < 5 and (b"SEND ".startswith(head) or b"CLOSE".startswith(head)):
                    break
                else:
                    out.append(SendProblem("unknown", f"unknown message {head!r}..."))
                    self._state = "skip"
            elif st == "length":
                i = 0
                while i < len(buf) and 48 <= buf[i] <= 57 and len(self._digits) + i < 10:
                    i += 1
                self._digits += bytes(buf[:i])
                del buf[:i]
                if not buf:
                    break
                if buf[0] == 32 and self._digits:
                    del buf[:1]
                    n = int(self._digits)
                    if n > self.max_bytes:
                        out.append(SendProblem("too-long", f"SEND of {n} bytes, more than {self.max_bytes}"))
                        self._state = "skip"
                    else:
                        self._need, self._body = n, bytearray()
                        self._state = "body"
                else:
                    out.append(SendProblem("no-length", "SEND without a length"))
                    self._state = "skip"
            elif st == "body":
                take = min(self._need, len(buf))
                self._body += buf[:take]
                del buf[:take]
                self._need -= take
                if self._need:
                    break
                self._state = "end"
            elif st == "end":
                if not buf:
                    break
                if buf[0] == 59:  # ;
                    del buf[:1]
                    out.append(bytes(self._body))
                    self._state = "head"
                else:
                    out.append(
                        SendProblem(
                            "wrong-length", f"SEND of {len(self._body)} bytes not followed by ';' (a wrong length)"
                        )
                    )
                    self._state = "skip"
                self._body = bytearray()
            elif st == "close":
                _skip_blanks(buf)
                if not buf:
                    break
                if buf[0] == 59:
                    del buf[:1]
                    out.append(self.CLOSE)
                    self._state = "head"
                else:
                    out.append(SendProblem("close", "CLOSE not followed by ';'"))
                    self._state = "skip"
            else:  # skip to the next ';'
                j = buf.find(b";")
                if j < 0:
                    buf.clear()
                    break
                del buf[: j + 1]
                self._state = "head"
        return out

    @property
    def partial(self) -> bool:
        """A frame was begun and not finished."""
        return self._state != "head" or bool(self._buf)
