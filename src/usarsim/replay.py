"""``usarsim replay``: run a recording's client lines again against a fresh server and
compare what the server answers with what it answered then.

A recording (``usarsim serve --record``) holds every chunk each connection sent and received,
in the order the server saw them, and the world, seed and options of the run
(:mod:`usarsim.server.recording.transcript`).  The replay starts a server of its own in this
process, on free ports of 127.0.0.1 and always in lock-step, opens the recorded connections
in their order and sends each one's bytes exactly as recorded.

Lock-step recordings replay exactly: before a client line is sent, every server line the
recording shows before it has arrived (so each line reaches the simulation at the same point
of the simulated clock as before), and when the next line comes from another connection the
last one is confirmed with a ``PING {Id usarsim-replay-N}`` (its PONG is not compared).  Every
server line is compared with the recording as it arrives; ``--check`` stops at the first
difference and names its connection, simulated time and both lines.

A recording made in real time replays its client lines in lock-step at their recorded
simulated times (a connection of the replay's own sends the STEPs); its server lines are then
compared kind by kind (the k-th ``SEN Scanner1`` with the k-th), and the report says how many
are identical and how far their numbers are apart.

Image-server connections are not replayed (their pictures are not kept), nor the wireless
ports (the ComServer dials out to the robots' own listening ports).

A recording is read from its first byte on (:mod:`usarsim.server.recording.reading`): one the
server did not close (killed, crashed) replays up to where it ends, with a warning that says
where, and what the server answers after that end is not compared.  A damaged file, or one
that is not a recording, is refused in one line (exit 1; the traceback in the log at -v).
The recording read back, the differences and the report: :mod:`usarsim.replay_io`.
"""

from __future__ import annotations

import asyncio
import logging
import math
import os
import re
import sys
import time
from collections import defaultdict

from usarsim.replay_io import Difference, Recording, ReplayError, Report, format_report, read_recording
from usarsim.server.recording.transcript import Chunk, split_lines

log = logging.getLogger("usarsim.replay")

REPLAYED_PORTS = ("control", "truth")
BARRIER_ID = "usarsim-replay-"
_PONG = re.compile(r"^PONG \{Id usarsim-replay-\d+\}")
_NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")
_TYPE = re.compile(r"\{Type ([^} ]*)")
_NAME = re.compile(r"\{Name ([^} ]*)")
LINE_LIMIT = 1 << 22  # the longest line read back (a 3-D sweep's row is a few kB)


class _Conn:
    """One replayed connection: its socket and the server lines read back."""

    def __init__(self, cid: int, port: str, peer: str, expected: list[tuple[Chunk, str]]):
        self.cid = cid
        self.port = port
        self.peer = peer
        self.expected = expected
        self.got: list[str] = []
        self.reader: asyncio.StreamReader | None = None
        self.writer: asyncio.StreamWriter | None = None
        self.task: asyncio.Task | None = None
        self.changed = asyncio.Event()
        self.eof = False
        self.target = 0  # server lines the recording shows by now
        self.partial = False  # the last bytes sent ended inside a line
        self.pongs: dict[str, asyncio.Future] = {}
        self.compared = 0  # server lines compared so far

    async def read(self) -> None:
        assert self.reader is not None
        try:
            while True:
                raw = await self.reader.readline()
                if not raw:
                    break
                line = raw.decode("latin-1").rstrip("\r\n") if raw.endswith(b"\n") else raw.decode("latin-1")
                if _PONG.match(line):
                    key = line.split("}", 1)[0][len("PONG {Id ") :]
                    fut = self.pongs.pop(key, None)
                    if fut is not None and not fut.done():
                        fut.set_result(line)
                    continue
                self.got.append(line)
                self.changed.set()
        except (ConnectionError, asyncio.IncompleteReadError, ValueError):
            pass
        self.eof = True
        self.changed.set()


