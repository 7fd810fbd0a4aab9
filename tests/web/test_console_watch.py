"""The operator console and robots it does not drive: a robot that another client spawned on
the control port is watched read-only (its sensor tree, range view and messages, never its
controls), and the page says so when it leaves the world.  Also: the console fits a
1280 x 720 laptop screen, and the world view names every start pose beside its marker.
Screenshots of the console are saved in tests/artifacts/."""

from __future__ import annotations

import asyncio
import json
import threading
import time
from pathlib import Path

import pytest

from helpers import DEFAULT_TIMEOUT, wait_for
from webtools import truth

aiohttp = pytest.importorskip("aiohttp")

ARTIFACTS = Path(__file__).resolve().parent.parent / "artifacts"
LAPTOP = {"width": 1280, "height": 720}
START_POSES = [f"PlayerStart{i}" for i in range(1, 9)]  # DM-USAR_yellow's


def run(scenario, timeout: float = 60.0):
    """Run ``scenario()`` (a coroutine function) to its end in a thread of its own: the
    browser's driver keeps an event loop running in this one once a browser test ran."""
    box: dict = {}

    def target() -> None:
        try:
            box["result"] = asyncio.run(asyncio.wait_for(scenario(), timeout))
        except BaseException as exc:  # handed back to the test
            box["error"] = exc

    t = threading.Thread(target=target, name="watch-test-client")
    t.start()
    t.join(timeout + DEFAULT_TIMEOUT)
    assert not t.is_alive(), "the scenario did not end"
    if "error" in box:
        raise box["error"]
    return box.get("result")


def init_robot(server, name: str, start: str):
    """A controller of its own on the control port: a raw TCP client that spawned a P2AT."""
    c = server.connect()
    c.nfo()
    c.send(f"INIT {{ClassName USARBot.P2AT}} {{Name {name}}} {{Start {start}}}")
    c.wait_line("SEN ")
    return c


def kind(line: str) -> str:
    """STA, or a SEN line's sensor type, or the line's first word."""
    if line.startswith("SEN ") and "{Type " in line:
        return line.split("{Type ", 1)[1].split("}", 1)[0]
    return line.split(" ", 1)[0]


def test_the_watch_socket_relays_another_controllers_robot_and_nothing_back(console_server):
    srv = console_server
    c = init_robot(srv, "TcpWatched", "PlayerStart7")
    url = f"ws://127.0.0.1:{srv.app.web.port}/ws/watch?robot=TcpWatched"

    async def scenario():
        async with aiohttp.ClientSession() as http, http.ws_connect(url) as ws:
            first = json.loads((await ws.receive(timeout=DEFAULT_TIMEOUT)).data)
            assert first["watching"] == "TcpWatched" and first["class"] == "P2AT"
            assert first["controller"].startswith("127.0.0.1:")
            described = first["describe"]
            assert any(d.startswith("GEO {Type Sonar} {Name F1 Location ") for d in described), described
            assert any(
                d.startswith("CONF {Type RangeScanner} {Name Scanner1}") and "{MaxRange " in d for d in described
            ), described
            # what the simulation sends the robot's controller, line by line
            seen: list[str] = []
            while not {"STA", "Sonar", "RangeScanner", "GroundTruth"} <= {kind(s) for s in seen}:
                msg = await ws.receive(timeout=DEFAULT_TIMEOUT)
                assert msg.type == aiohttp.WSMsgType.TEXT, msg
                seen.append(msg.data)
            assert all(not s.endswith("\n") for s in seen)
            # read-only: what the page sends on this socket goes nowhere
            before = truth(srv.app.truth.port, "TcpWatched")[0]["location"]
            for line in (
                "DRIVE {Left 5} {Right 5}",
                "INIT {ClassName USARBot.P2AT} {Name Intruder}",
                "SET {Type Odometry} {Opcode RESET}",
            ):
                await ws.send_str(line)
            await asyncio.sleep(1.0)
            after = truth(srv.app.truth.port, "TcpWatched")[0]["location"]
            assert abs(after[0] - before[0]) < 0.05 and abs(after[1] - before[1]) < 0.05, (before, after)
            assert srv.connection_count() == 1 and srv.robot_count() == 1  # no connection opened for the page
            # and its controller got no answer to any of it
            answered = [ln.text for ln in c.sync() if ln.text.startswith(("RES", "ERROR"))]
            assert answered == []
            # the controller disconnects: the last message says the robot left, then the socket ends
            c.close()
            left = None
            while True:
                msg = await ws.receive(timeout=DEFAULT_TIMEOUT)
                if msg.type != aiohttp.WSMsgType.TEXT:
                    break
                if msg.data.startswith("{"):
                    left = json.loads(msg.data)
            assert left is not None and left["left"] == "TcpWatched" and left["time"] > 0 and left["reason"]
            assert msg.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED, aiohttp.WSMsgType.CLOSING)
            assert ws.close_code == 1000

    try:
        run(scenario)
    finally:
        c.close()


