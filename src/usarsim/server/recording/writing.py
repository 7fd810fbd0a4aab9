"""How the recorder's thread writes what it takes from its queue (:class:`RecordingWriter`):
the protocol transcript's chunks (the file only), the world's static geometry, the server log
as ``foxglove.Log``, robots' outputs (lasers as ``foxglove.LaserScan``, 3-D scanners as
``foxglove.PointCloud``, odometry as ``foxglove.PoseInFrame``, status as JSON), frames of the
world (robots, the frame-transform tree, poses, battery and speed, movable objects, radio
links) and camera pictures (``foxglove.CompressedImage``), each to every destination
(:class:`Sink`: the MCAP file, the live server).

:class:`RecordingWriter` is a part of :class:`usarsim.server.recording.Recorder` and runs on its
thread: it uses the recorder's world, destinations, counters, clock and queue, and the state
it keeps of the robots and objects seen (the attributes declared on the class).
"""

from __future__ import annotations

import io
import json
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import foxglove
import numpy as np
from foxglove.messages import (
    CompressedImage,
    FrameTransform,
    FrameTransforms,
    Log,
    Pose,
    PoseInFrame,
    SceneUpdate,
)
from foxglove.messages import LaserScan as FLaserScan
from PIL import Image

from usarsim.config.world import WorldConfig
from usarsim.readings import OdometryReading, RangeScan3DReading, RangeScanReading, RobotStatus
from usarsim.sim.types import Output, Tile, WorldFrame

from . import channels as ch
from . import scene
from .transcript import TOPIC, Chunk, encode_chunk

log = logging.getLogger("usarsim.record")

# Static transforms (mounts) and robot entities are sent again this often (simulated s), so
# that a viewer that joins late or seeks still has them.
REFRESH_S = 1.0
# Outputs of a robot not yet seen in a frame (spawned since the last) wait, this many at most.
MAX_WAITING_OUTPUTS = 256
CAMERA_JPEG_QUALITY = 75  # the image server's "normal" (usarsim.server.image.JPEG_QUALITY)


@dataclass(slots=True)
class Seen:
    """What the recorder knows of a robot in the world."""

    class_name: str
    dimensions: tuple
    mounts: tuple  # (item name, location, orientation) of each mounted item
    cameras: tuple[str, ...]
    start: tuple  # (location, rotation) where it appeared: its odometry's origin
    location: tuple  # at the last frame
    time: float  # of the last frame
    pose_topic: str
    state_topic: str


def _moved(before, now) -> bool:
    if before is None:
        return True
    return (
        math.dist(before.location, now.location) > 1e-3
        or max(abs(math.remainder(a - b, math.tau)) for a, b in zip(before.rotation, now.rotation, strict=True)) > 1e-3
    )


class Sink:
    """One destination (the MCAP file or the live server): a foxglove context and its channels."""

    def __init__(self, ctx: foxglove.Context):
        self.ctx = ctx
        self.channels: dict[str, object] = {}

    def channel(self, topic: str, make: Callable[[str, foxglove.Context], object]):
        channel = self.channels.get(topic)
        if channel is None:
            channel = self.channels[topic] = make(topic, self.ctx)
        return channel