class Replayer:
    """Replays one recording against a server of its own (:meth:`run`)."""

    def __init__(self, rec: Recording, *, check: bool = False, timeout: float = 10.0, progress=None):
        self.rec = rec
        self.check = check
        self.timeout = timeout
        self.progress = progress  # called with (chunks done, chunks in all)
        self.report = Report(rec.info)
        self.conns: dict[int, _Conn] = {}
        self._barrier = 0
        self._clock: _Conn | None = None

    # the server ------------------------------------------------------------------
    def _application(self):
        from usarsim.config.catalog import resolve_world
        from usarsim.errors import UsarsimError
        from usarsim.server.app import Application
        from usarsim.server.config import ServeConfig
        from usarsim.sim.settings import SimSettings

        info = self.rec.info
        try:
            world = resolve_world(
                info.world_path if info.world_path and os.path.isfile(info.world_path) else info.world
            )
        except UsarsimError as exc:
            raise ReplayError(f"the recorded world {info.world!r} cannot be loaded: {exc}") from exc
        opts = info.options
        dirs = tuple(d for d in opts.get("robot_dirs", []) if os.path.isdir(d))
        return Application(
            ServeConfig(
                world=world,
                host="127.0.0.1",
                port=0,
                seed=info.seed,
                speed=None,
                lockstep=True,
                max_connections=max(64, int(opts.get("max_connections") or 64)),
                robot_dirs=dirs,
                truth_port=0,
                image_port=None,
                wireless=None,
                web_port=None,
                max_robots=opts.get("max_robots"),
                max_line_bytes=int(opts.get("max_line_bytes") or 8192),
                # the instants robots reported at (recordings made before the setting: the grid)
                sim=SimSettings(report_phases=str(opts.get("report_phases") or "grid")),
            )
        )

    async def run(self) -> Report:
        t0 = time.perf_counter()
        app = self._application()
        await app.start()
        try:
            self.ports = {"control": app.control.port, "truth": app.truth.port if app.truth else None}
            await self._replay()
        finally:
            for c in self.conns.values():
                if c.writer is not None:
                    c.writer.close()
            await app.stop()
        self.report.wall_s = time.perf_counter() - t0
        return self.report

    # the replay ------------------------------------------------------------------
    async def _replay(self) -> None:
        chunks = self.rec.chunks
        by_conn: dict[int, list[Chunk]] = defaultdict(list)
        for c in chunks:
            if c.kind == "out":
                by_conn[c.conn].append(c)
        lockstep = self.rec.info.lockstep
        if not lockstep:
            self._clock = await self._open(-1, "control", "replay clock", [])
            await self._wait_lines(self._clock, 1)  # its NFO
        # the lines of each connection, counted as chunks come (to know how many are due)
        line_ends: dict[int, dict[int, int]] = {}  # conn -> seq -> lines complete after that chunk
        expected: dict[int, list[tuple[Chunk, str]]] = {}
        for cid, outs in by_conn.items():
            lines = list(split_lines(outs))
            if not self.rec.complete and lines and not outs[-1].text.endswith("\n"):
                lines.pop()  # a line the end of an unclosed recording cut short
            expected[cid] = lines
            counts: dict[int, int] = {}
            for k, (ch, _) in enumerate(lines):
                counts[ch.seq] = k + 1
            line_ends[cid] = counts
        last_in: _Conn | None = None
        now = 0.0
        total = len(chunks)
        for i, ch in enumerate(chunks):
            if self.progress is not None and i % 64 == 0:
                self.progress(i, total)
            if ch.port not in REPLAYED_PORTS:
                if ch.kind == "open":
                    self.report.skipped[ch.port] = self.report.skipped.get(ch.port, 0) + 1
                continue
            if not lockstep and ch.kind != "out" and ch.sim_time > now + 1e-9:
                now = await self._advance_to(ch.sim_time, now)  # real time: the clock to the recorded instant
            if ch.kind == "open":
                await self._settle(lockstep)
                self.conns[ch.conn] = await self._open(ch.conn, ch.port, ch.peer, expected.get(ch.conn, []))
                self.report.connections[ch.port] = self.report.connections.get(ch.port, 0) + 1
                continue
            conn = self.conns.get(ch.conn)
            if conn is None:
                continue
            if ch.kind == "out":
                n = line_ends.get(ch.conn, {}).get(ch.seq)
                if n is not None:
                    conn.target = n
                continue
            if ch.kind == "close":
                await self._settle(lockstep)
                if conn.writer is not None:
                    conn.writer.close()
                continue
            # a client's bytes
            if lockstep:
                if not await self._settle(True):
                    return
                if (
                    last_in is not None
                    and last_in is not conn
                    and last_in.port == "control"
                    and not last_in.partial
                    and not last_in.eof
                ):
                    await self._confirm(last_in)
            assert conn.writer is not None
            conn.writer.write(ch.data)
            conn.partial = not ch.text.endswith("\n")
            self.report.client_lines += ch.text.count("\n")
            self.report.last_time = max(self.report.last_time, ch.sim_time)
            last_in = conn
        if lockstep:
            await self._settle(True)
            await asyncio.sleep(0.2)  # a line the recording does not have
            self._compare_all(final=True)
        else:
            end = max((c.sim_time for c in chunks), default=0.0)
            if end > now:
                await self._advance_to(end, now)
            await asyncio.sleep(0.2)
            self._compare_kinds()
        if self.progress is not None:
            self.progress(total, total)

    async def _open(self, cid: int, port: str, peer: str, expected) -> _Conn:
        conn = _Conn(cid, port, peer, expected)
        conn.reader, conn.writer = await asyncio.open_connection("127.0.0.1", self.ports[port], limit=LINE_LIMIT)
        conn.task = asyncio.create_task(conn.read())
        return conn

    async def _wait_lines(self, conn: _Conn, n: int) -> bool:
        deadline = time.monotonic() + self.timeout
        while len(conn.got) < n and not conn.eof:
            conn.changed.clear()
            left = deadline - time.monotonic()
            if left <= 0:
                return False
            try:
                await asyncio.wait_for(conn.changed.wait(), left)
            except TimeoutError:
                return False
        return len(conn.got) >= n

    async def _settle(self, compare: bool) -> bool:
        """Wait until every connection has the server lines the recording shows by now;
        compare them (lock-step).  False when a difference ends a --check."""
        if not self.rec.info.lockstep:
            return True
        for conn in list(self.conns.values()):
            if conn.target > len(conn.got):
                await self._wait_lines(conn, conn.target)
        if compare:
            self._compare_all(final=False)
            if self.check and self.report.first is not None:
                return False
        return True

    async def _confirm(self, conn: _Conn) -> None:
        """The server has handled everything sent on ``conn``: PING, wait for its PONG."""
        self._barrier += 1
        key = f"{BARRIER_ID}{self._barrier}"
        fut = asyncio.get_running_loop().create_future()
        conn.pongs[key] = fut
        assert conn.writer is not None
        conn.writer.write(f"PING {{Id {key}}}\r\n".encode())
        try:
            await asyncio.wait_for(fut, self.timeout)
        except TimeoutError:
            conn.pongs.pop(key, None)

    async def _advance_to(self, t: float, now: float) -> float:
        """Real-time recordings: the replay's own connection STEPs the clock to ``t``."""
        clock = self._clock
        assert clock is not None and clock.writer is not None
        clock.writer.write(f"STEP {{Time {t - now:.6f}}}\r\n".encode())
        await self._wait_lines(clock, len(clock.got) + 1)
        return t

    # comparing -------------------------------------------------------------------
    def _compare_all(self, final: bool) -> None:
        rep = self.report
        for conn in self.conns.values():
            start = conn.compared
            upto = len(conn.expected) if final else min(conn.target, len(conn.expected))
            k = start
            while k < upto:
                recorded = conn.expected[k][1]
                replayed = conn.got[k] if k < len(conn.got) else None
                rep.compared += 1
                if replayed == recorded:
                    rep.identical += 1
                elif rep.first is None:
                    rep.first = Difference(
                        conn.cid, conn.port, conn.peer, k + 1, conn.expected[k][0].sim_time, recorded, replayed
                    )
                k += 1
            conn.compared = k
            # a recording the server did not close ends where it ends: what the server sent
            # after that is not a difference
            if final and self.rec.complete and len(conn.got) > len(conn.expected) and rep.first is None:
                k = len(conn.expected)
                t = conn.expected[-1][0].sim_time if conn.expected else 0.0
                rep.first = Difference(conn.cid, conn.port, conn.peer, k + 1, t, None, conn.got[k])

    def _compare_kinds(self) -> None:
        """Real time: the k-th line of each kind against the k-th; how far the numbers are."""
        rep = self.report
        for conn in self.conns.values():
            mine: dict[str, list[tuple[Chunk, str]]] = defaultdict(list)
            theirs: dict[str, list[str]] = defaultdict(list)
            for ch, line in conn.expected:
                mine[_kind(line)].append((ch, line))
            for line in conn.got:
                theirs[_kind(line)].append(line)
            for kind, lines in mine.items():
                other = theirs.get(kind, [])
                for k, (ch, recorded) in enumerate(lines):
                    replayed = other[k] if k < len(other) else None
                    rep.compared += 1
                    if replayed == recorded:
                        rep.identical += 1
                        continue
                    if rep.first is None:
                        rep.first = Difference(
                            conn.cid,
                            conn.port,
                            conn.peer,
                            conn.expected.index((ch, recorded)) + 1,
                            ch.sim_time,
                            recorded,
                            replayed,
                        )
                    if replayed is not None:
                        a, b = _NUMBER.findall(recorded), _NUMBER.findall(replayed)
                        if len(a) == len(b):
                            d = max((abs(float(x) - float(y)) for x, y in zip(a, b, strict=True)), default=0.0)
                            rep.numbers[kind] = max(rep.numbers.get(kind, 0.0), d)
                        else:
                            rep.numbers[kind] = math.inf