def test_watching_a_robot_nobody_drives_is_refused(console_server):
    async def scenario():
        url = f"ws://127.0.0.1:{console_server.app.web.port}/ws/watch?robot=NoSuchRobot"
        async with aiohttp.ClientSession() as http, http.ws_connect(url) as ws:
            msg = await ws.receive(timeout=DEFAULT_TIMEOUT)
            return json.loads(msg.data)

    answer = run(scenario, 30)
    assert answer == {"error": "no robot called NoSuchRobot in the world"}


def test_a_failing_output_watcher_does_not_stop_the_world(console_server):
    """The facade hands outputs to watchers on the simulation thread: one that raises is
    logged and removed, and the world goes on, its clients served."""
    calls = []

    def broken(outs):
        calls.append(len(outs))
        raise RuntimeError("a broken watcher")

    facade = console_server.app.facade
    with console_server.connect() as c:
        c.nfo()
        facade.add_output_watcher(broken)
        try:
            c.send("INIT {ClassName USARBot.P2AT} {Name WatchedByBroken} {Start PlayerStart3}")
            first = c.wait_line("SEN ")
            wait_for(lambda: calls, timeout=DEFAULT_TIMEOUT, interval=0.02, what="the watcher to be called")
            t0 = facade.time
            c.wait_line(lambda ln: ln.text.startswith("STA ") and ln is not first)
            wait_for(lambda: facade.time > t0 + 0.2, timeout=DEFAULT_TIMEOUT, interval=0.02, what="the clock to go on")
            assert len(calls) == 1  # dropped after its failure
        finally:
            facade.remove_output_watcher(broken)

        class Counter:
            n = 0

            def seen(self, outs) -> None:
                self.n += 1

        counter = Counter()
        facade.add_output_watcher(counter.seen)
        wait_for(lambda: counter.n > 2, timeout=DEFAULT_TIMEOUT, interval=0.02, what="a watcher to be called")
        facade.remove_output_watcher(counter.seen)  # another bound-method object for the same watcher
        n = counter.n
        time.sleep(0.3)
        assert counter.n == n
    wait_for(
        lambda: console_server.robot_count() == 0,
        timeout=DEFAULT_TIMEOUT,
        interval=0.05,
        what="the robot to be removed",
    )


def boxes_within(page, selectors: list[str], width: int, height: int) -> dict[str, dict]:
    """Each selector's bounding box, checked to lie within the viewport and to be what is
    seen at its centre (not hidden behind or clipped by another element)."""
    out = {}
    for sel in selectors:
        box = page.locator(sel).bounding_box()
        assert box is not None, f"{sel} is not displayed"
        assert box["x"] >= 0 and box["y"] >= 0, (sel, box)
        assert box["x"] + box["width"] <= width and box["y"] + box["height"] <= height, (sel, box)
        seen = page.evaluate(
            "([sel, x, y]) => { const e = document.querySelector(sel);"
            " const at = document.elementFromPoint(x, y); return !!at && (at === e || e.contains(at)); }",
            [sel, box["x"] + box["width"] / 2, box["y"] + box["height"] / 2],
        )
        assert seen, f"{sel} is covered or clipped at {box}"
        out[sel] = box
    return out


KEY_CONTROLS = [
    "#spawn-class",
    "#spawn-start",
    "#spawn-name",
    "#spawn-button",
    "#command",
    "#command-send",
    "#wheels [data-act='forward']",
    "#wheels [data-act='back']",
    "#wheels [data-act='left']",
    "#wheels [data-act='right']",
    "#wheels .pad [data-act='stop']",
    "#wheels [data-act='faster']",
    "#camera-group [data-act='tilt-up']",
    "#camera-group [data-act='zoom-out']",
    "#lights-button",
    "#range-view",
    "#video",
    "#world-view",
]


