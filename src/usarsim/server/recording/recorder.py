"""Records a run to an MCAP file and shows it live to Foxglove (``usarsim serve --record``,
``--foxglove``).

What it writes (docs/recording.md lists every channel):

* the protocol transcript (:mod:`.transcript`), noted by the listeners' taps (:mod:`.tap`)
  on the event loop;
* the world's static geometry once (:func:`.scene.world_scene`), robots, movable objects and
  the frame-transform tree from frames of the world (:class:`usarsim.sim.types.WorldFrame`,
  every ``frame_period_s`` of simulated time), lasers as ``foxglove.LaserScan``, 3-D
  scanners as ``foxglove.PointCloud``, odometry and ground truth as ``foxglove.PoseInFrame``,
  battery, speed and radio links as JSON for plots, and the server log as ``foxglove.Log``;
  all from the outputs the servers get anyway (the simulation does no extra work per message).

The taps and watchers only queue what they see; one thread of its own encodes and writes
(:mod:`.writing`; ``foxglove-sdk``, whose writer and WebSocket server run in native code).  Log times are
simulated times, so that a recording plays back on the simulated clock; each transcript
chunk carries its wall time too.  Nothing queued is dropped: a recording is whole.  The file's
current chunk is finished and handed to the operating system every simulated and every
wall-clock second (:data:`FLUSH_SIM_S`, :data:`FLUSH_WALL_S`), so that a server killed leaves
a file readable up to about a second before its end (:mod:`.reading`).  A live viewer that
reads too slowly loses its oldest messages (the server's backlog), never the simulation's
time.
"""

from __future__ import annotations

import logging
import math
import queue
import re
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import foxglove
from foxglove.websocket import ServerListener

from usarsim.config.world import WorldConfig
from usarsim.sim.types import Output, RadioModel, WorldFrame

from . import channels as ch
from .transcript import METADATA_NAME
from .writing import RecordingWriter, Seen, Sink

if TYPE_CHECKING:
    from foxglove.mcap import MCAPWriter

log = logging.getLogger("usarsim.record")


# Frames of the world handed to the recorder per simulated second by default (10 Hz, the
# rate of most USARSim sensors, protocol.md 5).
FRAME_PERIOD_S = 0.1
# Camera pictures recorded by default (--record-camera-size): a quarter of the image server's
# default 640x480, enough to see where a robot looks at a few megabytes a robot-minute.
CAMERA_SIZE = (320, 240)
LIVE_BACKLOG = 1024  # messages per live viewer before its oldest are dropped (foxglove-sdk's default)
# The file's current chunk is finished and handed to the operating system at least this often,
# in wall-clock and in simulated seconds, so that a server killed (kill -9, a crash) leaves a
# recording readable up to about a second before its end (usarsim replay reads such a file,
# docs/recording.md; a power cut also loses what the operating system had not yet written to
# the disk).  A chunk is also finished when it holds CHUNK_SIZE bytes.
FLUSH_WALL_S = 1.0
FLUSH_SIM_S = 1.0
CHUNK_SIZE = 1 << 20  # uncompressed bytes a chunk (foxglove-sdk's default)
BACKLOG_WARNING = 200_000  # items queued for the recorder's thread before a warning


def _write_options():
    """Chunks compressed with zstd at its fastest level, on the writer's own thread only: the
    physics keeps the other core."""
    from foxglove.mcap import MCAPCompression, MCAPWriteOptions

    return MCAPWriteOptions(
        compression=MCAPCompression.Zstd, compression_level=1, compression_threads=0, chunk_size=CHUNK_SIZE
    )


# foxglove-sdk's own log: its native WebSocket server logs through Python's logging, under
# these names (its Rust modules'; pyo3-log hands each record to the logger of that exact name,
# so a filter goes on each).
SDK_LOGGERS = (
    "foxglove.websocket.server",
    "foxglove.websocket_server",
    "foxglove.websocket.connected_client",
    "foxglove.websocket.connected_client.poller",
    "foxglove.websocket.connected_client.send_lossy",
    "foxglove.websocket.advertise",
)
# A viewer gone without closing its WebSocket (an app killed, a laptop closed, a network
# dropped): what the sdk logs then, as an ERROR.
_VIEWER_GONE = re.compile(
    r"Connection reset|without closing handshake|Broken pipe|Connection aborted|timed out|"
    r"os error (?:32|103|104|110)\b"
)
_HANDSHAKE_FAILED = re.compile(r"Dropping client (\S+): handshake failed")
# The WebSocket subprotocols the sdk's server accepts (foxglove-sdk 0.30); a viewer that
# offers none of them is answered HTTP 400 (docs/recording.md, "Live in Foxglove").
SUBPROTOCOLS = ("foxglove.sdk.v1", "foxglove.sdk.v1.1")


