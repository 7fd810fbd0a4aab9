"""Sans-IO USARSim protocol: bytes <-> lines <-> typed commands and messages.

* :mod:`.framing`: :class:`LineBuffer` splits a byte stream into lines.
* :mod:`.grammar`: the generic ``TYPE {Key Value} ...`` line grammar and value parsers.
* :mod:`.commands`: client commands (:func:`parse_command`, :func:`format_command`).
* :mod:`.messages`: server messages (:func:`format_message`, :func:`parse_message`).
* :mod:`.outputs`: what the simulation reports, as messages (:func:`~.outputs.message_for`).
* :mod:`.numbers`: number formatting shared by every message.

This package imports the standard library and :mod:`usarsim.readings` /
:mod:`usarsim.errors` only: no sockets, no asyncio, no simulation.
"""

from __future__ import annotations

from .commands import Command, format_command, parse_command
from .framing import LineBuffer
from .grammar import RawMessage, Segment, parse_line
from .messages import Message, format_message, parse_message

__all__ = [
    "Command",
    "LineBuffer",
    "Message",
    "RawMessage",
    "Segment",
    "format_command",
    "format_message",
    "parse_command",
    "parse_line",
    "parse_message",
]
