"""The console's server side without a browser: the JSON it serves, the WebSocket bridge to
the control port (every line relayed both ways; closing it removes the robot), pictures
relayed from the image server for a binding made over the page's own control connection,
the chase view, and the ``serve`` options that start and stop the console."""

from __future__ import annotations

import asyncio
import json
import re
import subprocess
import sys
import urllib.request

import pytest

from helpers import DEFAULT_TIMEOUT, wait_for
from webtools import gl_problem, truth

aiohttp = pytest.importorskip("aiohttp")
NEEDS_GL = pytest.mark.skipif(bool(gl_problem()), reason="pictures need an OpenGL context (MUJOCO_GL=egl)")


def get_json(srv, path: str):
    with urllib.request.urlopen(f"http://127.0.0.1:{srv.app.web.port}{path}", timeout=DEFAULT_TIMEOUT) as r:
        assert r.headers["Content-Type"].startswith("application/json")
        return json.loads(r.read())


@pytest.fixture
def live(server_factory):
    """DM-USAR_yellow in real time (status and sensor lines flow without STEP)."""
    return server_factory(lockstep=False, speed=1.0)


def run(coro):
    return asyncio.run(asyncio.wait_for(coro, 60))


async def lines_until(ws, predicate, seen: list[str]) -> str:
    while True:
        msg = await ws.receive(timeout=DEFAULT_TIMEOUT)
        assert msg.type == aiohttp.WSMsgType.TEXT, msg
        seen.append(msg.data)
        if predicate(msg.data):
            return msg.data


def test_the_page_and_its_files_are_served(live):
    base = f"http://127.0.0.1:{live.app.web.port}"
    with urllib.request.urlopen(base + "/", timeout=DEFAULT_TIMEOUT) as r:
        page = r.read().decode()
        assert r.headers["Content-Type"].startswith("text/html")
    for src in re.findall(r'(?:src|href)="(/static/[^"]+)"', page) + ["/static/robot.js", "/favicon.ico"]:
        with urllib.request.urlopen(base + src, timeout=DEFAULT_TIMEOUT) as r:
            assert r.status == 200 and r.read(), src


def test_the_world_and_the_classes_as_json(live, yellow_world):
    info = get_json(live, "/api/info")
    assert info["world"] == "DM-USAR_yellow"
    assert info["ports"] == {
        "control": live.port,
        "truth": live.app.truth.port,
        "image": live.app.image.port,
        "web": live.app.web.port,
    }
    world = get_json(live, "/api/world")
    assert len(world["objects"]) == len(yellow_world.objects)
    assert [p["name"] for p in world["start_poses"]] == [p.name for p in yellow_world.start_poses]
    wall = next(o for o in world["objects"] if not o["movable"] and o["shape"] == "box")
    assert len(wall["poly"]) == 4 and wall["top"] > 0  # a box seen from above: a rectangle above the floor
    x0, y0, x1, y1 = world["bounds"]
    assert x0 < -9.5 < x1 and y0 < 0 < y1  # the start poses lie inside
    classes = {c["name"]: c for c in get_json(live, "/api/classes")}
    assert classes["P2AT"]["drive"] == "skid" and classes["P2AT"]["cameras"] == ["Camera"]
    assert classes["Hummer"]["drive"] == "ackermann" and classes["Hummer"]["max_front_steer"] > 0
    assert {"CameraPanTilt"} <= {p["name"] for p in classes["P2AT"]["packages"]}
    objects = get_json(live, "/api/truth")["objects"]
    assert {"Victim", "RFIDTag"} <= {o["class"] for o in objects}


def test_the_control_bridge_relays_every_line_and_closing_it_removes_the_robot(live):
    async def scenario():
        async with aiohttp.ClientSession() as http:
            async with http.ws_connect(f"http://127.0.0.1:{live.app.web.port}/ws/control?page=t1") as ws:
                seen: list[str] = []
                first = await lines_until(ws, lambda t: True, seen)
                assert first == "NFO {Gametype BotDeathMatch} {Level DM-USAR_yellow} {TimeLimit 0}"
                await ws.send_str("INIT {ClassName USARBot.P2AT} {Name Bridged} {Start PlayerStart1}\nGETSTARTPOSES")
                await lines_until(ws, lambda t: t.startswith("NFO {StartPoses 8}"), seen)
                await lines_until(ws, lambda t: t.startswith("SEN {Time") and "{Type Sonar}" in t, seen)
                await lines_until(ws, lambda t: t.startswith("STA {Type GroundVehicle}"), seen)
                assert [row["class"] for row in truth(live.app.truth.port, "Bridged")] == ["P2AT"]
                assert live.robot_count() == 1
        wait_for(lambda: live.robot_count() == 0, what="the robot to be removed with its connection")

    run(scenario())