class _SdkLogFilter(logging.Filter):
    """foxglove-sdk's log as a user reads it: a viewer that goes away without closing is news
    (INFO, with -v), not an error; a connection refused at the handshake says why."""

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno < logging.WARNING:
            return True
        msg = record.getMessage()
        if _VIEWER_GONE.search(msg):
            record.levelno, record.levelname = logging.INFO, "INFO"
            record.msg, record.args = f"Foxglove viewer gone without closing its connection ({msg})", None
            return logging.getLogger(record.name).isEnabledFor(logging.INFO)
        refused = _HANDSHAKE_FAILED.search(msg)
        if refused:
            record.levelno, record.levelname = logging.WARNING, "WARNING"
            record.msg, record.args = (
                (
                    f"Foxglove: refused the connection from {refused.group(1)} (HTTP 400): not a WebSocket viewer "
                    f"that offers the subprotocol {' or '.join(SUBPROTOCOLS)}; a viewer that offers only "
                    "foxglove.websocket.v1 (Lichtblick up to 1.21, older Foxglove Studio builds) cannot connect: use "
                    "the Foxglove app or a newer Lichtblick (docs/recording.md, 'Live in Foxglove')"
                ),
                None,
            )
        return True


class _LogTap(logging.Handler):
    """The server's log lines, queued for the recording."""

    def __init__(self, rec: Recorder):
        super().__init__(logging.DEBUG)
        self.rec = rec

    def emit(self, record: logging.LogRecord) -> None:
        if record.name.startswith("usarsim.record"):
            return  # the recorder's own lines are not recorded (no loop through the queue)
        try:
            msg = record.getMessage()
        except Exception:  # a bad format string in a log call must not stop the server
            msg = str(record.msg)
        self.rec._q.put(("log", self.rec.sim_time(), record.levelno, record.name, msg, record.pathname, record.lineno))


class _CountingQueue:
    """A queue that counts what was put in and what was taken out and handled."""

    __slots__ = ("_q", "queued", "done", "_warned")

    def __init__(self):
        self._q: queue.SimpleQueue = queue.SimpleQueue()
        self.queued = 0  # put
        self.done = 0  # handled (the recorder's thread counts)
        self._warned = False

    def put(self, item) -> None:
        self.queued += 1  # several threads put: a lost increment only delays a benchmark's wait
        self._q.put(item)
        if self.queued - self.done > BACKLOG_WARNING and not self._warned:
            self._warned = True
            log.warning(
                "recording: %d items wait to be written: the recorder falls behind the simulation "
                "(nothing is dropped; memory grows until it catches up)",
                self.queued - self.done,
            )

    def get(self, timeout: float | None = None):
        """The next item; queue.Empty when none came within ``timeout`` seconds."""
        return self._q.get(timeout=timeout)


