"""What the three wireless protocols (protocol.md 12) share: TCP port numbers as robots
write them, and the checks of text a client is about to send."""

from __future__ import annotations

from usarsim.errors import ProtocolError

from ..grammar import Segment, format_segment

__all__ = ["MAX_PORT", "check_port", "check_value", "check_word", "format_unknown", "parse_port"]

MAX_PORT = 65535
"""Largest TCP port number; 0 (pick any) is not a port a robot can listen on or name."""

_SHOWN = 80  # characters of an offending value quoted in error messages


def shorten(text: str) -> str:
    """``text`` quoted for an error message, cut after a few dozen characters."""
    return repr(text if len(text) <= _SHOWN else text[:_SHOWN] + "...")


def parse_port(text: str, what: str = "port", *, zero: bool = False) -> int:
    """A TCP port 1-65535 (0-65535 with ``zero``, where the protocol gives 0 a meaning)
    written in ASCII digits (blanks around it allowed); anything else raises
    :class:`~usarsim.errors.ProtocolError` naming ``what``."""
    t = text.strip()
    low = 0 if zero else 1
    if t.isascii() and t.isdigit() and len(t) <= 5 and low <= int(t) <= MAX_PORT:
        return int(t)
    raise ProtocolError(f"{what} must be a TCP port {low} to {MAX_PORT}, got {shorten(text)}")


def check_port(port: int, what: str = "port", *, zero: bool = False) -> str:
    """``port`` written for a client to send, when it is a TCP port 1-65535 (or 0, with
    ``zero``); otherwise :class:`~usarsim.errors.ProtocolError`."""
    low = 0 if zero else 1
    if isinstance(port, bool) or not isinstance(port, int) or not low <= port <= MAX_PORT:
        raise ProtocolError(f"cannot send {what} {port!r}: it must be a TCP port {low} to {MAX_PORT}")
    return str(port)


def check_word(text: str, what: str, forbidden: str) -> str:
    """``text`` when it is one non-empty word free of the ``forbidden`` characters, for
    formatting what a client sends; otherwise :class:`~usarsim.errors.ProtocolError`."""
    if not text or len(text.split()) != 1 or text != text.strip() or any(c in forbidden for c in text):
        raise ProtocolError(
            f"cannot send {what} {shorten(text)}: it must be one word without spaces or any of {forbidden!r}"
        )
    return text


def check_value(text: str, what: str) -> str:
    """``text`` when it can be the value of a ``{Key value}`` segment and read back as it is
    (no braces or line breaks, no blanks around it, not empty); otherwise
    :class:`~usarsim.errors.ProtocolError`."""
    if not text or text != text.strip() or any(c in "{}\r\n" for c in text):
        raise ProtocolError(
            f"cannot send {what} {shorten(text)}: it must be non-empty text without "
            "braces, line breaks or blanks at its ends"
        )
    return text


def format_unknown(word: str, segments: tuple[Segment, ...]) -> str:
    """``WORD {Key value} ...`` ending with CR LF: a request of a word the server does not
    know, as a client would send it (to test a server's answer)."""
    parts = [check_word(word, "request word", "{}")]
    parts += [
        format_segment(check_word(s.key, "key", "{}"), check_value(s.value, s.key) if s.value else "") for s in segments
    ]
    return " ".join(parts) + "\r\n"
