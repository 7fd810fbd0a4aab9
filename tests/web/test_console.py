"""The operator console end to end, in a real headless browser (Chromium through Playwright):
the page loads cleanly, a robot spawned from it appears in the world view, the arrow key
drives it, its camera's pictures are decoded on the page, and the command box reaches the
robot while the log shows what it receives.  A screenshot of the console is saved in
tests/artifacts/ after each test."""

from __future__ import annotations

import time

import pytest

from helpers import wait_for
from webtools import gl_problem, truth


def test_the_page_loads_with_no_console_errors(console_page, console_server):
    page = console_page.open().page
    assert page.text_content("#world-name") == "DM-USAR_yellow"
    classes = page.eval_on_selector_all("#spawn-class option", "els => els.map(e => e.value)")
    assert "P2AT" in classes and len(classes) >= 20
    starts = page.eval_on_selector_all("#spawn-start option", "els => els.map(e => e.value)")
    assert starts[:2] == ["PlayerStart1", "PlayerStart2"]
    # the static geometry was drawn: the world view is not a blank canvas
    assert (
        page.evaluate("""() => {
        const c = document.getElementById('world-view');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        const seen = new Set();
        for (let i = 0; i < d.length; i += 4 * 97) seen.add(d[i] + ',' + d[i + 1] + ',' + d[i + 2]);
        return seen.size;
    }""")
        > 5
    )
    page.wait_for_timeout(600)  # a few rounds of ground truth
    assert console_page.errors == []


def test_spawning_a_p2at_from_the_page_shows_it_in_the_world_view(console_page, console_server):
    page = console_page.open().page
    console_page.spawn("P2AT", "PlayerStart2", "WebScout")
    page.wait_for_selector("#world-robots li[data-name='WebScout']")
    assert page.text_content("#world-robots li[data-name='WebScout'] .cls") == "P2AT"
    # the world view draws it where the ground-truth service says it is
    drawn = page.evaluate("window.usarsimConsole.map.robots.get('WebScout').location")
    [row] = truth(console_server.app.truth.port, "WebScout")
    assert row["class"] == "P2AT"
    assert abs(drawn[0] - row["location"][0]) < 0.3 and abs(drawn[1] - row["location"][1]) < 0.3
    assert abs(row["location"][0] - -9.5) < 0.2 and abs(row["location"][1] - -4.0) < 0.2  # PlayerStart2
    assert console_page.errors == []


def test_the_forward_arrow_drives_the_robot(console_page, console_server):
    page = console_page.open().page
    console_page.spawn("P2AT", "PlayerStart3", "WebDriver")
    port = console_server.app.truth.port
    time.sleep(0.5)  # settled on its wheels
    [before] = truth(port, "WebDriver")
    page.click("#world-view")  # the page has the focus, not a form field
    page.keyboard.down("ArrowUp")
    try:
        moved = wait_for(
            lambda: truth(port, "WebDriver")[0]["location"][0] - before["location"][0] > 0.15,
            timeout=10,
            interval=0.1,
            what="the robot to move forward",
        )
    finally:
        page.keyboard.up("ArrowUp")
    assert moved
    [after] = truth(port, "WebDriver")
    assert abs(after["location"][1] - before["location"][1]) < 0.1  # straight ahead (+X, its heading)
    # released: it stops
    page.wait_for_function(
        "[...document.querySelectorAll('#log .entry.out .txt')].pop()?.textContent === 'DRIVE {Left 0} {Right 0}'"
    )
    sent = page.eval_on_selector_all("#log .entry.out .txt", "els => els.map(e => e.textContent)")
    assert any(t.startswith("DRIVE {Left ") and "{Left 0}" not in t for t in sent)
    assert console_page.errors == []


@pytest.mark.skipif(bool(gl_problem()), reason="pictures need an OpenGL context (MUJOCO_GL=egl)")
def test_the_video_shows_a_decoded_picture(console_page, console_server):
    page = console_page.open().page
    console_page.spawn("P2AT", "PlayerStart1", "WebEye")
    # the spawned robot's camera is attached: pictures arrive from the image server
    page.wait_for_function("document.getElementById('video-width').textContent === '640'", timeout=30000)
    stats = page.evaluate("""() => {
        const c = document.getElementById('video');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let n = 0, sum = 0, sq = 0;
        for (let i = 0; i < d.length; i += 4 * 13) { const v = (d[i] + d[i + 1] + d[i + 2]) / 3; n++; sum += v; sq += v * v; }
        const mean = sum / n;
        return { width: c.width, height: c.height, mean, std: Math.sqrt(sq / n - mean * mean) };
    }""")
    assert (stats["width"], stats["height"]) == (640, 480)
    assert 20 < stats["mean"] < 235 and stats["std"] > 10, stats  # a picture, not a uniform field
    assert page.text_content("#video-robot") == "WebEye"
    # C: the view from above and behind the robot
    page.click("#world-view")
    page.keyboard.press("c")
    page.wait_for_function("document.getElementById('video-camera').value === 'Chase'")
    assert console_page.errors == []


def test_the_command_box_sends_a_line_and_the_log_shows_sen_lines(console_page, console_server):
    page = console_page.open().page
    console_page.spawn("P2AT", "PlayerStart5", "WebTyped")
    page.fill("#command", "DRIVE {Left 1} {Right 1}")
    page.press("#command", "Enter")
    page.wait_for_function("""() => {
        const e = [...document.querySelectorAll('#log .entry')];
        const i = e.findIndex(x => x.classList.contains('out') && x.textContent.includes('DRIVE {Left 1} {Right 1}'));
        return i >= 0 && e.slice(i + 1).some(x => x.classList.contains('in') && x.textContent.includes('SEN {Time'));
    }""")
    who = page.eval_on_selector_all("#log .entry.in .who", "els => els.map(e => e.textContent)")
    assert set(who) == {"WebTyped"}
    [row] = truth(console_server.app.truth.port, "WebTyped")
    wait_for(
        lambda: truth(console_server.app.truth.port, "WebTyped")[0]["location"][0] > row["location"][0] + 0.05,
        timeout=10,
        interval=0.1,
        what="the robot to drive on DRIVE {Left 1} {Right 1}",
    )
    # a message opens in full (the log held still: new lines would scroll it under the pointer)
    page.uncheck("#log-follow")
    page.click("#log .entry.in >> nth=-1")
    assert page.is_visible("#message-dialog")
    assert page.text_content("#message-text").startswith(("SEN ", "STA ", "MISSTA "))
    assert console_page.errors == []


def test_the_robot_classes_say_where_each_stands_and_how_fast_velocities_may_take_it(console_server):
    """/api/classes asks each robot's drive: an aerial robot's velocity limits are its file's
    ``aerial`` section (the stick is scaled by them), a wheeled robot has none, and a walking
    robot stands on its legs, below its body."""
    import json
    import urllib.request

    from usarsim.config.catalog import resolve_robot

    with urllib.request.urlopen(f"http://127.0.0.1:{console_server.app.web.port}/api/classes", timeout=30) as r:
        classes = {c["name"]: c for c in json.load(r)}
    assert classes["AirRobot"]["velocities"] == {"linear": 2.0, "lateral": 2.0, "vertical": 2.0, "yaw_rate": 1.7453}
    assert classes["Helicopter"]["velocities"]["linear"] == 5.0
    assert classes["P2AT"]["velocities"] is None
    ers = resolve_robot("ERS")
    assert classes["ERS"]["spawn_z"] < -(ers.body_lowest_point_m + ers.spawn_clearance_m) - 0.05