@NEEDS_GL
def test_the_video_bridge_binds_over_the_page_connection_and_relays_jpeg_pictures(live):
    async def scenario():
        base = f"http://127.0.0.1:{live.app.web.port}"
        async with aiohttp.ClientSession() as http:
            async with (
                http.ws_connect(f"{base}/ws/control?page=t2") as ctl,
                http.ws_connect(f"{base}/ws/video?page=t2") as video,
            ):
                seen: list[str] = []
                await ctl.send_str("INIT {ClassName USARBot.P2AT} {Name Seen} {Start PlayerStart1}")
                await lines_until(ctl, lambda t: t.startswith("STA "), seen)
                pictures = {}
                for camera in ("Camera", "Chase"):
                    await video.send_str(json.dumps({"bind": "Seen", "camera": camera}))
                    answer = await video.receive_json(timeout=DEFAULT_TIMEOUT)
                    assert answer["bound"] == "Seen" and answer["camera"] == camera
                    assert answer["via"] == "control"  # SET {Type Camera} over the page's own connection
                    assert answer["line"].startswith(
                        f"SET {{Type Camera}} {{Robot Seen}} {{Name {camera}}} {{Client 127.0.0.1:"
                    )
                    await video.send_str("OK")
                    msg = await video.receive(timeout=30)
                    assert msg.type == aiohttp.WSMsgType.BINARY
                    assert msg.data[:2] == b"\xff\xd8"  # a JPEG file
                    pictures[camera] = msg.data
                assert pictures["Camera"] != pictures["Chase"]
                # a robot of another controller, and a page without a robot: bound directly, as a spectator
                outsider = live.connect()
                outsider.nfo()
                outsider.send("INIT {ClassName USARBot.P2DX} {Name Outsider} {Start PlayerStart2}")
                outsider.wait_line("STA ")
                async with http.ws_connect(f"{base}/ws/video?page=other") as spectator:
                    await spectator.send_str(json.dumps({"bind": "Outsider", "camera": "Camera"}))
                    assert (await spectator.receive_json(timeout=DEFAULT_TIMEOUT))["via"] == "direct"
                    await spectator.send_str("OK")
                    msg = await spectator.receive(timeout=30)
                    assert msg.type == aiohttp.WSMsgType.BINARY and msg.data[:2] == b"\xff\xd8"

    run(scenario())


@NEEDS_GL
def test_the_chase_view_looks_at_the_robot_from_behind_and_above(live):
    import io

    import numpy as np
    from PIL import Image

    from usarsim.sim.tiles import Tile

    robot = live.connect()
    robot.nfo()
    robot.send("INIT {ClassName USARBot.P2AT} {Name Chased} {Start PlayerStart1}")
    robot.wait_line("STA ")
    renderer = live.app.image.renderer

    def picture(camera):
        uid = live.on_sim(lambda sim: next(r.uid for r in sim.robots.values() if r.name == "Chased"))
        return renderer.render(320, 240, [Tile(uid, camera, 0, 0, 320, 240)]).result(30)

    chase = picture("Chase")
    assert chase.shape == (240, 320, 3) and chase.std() > 10
    # the red chassis in the lower middle of the picture
    patch = chase[120:220, 130:190].reshape(-1, 3).astype(float)
    red = (patch[:, 0] > 1.5 * patch[:, 1]) & (patch[:, 0] > 1.5 * patch[:, 2]) & (patch[:, 0] > 60)
    assert red.mean() > 0.2, patch.mean(axis=0)
    assert not np.array_equal(chase, picture("Camera"))
    Image.fromarray(chase).save(io.BytesIO(), "PNG")


def test_serve_prints_the_console_address_and_no_web_turns_it_off(tmp_path):
    def serve(*extra):
        proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "usarsim",
                "serve",
                "--port",
                "0",
                "--truth-port",
                "0",
                "--image-port",
                "0",
                "--no-wireless",
                *extra,
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            stdin=subprocess.DEVNULL,
            text=True,
        )
        return proc

    proc = serve("--web-port", "0")
    try:
        lines = []
        while not lines or not lines[-1].startswith("usarsim: operator console at "):
            line = proc.stdout.readline()
            assert line, f"serve ended early: {lines}"
            lines.append(line.strip())
        m = re.fullmatch(r"usarsim: web listening on 127\.0\.0\.1:(\d+)", lines[-2])
        assert m, lines
        assert lines[-1] == f"usarsim: operator console at http://127.0.0.1:{m.group(1)}/"
        with urllib.request.urlopen(f"http://127.0.0.1:{m.group(1)}/api/info", timeout=DEFAULT_TIMEOUT) as r:
            assert json.loads(r.read())["world"] == "DM-USAR_yellow"
    finally:
        proc.terminate()
        assert proc.wait(10) == 0
        proc.stdout.close()
    proc = serve("--no-web")
    try:
        first = proc.stdout.readline()
        assert first.startswith("usarsim: control listening on ")
    finally:
        proc.terminate()
        out = proc.stdout.read()
        proc.wait(10)
        proc.stdout.close()
    assert "web" not in out and "operator console" not in out