def test_the_controls_fit_a_1280x720_laptop_screen(console_page, console_server):
    page = console_page.page
    page.set_viewport_size(LAPTOP)
    console_page.open()
    console_page.spawn("P2AT", "PlayerStart8", "Laptop")
    boxes = boxes_within(page, KEY_CONTROLS, LAPTOP["width"], LAPTOP["height"])
    assert boxes["#video"]["height"] > 150 and boxes["#range-view"]["height"] > 150
    # the page itself does not scroll
    assert page.evaluate("document.scrollingElement.scrollHeight") <= LAPTOP["height"]
    assert page.evaluate("document.scrollingElement.scrollWidth") <= LAPTOP["width"]
    # and the buttons work from there: Forward sends a DRIVE
    page.click("#wheels [data-act='forward']")
    page.wait_for_function(
        "[...document.querySelectorAll('#log .entry.out .txt')].some(e => /^DRIVE \\{Left [1-9]/.test(e.textContent))"
    )
    assert console_page.errors == []


def test_the_page_watches_another_controllers_robot_and_says_when_it_leaves(console_page, console_server):
    srv = console_server
    page = console_page.page
    page.set_viewport_size(LAPTOP)
    console_page.open()
    c = init_robot(srv, "Outsider", "PlayerStart4")
    try:
        c.send("DRIVE {Left 1} {Right 1}")
        page.click("#world-robots li[data-name='Outsider']")
        # its sensors, range view and messages, as its controller receives them
        page.wait_for_selector("#sensor-tree details[data-key='SEN Sonar']")
        page.wait_for_selector("#sensor-tree details[data-key='SEN RangeScanner']")
        page.wait_for_selector("#sensor-tree details[data-key='STA']")
        page.wait_for_function(
            "[...document.querySelectorAll('#log .entry.in')]"
            ".filter(e => e.querySelector('.who').textContent === 'Outsider'"
            " && e.querySelector('.txt').textContent.startsWith('SEN {Time')).length >= 5"
        )
        banner = page.text_content("#robot-banner")
        assert page.is_visible("#robot-banner") and banner.startswith("Watching Outsider, driven by 127.0.0.1:")
        assert "read-only" in banner
        # the range view draws its eight front sonars where GEO says they are mounted
        ranges = page.evaluate("""async () => {
            const m = await import('/static/sensors.js');
            const s = window.usarsimConsole.selected;
            const g = m.rangeGeometry(s);
            return { watch: s.watch, name: s.name, wedges: g.wedges.map(w => [w.x, w.y, w.yaw]),
                     sonarGeo: Object.keys(s.geo.Sonar || {}).length, laserConf: (s.conf.RangeScanner || {}).Scanner1 };
        }""")
        assert ranges["watch"] is True and ranges["name"] == "Outsider"
        assert ranges["sonarGeo"] >= 8 and len(ranges["wedges"]) >= 8
        assert all(abs(x) > 0.05 for x, _, _ in ranges["wedges"]), ranges["wedges"]  # mounted, not at the centre
        assert float(ranges["laserConf"]["MaxRange"]) > 0
        assert page.locator("#sessions button.watch").text_content().startswith("Outsider · watching")
        # read-only: no control, no key, no command box reaches it
        assert page.evaluate(
            "['wheels', 'camera-group', 'light-group'].every(id => document.getElementById(id).disabled)"
        )
        assert page.is_disabled("#wheels [data-act='forward']") and page.is_disabled("#lights-button")
        assert page.text_content("#command-target") == "a new connection"
        page.click("#world-view", position={"x": 5, "y": 5})
        page.keyboard.down("ArrowUp")
        page.wait_for_timeout(400)
        page.keyboard.up("ArrowUp")
        page.keyboard.press("l")
        assert page.eval_on_selector_all("#log .entry.out", "els => els.length") == 0
        assert srv.connection_count() == 1  # the robot's own controller, nothing from the page
        # every key control is still above the fold with the banner shown
        boxes_within(page, KEY_CONTROLS, LAPTOP["width"], LAPTOP["height"])
        ARTIFACTS.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "console-watching-another-controllers-robot.png"))
        readings = page.eval_on_selector_all("#sensor-tree > details", "els => els.map(e => e.dataset.key)")
    finally:
        c.close()
    # its controller disconnected: the page says the robot left, and keeps what it last showed
    page.wait_for_function(
        "document.getElementById('robot-banner').textContent.includes('Robot Outsider left the world')"
    )
    assert page.is_visible("#robot-banner")
    assert "last it sent" in page.text_content("#robot-banner")
    assert page.get_attribute("#robot-banner", "class").split() == ["banner", "gone"]
    assert "stale" in page.get_attribute("#operation", "class").split()
    tab = page.locator("#sessions button.watch")
    assert "dead" in tab.get_attribute("class").split() and tab.text_content().startswith("Outsider · left")
    assert page.eval_on_selector_all("#sensor-tree > details", "els => els.map(e => e.dataset.key)") == readings
    assert page.text_content("#video-overlay") == "Outsider left the world."
    page.wait_for_function(
        "[...document.querySelectorAll('#log .entry.note .txt')]"
        ".some(e => e.textContent.startsWith('Outsider left the world at '))"
    )
    wait_for(lambda: srv.robot_count() == 0, timeout=DEFAULT_TIMEOUT, interval=0.05, what="the robot to be removed")
    # Esc: the page stops showing it
    page.keyboard.press("Escape")
    page.wait_for_selector("#robot-banner", state="hidden")
    assert page.locator("#sessions button").count() == 0
    assert console_page.errors == []


