"""Pictures of the robots' cameras (protocol.md 7.11, 10, 11), rendered with MuJoCo's
offscreen renderer on one dedicated thread that owns the GL context (Mesa EGL on a machine
without a GPU, the GPU's driver where there is one).

A picture is rendered only when a client asks for one.  The render thread asks the
simulation thread for a snapshot (a copy of the physics state, taken between two steps: a
memory copy) and renders from the copy while the physics runs on; a frame budget (pictures
per second of wall-clock time, all clients together) keeps rendering from taking the
machine away from the physics.

Layouts: a picture is a grid of tiles, each showing one robot camera (or nothing, black).
A camera bound to a client fills the whole picture; the MultiView (manual 3.2.6) tiles
several robots' cameras.  An omnidirectional camera renders a panorama: four 90-degree
views side by side, from 135 degrees left to 135 degrees right of its heading.

A free camera belongs to no robot: the operator console's 3-D view orbits it about a point
of the world (MuJoCo's free camera: a look-at point, azimuth, elevation and distance, in
MuJoCo's frame: X forward, Y left, Z up), or about a robot's chassis that it follows.
"""

from __future__ import annotations

import logging
import math
import queue
import threading
import time
from collections.abc import Callable, Iterable
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any, cast

import mujoco
import numpy as np

from usarsim.sim import pictures
from usarsim.sim.builder import MAX_PICTURE_HEIGHT as MAX_HEIGHT
from usarsim.sim.builder import MAX_PICTURE_WIDTH as MAX_WIDTH
from usarsim.sim.pictures import SceneTables
from usarsim.sim.robotspec import camera_fovy_deg
from usarsim.sim.underwater import Water, through_water, water_of

log = logging.getLogger("usarsim.render")

# Renderers (one offscreen context each, by picture size) kept at most; the least recently
# used one is closed beyond this, so that a console page resized again and again does not
# pile up contexts.
MAX_RENDERERS = 8

# The near clipping plane of every picture (m).  MuJoCo puts it at 1 % of the model's extent,
# which in a large world cuts away everything close to the camera: 5 m in a town 300 m
# across, where a road robot's camera then sees the sky through the road ahead of it.
NEAR_CLIP_M = 0.02


def _seen_groups() -> mujoco.MjvOption:
    """What pictures show: every geom group a camera sees (world, robots, movable objects,
    wheels, water and the victims' faces: groups 0 to 4; MuJoCo draws 0 to 2 by default).  Geoms
    that only carry contacts (tread capsules, probes) are transparent."""
    opt = mujoco.MjvOption()
    opt.geomgroup[:5] = 1
    return opt


SEEN = _seen_groups()


# Textures are sampled from the nearest of their mipmaps (GL_LINEAR_MIPMAP_NEAREST) instead of
# blending the two nearest (MuJoCo's GL_LINEAR_MIPMAP_LINEAR): on a software renderer the
# blend is most of what textures cost (2-core machine, 640x480: 25-27 % fewer frames a second
# than plain colours with the blend, 16-21 % without), for pictures that differ by 2 levels
# of 255 on average.
MIN_FILTER_NEAREST_MIPMAP = 0x2701  # GL_LINEAR_MIPMAP_NEAREST (OpenGL 1.0)


def nearest_mipmap(r: mujoco.Renderer) -> None:
    """Sample ``r``'s 2-D textures from their nearest mipmap (see MIN_FILTER_NEAREST_MIPMAP);
    left as MuJoCo made them where its renderer's context cannot be reached."""
    ctx, gl = getattr(r, "_mjr_context", None), getattr(r, "_gl_context", None)
    if ctx is None or gl is None:
        return
    try:
        from OpenGL import GL

        gl.make_current()
        for i in range(ctx.ntexture):
            if ctx.textureType[i] == int(mujoco.mjtTexture.mjTEXTURE_2D):
                GL.glBindTexture(GL.GL_TEXTURE_2D, int(ctx.texture[i]))
                GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, MIN_FILTER_NEAREST_MIPMAP)
        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
    except Exception as exc:  # a GL binding missing or refusing: keep MuJoCo's filtering
        log.debug("texture filtering left as MuJoCo made it: %s", exc)


