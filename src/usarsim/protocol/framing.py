"""Splitting a client's byte stream into command lines (protocol.md §1).

Clients end their commands with CR LF (most), LF CR (the Player Ackermann command, Pyro) or
a bare LF, and some send several commands in one TCP write (MOAST sends
``GETSTARTPOSES\\r\\nINIT ...\\r\\n``).  Any run of CR and/or LF therefore ends a line, empty
lines are skipped, and a partial line waits for the rest of it in later reads.

Floods of DRIVE lines: a controller may send the same ``DRIVE {Left 1} {Right 1}`` thousands
of times a second.  The control port's buffer (``drop_repeated_drives``) drops a DRIVE line
that repeats the line just before it when it sets speeds or lights only (no joint ``Order``,
no ``Flip``): the newest DRIVE of a robot wins, and sending the same speeds again changes
nothing.  A DRIVE, another line, the same DRIVE: both DRIVEs are kept.
"""

from __future__ import annotations

import re

__all__ = ["DEFAULT_MAX_LINE_BYTES", "REPEATED_DRIVE", "LineBuffer", "repeatable_drive"]

DEFAULT_MAX_LINE_BYTES = 8192
"""Longest accepted command line; clients keep lines well under 4096 bytes."""

_TERMINATORS = re.compile(rb"[\r\n]+")
# ``empty_lines``: one terminator, CR LF, LF CR, CR or LF
_ONE_TERMINATOR = re.compile(rb"\r\n|\n\r|\r|\n")
_OTHER_HALF = {b"\r": b"\n", b"\n": b"\r"}

REPEATED_DRIVE = re.compile(rb"(?:^|(?<=[\r\n]))(DRIVE(?:(?!(?i:order|flip))[^\r\n])*[\r\n]+)(?:\1)+")
"""A run of the same repeatable DRIVE line (with the same terminator), from the start of a
line: ``sub(rb"\\1", data)`` leaves one.  The bytes-level fast path of the rule below, so
that a flood of millions of lines costs one regular-expression pass, not a string each."""
_FAST_PATH_BYTES = 2048  # reads shorter than this go the line-by-line way only


def repeatable_drive(line: str) -> bool:
    """A DRIVE that sets speeds or lights only (no joint Order, no Flip): sending it again
    changes nothing."""
    if line[:5].upper() != "DRIVE":
        return False
    low = line.lower()
    return "order" not in low and "flip" not in low


class LineBuffer:
    """Incremental line splitter: bytes in, complete text lines out.

    * Bytes are decoded as ASCII; any other byte becomes U+FFFD, so binary garbage never
      raises (the parser rejects such lines later, one at a time).
    * A line longer than ``max_line_bytes`` is dropped entirely, including the part of it
      that arrives in later reads up to its terminator, and counted in ``dropped_lines``.
      The next line is delivered normally.  The caller decides whether a dropped line is a
      reason to close the connection.
    * Lines made only of whitespace are skipped like empty ones; with ``empty_lines`` they
      are delivered as ``""`` instead (a terminator is then one CR LF, LF CR, CR or LF, and a
      CR LF or LF CR split between two reads is still one), for a port where an empty line is
      a request (the ground-truth port answers it).
    * With ``drop_repeated_drives``, a repeatable DRIVE line (:func:`repeatable_drive`) the
      same as the line before it, also across reads, is dropped and counted in
      ``repeated_drives``.

    ``feed`` never raises.
    """

    __slots__ = (
        "max_line_bytes",
        "dropped_lines",
        "drop_repeated_drives",
        "repeated_drives",
        "_buf",
        "_discarding",
        "_last",
        "empty_lines",
        "_half",
    )

    def __init__(
        self,
        max_line_bytes: int = DEFAULT_MAX_LINE_BYTES,
        *,
        drop_repeated_drives: bool = False,
        empty_lines: bool = False,
    ):
        if max_line_bytes < 1:
            raise ValueError(f"max_line_bytes must be at least 1, got {max_line_bytes}")
        self.max_line_bytes = max_line_bytes
        self.dropped_lines = 0
        self.drop_repeated_drives = drop_repeated_drives
        self.repeated_drives = 0
        self._buf = bytearray()
        # True while skipping the tail of an over-long line (already counted).
        self._discarding = False
        self._last = ""  # the last line delivered (drop_repeated_drives)
        self.empty_lines = empty_lines
        self._half: bytes | None = None  # empty_lines: the other half of a CR LF the last read ended in

    @property
    def pending_bytes(self) -> int:
        """Bytes of an unfinished line held until its terminator arrives."""
        return len(self._buf)

    @property
    def discarding(self) -> bool:
        """True while the tail of an over-long line is being skipped."""
        return self._discarding

    def feed(self, data: bytes) -> list[str]:
        """Add received bytes; return the lines they complete, in order."""
        if not self.drop_repeated_drives:
            return self._split(data)
        if len(data) > _FAST_PATH_BYTES and b"DRIVE" in data:
            data = self._collapse(data)
        out = []
        last = self._last
        for line in self._split(data):
            if line == last and repeatable_drive(line):
                self.repeated_drives += 1
            else:
                out.append(line)
                last = line
        self._last = last
        return out

    def _collapse(self, data: bytes) -> bytes:
        """``data`` with each run of a repeated repeatable DRIVE line cut to one line."""
        head = b""
        if self._buf or self._discarding:  # the read begins in the middle of a line
            ends = [i for i in (data.find(b"\r"), data.find(b"\n")) if i >= 0]
            if not ends:
                return data
            head, data = data[: min(ends)], data[min(ends) :]

        def one(m: re.Match[bytes]) -> bytes:
            line: bytes = m.group(1)
            self.repeated_drives += (m.end() - m.start()) // len(line) - 1
            return line

        return head + REPEATED_DRIVE.sub(one, data)

    def _split(self, data: bytes) -> list[str]:
        if self.empty_lines:
            if self._half is not None and data[:1] == self._half:
                data = data[1:]  # the rest of the terminator the last read ended in
            self._half = None
        buf = self._buf
        # The bytes already held contain no terminator: only new bytes need scanning.
        scan_from = len(buf)
        buf += data
        lines: list[str] = []
        limit = self.max_line_bytes
        start = 0
        empty = self.empty_lines
        match = None
        for match in (_ONE_TERMINATOR if empty else _TERMINATORS).finditer(buf, scan_from):
            end = match.start()
            if self._discarding:
                # This terminator ends the over-long line counted earlier.
                self._discarding = False
            elif end - start > limit:
                self.dropped_lines += 1
            elif end > start:
                line = buf[start:end].decode("ascii", "replace")
                if not line.isspace():
                    lines.append(line)
                elif empty:
                    lines.append("")
            elif empty:
                lines.append("")
            start = match.end()
        if empty and match is not None and match.end() == len(buf) and match.end() - match.start() == 1:
            self._half = _OTHER_HALF[bytes(buf[match.start() : match.end()])]
        if start:
            del buf[:start]
        if len(buf) > limit:
            if not self._discarding:
                self._discarding = True
                self.dropped_lines += 1
            buf.clear()
        elif self._discarding:
            # Everything held belongs to the line being skipped.
            buf.clear()
        return lines