def test_start_poses_are_named_beside_their_markers(console_page, console_server):
    page = console_page.page
    page.set_viewport_size(LAPTOP)
    console_page.open()
    page.wait_for_function(f"document.getElementById('world-view').dataset.startLabels === {' '.join(START_POSES)!r}")

    def labels():
        return page.evaluate("""() => {
            const m = window.usarsimConsole.map;
            m.draw();
            return { labels: m.startLabels, w: m.canvas.width / m.dpr, h: m.canvas.height / m.dpr, scale: m.view.scale };
        }""")

    def check(state):
        assert [lab["name"] for lab in state["labels"]] == START_POSES
        for lab in state["labels"]:
            assert 0 <= lab["x"] and lab["x"] + lab["w"] <= state["w"], lab
            assert 0 <= lab["y"] and lab["y"] + lab["h"] <= state["h"], lab
            mx, my = lab["marker"]
            dx = max(lab["x"] - mx, 0, mx - (lab["x"] + lab["w"]))
            dy = max(lab["y"] - my, 0, my - (lab["y"] + lab["h"]))
            assert (dx * dx + dy * dy) ** 0.5 < max(12, 0.3 * state["scale"] + 6), lab  # beside its marker
        for i, a in enumerate(state["labels"]):
            for b in state["labels"][i + 1 :]:
                apart = (
                    a["x"] + a["w"] <= b["x"]
                    or b["x"] + b["w"] <= a["x"]
                    or a["y"] + a["h"] <= b["y"]
                    or b["y"] + b["h"] <= a["y"]
                )
                assert apart, (a, b)

    fitted = labels()
    check(fitted)
    # the names are painted: each name's box differs from the same picture drawn without names
    changed = page.evaluate("""() => {
        const m = window.usarsimConsole.map;
        const grab = () => m.startLabels.map(l => m.ctx.getImageData(Math.floor(l.x * m.dpr), Math.floor(l.y * m.dpr),
                                                                      Math.ceil(l.w * m.dpr), Math.ceil(l.h * m.dpr)).data);
        m.showStartLabels = true; m.draw();
        const boxes = m.startLabels.map(l => ({ ...l }));
        const named = grab();
        m.showStartLabels = false; m.draw();
        m.startLabels = boxes;
        const bare = grab();
        m.showStartLabels = true; m.draw();
        return named.map((d, i) => { let n = 0; for (let k = 0; k < d.length; k += 4)
            if (Math.abs(d[k] - bare[i][k]) + Math.abs(d[k + 1] - bare[i][k + 1]) > 60) n++; return n; });
    }""")
    assert len(changed) == len(START_POSES) and min(changed) > 15, changed
    # zoomed in on the staging area, every name sits right of its marker
    page.evaluate(
        "() => { const m = window.usarsimConsole.map; m.view.cx = -12.5; m.view.cy = 0;"
        " m.view.scale = 22; m.dirty = true; }"
    )
    page.wait_for_timeout(50)
    close = labels()
    check(close)
    assert all(lab["x"] > lab["marker"][0] for lab in close["labels"])
    time.sleep(0.1)
    assert console_page.errors == []
