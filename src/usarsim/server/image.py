"""The image server (UPIS, protocol.md 10; TCP 5003 by default, ``--image-port``).

A client sends ``OK`` for one whole picture or ``U`` and four 32-bit big-endian numbers
(x, y, width, height) for a sub-rectangle of it; any other byte is ignored.  Each picture
goes back as a type byte (0 raw, 1..5 JPEG from "superb" to "bad"), a 4-byte big-endian
length and the payload: a JPEG file, or for raw pictures the width and height (16-bit
big-endian) and the pixels as B, G, R, rows top to bottom.

What a connection sees: the robot camera its address is bound to by ``SET {Type Camera}
{Robot r} {Name cam} {Client ip}`` on a control connection (``ip`` or ``ip:port``, the
latter for several viewers on one machine), else the MultiView of several robots'
cameras (protocol.md 11).
"""

from __future__ import annotations

import collections
import io
import logging
import threading
from dataclasses import dataclass

import numpy as np

from usarsim.protocol import upis
from usarsim.server.connection import ServerConnection, peer_address
from usarsim.server.listener import TcpListener
from usarsim.sim.types import Tile, grid_tiles

log = logging.getLogger("usarsim.server")

# UPIS image types (protocol.md 10): 0 raw, then JPEG quality levels from best to worst
IMAGE_TYPES = {"raw": 0, "superb": 1, "super": 1, "good": 2, "normal": 3, "fair": 4, "average": 4, "bad": 5}
# JPEG quality (libjpeg's 1..100 scale) of each UPIS level: our own choice of five steps
JPEG_QUALITY = {1: 95, 2: 85, 3: 75, 4: 60, 5: 40}
MAX_PENDING = 8  # requests a connection may have waiting; beyond them its socket is not read


@dataclass
class ImageSettings:
    """How pictures are made (UPIS ini ``ImageType``, ``FrameSkip``; MultiView's
    ``CameraNum``, ``WideMode``, ``CameraXres``/``CameraYres``, manual 3.2.5.2, 3.2.6)."""

    image_type: int = 3
    width: int = 640  # a bound camera's picture
    height: int = 480
    camera_num: int = 4
    wide_mode: int = 0
    tile_width: int = 320
    tile_height: int = 240
    frame_skip: int = 0  # a new picture for every (frame_skip + 1)-th request; the others repeat it
    max_fps: float = 30.0  # frame budget: new pictures per second, all clients together


class CameraBindings:
    """Which robot camera each viewer address sees (``SET {Type Camera} ... {Client ip}``)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._by_client: dict[str, tuple[str, str]] = {}

    MAX_BINDINGS = 1024  # viewer addresses bound at once; a new one beyond them is refused
    MAX_ADDRESS = 64  # the longest viewer address (an IPv6 address with a port is 47 characters)

    def bind(self, client: str, robot: str, camera: str) -> bool:
        """False (nothing bound) when ``client`` is too long to be an address or the table is
        full, so that a client cannot grow it without bound."""
        key = client.strip().lower()
        if len(key) > self.MAX_ADDRESS:
            return False
        with self._lock:
            if key not in self._by_client and len(self._by_client) >= self.MAX_BINDINGS:
                return False
            self._by_client[key] = (robot, camera)
            return True

    def __len__(self) -> int:
        return len(self._by_client)

    def release(self, client: str) -> None:
        with self._lock:
            self._by_client.pop(client.strip().lower(), None)

    def lookup(self, ip: str, port: int) -> tuple[str, str] | None:
        with self._lock:
            return self._by_client.get(peer_address(ip, port).lower()) or self._by_client.get(ip.lower())


def encode_picture(rgb: np.ndarray, image_type: int) -> bytes:
    """One UPIS frame (:func:`usarsim.protocol.upis.frame`) of an RGB picture, or, whatever
    ``image_type`` says, a PNG frame of a picture beyond colour (:func:`beyond_colour_png`)."""
    h, w = rgb.shape[:2]
    if (rgb.ndim == 2 or rgb.shape[2] == 2) and w > 0 and h > 0:
        return upis.frame(upis.PNG, beyond_colour_png(rgb))
    if image_type == upis.RAW or w == 0 or h == 0:  # an empty rectangle goes back as an empty raw picture
        image_type = upis.RAW
        payload = upis.raw_payload(w, h, np.ascontiguousarray(rgb[:, :, ::-1]).tobytes())
    else:
        from PIL import Image

        buf = io.BytesIO()
        Image.fromarray(np.ascontiguousarray(rgb)).save(buf, "JPEG", quality=JPEG_QUALITY[image_type])
        payload = buf.getvalue()
    return upis.frame(image_type, payload)


def beyond_colour_png(picture: np.ndarray) -> bytes:
    """A depth picture (16-bit millimetres) as a 16-bit grey PNG, a thermal one (8-bit) as an
    8-bit grey PNG, a label picture (class, instance) as an RGB PNG: red the class, green and
    blue the instance's high and low byte (usarsim.sim.pictures)."""
    from PIL import Image

    if picture.ndim == 3:
        cls, inst = picture[..., 0], picture[..., 1]
        rgb = np.stack([cls, inst >> 8, inst & 0xFF], axis=-1).astype(np.uint8)
        image = Image.fromarray(rgb)
    elif picture.dtype == np.uint16:
        image = Image.fromarray(np.ascontiguousarray(picture))  # mode I;16
    else:
        image = Image.fromarray(np.ascontiguousarray(picture))  # mode L
    buf = io.BytesIO()
    image.save(buf, "PNG", compress_level=1)  # fast: a picture a frame
    return buf.getvalue()


