"""Splitting a client's byte stream into command lines (protocol.md §1).

Clients end their commands with CR LF (most), LF CR (the Player Ackermann command, Pyro) or
a bare LF, and some send several commands in one TCP write (MOAST sends
``GETSTARTPOSES\\r\\nINIT ...\\r\\n``).  Any run of CR and/or LF therefore ends a line, empty
lines are skipped, and a partial line waits for the rest of it in later reads.
"""

from __future__ import annotations

import re

__all__ = ["DEFAULT_MAX_LINE_BYTES", "LineBuffer"]

DEFAULT_MAX_LINE_BYTES = 8192
"""Longest accepted command line; clients keep lines well under 4096 bytes."""

_TERMINATORS = re.compile(rb"[\r\n]+")


class LineBuffer:
    """Incremental line splitter: bytes in, complete text lines out.

    * Bytes are decoded as ASCII; any other byte becomes U+FFFD, so binary garbage never
      raises (the parser rejects such lines later, one at a time).
    * A line longer than ``max_line_bytes`` is dropped entirely, including the part of it
      that arrives in later reads up to its terminator, and counted in ``dropped_lines``.
      The next line is delivered normally.  The caller decides whether a dropped line is a
      reason to close the connection.
    * Lines made only of whitespace are skipped like empty ones.

    ``feed`` never raises.
    """

    __slots__ = ("max_line_bytes", "dropped_lines", "_buf", "_discarding")

    def __init__(self, max_line_bytes: int = DEFAULT_MAX_LINE_BYTES):
        if max_line_bytes < 1:
            raise ValueError(f"max_line_bytes must be at least 1, got {max_line_bytes}")
        self.max_line_bytes = max_line_bytes
        self.dropped_lines = 0
        self._buf = bytearray()
        # True while skipping the tail of an over-long line (already counted).
        self._discarding = False

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
        buf = self._buf
        # The bytes already held contain no terminator: only new bytes need scanning.
        scan_from = len(buf)
        buf += data
        lines: list[str] = []
        limit = self.max_line_bytes
        start = 0
        for match in _TERMINATORS.finditer(buf, scan_from):
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
            start = match.end()
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