def camera_renderer(model: mujoco.MjModel, width: int, height: int, shadows: bool) -> mujoco.Renderer:
    """An offscreen renderer drawing the way cameras draw: shadows as asked, no reflections
    (they cost more than they tell an operator), textures from their nearest mipmap."""
    r = mujoco.Renderer(model, height, width)
    r.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = int(shadows)
    r.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
    nearest_mipmap(r)
    return r


@dataclass
class CameraState:
    """A robot camera in a snapshot: its MuJoCo camera, its current horizontal field of view in radians (the zoom),
    and whether it is omnidirectional (rendered as a panorama)."""

    cam_id: int  # the MuJoCo camera
    fov_rad: float  # horizontal field of view (zoom)
    omni: bool
    picture: str = "colour"  # what it sees (usarsim.sim.pictures.PICTURES)
    max_depth_m: float = 10.0  # a depth camera's reach
    size: tuple[int, int] = (320, 240)  # its own pictures' width and height (those beyond colour are served so)


@dataclass
class Snapshot:
    """What the render thread draws from: the model, a private copy of the state, the
    simulated time and every robot camera, by (robot id, camera name in lower case)."""

    model: mujoco.MjModel
    data: mujoco.MjData
    time: float
    cameras: dict[tuple[int, str], CameraState] = field(default_factory=dict)
    robots: dict[str, int] = field(default_factory=dict)  # robot id by its name, in lower case
    multiview: list[tuple[int, str]] = field(default_factory=list)  # what the MultiView shows
    bodies: dict[str, int] = field(default_factory=dict)  # each robot's chassis body, by its name in lower case
    tables: SceneTables | None = None  # what thermal and label cameras see of each geom
    cold_robots: frozenset[int] = frozenset()  # robots whose battery is empty (cold to a thermal camera)
    relays: tuple[tuple[float, ...], ...] = ()  # the antennas of the radio relays robots dropped (MuJoCo frame)


@dataclass(frozen=True)
class FreeView:
    """A free camera (MuJoCo's ``mjCAMERA_FREE``): it looks at ``lookat`` (MuJoCo's frame,
    metres) from ``distance`` metres away, turned ``azimuth`` degrees about the vertical
    (0: looking along +X, 90: along +Y) and ``elevation`` degrees above the horizontal
    (negative: looking down).  ``follow`` names a robot whose chassis replaces ``lookat``."""

    lookat: tuple[float, float, float]
    azimuth: float
    elevation: float
    distance: float
    width: int
    height: int
    follow: str | None = None


# snapshot -> (width, height, tiles): how a picture of robot cameras is laid out
_Layout = Callable[[Snapshot], tuple[int, int, Iterable[Any]]]


@dataclass
class _Job:
    layout: _Layout | None  # snapshot -> (width, height, tiles); None for a free camera
    future: Future
    free: FreeView | None = None


