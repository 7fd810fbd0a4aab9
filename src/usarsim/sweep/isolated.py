"""The launcher of an isolated controller (docs/experiments.md, "Isolation"), run by the sweep
worker inside a network and mount namespace of its own (``unshare --net --mount``)::

    python -m usarsim.sweep.isolated --dir DIR --ports 3000,5874 -- COMMAND ...

Inside the new namespace nothing answers but what this process serves: the loopback interface
is brought up, a private file system is mounted on /dev/shm, and each simulator port
of ``--ports`` is served on 127.0.0.1 and relayed to the Unix socket ``DIR/PORT.sock``, where
the worker relays it on to the simulator (:class:`usarsim.sweep.isolation.HostRelay`).  The
command then runs here; its exit status is this process's.  SIGTERM and SIGINT are passed on
to it.
"""

from __future__ import annotations

import argparse
import asyncio
import ctypes
import fcntl
import functools
import os
import signal
import socket
import struct
import sys
from pathlib import Path

# linux/sockios.h and linux/if.h: read and set an interface's flags; IFF_UP brings it up
SIOCGIFFLAGS, SIOCSIFFLAGS, IFF_UP = 0x8913, 0x8914, 0x1
# POSIX shared memory and semaphores: one controller's are not another's.  (/tmp stays shared:
# the controller's folder, its interpreter or its libraries may be there.)
PRIVATE_MOUNTS = ("/dev/shm",)
CHUNK = 65536


async def pipe(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
    """Copy ``reader`` to ``writer`` until the end of the stream, then end the writer's side."""
    try:
        while data := await reader.read(CHUNK):
            writer.write(data)
            await writer.drain()
        if writer.can_write_eof():
            writer.write_eof()
    except (ConnectionError, OSError):
        writer.close()


async def join(reader: asyncio.StreamReader, writer: asyncio.StreamWriter, peer) -> None:
    """Relay one connection (``reader``, ``writer``) both ways to the one ``peer`` opens."""
    try:
        r2, w2 = await peer()
    except OSError:
        writer.close()
        return
    try:
        await asyncio.gather(pipe(reader, w2), pipe(r2, writer))
    finally:
        for w in (writer, w2):
            w.close()


def namespaces() -> str:
    """This process's network and mount namespaces, as ``NET,MNT`` (their inode numbers)."""
    return ",".join(str(os.stat(f"/proc/self/ns/{ns}").st_ino) for ns in ("net", "mnt"))


def in_own_namespaces(outside: str) -> bool:
    """Whether this process's network and mount namespaces both differ from ``outside`` (the
    starting process's :func:`namespaces`)."""
    try:
        return all(a != b for a, b in zip(namespaces().split(","), outside.split(","), strict=True))
    except (OSError, ValueError):
        return False


def loopback_up() -> None:
    """Bring up the namespace's loopback interface (it starts down)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        req = struct.pack("16sh", b"lo", 0)
        flags = struct.unpack("16sh", fcntl.ioctl(s.fileno(), SIOCGIFFLAGS, req))[1]
        fcntl.ioctl(s.fileno(), SIOCSIFFLAGS, struct.pack("16sh", b"lo", flags | IFF_UP))


def private_mounts() -> None:
    """An empty file system of this namespace's own on each of PRIVATE_MOUNTS."""
    libc = ctypes.CDLL(None, use_errno=True)
    for where in PRIVATE_MOUNTS:
        if Path(where).is_dir() and libc.mount(b"tmpfs", where.encode(), b"tmpfs", 0, b"mode=1777") != 0:
            err = ctypes.get_errno()
            raise OSError(err, f"cannot mount a private {where}")


async def serve(folder: Path, ports: list[int], command: list[str]) -> int:
    servers = [
        await asyncio.start_server(
            functools.partial(join, peer=functools.partial(asyncio.open_unix_connection, str(folder / f"{p}.sock"))),
            "127.0.0.1",
            p,
        )
        for p in ports
    ]
    proc = await asyncio.create_subprocess_exec(*command)
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(sig, proc.send_signal, sig)
    try:
        return await proc.wait()
    finally:
        for srv in servers:
            srv.close()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m usarsim.sweep.isolated",
        description="Run a controller command in this (new) network namespace, reaching only the simulator "
        "ports relayed through the Unix sockets of --dir.",
    )
    p.add_argument("--dir", required=True, type=Path, help="the folder of the worker's Unix sockets, PORT.sock")
    p.add_argument("--ports", required=True, help="the simulator ports to serve on 127.0.0.1, comma-separated")
    p.add_argument(
        "--outside", required=True, help="the starting process's network and mount namespaces (inodes NET,MNT)"
    )
    p.add_argument("command", nargs=argparse.REMAINDER, help="-- then the controller command")
    args = p.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        p.error("no command given after --")
    try:
        ports = [int(x) for x in args.ports.split(",") if x]
    except ValueError:
        p.error(f"--ports takes port numbers separated by commas, got {args.ports!r}")
    if not ports or not all(0 < x < 65536 for x in ports):
        p.error(f"--ports takes port numbers from 1 to 65535, got {args.ports!r}")
    if not in_own_namespaces(args.outside):
        p.error(
            "this runs inside a network and mount namespace of its own (the sweep starts it under "
            "'unshare --net --mount'); here it would change the machine's /dev/shm"
        )
    loopback_up()
    private_mounts()
    try:
        return asyncio.run(serve(args.dir, ports, command))
    except OSError as exc:
        print(f"usarsim isolation: {exc}", file=sys.stderr)
        return 127


if __name__ == "__main__":
    sys.exit(main())
