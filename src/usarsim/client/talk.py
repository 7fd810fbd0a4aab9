"""Talk to a simulator by hand: ``python -m usarsim.client.talk [--host H] [--port P]``.

Each line typed (or piped in) is sent with USARSim's CR LF; every line the server sends is
printed as it comes.  End with Ctrl-D (the end of the input), after which it waits ``--linger``
seconds for the last answers, or Ctrl-C.  A line-based TCP client such as ``nc`` does the same.
"""

from __future__ import annotations

import argparse
import socket
import sys
import threading
import time


def _print_lines(sock: socket.socket, hide: frozenset[str], done: threading.Event) -> None:
    buffer = b""
    while True:
        try:
            data = sock.recv(65536)
        except OSError:
            data = b""
        if not data:
            if not done.is_set():
                print("talk: the server closed the connection", file=sys.stderr, flush=True)
            done.set()
            return
        buffer += data
        *lines, buffer = buffer.split(b"\n")
        for raw in lines:
            line = raw.rstrip(b"\r").decode("utf-8", "replace")
            if line.split(" ", 1)[0] not in hide:
                print(line, flush=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m usarsim.client.talk",
        description=__doc__.split("\n\n")[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("--host", default="127.0.0.1", help="the simulator's address (default: %(default)s)")
    ap.add_argument("--port", type=int, default=3000, help="its control port (default: %(default)s)")
    ap.add_argument(
        "--hide",
        default="",
        metavar="WORDS",
        help="message types not to print, comma-separated, e.g. STA,SEN (default: none)",
    )
    ap.add_argument(
        "--linger",
        type=float,
        default=1.0,
        metavar="S",
        help="seconds to wait for answers after the end of the input (default: %(default)s)",
    )
    args = ap.parse_args(argv)
    try:
        sock = socket.create_connection((args.host, args.port), timeout=5.0)
    except OSError as exc:
        print(
            f"talk: no simulator on {args.host}:{args.port} ({exc.strerror or exc}): start one with "
            "'usarsim serve' (or bash scripts/serve.sh)",
            file=sys.stderr,
        )
        return 1
    sock.settimeout(None)
    done = threading.Event()
    hide = frozenset(w.strip().upper() for w in args.hide.split(",") if w.strip())
    reader = threading.Thread(target=_print_lines, args=(sock, hide, done), daemon=True)
    reader.start()
    try:
        for line in sys.stdin:
            if done.is_set():
                break
            sock.sendall(line.rstrip("\r\n").encode("utf-8") + b"\r\n")
        deadline = time.monotonic() + max(0.0, args.linger)
        while not done.is_set() and time.monotonic() < deadline:
            time.sleep(0.05)
    except KeyboardInterrupt:
        pass
    except OSError as exc:
        print(f"talk: the connection failed: {exc}", file=sys.stderr)
        return 1
    finally:
        done.set()
        sock.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