class RecordingWriter:
    """The recorder's writers, one for each kind of item its thread takes from the queue (see
    the module's description)."""

    world: WorldConfig
    camera_fps: float  # every robot camera's picture each 1 / camera_fps simulated seconds
    camera_size: tuple[int, int]
    server: Any  # foxglove-sdk's live WebSocket server, None without one
    messages: int
    chunks: int
    pictures: int
    _q: Any  # the recorder's queue: the pictures come back through it
    _time: Callable[[], float]  # the simulated time
    _describe: Any  # the facade's describe_robot, None before the recorder is attached
    _renderer: Any  # the render thread of the camera pictures, None without them
    _rendering: set[tuple[str, str]]
    _last_pictures: float
    _sinks: list[Sink]
    _file_sink: Sink | None
    _live_sink: Sink | None
    _names: dict[int, str]
    _seen: dict[str, Seen]
    _objects: dict[str, object]
    _relays: int
    _waiting: dict[int, list[Output]]
    _last_refresh: float
    _map: Any = None  # the ground-truth map's Grid, made once

    def _log(self, topic: str, make, msg, t: float, sinks: list[Sink] | None = None) -> None:
        ns = scene.to_ns(t)
        for sink in self._sinks if sinks is None else sinks:
            sink.channel(topic, make).log(msg, log_time=ns)
        self.messages += 1

    def _write_chunk(
        self, seq: int, conn: int, where, kind: str, sim_time: float, wall_time: float, data, size: int | None
    ) -> None:
        if self._file_sink is None:  # the transcript is for replay: the file only
            return
        port, peer = where or ("?", "?")
        c = Chunk(seq, conn, port, peer, kind, sim_time, wall_time, bytes(data).decode("latin-1"), size)
        self._file_sink.channel(TOPIC, ch.TRANSCRIPT).log(encode_chunk(c), log_time=scene.to_ns(sim_time))
        self.chunks += 1

    def _write_world(self, sinks: list[Sink] | None = None) -> None:
        self._log(ch.WORLD_TOPIC, ch.SCENE, scene.world_scene(self.world, 0.0), 0.0, sinks)
        if self._map is None:
            self._map = ch.ground_truth_grid(self.world, 0.0)
        self._log(ch.MAP_TOPIC, ch.GRID, self._map, 0.0, sinks)

    def _resend_static(self) -> None:
        """A live viewer subscribed to the world: it gets the static geometry now."""
        if self._live_sink is not None:
            self._write_world([self._live_sink])

    def _write_log(self, t: float, levelno: int, name: str, msg: str, path: str, line: int) -> None:
        self._log(
            ch.LOG_TOPIC,
            ch.LOG,
            Log(
                timestamp=scene.timestamp(t), level=ch.log_level(levelno), message=msg, name=name, file=path, line=line
            ),
            t,
        )

    # outputs ------------------------------------------------------------------------
    def _write_outputs(self, outs: list[Output]) -> None:
        for o in outs:
            name = self._names.get(o.uid)
            if name is None:
                waiting = self._waiting.setdefault(o.uid, [])
                if len(waiting) < MAX_WAITING_OUTPUTS:
                    waiting.append(o)
                continue
            self._write_output(name, o)

    def _write_output(self, robot: str, o: Output) -> None:
        v = o.value
        t = o.time if o.time is not None else self._time()
        if isinstance(v, RangeScanReading):
            n = len(v.ranges_m)
            half = (n - 1) * v.resolution_rad / 2.0 if n > 1 else 0.0
            # USARSim sends the rightmost beam first: counter-clockwise from -half seen from above;
            # the ranges as the SEN line gives them (4 decimals, protocol.md 5)
            self._log(
                f"/{robot}/{v.name}",
                ch.LASER,
                FLaserScan(
                    timestamp=scene.timestamp(t),
                    frame_id=f"{robot}/{v.name}",
                    start_angle=-half,
                    end_angle=half,
                    ranges=np.round(np.asarray(v.ranges_m, dtype=float), 4).tolist(),
                ),
                t,
            )
        elif isinstance(v, RangeScan3DReading):
            self._log(f"/{robot}/{v.name}", ch.CLOUD, ch.point_cloud(robot, v, t), t)
        elif isinstance(v, OdometryReading):
            self._log(
                f"/{robot}/odometry",
                ch.POSE,
                PoseInFrame(
                    timestamp=scene.timestamp(t),
                    frame_id=f"{robot}/odom",
                    pose=scene.pose((v.x_m, v.y_m, 0.0), (0.0, 0.0, v.theta_rad)),
                ),
                t,
            )
        elif isinstance(v, RobotStatus):
            self._log(
                f"/{robot}/status",
                ch.STATUS,
                json.dumps(
                    {
                        "battery_s": v.battery_s,
                        "front_steer": v.front_steer,
                        "rear_steer": v.rear_steer,
                        "light": v.light_toggle,
                    }
                ).encode(),
                t,
            )

    # frames -------------------------------------------------------------------------
    def _write_frame(self, f: WorldFrame) -> None:
        t = f.time
        ts = scene.timestamp(t)
        present = set()
        tfs = []
        refresh = t - self._last_refresh >= REFRESH_S - 1e-9
        if refresh:
            self._last_refresh = t
        for r in f.robots:
            name = r.name
            present.add(name)
            self._names[r.uid] = name
            seen = self._seen.get(name)
            new = seen is None
            if seen is None:
                seen = self._seen[name] = self._appears(r, t)
            if new or refresh:
                self._log(
                    ch.ROBOTS_TOPIC,
                    ch.SCENE,
                    SceneUpdate(entities=[scene.robot_entity(name, seen.class_name, seen.dimensions, t)]),
                    t,
                )
                tfs.append(scene.transform(scene.WORLD_FRAME, f"{name}/odom", seen.start[0], seen.start[1], t))
                tfs += [scene.transform(name, f"{name}/{n}", loc, rot, t) for n, loc, rot in seen.mounts]
            position = scene.vec(r.location)
            rotation = scene.quat(r.rotation)
            tfs.append(
                FrameTransform(
                    timestamp=ts,
                    parent_frame_id=scene.WORLD_FRAME,
                    child_frame_id=name,
                    translation=position,
                    rotation=rotation,
                )
            )
            dt = t - seen.time
            speed = math.dist(r.location, seen.location) / dt if dt > 0 else 0.0
            seen.location, seen.time = r.location, t
            self._log(
                seen.pose_topic,
                ch.POSE,
                PoseInFrame(
                    timestamp=ts, frame_id=scene.WORLD_FRAME, pose=Pose(position=position, orientation=rotation)
                ),
                t,
            )
            self._log(
                seen.state_topic,
                ch.STATE,
                (
                    '{"battery_s":%.3f,"speed_m_s":%.4f,"x":%.4f,"y":%.4f,"z":%.4f,"yaw":%.4f}'
                    % (r.battery_s, speed, r.location[0], r.location[1], r.location[2], r.rotation[2])
                ).encode(),
                t,
            )
            waiting = self._waiting.pop(r.uid, None)
            for o in waiting or ():
                self._write_output(name, o)
        if present != self._seen.keys():  # a robot left (another may have come in its place)
            for gone in [n for n in self._seen if n not in present]:
                del self._seen[gone]
                self._log(ch.ROBOTS_TOPIC, ch.SCENE, scene.robot_deletion(gone, t), t)
            self._names = {u: n for u, n in self._names.items() if n in present}
        if tfs:
            self._log(ch.TF_TOPIC, ch.TF, FrameTransforms(transforms=tfs), t)
        if f.objects:
            # movable objects: those that moved (by a millimetre or a milliradian), all of them
            # every REFRESH_S
            moved = [o for o in f.objects if refresh or _moved(self._objects.get(o.name), o)]
            if moved:
                for obj in moved:
                    self._objects[obj.name] = obj
                self._log(ch.OBJECTS_TOPIC, ch.SCENE, scene.objects_scene(self.world, moved, t), t)
        for ln in f.links or ():
            self._log(
                f"{ch.RADIO_PREFIX}{ln.a}-{ln.b}",
                ch.LINK,
                json.dumps(
                    {
                        "signal_dbm": round(ln.signal_dbm, 3),
                        "distance_m": round(ln.distance_m, 3),
                        "walls": ln.walls,
                        "holds": ln.holds,
                    }
                ).encode(),
                t,
            )
        if f.traffic:
            body = {
                f"{x.src}>{x.dst}": {
                    "delivered": x.delivered,
                    "delivered_bytes": x.delivered_bytes,
                    "dropped_range": x.dropped_range,
                    "dropped_loss": x.dropped_loss,
                    "dropped_capacity": x.dropped_capacity,
                    "dropped_bytes": x.dropped_bytes,
                    "mean_delay_s": round(x.mean_delay_s, 6),
                }
                for x in f.traffic
            }
            self._log(ch.TRAFFIC_TOPIC, ch.TRAFFIC, json.dumps(body).encode(), t)
        if len(f.relays) != self._relays:  # a relay was dropped: all of them again
            self._relays = len(f.relays)
            self._log(ch.RELAYS_TOPIC, ch.SCENE, scene.relays_scene(f.relays, t), t)
        if self._renderer is not None and t - self._last_pictures >= 1.0 / self.camera_fps - 1e-9:
            self._last_pictures = t
            self._ask_pictures()
        if self.server is not None:
            self.server.broadcast_time(scene.to_ns(t))

    def _appears(self, r, t: float) -> Seen:
        """A robot seen for the first time: its class, size, mounts and cameras."""
        numbers, items = self._describe(r.config) if self._describe is not None else (None, [])
        log.debug("recording: robot %s (%s) appears at t=%.3f", r.name, r.config.class_name, t)
        return Seen(
            class_name=r.config.class_name,
            dimensions=numbers.dimensions if numbers is not None else r.config.geometry.dimensions,
            mounts=tuple((i.name, i.location, i.orientation) for i in items),
            cameras=tuple(i.name for i in items if i.item_type == "Camera"),
            start=(r.location, r.rotation),
            location=r.location,
            time=t,
            pose_topic=f"/{r.name}/pose",
            state_topic=f"/{r.name}/state",
        )

    # cameras ------------------------------------------------------------------------
    def _ask_pictures(self) -> None:
        """Ask the render thread for a picture of every robot camera, except those whose last
        picture is not back yet (a slow renderer skips pictures, it does not queue them)."""
        w, h = self.camera_size
        for robot, seen in self._seen.items():
            for cam in seen.cameras:
                key = (robot, cam)
                if key in self._rendering:
                    continue
                self._rendering.add(key)
                when: dict[str, float] = {}

                def layout(snap, robot=robot, cam=cam, when=when):
                    when["t"] = snap.time  # the simulated instant the picture shows
                    uid = snap.robots.get(robot.lower())
                    return w, h, ([Tile(uid, cam, 0, 0, w, h)] if uid is not None else [])

                fut = self._renderer.render_layout(layout)
                fut.add_done_callback(lambda f, key=key, when=when: self._picture_done(key, f, when))

    def _picture_done(self, key: tuple[str, str], fut, when: dict) -> None:
        """On the render thread: JPEG-encode the picture and queue it."""
        try:
            rgb = fut.result()
            t = when["t"]
        except Exception as exc:
            self._q.put(("picture", key, None, None, str(exc)))
            return
        buf = io.BytesIO()
        Image.fromarray(np.ascontiguousarray(rgb)).save(buf, "JPEG", quality=CAMERA_JPEG_QUALITY)
        self._q.put(("picture", key, t, buf.getvalue(), None))

    def _write_picture(self, key: tuple[str, str], t: float | None, jpeg: bytes | None, error: str | None) -> None:
        self._rendering.discard(key)
        robot, cam = key
        if jpeg is None or t is None:
            if self.pictures == 0 and error:
                log.warning("recording: no camera pictures: %s", error)
            return
        self.pictures += 1
        self._log(
            f"/{robot}/{cam}",
            ch.IMAGE,
            CompressedImage(timestamp=scene.timestamp(t), frame_id=f"{robot}/{cam}", data=jpeg, format="jpeg"),
            t,
        )