class Recorder(RecordingWriter):
    """Records to ``path`` (an MCAP file) and/or serves ``foxglove_port`` live; either may be
    None.  :meth:`attach` before the simulation starts, :meth:`start`, then :meth:`stop`."""

    def __init__(
        self,
        world: WorldConfig,
        info: dict[str, str],
        *,
        path: str | None = None,
        foxglove_port: int | None = None,
        host: str = "127.0.0.1",
        frame_period_s: float = FRAME_PERIOD_S,
        camera_fps: float = 0.0,
        camera_size: tuple[int, int] = CAMERA_SIZE,
    ):
        self.world = world
        self.info = info
        self.path = path
        self.foxglove_port = foxglove_port
        self.host = host
        self.frame_period_s = frame_period_s
        # cameras: every robot camera's picture each 1 / camera_fps simulated seconds (0: none)
        self.camera_fps = max(0.0, float(camera_fps))
        self.camera_size = camera_size
        self._renderer = None
        self._rendering: set[tuple[str, str]] = set()  # (robot, camera) pictures asked and not back yet
        self._last_pictures = -math.inf
        self.pictures = 0
        self._q = _CountingQueue()
        self._thread = threading.Thread(target=self._run, name="usarsim-record", daemon=True)
        self._seq = 0
        self._conns: dict[int, tuple[str, str]] = {}  # conn -> (port, peer)
        self._next_conn = 0
        self._sinks: list[Sink] = []
        self._file_sink: Sink | None = None
        self._live_sink: Sink | None = None
        self._writer: MCAPWriter | None = None
        self.server = None  # the live WebSocket server
        self._time: Callable[[], float] = lambda: 0.0
        self._describe = None
        self._log_tap = _LogTap(self)
        self._sdk_filter = _SdkLogFilter()
        # worker state
        self._names: dict[int, str] = {}  # uid -> robot name
        self._seen: dict[str, Seen] = {}  # robots by name
        self._objects: dict[str, object] = {}  # movable objects as last written
        self._relays: int = 0  # relays written to the relays channel
        self._waiting: dict[int, list[Output]] = {}
        self._last_refresh = -math.inf
        self.messages = 0  # written (every sink counted once)
        self.chunks = 0
        self.flushes = 0  # chunks finished and handed to the operating system on time (FLUSH_*)
        self._unflushed = False  # something was written to the file since its last flush
        self._flushed_wall = 0.0  # time.monotonic() of the last flush
        self._flushed_sim = 0.0  # simulated time of the last flush
        self.error: BaseException | None = None

    # Wiring --------------------------------------------------------------------------
    def attach(self, facade, radio_model: RadioModel | None = None) -> None:
        """Watch ``facade``'s outputs and frames of its world (before its simulation starts)."""
        self._time = lambda: facade.time
        self._describe = facade.describe_robot
        facade.add_output_watcher(self._on_outputs)
        facade.watch_frames(self.frame_period_s, self._on_frame, radio_model=radio_model)
        if self.camera_fps > 0:
            # a render thread of the recording's own, without a frame budget: it is asked for
            # camera_fps pictures a camera per simulated second, and a picture not back when
            # the next is due is skipped
            self._renderer = facade.render_service(max_fps=0.0)

    def sim_time(self) -> float:
        return self._time()

    def mark(self) -> int:
        """A mark of what has been queued so far: :meth:`written` reaches it once all of that
        is written (benchmarks count the time it takes)."""
        return self._q.queued

    def written(self) -> int:
        return self._q.done

    def start(self) -> None:
        """Open the file and the live server; an OSError says which could not be opened
        (its ``usarsim_listener``), and leaves neither open."""
        try:
            if self.path is not None:
                ctx = foxglove.Context()
                self._writer = foxglove.open_mcap(
                    self.path, allow_overwrite=True, context=ctx, writer_options=_write_options()
                )
                self._writer.write_metadata(METADATA_NAME, self.info)
                self._file_sink = Sink(ctx)
                self._sinks.append(self._file_sink)
        except Exception as exc:
            err = OSError(0, str(exc))
            what = f"the recording {self.path} (--record)"
            err.usarsim_listener = what  # type: ignore[attr-defined]  # read by the CLI (names what failed)
            raise err from exc
        if self.foxglove_port is not None:
            ctx = foxglove.Context()
            try:
                self.server = foxglove.start_server(
                    name=f"usarsim {self.world.name}",
                    host=self.host,
                    port=self.foxglove_port,
                    context=ctx,
                    capabilities=[foxglove.Capability.Time],
                    server_listener=_Listener(self),
                    message_backlog_size=LIVE_BACKLOG,
                )
            except Exception as exc:
                if self._writer is not None:
                    self._writer.close()
                    self._writer = None
                err = OSError(0, str(exc))
                what = f"the Foxglove port {self.foxglove_port} (--foxglove)"
                err.usarsim_listener = what  # type: ignore[attr-defined]  # read by the CLI (names what failed)
                raise err from exc
            self._live_sink = Sink(ctx)
            self._sinks.append(self._live_sink)
            self.foxglove_port = self.server.port
            for name in SDK_LOGGERS:
                logging.getLogger(name).addFilter(self._sdk_filter)
        logging.getLogger("usarsim").addHandler(self._log_tap)
        self._q.put(("world",))
        self._thread.start()

    def stop(self) -> None:
        """Write what is queued, then close the file and the live server."""
        logging.getLogger("usarsim").removeHandler(self._log_tap)
        if self._renderer is not None:
            self._renderer.stop()  # its last pictures are queued before the end
        if self._thread.is_alive():
            self._q.put(None)
            self._thread.join()
        if self._writer is not None:
            self._writer.close()
            self._writer = None
            log.info(
                "recording: %d transcript chunks and %d messages written to %s", self.chunks, self.messages, self.path
            )
        if self.server is not None:
            self.server.stop()
            self.server = None
            for name in SDK_LOGGERS:
                logging.getLogger(name).removeFilter(self._sdk_filter)

    # Taps (event loop) ---------------------------------------------------------------
    def opened(self, port: str, peer: str) -> int:
        conn = self._next_conn
        self._next_conn += 1
        self._conns[conn] = (port, peer)
        self._chunk(conn, "open", b"")
        return conn

    def note(self, conn: int, kind: str, data) -> None:
        self._chunk(conn, kind, data)

    def note_binary(self, conn: int, size: int) -> None:
        self._chunk(conn, "out", b"", size)

    def closed(self, conn: int) -> None:
        self._chunk(conn, "close", b"")
        self._conns.pop(conn, None)

    def _chunk(self, conn: int, kind: str, data, size: int | None = None) -> None:
        """Queue a chunk (the recorder's thread makes it a :class:`Chunk`): the event loop
        only counts, reads the clocks and queues."""
        self._q.put(("chunk", self._seq, conn, self._conns.get(conn), kind, self._time(), time.time(), data, size))
        self._seq += 1

    # Watchers (simulation thread): queue only --------------------------------------
    def _on_outputs(self, outs: list[Output]) -> None:
        self._q.put(("outs", outs))

    def _on_frame(self, frame: WorldFrame) -> None:
        self._q.put(("frame", frame))

    # The recorder's thread -----------------------------------------------------------
    def _run(self) -> None:
        handlers: dict[str, Callable[..., Any]] = {
            "chunk": self._write_chunk,
            "outs": self._write_outputs,
            "frame": self._write_frame,
            "log": self._write_log,
            "world": self._write_world,
            "resend": self._resend_static,
            "picture": self._write_picture,
        }
        self._flushed_wall = time.monotonic()
        while True:
            wait = None
            if self._unflushed:  # nothing more may come for a while: the file is flushed meanwhile
                wait = max(0.0, self._flushed_wall + FLUSH_WALL_S - time.monotonic())
            try:
                item = self._q.get(wait)
            except queue.Empty:
                self._flush()
                continue
            if item is None:
                return
            try:
                handlers[item[0]](*item[1:])
            except Exception as exc:  # a recording problem must not stop the server
                if self.error is None:
                    self.error = exc
                    log.exception("recording: cannot write %s", item[0])
            self._q.done += 1
            if self._writer is not None and item[0] != "resend":
                self._unflushed = True
                if (
                    time.monotonic() - self._flushed_wall >= FLUSH_WALL_S
                    or self._time() - self._flushed_sim >= FLUSH_SIM_S
                ):
                    self._flush()

    def _flush(self) -> None:
        """Finish the file's current chunk and hand what is written to the operating system:
        a server killed from now on leaves all of it readable."""
        self._flushed_wall = time.monotonic()
        self._flushed_sim = self._time()
        self._unflushed = False
        writer = self._writer
        if writer is None:
            return
        try:
            writer.flush()
            self.flushes += 1
        except Exception as exc:  # a full disk: the server goes on, the recording stops growing
            if self.error is None:
                self.error = exc
                log.exception("recording: cannot flush %s", self.path)


class _Listener(ServerListener):
    """Live viewers: one that subscribes to the world is sent its static geometry.  The sdk's
    ServerListener answers every other callback (an unsubscription, a viewer leaving) with
    nothing."""

    def __init__(self, rec: Recorder):
        self.rec = rec

    def on_subscribe(self, client, channel) -> None:
        if channel.topic == ch.WORLD_TOPIC:
            self.rec._q.put(("resend",))
