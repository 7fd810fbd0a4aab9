"""The ``usarsim`` command's building blocks: argument types, the default ports of ``usarsim serve`` and
how they are resolved, and the argument parser with its one-line errors."""

from __future__ import annotations

import argparse
import difflib
import re


def _speed(text: str) -> float | None:
    if text.lower() == "max":
        return None
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number > 0 or 'max', got {text!r}") from None
    if not (v > 0 and v < 1e6):
        raise argparse.ArgumentTypeError(f"expected a number > 0 or 'max', got {text!r}")
    return v


def _int_within(low: int, high: int, what: str):
    """An argument type: an integer ``low..high`` (``what`` names it in the error)."""

    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            v = None
        if v is None or not low <= v <= high:
            raise argparse.ArgumentTypeError(f"expected {what} {low}..{high}, got {text!r}")
        return v

    return parse


_port = _int_within(0, 65535, "a port number")
_micros = _int_within(0, 1_000_000, "microseconds")


def _threads(text: str) -> str:
    """``--physics-threads``: a number of threads (0: none) or 'auto'."""
    value = text.strip().lower()
    if value == "auto" or (value.isdigit() and int(value) <= 256):
        return value
    raise argparse.ArgumentTypeError(f"expected a number of threads from 0 to 256 or 'auto', got {text!r}")


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT such as 320x240, got {text!r}") from None
    if not (1 <= w <= 1920 and 1 <= h <= 1080):
        raise argparse.ArgumentTypeError(f"a picture from 1x1 to 1920x1080, got {text!r}")
    return w, h


def _variant(text: str) -> int:
    """A world's variant: a whole number >= 0 (usarsim.maps.variation)."""
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a variant is a whole number >= 0, got {text!r}") from None
    if n < 0:
        raise argparse.ArgumentTypeError(f"a variant is a whole number >= 0, got {text!r}")
    return n


# The ports ``usarsim serve`` listens on when none is given, by option; ``--port-offset N``
# adds N to each (a second server beside the first needs nothing else).
FOXGLOVE_PORT = 8765  # Foxglove's own default for a live WebSocket connection
FOXGLOVE_DEFAULT = -1  # --foxglove without a port: FOXGLOVE_PORT plus --port-offset (resolve_foxglove_port)
DEFAULT_PORTS = {
    "port": 3000,
    "truth_port": 3989,
    "image_port": 5003,
    "web_port": 8080,
    "wcs_port": 5874,
    "wss_port": 50000,
    "cominterface_port": 7435,
}


def resolve_ports(
    given: dict[str, int | None], offset: int = 0, from_file: dict[str, int | None] | None = None
) -> dict[str, int]:
    """Every listener's port: the one given on the command line, else the one of the
    --wireless-config file (ComServer, ComServerInterface), else the default plus ``offset``.
    A port given explicitly (0 included) keeps its value.  ValueError names the option whose
    default the offset puts beyond 65535 (or below 1)."""
    from_file = from_file or {}
    ports = {}
    for name, default in DEFAULT_PORTS.items():
        value = given.get(name)
        if value is None:
            value = from_file.get(name)
        if value is None:
            value = default + offset
            if not 1 <= value <= 65535:
                option = "--" + name.replace("_", "-")
                raise ValueError(
                    f"--port-offset {offset} puts the default of {option} ({default}) at {value}, outside 1..65535"
                )
        ports[name] = value
    return ports


def resolve_foxglove_port(given: int | None, offset: int = 0) -> int | None:
    """--foxglove's port: None when not asked for, FOXGLOVE_PORT plus ``offset`` when asked
    for without a port, else the port given (0 included, a free one)."""
    if given is None:
        return None
    return FOXGLOVE_PORT + offset if given == FOXGLOVE_DEFAULT else given


def _port_offset(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number 0..{65535 - 50000}, got {text!r}") from None
    if not 0 <= v <= 65535 - 50000:
        raise argparse.ArgumentTypeError(
            f"expected a number 0..{65535 - 50000} (the WSS port is 50000 + N), got {text!r}"
        )
    return v


class _Parser(argparse.ArgumentParser):
    """argparse, with a usage error said in one line (no usage block before it), naming the
    command's --help, and "did you mean" for a misspelt command, choice or option."""

    def parse_args(self, args=None, namespace=None):  # noqa: ANN001, ANN201 (argparse's signature)
        parsed, extras = self.parse_known_args(args, namespace)
        if extras:
            msg = "unrecognized arguments: " + " ".join(extras)
            command = self._subparser(getattr(parsed, "command", None))
            guess = next(
                (
                    g
                    for e in extras
                    if e.startswith("--")
                    for g in difflib.get_close_matches(e.split("=")[0], command._option_string_actions, n=1)
                ),
                None,
            )
            if guess:
                msg += f" (did you mean {guess}?)"
            command.error(msg)
        return parsed

    def _subparser(self, command: str | None) -> argparse.ArgumentParser:
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction) and command in action.choices:
                return action.choices[command]
        return self

    def error(self, message: str):  # noqa: ANN201 (argparse's signature: never returns)
        choice = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if choice:
            options = re.findall(r"'([^']*)'", choice.group(2))
            guess = difflib.get_close_matches(choice.group(1), options, n=1)
            if guess:
                message += f" (did you mean {guess[0]!r}?)"
        self.exit(2, f"{self.prog}: error: {message}; see '{self.prog} --help'\n")


_VERBOSE_HELP = "more log output: -v logs connections, spawns and removals, -vv everything (debug)"


def _add_verbose(parser: argparse.ArgumentParser, dest: str) -> None:
    parser.add_argument("-v", "--verbose", action="count", default=0, dest=dest, help=_VERBOSE_HELP)