class RenderService:
    """The render thread.  ``take_snapshot(reuse)`` must run a snapshot on the simulation
    thread and return a future of it; ``render`` returns a Future of an RGB picture (height x
    width x 3, uint8, rows top to bottom)."""

    def __init__(self, take_snapshot, max_fps: float = 30.0, shadows: bool = False):
        """``shadows``: the lights that cast shadows do (SimSettings.shadows): each draws the
        scene once more, into its shadow map; on a software renderer (Mesa llvmpipe, 2 cores)
        that halves the frames a second."""
        self._take_snapshot = take_snapshot
        self.max_fps = max_fps
        self.shadows = bool(shadows)
        self._queue: queue.Queue[_Job | None] = queue.Queue()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()
        self._renderers: dict[tuple[int, int], mujoco.Renderer] = {}
        self._model: mujoco.MjModel | None = None
        self._water: Water | None = None  # the model's water volumes, found once per model
        self._snapshot: Snapshot | None = None
        self._next_frame = 0.0
        self.frames = 0
        self.available: bool | None = None  # None: not tried yet; False: no GL context here
        self.error = ""

    def render(self, width: int, height: int, tiles) -> Future:
        """A picture of ``width`` x ``height`` made of ``tiles``."""
        tiles = tuple(tiles)
        return self.render_layout(lambda snap: (width, height, tiles))

    def render_layout(self, layout) -> Future:
        """A picture laid out from the snapshot: ``layout(snapshot)`` returns its width,
        height and tiles (so that robot names and the MultiView are read at the same
        instant as the picture)."""
        return self._submit(_Job(layout, Future()))

    def render_free(
        self,
        width: int,
        height: int,
        *,
        lookat,
        azimuth: float,
        elevation: float,
        distance: float,
        follow: str | None = None,
    ) -> Future:
        """A picture of ``width`` x ``height`` from a free camera (see :class:`FreeView`);
        the Future's result is ``(picture, camera)``: the RGB picture and a dict of the camera
        it was seen from (``lookat``, ``azimuth``, ``elevation``, ``distance``, ``fovy``, the
        vertical field of view in degrees, ``time``, the simulated time of the picture, and
        ``follow``, the robot followed or None when it is not in the world)."""
        view = FreeView(
            lookat=cast("tuple[float, float, float]", tuple(float(v) for v in lookat)),  # x, y, z
            azimuth=float(azimuth),
            elevation=float(elevation),
            distance=float(distance),
            width=int(width),
            height=int(height),
            follow=follow,
        )
        return self._submit(_Job(None, Future(), free=view))

    def _submit(self, job: _Job) -> Future:
        with self._lock:
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="usarsim-render", daemon=True)
                self._thread.start()
        self._queue.put(job)
        return job.future

    def stop(self) -> None:
        with self._lock:
            thread, self._thread = self._thread, None
        if thread is not None:
            # the thread ends after the picture it is drawing (a snapshot waits up to 30 s for
            # the simulation) and closes its GL contexts itself: it must have ended before the
            # interpreter finalises, or its native frames are unwound by force
            self._queue.put(None)
            thread.join(timeout=60.0)
            if thread.is_alive():
                log.error("the render thread did not stop within 60 s")

    # the render thread -------------------------------------------------------------
    def _run(self) -> None:
        try:
            while True:
                job = self._queue.get()
                if job is None:
                    return
                if not job.future.set_running_or_notify_cancel():
                    continue  # its client gave up waiting: no picture is made for nobody
                try:
                    self._pace()
                    snap = self._snapshot_now()
                    job.future.set_result(self._draw(snap, job))
                    self.frames += 1
                except BaseException as exc:  # the thread must live on: the error goes to the client
                    if not job.future.done():
                        job.future.set_exception(exc)
        finally:
            for r in self._renderers.values():
                try:
                    r.close()
                except Exception:  # a context that failed to open cannot close either
                    pass
            self._renderers.clear()

    def _pace(self) -> None:
        """The frame budget: at most ``max_fps`` pictures per second, all clients together."""
        if self.max_fps <= 0:
            return
        now = time.monotonic()
        if now < self._next_frame:
            time.sleep(self._next_frame - now)
            now = self._next_frame
        self._next_frame = now + 1.0 / self.max_fps

    def _snapshot_now(self) -> Snapshot:
        future = self._take_snapshot(self._snapshot)
        try:
            self._snapshot = future.result(30.0)
        except TimeoutError:
            raise TimeoutError("the simulation did not answer a snapshot request within 30 s") from None
        return self._snapshot

    def _renderer(self, model: mujoco.MjModel, width: int, height: int) -> mujoco.Renderer:
        if model is not self._model:  # robots came or went: the model was rebuilt
            for r in self._renderers.values():
                r.close()
            self._renderers.clear()
            self._model = model
            self._water = None
        r = self._renderers.pop((width, height), None)
        if r is None:
            while len(self._renderers) >= MAX_RENDERERS:  # the least recently used goes
                self._renderers.pop(next(iter(self._renderers))).close()
            try:
                r = camera_renderer(model, width, height, self.shadows)
            except Exception as exc:
                self.available = False
                self.error = f"no OpenGL context for rendering ({exc}); set MUJOCO_GL=egl or osmesa"
                raise RuntimeError(self.error) from exc
            self.available = True
        self._renderers[(width, height)] = r  # (again) the most recently used
        return r

    def _draw(self, snap: Snapshot, job: _Job):
        if job.free is not None:
            return self._free(snap, job.free)
        width, height, tiles = cast("_Layout", job.layout)(snap)  # a job without a free camera has its layout
        if not (1 <= width <= MAX_WIDTH and 1 <= height <= MAX_HEIGHT):
            raise ValueError(f"picture {width}x{height} is outside 1x1..{MAX_WIDTH}x{MAX_HEIGHT}")
        tiles = list(tiles)
        if len(tiles) == 1 and (tiles[0].x, tiles[0].y, tiles[0].width, tiles[0].height) == (0, 0, width, height):
            cam = snap.cameras.get((tiles[0].uid, tiles[0].camera.lower()))
            if cam is not None and cam.picture != "colour":  # one camera's own picture: depth, thermal or labels
                return self._view(snap, cam, width, height)
        picture = np.zeros((height, width, 3), dtype=np.uint8)
        for t in tiles:
            cam = snap.cameras.get((t.uid, t.camera.lower()))
            w = min(t.width, width - t.x)
            h = min(t.height, height - t.y)
            if cam is None or w <= 0 or h <= 0:
                continue
            view = pictures.as_colour(self._view(snap, cam, t.width, t.height))
            picture[t.y : t.y + h, t.x : t.x + w] = view[:h, :w]
        return picture

    def _view(self, snap: Snapshot, cam: CameraState, width: int, height: int) -> np.ndarray:
        model, data = snap.model, snap.data
        model.vis.map.znear = NEAR_CLIP_M / max(float(model.stat.extent), 1e-6)
        if not cam.omni:
            model.cam_fovy[cam.cam_id] = camera_fovy_deg(cam.fov_rad, width, height)
            r = self._renderer(model, width, height)
            r.update_scene(data, camera=cam.cam_id, scene_option=SEEN)
            draw_relays(r.scene, snap.relays)
            if cam.picture != "colour":
                return self._beyond_colour(r, snap, cam)
            return self._shoot(r, snap)
        # a panorama: four quarter views, each turned about the camera's own up axis
        edges = [round(k * width / 4) for k in range(5)]
        base = data.cam_xmat[cam.cam_id].reshape(3, 3).copy()
        out = np.empty((height, width, 3), dtype=np.uint8)
        try:
            for k in range(4):
                w = edges[k + 1] - edges[k]
                turn = math.radians(-135.0 + 90.0 * k)  # right of the heading is positive
                c, s = math.cos(-turn), math.sin(-turn)
                about_up = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
                data.cam_xmat[cam.cam_id] = (base @ about_up).ravel()
                model.cam_fovy[cam.cam_id] = camera_fovy_deg(math.pi / 2, w, height)
                r = self._renderer(model, w, height)
                r.update_scene(data, camera=cam.cam_id, scene_option=SEEN)
                draw_relays(r.scene, snap.relays)
                out[:, edges[k] : edges[k + 1]] = self._shoot(r, snap)
        finally:
            data.cam_xmat[cam.cam_id] = base.ravel()
        return out

    @staticmethod
    def _beyond_colour(r: mujoco.Renderer, snap: Snapshot, cam: CameraState) -> np.ndarray:
        """A depth, thermal or label picture of ``r``'s scene (usarsim.sim.pictures)."""
        if cam.picture == "depth":
            return pictures.depth_picture(r, cam.max_depth_m)
        tables = snap.tables
        if tables is None:
            raise ValueError(f"no scene tables for a {cam.picture} picture")
        ids = pictures.geoms_seen(r)
        if cam.picture == "label":
            return pictures.label_picture(ids, tables)
        # the sensor's noise, drawn the same for the same instant and camera
        rng = np.random.default_rng([round(snap.time * 1e4), cam.cam_id])
        return pictures.thermal_picture(ids, tables.temperatures(snap.cold_robots), rng)

    def _shoot(self, r: mujoco.Renderer, snap: Snapshot) -> np.ndarray:
        """The picture of ``r``'s scene (its camera placed by ``update_scene``): as MuJoCo
        renders it, or, from a camera under water, rendered with its depth and seen through the
        water (:mod:`usarsim.sim.underwater`)."""
        if self._water is None:
            self._water = water_of(snap.model, snap.data)
        glcam = r.scene.camera[0]
        box = self._water.around(glcam.pos) if self._water.boxes else None
        if box is None:
            return r.render()
        rgb, depth = render_with_depth(r)
        return through_water(rgb, depth, glcam, box, self._water.colour)

    def _free(self, snap: Snapshot, v: FreeView) -> tuple[np.ndarray, dict]:
        if not (1 <= v.width <= MAX_WIDTH and 1 <= v.height <= MAX_HEIGHT):
            raise ValueError(f"picture {v.width}x{v.height} is outside 1x1..{MAX_WIDTH}x{MAX_HEIGHT}")
        model, data = snap.model, snap.data
        model.vis.map.znear = NEAR_CLIP_M / max(float(model.stat.extent), 1e-6)
        lookat = np.array(v.lookat, dtype=float)
        followed = None
        if v.follow is not None:
            body = snap.bodies.get(v.follow.lower())
            if body is not None:
                lookat = data.xpos[body].copy()
                followed = v.follow
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        cam.lookat[:] = lookat
        cam.azimuth = v.azimuth
        cam.elevation = v.elevation
        cam.distance = v.distance
        r = self._renderer(model, v.width, v.height)
        r.update_scene(data, camera=cam, scene_option=SEEN)
        draw_relays(r.scene, snap.relays)
        picture = self._shoot(r, snap)
        return picture, {
            "lookat": [round(float(c), 4) for c in lookat],
            "azimuth": v.azimuth,
            "elevation": v.elevation,
            "distance": v.distance,
            "fovy": float(model.vis.global_.fovy),
            "time": round(snap.time, 4),
            "follow": followed,
        }