class ImageConnection(ServerConnection):
    """An image client's connection (protocol.md 10): its ``OK`` and ``U`` requests are queued and answered in order,
    one picture at a time, with the bound camera's view or the MultiView, whole or the sub-rectangle asked for."""

    what = "image"
    limit_option = "--max-viewers"
    max_waiting = MAX_PENDING
    waiting_note = "more than %d pictures asked for at once: reading paused until they are sent"

    def __init__(self, server: ImageServer):
        super().__init__(server)
        self.requests_in = upis.RequestReader()
        self.pending: collections.deque[tuple[int, int, int, int] | None] = collections.deque()
        self.busy = False
        self.requests = 0
        self.last: np.ndarray | None = None

    def writing_resumed(self) -> None:
        self._next()

    def data_received(self, data: bytes) -> None:
        for rect in self.requests_in.feed(data):
            self._queue(rect)
        self._next()

    def _queue(self, rect) -> None:
        self.pending.append(rect)
        self.queued(len(self.pending))

    def _next(self) -> None:
        # no picture is made for a client that does not read the ones sent: its unread
        # output stays within one picture beyond asyncio's high-water mark
        if self.busy or not self.writable or not self.pending or self.transport is None:
            return
        rect = self.pending.popleft()
        self.taken(len(self.pending))
        settings = self.server.settings
        self.requests += 1
        if self.last is not None and settings.frame_skip > 0 and (self.requests - 1) % (settings.frame_skip + 1):
            self._send(self.last, rect)  # FrameSkip: the last picture again
            self._next()
            return
        self.busy = True
        binding = self.server.bindings.lookup(self.ip, self.port)
        fut = self.server.renderer.render_layout(lambda snap: self.server.layout(snap, binding))
        done = self.server.threadsafe(self._done)
        fut.add_done_callback(lambda f: done(f, rect))

    def _done(self, fut, rect) -> None:
        self.busy = False
        if fut.exception() is not None:
            self.log_once("render", "no picture: %s", fut.exception())
            if self.transport is not None:
                self.transport.close()
            return
        self.last = fut.result()
        self._send(self.last, rect)
        self._next()

    def _send(self, picture: np.ndarray, rect) -> None:
        if self.transport is None or self.transport.is_closing():
            return  # no picture cut and encoded for nobody
        if rect is not None:  # the asked sub-rectangle, cut to the picture
            x, y, w, h = rect
            ph, pw = picture.shape[:2]
            x0, y0 = min(x, pw), min(y, ph)
            picture = picture[y0 : min(y0 + h, ph), x0 : min(x0 + w, pw)]
        self.write(encode_picture(picture, self.server.settings.image_type))


class ImageServer(TcpListener):
    """The image server's listener (protocol.md 10, TCP 5003 by default): it admits image clients up to
    ``--max-viewers`` and lays out what each picture shows, one bound camera or the MultiView of several robots'
    cameras (protocol.md 11)."""

    def __init__(
        self,
        renderer,
        bindings: CameraBindings,
        settings: ImageSettings | None = None,
        *,
        host: str = "127.0.0.1",
        port: int = 5003,
        max_connections: int = 16,
    ):
        super().__init__(host, port)
        self.renderer = renderer
        self.bindings = bindings
        self.settings = settings or ImageSettings()
        self.max_connections = max_connections

    def make_protocol(self) -> ImageConnection:
        return ImageConnection(self)

    def layout(self, snap, binding) -> tuple[int, int, list[Tile]]:
        """What a picture shows: the bound robot camera over the whole picture (the server's
        picture size; a depth, thermal or label camera's own), or the MultiView (black where a
        robot or camera is missing)."""
        s = self.settings
        if binding is not None:
            robot, camera = binding
            uid = snap.robots.get(robot.lower())
            width, height = s.width, s.height
            cam = snap.cameras.get((uid, camera.lower())) if uid is not None else None
            if cam is not None and cam.picture != "colour":  # a depth, thermal or label camera: its own size
                width, height = cam.size
            tiles = [Tile(uid, camera, 0, 0, width, height)] if uid is not None else []
            return width, height, tiles
        tiles, width, height = grid_tiles(snap.multiview, s.camera_num, s.wide_mode, s.tile_width, s.tile_height)
        return width, height, tiles

    async def stop(self) -> None:
        await super().stop()
        self.renderer.stop()
