"""The recording's channels: topic names, the JSON schemas of usarsim's own plottable
messages, the makers of each kind of foxglove-sdk channel (made once), and the messages built
from readings that need more than a constructor (a 3-D sweep's point cloud, a log level)."""

from __future__ import annotations

import json
import logging
from collections.abc import Callable

import foxglove
import numpy as np
from foxglove import channels as fch
from foxglove.messages import LogLevel, PackedElementField, PackedElementFieldNumericType, PointCloud

from usarsim.readings import RangeScan3DReading

from . import scene
from .transcript import SCHEMA, SCHEMA_NAME

# Topics (docs/recording.md); a robot's own are /<robot>/<sensor>, /<robot>/pose, ...
WORLD_TOPIC = "/usarsim/world"
ROBOTS_TOPIC = "/usarsim/robots"
OBJECTS_TOPIC = "/usarsim/objects"
MAP_TOPIC = "/usarsim/map"  # the ground-truth occupancy map (usarsim.maps.truth), once
TF_TOPIC = "/tf"
LOG_TOPIC = "/usarsim/log"
RADIO_PREFIX = "/usarsim/radio/"

STATE_SCHEMA = {
    "title": "usarsim.RobotState",
    "type": "object",
    "properties": {
        "battery_s": {"type": "number", "description": "battery left, s"},
        "speed_m_s": {"type": "number", "description": "ground speed from the ground truth, m/s"},
        "x": {"type": "number"},
        "y": {"type": "number"},
        "z": {"type": "number"},
        "yaw": {"type": "number", "description": "USARSim yaw, rad"},
    },
}
STATUS_SCHEMA = {
    "title": "usarsim.RobotStatus",
    "type": "object",
    "properties": {
        "battery_s": {"type": "integer", "description": "STA's Battery, s"},
        "front_steer": {"type": "number"},
        "rear_steer": {"type": "number"},
        "light": {"type": "boolean"},
    },
}
LINK_SCHEMA = {
    "title": "usarsim.RadioLink",
    "type": "object",
    "properties": {
        "signal_dbm": {"type": "number"},
        "distance_m": {"type": "number"},
        "walls": {"type": "integer"},
        "holds": {"type": "boolean"},
    },
}

TRAFFIC_SCHEMA = {
    "title": "usarsim.RadioTraffic",
    "type": "object",
    "description": "what the radio channel carried on each link (sender>receiver) since the start",
    "additionalProperties": {
        "type": "object",
        "properties": {
            "delivered": {"type": "integer"},
            "delivered_bytes": {"type": "integer"},
            "dropped_range": {"type": "integer"},
            "dropped_loss": {"type": "integer"},
            "dropped_capacity": {"type": "integer"},
            "dropped_bytes": {"type": "integer"},
            "mean_delay_s": {"type": "number"},
        },
    },
}
TRAFFIC_TOPIC = "/usarsim/radio/traffic"
RELAYS_TOPIC = "/usarsim/relays"

LEVELS = ((logging.ERROR, LogLevel.Error), (logging.WARNING, LogLevel.Warning), (logging.INFO, LogLevel.Info))


def log_level(levelno: int) -> LogLevel:
    if levelno >= logging.CRITICAL:
        return LogLevel.Fatal
    for at, lv in LEVELS:
        if levelno >= at:
            return lv
    return LogLevel.Debug


def json_channel(schema: dict) -> Callable[[str, foxglove.Context], object]:
    return lambda topic, ctx: foxglove.Channel(
        topic,
        schema=foxglove.Schema(name=schema["title"], encoding="jsonschema", data=json.dumps(schema).encode()),
        message_encoding="json",
        context=ctx,
    )


def typed(cls) -> Callable[[str, foxglove.Context], object]:
    return lambda topic, ctx: cls(topic, context=ctx)


TRANSCRIPT = json_channel(SCHEMA)
assert SCHEMA["title"] == SCHEMA_NAME
# the makers of each kind of channel, made once
SCENE = typed(fch.SceneUpdateChannel)
GRID = typed(fch.GridChannel)
LOG = typed(fch.LogChannel)
LASER = typed(fch.LaserScanChannel)
CLOUD = typed(fch.PointCloudChannel)
POSE = typed(fch.PoseInFrameChannel)
TF = typed(fch.FrameTransformsChannel)
IMAGE = typed(fch.CompressedImageChannel)
STATE = json_channel(STATE_SCHEMA)
STATUS = json_channel(STATUS_SCHEMA)
LINK = json_channel(LINK_SCHEMA)
TRAFFIC = json_channel(TRAFFIC_SCHEMA)


_XYZ = [
    PackedElementField(name="x", offset=0, type=PackedElementFieldNumericType.Float32),
    PackedElementField(name="y", offset=4, type=PackedElementFieldNumericType.Float32),
    PackedElementField(name="z", offset=8, type=PackedElementFieldNumericType.Float32),
]


def point_cloud(robot: str, v: RangeScan3DReading, t: float) -> PointCloud:
    """A 3-D sweep as points in the scanner's frame (Foxglove's axes): rows from the top, each
    from the right (the order of the SEN lines, usarsim.sensors.scanner.RangeScanner3D)."""
    vres, hres = v.resolution_rad
    vfov, hfov = v.fov_rad
    rows = v.frames or (max(1, int(round(vfov / vres)) + 1) if vres > 0 else 1)
    r = np.asarray(v.ranges_m, dtype=float)
    cols = max(1, len(r) // rows)
    k = np.arange(len(r))
    pitch = vfov / 2.0 - vres * (k // cols)
    yaw = hfov / 2.0 - hres * (k % cols)  # USARSim yaw: to the right
    c = np.cos(pitch)
    xyz = np.column_stack((r * c * np.cos(yaw), -r * c * np.sin(yaw), r * np.sin(pitch))).astype("<f4")
    return PointCloud(
        timestamp=scene.timestamp(t), frame_id=f"{robot}/{v.name}", point_stride=12, fields=_XYZ, data=xyz.tobytes()
    )


# the ground-truth map of a recording: 5 cm cells, coarser (twice, four times...) for a world
# so large that it would have more than MAP_MAX_CELLS of them
MAP_MAX_CELLS = 4_000_000


def ground_truth_grid(world, t: float) -> object:
    """The world's ground-truth occupancy map (usarsim.maps.truth; its variant applied) as a
    foxglove Grid in the world frame, one signed byte a cell: 0 free, 100 occupied, -1 unknown."""
    from foxglove.messages import Grid, Pose, Quaternion, Vector2, Vector3

    from usarsim.maps.truth import DEFAULT_RESOLUTION_M, ground_truth_map

    res = DEFAULT_RESOLUTION_M
    sx, sy = world.floor.size
    while (sx / res) * (sy / res) > MAP_MAX_CELLS:
        res *= 2.0
    g = ground_truth_map(world, resolution=res, variant=world.variant).grid
    rows, cols = g.shape
    return Grid(
        timestamp=scene.timestamp(t),
        frame_id=scene.WORLD_FRAME,
        # the map frame is the recording's world frame (x north, y west): the grid's corner at
        # its origin, a millimetre above the floor
        pose=Pose(position=Vector3(x=g.origin[0], y=g.origin[1], z=0.001), orientation=Quaternion(x=0, y=0, z=0, w=1)),
        column_count=cols,
        cell_size=Vector2(x=g.resolution, y=g.resolution),
        row_stride=cols,
        cell_stride=1,
        fields=[PackedElementField(name="occupancy", offset=0, type=PackedElementFieldNumericType.Int8)],
        data=g.data.astype(np.int8).tobytes(),
    )