# A dropped radio relay in pictures: an orange box on the ground with a short black antenna (the
# antenna point is its tip; sizes are estimates of a breadcrumb, as usarsim.effecters.relay_dropper's)
RELAY_BOX_M = 0.15
RELAY_RGBA = np.array([1.0, 0.55, 0.0, 1.0], dtype=np.float32)
ANTENNA_RGBA = np.array([0.05, 0.05, 0.05, 1.0], dtype=np.float32)
RELAY_ANTENNA_M = 0.2


def draw_relays(scene: mujoco.MjvScene, relays) -> None:
    """Add the relays (their antenna tips, MuJoCo frame) to ``scene`` as decorations: they are
    drawn in every picture, and no sensor's ray meets them."""
    eye = np.eye(3).ravel()
    for x, y, z in relays:
        for kind, size, pos, rgba in (
            (
                mujoco.mjtGeom.mjGEOM_BOX,
                [RELAY_BOX_M / 2] * 3,
                (x, y, z - RELAY_ANTENNA_M + RELAY_BOX_M / 2),
                RELAY_RGBA,
            ),
            (
                mujoco.mjtGeom.mjGEOM_CYLINDER,
                [0.006, RELAY_ANTENNA_M / 2, 0.0],
                (x, y, z - RELAY_ANTENNA_M / 2),
                ANTENNA_RGBA,
            ),
        ):
            if scene.ngeom >= scene.maxgeom:
                return
            mujoco.mjv_initGeom(
                scene.geoms[scene.ngeom], int(kind), np.array(size, dtype=float), np.array(pos, dtype=float), eye, rgba
            )
            scene.ngeom += 1


def render_with_depth(r: mujoco.Renderer) -> tuple[np.ndarray, np.ndarray]:
    """One rendering of ``r``'s scene read back twice: the RGB picture (as ``r.render()``
    makes it) and the raw depth buffer (reverse Z), rows top to bottom."""
    h, w = r.height, r.width
    rgb = np.empty((h, w, 3), dtype=np.uint8)
    depth = np.empty((h, w), dtype=np.float32)
    gl = r._gl_context
    if gl is not None:
        gl.make_current()
    mujoco.mjr_render(r._rect, r.scene, r._mjr_context)
    mujoco.mjr_readPixels(rgb, depth, r._rect, r._mjr_context)
    if gl is None:  # a renderer without an OpenGL context of its own reads rows top down
        return rgb, depth
    return np.flipud(rgb), np.flipud(depth)