def _kind(line: str) -> str:
    """What a line is, for matching lines of a real-time replay: its first word, its Type
    and the first word of its Name (``SEN Encoder ECLeft``)."""
    word = line.split(" ", 1)[0]
    typ = _TYPE.search(line)
    name = _NAME.search(line)
    return " ".join(x for x in (word, typ.group(1) if typ else "", name.group(1) if name else "") if x)


def replay(path: str | os.PathLike, *, check: bool = False, timeout: float = 10.0, progress=None) -> Report:
    """Replay the recording at ``path`` (see the module's description); the report."""
    rec = read_recording(path)
    return asyncio.run(Replayer(rec, check=check, timeout=timeout, progress=progress).run())


def main(args) -> int:
    """``usarsim replay FILE [--check] [--timeout S]``: 0 when replayed (and, with --check,
    identical), 1 when it differs or the file cannot be replayed (one line on stderr: what is
    wrong and what to do; the traceback in the log at -v)."""
    try:
        rec = read_recording(args.path)
    except ReplayError as exc:
        return _refuse(exc)
    except Exception as exc:  # noqa: BLE001 (a file no case above foresaw: still one line)
        return _refuse(ReplayError(f"{args.path} cannot be read: {type(exc).__name__}: {exc}"), exc)
    ending = rec.ending()
    if ending is not None:
        print(f"usarsim replay: warning: {ending}", file=sys.stderr, flush=True)
    bar = None
    progress = None
    if sys.stderr.isatty():
        from rich.progress import Progress

        bar = Progress(transient=True)
        task = bar.add_task("replaying", total=None)

        def progress(done: int, total: int) -> None:
            bar.update(task, completed=done, total=total)

        bar.start()
    try:
        rep = asyncio.run(Replayer(rec, check=args.check, timeout=args.timeout, progress=progress).run())
    except ReplayError as exc:
        return _refuse(exc)
    finally:
        if bar is not None:
            bar.stop()
    print(format_report(args.path, rep))
    if ending is not None:
        print(f"note: {ending}")
    if args.check and not rep.info.lockstep:
        print("note: a real-time recording never replays identically; --check compares lock-step recordings")
    return 0 if rep.ok or not args.check else 1


def _refuse(exc: Exception, cause: BaseException | None = None) -> int:
    """One line on stderr; the traceback in the log at -v."""
    log.info("usarsim replay: %s", exc, exc_info=cause or exc)
    print(f"usarsim replay: {exc}", file=sys.stderr, flush=True)
    return 1
