"""Recording a run (usarsim serve --record), reading it back with the mcap reader, replaying
it (usarsim replay --check) and watching it live over Foxglove's WebSocket protocol."""

from __future__ import annotations

import asyncio
import json
import math
import os
import shutil
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.writer import Writer
from mcap_protobuf.decoder import DecoderFactory

from usarsim.cli import FOXGLOVE_PORT
from usarsim.client import launch
from usarsim.protocol import messages as M
from usarsim.server.recording.transcript import TOPIC, decode_chunk, encode_chunk, split_lines

ENV = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}


def usarsim(*args: str, timeout: float = 180) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "usarsim", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=ENV,
        stdin=subprocess.DEVNULL,
    )


def read_all(path: Path) -> tuple[dict, dict[str, list]]:
    """(metadata, topic -> [(schema name, log time, decoded message)]) of a recording; protobuf
    messages decoded with the schemas the file carries, JSON ones parsed."""
    decoders = DecoderFactory()
    out: dict[str, list] = defaultdict(list)
    with path.open("rb") as f:
        reader = make_reader(f)
        meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        f.seek(0)
        reader = make_reader(f)
        for schema, channel, msg in reader.iter_messages():
            if channel.message_encoding == "protobuf":
                value = decoders.decoder_for("protobuf", schema)(msg.data)
            else:
                assert channel.message_encoding == "json", channel
                value = json.loads(msg.data)
            out[channel.topic].append((schema.name, msg.log_time, value))
    return meta, out


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A lock-step session of two robots (a P2AT and a Kurt3D with its 3-D scanner) over the
    wireless model, recorded; with what the client saw at the end."""
    path = tmp_path_factory.mktemp("rec") / "run.mcap"
    seen = {}
    with launch(world="DM-USAR_yellow", seed=3, wireless=True, record=path) as srv:
        with srv.connect() as world:
            r1 = world.spawn("P2AT", name="R1", start="PlayerStart1")
            r2 = world.spawn("Kurt3D", name="K1", start="PlayerStart2")
            r1.send("DRIVE {Left garbage}")  # a warning in the server's log
            for k in range(20):
                r1.drive(left=1.5, right=2.0 if k < 10 else 1.0)
                r2.drive(left=1.0, right=1.0)
                world.step(0.1)
            seen["time"] = world.time
            seen["scan"] = r1.scan("Scanner1")
            seen["truth"] = {o.name: o for o in world.truth()}
    assert path.is_file() and path.stat().st_size > 10_000
    return path, seen


def test_every_channel_decodes_and_agrees_with_the_run(recorded):
    path, seen = recorded
    meta, topics = read_all(path)
    info = meta["usarsim"]
    assert info["world"] == "DM-USAR_yellow" and info["seed"] == "3" and info["clock"] == "lockstep"
    assert json.loads(info["options"])["wireless"] is True
    expected = {
        "/usarsim/transcript": "usarsim.TranscriptChunk",
        "/usarsim/world": "foxglove.SceneUpdate",
        "/usarsim/robots": "foxglove.SceneUpdate",
        "/usarsim/objects": "foxglove.SceneUpdate",
        "/tf": "foxglove.FrameTransforms",
        "/usarsim/log": "foxglove.Log",
        "/R1/Scanner1": "foxglove.LaserScan",
        "/R1/odometry": "foxglove.PoseInFrame",
        "/R1/pose": "foxglove.PoseInFrame",
        "/R1/state": "usarsim.RobotState",
        "/R1/status": "usarsim.RobotStatus",
        "/K1/pose": "foxglove.PoseInFrame",
        "/usarsim/radio/k1-r1": "usarsim.RadioLink",
    }
    scanners3d = [t for t in topics if t.startswith("/K1/") and topics[t][0][0] == "foxglove.PointCloud"]
    assert scanners3d, sorted(topics)
    for topic, schema in expected.items():
        assert topic in topics, (topic, sorted(topics))
        assert topics[topic][0][0] == schema, topic
    for topic, msgs in topics.items():  # every message of every channel decodes
        assert msgs, topic

    # the laser: the last LaserScan holds the ranges of the last SEN line the client got
    scan = seen["scan"]
    last = topics["/R1/Scanner1"][-1][2]
    assert last.frame_id == "R1/Scanner1"
    assert len(last.ranges) == len(scan.ranges) == 181
    assert max(abs(a - b) for a, b in zip(last.ranges, scan.ranges, strict=True)) < 1e-9
    # the beams' directions as the client library reads them (rightmost first, about -90 degrees)
    assert last.start_angle == pytest.approx(scan.angles[0]) and last.end_angle == pytest.approx(scan.angles[-1])
    assert last.start_angle == pytest.approx(-math.pi / 2, abs=0.01)
    # ... and every LaserScan is a SEN line of the transcript, to the digit
    sen = [
        line
        for _, line in _server_lines(path, "control")
        if line.startswith("SEN") and "{Name Scanner1}" in line and "RangeScanner}" in line
    ]
    assert len(sen) >= len(topics["/R1/Scanner1"]) > 5
    first = M.parse_message(sen[0])
    assert [round(r, 4) for r in topics["/R1/Scanner1"][0][2].ranges] == [round(r, 4) for r in first.reading.ranges_m]

    # the pose: the last ground-truth pose is where the truth service said the robot was
    t_end = seen["time"]
    pose_t, pose = max(((lt, m) for _, lt, m in topics["/R1/pose"]), key=lambda x: x[0])
    assert pose_t == round(t_end * 1e9)
    truth = seen["truth"]["R1"]
    p = pose.pose.position
    assert (p.x, -p.y, -p.z) == pytest.approx(truth.location, abs=2e-3)  # Foxglove's frame: Y left, Z up
    q = pose.pose.orientation
    yaw = -math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))  # USARSim yaw: clockwise
    assert math.remainder(yaw - truth.rotation[2], math.tau) == pytest.approx(0.0, abs=2e-3)
    # the transform tree: world -> R1 at the same pose, R1 -> its laser at its mount
    tfs = [tf for _, lt, m in topics["/tf"] if lt == pose_t for tf in m.transforms]
    r1 = next(tf for tf in tfs if tf.child_frame_id == "R1")
    assert r1.parent_frame_id == "world" and r1.translation.x == pytest.approx(p.x)
    mounts = {tf.child_frame_id: tf for _, _, m in topics["/tf"] for tf in m.transforms if tf.parent_frame_id == "R1"}
    assert "R1/Scanner1" in mounts and mounts["R1/Scanner1"].translation.x > 0.05  # in front of the chassis origin

    # the robot drove forward and turned: speed and battery are plottable, falling battery
    states = [m for _, _, m in topics["/R1/state"]]
    assert max(s["speed_m_s"] for s in states) > 0.1
    assert states[-1]["battery_s"] < states[0]["battery_s"]
    # the radio link between the two robots, a plottable signal strength
    link = topics["/usarsim/radio/k1-r1"][-1][2]
    assert link["signal_dbm"] < 0 and link["distance_m"] > 0.5 and isinstance(link["holds"], bool)
    # the world's static geometry: floor, walls, victims
    world = topics["/usarsim/world"][0][2]
    ids = {e.id for e in world.entities}
    assert {"floor", "static", "victims"} <= ids
    assert len(next(e for e in world.entities if e.id == "static").cubes) > 20
    # the server's log: the garbage DRIVE was logged
    assert any("malformed" in m.message for _, _, m in topics["/usarsim/log"])
    # the 3-D scanner: points in front of the robot, as many as its ranges
    cloud = topics[scanners3d[0]][-1][2]
    assert cloud.point_stride == 12 and len(cloud.data) // 12 > 100


def _server_lines(path: Path, port: str) -> list[tuple[int, str]]:
    """(connection, line) of every server line on ``port``, in order."""
    chunks = []
    with path.open("rb") as f:
        for _, _, msg in make_reader(f).iter_messages(topics=[TOPIC]):
            chunks.append(decode_chunk(msg.data))
    by_conn = defaultdict(list)
    for c in sorted(chunks, key=lambda c: c.seq):
        if c.port == port and c.kind == "out":
            by_conn[c.conn].append(c)
    return [(cid, line) for cid, outs in by_conn.items() for _, line in split_lines(outs)]


def test_the_transcript_holds_every_line_in_the_order_the_server_saw_it(recorded):
    path, _ = recorded
    chunks = []
    with path.open("rb") as f:
        for _, _, msg in make_reader(f).iter_messages(topics=[TOPIC], log_time_order=False):
            chunks.append(decode_chunk(msg.data))
    assert [c.seq for c in chunks] == list(range(len(chunks)))  # none lost, in order
    kinds = {c.kind for c in chunks}
    assert kinds == {"open", "in", "out", "close"}
    ports = {c.port for c in chunks}
    assert {"control", "truth"} <= ports
    first_in = next(c for c in chunks if c.kind == "in" and c.text.startswith("INIT"))
    assert first_in.text.startswith("INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}\r\n")
    nfo = next(c for c in chunks if c.kind == "out" and c.port == "control")
    assert nfo.text == "NFO {Gametype BotDeathMatch} {Level DM-USAR_yellow} {TimeLimit 0}\r\n"
    steps = [c for c in chunks if c.kind == "in" and c.text.startswith("STEP")]
    assert len(steps) == 20 and steps[-1].sim_time == pytest.approx(1.9, abs=1e-9)


def test_replay_check_passes_on_the_recording(recorded):
    path, _ = recorded
    out = usarsim("replay", str(path), "--check")
    assert out.returncode == 0, out.stdout + out.stderr
    assert "identical: all" in out.stdout
    n = int(out.stdout.split("identical: all ")[1].split()[0])
    assert n > 200  # every server line compared
    assert "not replayed" not in out.stdout or "image" not in out.stdout


def _altered(src: Path, dst: Path, change) -> None:
    """A copy of a recording with one transcript chunk changed by ``change(chunk) -> chunk|None``
    (None: keep it), written with the mcap writer."""
    with src.open("rb") as f, dst.open("wb") as g:
        reader = make_reader(f)
        summary = reader.get_summary()
        w = Writer(g)
        w.start(profile="", library="test")
        schema_ids = {sid: w.register_schema(s.name, s.encoding, s.data) for sid, s in summary.schemas.items()}
        channel_ids = {
            cid: w.register_channel(c.topic, c.message_encoding, schema_ids.get(c.schema_id, 0), dict(c.metadata))
            for cid, c in summary.channels.items()
        }
        f.seek(0)
        for m in make_reader(f).iter_metadata():
            w.add_metadata(m.name, dict(m.metadata))
        f.seek(0)
        done = False
        for _, channel, msg in make_reader(f).iter_messages(log_time_order=False):
            data = msg.data
            if channel.topic == TOPIC and not done:
                new = change(decode_chunk(data))
                if new is not None:
                    data, done = encode_chunk(new), True
            w.add_message(channel_ids[msg.channel_id], msg.log_time, data, msg.publish_time, msg.sequence)
        w.finish()
    assert done


def test_replay_check_names_the_first_line_that_differs(recorded, tmp_path):
    path, _ = recorded
    bad = tmp_path / "altered.mcap"
    target = {}

    def change(c):
        # the battery of the R1 connection's STA at 1.0 s, one second less
        if (
            c.kind == "out"
            and c.port == "control"
            and c.text.startswith("STA")
            and c.sim_time >= 1.0
            and "{Battery " in c.text
        ):
            before, rest = c.text.split("{Battery ", 1)
            value, after = rest.split("}", 1)
            target.update(line=c.text.rstrip("\r\n").split("\r\n")[0], conn=c.conn, t=c.sim_time)
            return type(c)(
                c.seq,
                c.conn,
                c.port,
                c.peer,
                c.kind,
                c.sim_time,
                c.wall_time,
                f"{before}{{Battery {int(value) - 1}}}{after}",
                c.size,
            )
        return None

    _altered(path, bad, change)
    out = usarsim("replay", str(bad), "--check")
    assert out.returncode == 1, out.stdout + out.stderr
    text = out.stdout
    assert f"first difference: connection {target['conn']} (control" in text
    assert "recorded: STA" in text and "replayed: STA" in text
    rec = text.split("recorded: ")[1].splitlines()[0]
    rep = text.split("replayed: ")[1].splitlines()[0]
    assert rec != rep and rep == target["line"]
    assert f"at t={target['t']:.3f} s" in text or "at t=" in text


def test_a_real_time_recording_replays_and_says_how_far_it_differs(tmp_path):
    path = tmp_path / "rt.mcap"
    with launch(world="DM-USAR_yellow", lockstep=False, speed=2.0, record=path) as srv:
        with srv.connect() as world:
            r = world.spawn("P2AT", name="R1")
            r.drive(left=2.0, right=2.0)
            time.sleep(1.0)
    out = usarsim("replay", str(path))
    assert out.returncode == 0, out.stdout + out.stderr
    assert "speed 2x" in out.stdout and "replayed 2 connections" in out.stdout
    assert "server lines compared are identical" in out.stdout or "identical: all" in out.stdout


def test_replay_refuses_what_is_not_a_recording(tmp_path):
    """One line on stderr, exit 1 (tests/integration/test_recording_crash.py: damaged files)."""
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not an mcap file at all")
    out = usarsim("replay", str(junk))
    assert out.returncode == 1 and out.stderr.strip() == (
        f"usarsim replay: {junk} is not an MCAP file (it does not start with MCAP's magic bytes); give a recording "
        "made with usarsim serve --record"
    )
    out = usarsim("replay", str(tmp_path / "missing.mcap"))
    assert out.returncode == 1 and out.stderr.strip().endswith(
        "missing.mcap: no such file; give a recording made with usarsim serve --record"
    )
    # an MCAP file that usarsim did not write: no run information
    other = tmp_path / "other.mcap"
    with other.open("wb") as f:
        w = Writer(f)
        w.start(profile="", library="test")
        w.add_message(w.register_channel("/x", "json", 0), 0, b"{}", 0)
        w.finish()
    out = usarsim("replay", str(other))
    assert out.returncode == 1 and "no 'usarsim' metadata" in out.stderr and "Traceback" not in out.stderr


def test_record_to_a_folder_that_does_not_exist_is_a_clear_error(tmp_path):
    out = usarsim(
        "serve",
        "--no-web",
        "--no-image",
        "--no-wireless",
        "--port",
        "0",
        "--truth-port",
        "0",
        "--record",
        str(tmp_path / "nowhere" / "run.mcap"),
        timeout=60,
    )
    assert out.returncode == 1
    assert "the recording" in out.stderr and "--record" in out.stderr


def test_foxglove_viewer_subscribes_to_a_laser_and_receives_it():
    websockets = pytest.importorskip("websockets")
    from foxglove.messages import LaserScan  # noqa: F401  (the schema the message is decoded with)
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    async def subscribe(ws, channel_id: int) -> None:
        await ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 7, "channelId": channel_id}]}))

    async def view(port: int) -> tuple[dict, bytes]:
        async with websockets.connect(
            f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"]
        ) as ws:
            channels = {}
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline:
                m = await asyncio.wait_for(ws.recv(), 30)
                if isinstance(m, str):
                    d = json.loads(m)
                    if d.get("op") == "advertise":
                        for c in d["channels"]:
                            channels[c["topic"]] = c
                        if "/R1/Scanner1" in channels and not any(k == "sub" for k in channels):
                            channels["sub"] = True
                            await subscribe(ws, channels["/R1/Scanner1"]["id"])
                    elif d.get("op") == "status" and "Unknown channel ID" in d.get("message", ""):
                        # foxglove-sdk 0.30 sends a channel's advertisement a moment before it
                        # takes subscriptions to it (about one subscription in 30 asked at once,
                        # beside another test), and refuses those asked for earlier: ask again
                        await asyncio.sleep(0.05)
                        await subscribe(ws, channels["/R1/Scanner1"]["id"])
                elif m[0] == 1 and int.from_bytes(m[1:5], "little") == 7:
                    return channels["/R1/Scanner1"], m[13:]
        raise AssertionError("no laser message within 30 s")

    with launch(world="DM-USAR_yellow", lockstep=False, speed=1.0, foxglove=True) as srv:
        assert srv.ports.get("foxglove"), srv.ports
        with srv.connect() as world:
            world.spawn("P2AT", name="R1")
            channel, payload = asyncio.run(view(srv.ports["foxglove"]))
    assert channel["encoding"] == "protobuf" and channel["schemaName"] == "foxglove.LaserScan"
    fds = descriptor_pb2.FileDescriptorSet.FromString(__import__("base64").b64decode(channel["schema"]))
    pool = descriptor_pool.DescriptorPool()
    for fd in fds.file:
        pool.Add(fd)
    cls = message_factory.GetMessageClass(pool.FindMessageTypeByName("foxglove.LaserScan"))
    scan = cls.FromString(payload)
    assert scan.frame_id == "R1/Scanner1" and len(scan.ranges) == 181
    assert 0.1 < min(scan.ranges) < 20.0


def test_launch_records_for_a_python_client(tmp_path):
    """usarsim.launch(record=...) writes the file when the server stops."""
    path = tmp_path / "client.mcap"
    with launch(record=path) as srv, srv.connect() as world:
        world.spawn("P2AT", name="R1")
        world.step(0.5)
    assert shutil.which("usarsim") is None or True
    meta, topics = read_all(path)
    assert "/R1/pose" in topics and len(topics["/R1/pose"]) == 5


def test_camera_pictures_are_recorded_when_asked(tmp_path):
    """--record-cameras 5: each robot camera's picture as a JPEG CompressedImage, five a
    simulated second, showing the arena (not a black frame)."""
    import io

    from PIL import Image

    path = tmp_path / "cams.mcap"
    with (
        launch(record=path, extra_args=("--record-cameras", "5", "--record-camera-size", "160x120")) as srv,
        srv.connect() as world,
    ):
        world.spawn("P2AT", name="R1")
        for _ in range(10):
            world.step(0.1)
            # the render thread draws beside the lock-step client: time for a picture even on a
            # machine busy with other tests (with 0.05 s a run under the suite's load saw one picture)
            time.sleep(0.2)
    _, topics = read_all(path)
    pictures = topics["/R1/Camera"]
    assert pictures[0][0] == "foxglove.CompressedImage"
    assert 2 <= len(pictures) <= 6
    msg = pictures[-1][2]
    assert msg.format == "jpeg" and msg.frame_id == "R1/Camera"
    img = Image.open(io.BytesIO(msg.data))
    assert img.size == (160, 120)
    import numpy as np

    pixels = np.asarray(img.convert("L"))
    assert int(pixels.max()) - int(pixels.min()) > 40  # walls, floor and sky: not one flat colour
    # the camera's mount is in the transform tree
    assert any(tf.child_frame_id == "R1/Camera" for _, _, m in topics["/tf"] for tf in m.transforms)


@pytest.mark.alone  # wall-clock pacing: run by itself (scripts/test.sh)
def test_a_viewer_that_does_not_read_never_holds_the_simulation_back():
    """A Foxglove viewer subscribed to every channel that stops reading: the server keeps at
    most its backlog for it and drops the oldest; the simulated clock keeps real time."""
    websockets = pytest.importorskip("websockets")

    async def stalled_viewer(port: int, clock, seconds: float) -> tuple[float, float]:
        async with websockets.connect(
            f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"], max_queue=4, close_timeout=1
        ) as ws:
            channels = {}
            deadline = time.monotonic() + 2.5
            while time.monotonic() < deadline:  # subscribe to whatever is advertised meanwhile
                try:
                    m = await asyncio.wait_for(ws.recv(), 0.5)
                except TimeoutError:
                    continue
                if isinstance(m, str) and json.loads(m).get("op") == "advertise":
                    new = [c for c in json.loads(m)["channels"] if c["id"] not in channels]
                    for c in new:
                        channels[c["id"]] = c
                    await ws.send(
                        json.dumps(
                            {"op": "subscribe", "subscriptions": [{"id": c["id"], "channelId": c["id"]} for c in new]}
                        )
                    )
            assert len(channels) >= 5
            t0, w0 = clock(), time.monotonic()
            await asyncio.sleep(seconds)  # reading nothing: its socket fills, then the server's backlog
            return clock() - t0, time.monotonic() - w0

    with launch(world="DM-USAR_yellow", lockstep=False, speed=1.0, foxglove=True) as srv, srv.connect() as world:
        robot = world.spawn("P2AT", name="R1")
        robot.drive(left=2.0, right=2.0)
        sim_s, wall_s = asyncio.run(stalled_viewer(srv.ports["foxglove"], lambda: world.truth("P2AT")[0].time, 3.0))
    assert sim_s == pytest.approx(wall_s, rel=0.15), (sim_s, wall_s)


def _abort(ws) -> None:
    """Drop a WebSocket connection the way a killed viewer does: no close frame, a TCP reset."""
    import socket
    import struct

    sock = ws.transport.get_extra_info("socket")
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    ws.transport.abort()


def test_a_viewer_that_vanishes_is_news_not_an_error_and_an_old_viewer_is_told_why():
    """A subscribed viewer whose connection is reset (a killed app) is logged at INFO, never
    ERROR; a viewer that offers only foxglove.websocket.v1 is refused (foxglove-sdk 0.30 speaks
    foxglove.sdk.v1) with a WARNING that says so."""
    websockets = pytest.importorskip("websockets")

    async def viewers(port: int) -> int:
        try:
            async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.websocket.v1"]):
                raise AssertionError("foxglove.websocket.v1 was accepted: docs/recording.md is out of date")
        except websockets.InvalidStatus as exc:
            refused = exc.response.status_code
        ws = await websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"])
        deadline = time.monotonic() + 20
        subscribed = 0
        while time.monotonic() < deadline and subscribed < 3:
            m = await asyncio.wait_for(ws.recv(), 20)
            if isinstance(m, str) and json.loads(m).get("op") == "advertise":
                chans = json.loads(m)["channels"]
                await ws.send(
                    json.dumps(
                        {"op": "subscribe", "subscriptions": [{"id": c["id"], "channelId": c["id"]} for c in chans]}
                    )
                )
                subscribed += len(chans)
        await asyncio.sleep(0.5)  # messages flow to it
        _abort(ws)
        await asyncio.sleep(1.0)  # the server notices
        return refused

    with launch(world="DM-USAR_yellow", lockstep=False, speed=1.0, foxglove=True, extra_args=("-v",)) as srv:
        with srv.connect() as world:
            world.spawn("P2AT", name="R1")
            status = asyncio.run(viewers(srv.ports["foxglove"]))
            world.truth()  # the server still serves
        srv.close(keep_stderr=True)
        log = srv.stderr_tail(200_000)
    assert status == 400
    assert "Foxglove viewer gone without closing its connection" in log, log[-3000:]
    assert " INFO foxglove.websocket.connected_client.poller: Foxglove viewer gone" in log
    errors = [line for line in log.splitlines() if " ERROR " in line]
    assert errors == [], errors
    refused = [line for line in log.splitlines() if "refused the connection" in line]
    assert len(refused) == 1 and " WARNING foxglove.websocket.server: Foxglove: refused" in refused[0], log[-3000:]
    assert "foxglove.sdk.v1" in refused[0] and "foxglove.websocket.v1" in refused[0]


def test_without_v_a_vanished_viewer_is_not_logged_at_all():
    websockets = pytest.importorskip("websockets")

    async def vanish(port: int) -> None:
        ws = await websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"])
        m = await asyncio.wait_for(ws.recv(), 20)  # serverInfo
        assert json.loads(m)["op"] == "serverInfo"
        _abort(ws)
        await asyncio.sleep(1.0)

    with launch(world="DM-USAR_yellow", lockstep=False, speed=1.0, foxglove=True) as srv:
        asyncio.run(vanish(srv.ports["foxglove"]))
        srv.close(keep_stderr=True)
        log = srv.stderr_tail(200_000)
    assert "ERROR" not in log and "Foxglove viewer gone" not in log, log


def test_foxglove_port_without_a_number_moves_with_the_port_offset():
    from usarsim.cli import build_parser, resolve_foxglove_port

    def port(*argv: str) -> int | None:
        args = build_parser().parse_args(["serve", *argv])
        return resolve_foxglove_port(args.foxglove, args.port_offset)

    assert port() is None and port("--port-offset", "100") is None  # not asked for
    assert port("--foxglove") == FOXGLOVE_PORT == 8765
    assert port("--foxglove", "--port-offset", "100") == 8865 == port("--port-offset", "100", "--foxglove")
    assert port("--port-offset", "100", "--foxglove", "9000") == 9000  # given explicitly: kept
    assert port("--port-offset", "100", "--foxglove", "0") == 0  # a free port
    helped = " ".join(usarsim("serve", "--help").stdout.split())
    assert "ComServerInterface 7435, Foxglove 8765 with --foxglove)" in helped  # --port-offset's help
    assert "(default port 8765 plus --port-offset; 0 picks a free port)" in helped  # --foxglove's


def test_a_server_with_a_port_offset_serves_foxglove_there():
    import socket

    for offset in range(1101, 15000, 997):  # one whose Foxglove port is free here
        with socket.socket() as sock:
            try:
                sock.bind(("127.0.0.1", FOXGLOVE_PORT + offset))
            except OSError:
                continue
        break
    else:
        pytest.skip("no free port for the test")
    with launch(world="DM-USAR_yellow", extra_args=("--port-offset", str(offset), "--foxglove")) as srv:
        deadline = time.monotonic() + 10
        while "foxglove" not in srv.ports and time.monotonic() < deadline:
            time.sleep(0.1)
        assert srv.ports.get("foxglove") == FOXGLOVE_PORT + offset, srv.ports
        assert srv.ports["control"] != 3000 + offset  # given explicitly (0): no offset


def test_a_recording_with_spread_report_phases_replays_identically(tmp_path):
    path = tmp_path / "spread.mcap"
    with launch(world="DM-USAR_yellow", seed=5, record=path, extra_args=("--report-phases", "spread")) as srv:
        with srv.connect() as world:
            r1 = world.spawn("P2AT", name="R1", start="PlayerStart1")
            r2 = world.spawn("P2AT", name="R2", start="PlayerStart2")
            for _ in range(10):
                r1.drive(left=1.0, right=1.0)
                r2.drive(left=1.0, right=-1.0)
                world.step(0.1)
    meta, _ = read_all(path)
    assert json.loads(meta["usarsim"]["options"])["report_phases"] == "spread"
    out = usarsim("replay", str(path), "--check")
    assert out.returncode == 0, out.stdout + out.stderr  # replayed with the recorded phases
    assert "identical: all" in out.stdout
