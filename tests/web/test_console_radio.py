"""The console's radio panel (docs/console.md): what the radio channel carried, link by link,
from ``/api/radio``; no panel under USARSim's ideal channel, which counts nothing."""

from __future__ import annotations

import json
import urllib.request

import pytest

from helpers import DEFAULT_TIMEOUT, ServerThread, wait_for

WORLD = """\
name: RadioPanelArena
description: two ComStations 20 m apart in the open, a capped and delayed channel (tests only)
floor: {center: [0.0, 0.0], size: [60.0, 40.0]}
wireless:
  channel: {link_bytes_per_s: 50000, latency_s: 0.004}
start_poses:
  - {name: S, location: [0.0, 5.0, -0.2], rotation: [0.0, 0.0, 0.0]}
"""


def radio_json(srv: ServerThread) -> dict:
    with urllib.request.urlopen(f"http://127.0.0.1:{srv.app.web.port}/api/radio", timeout=DEFAULT_TIMEOUT) as r:
        return json.loads(r.read())


@pytest.fixture(scope="module")
def channel_server(tmp_path_factory):
    from usarsim.config.catalog import ROBOTS_DIR
    from usarsim.config.world_file import load_world

    folder = tmp_path_factory.mktemp("radio")
    p = folder / "RadioPanelArena.yaml"
    p.write_text(WORLD)
    # a P2AT carrying one radio relay
    head = (ROBOTS_DIR / "P2AT.yaml").read_text().split("\nsensors:")[0]
    (folder / "Courier.yaml").write_text(
        head.replace("class_name: P2AT", "class_name: Courier")
        + "\nsensors:\n  - {type: RelayDropper, name: Relays, location: [-0.2, 0.0, 0.08], capacity: 1}\n"
    )
    srv = ServerThread(load_world(p), seed=3, lockstep=False, speed=1.0, robot_dirs=(str(folder),)).start()
    clients = []
    for name, x in (("A0", -10.0), ("B0", 10.0)):
        c = srv.connect()
        c.nfo()
        c.send(f"INIT {{ClassName USARBot.ComStation}} {{Name {name}}} {{Location {x},0,-0.61}}")
        c.sync()
        clients.append(c)
    yield srv
    for c in clients:
        c.close()
    srv.stop()


def test_the_ideal_channel_has_no_traffic_to_show(console_server):
    assert radio_json(console_server) == {"channel": "ideal", "links": []}


def test_the_radio_panel_shows_each_links_messages(browser, channel_server):
    from usarsim.client.radio import Radio, link

    srv = channel_server
    a, b = (Radio("127.0.0.1", srv.app.wireless.comserver.port, n) for n in ("A0", "B0"))
    try:
        assert link(a, b)
        for k in range(20):
            a.send("B0", bytes([k]) * 100)
        wait_for(lambda: (b.poll(), b.received)[1] == 20, what="B0 to receive 20 messages")
    finally:
        a.close()
        b.close()
    data = radio_json(srv)
    assert "50000 bytes/s a link" in data["channel"]
    (row,) = data["links"]
    # each message: the client's 4-byte length, then its 100 bytes
    assert (row["from"], row["to"], row["delivered"], row["delivered_bytes"]) == ("a0", "b0", 20, 2080)
    assert row["dropped"] == {"range": 0, "loss": 0, "capacity": 0} and row["mean_delay_s"] > 0.004
    context = browser.new_context(viewport={"width": 1400, "height": 900})
    try:
        page = context.new_page()
        page.goto(f"http://127.0.0.1:{srv.app.web.port}/")
        page.wait_for_selector("#radio-traffic:not([hidden])", timeout=DEFAULT_TIMEOUT * 1000)
        cells = page.locator("#radio-links tbody tr").first.locator("td").all_text_contents()
        assert cells[:3] == ["a0 → b0", "20", "0"] and float(cells[3]) > 4.0  # the mean delay, ms
        assert "50000 bytes/s a link" in page.text_content("#radio-channel")
    finally:
        context.close()


def test_a_dropped_relay_is_an_orange_square_on_the_map(browser, channel_server):
    srv = channel_server
    with srv.connect() as courier:
        courier.nfo()
        courier.send("INIT {ClassName USARBot.Courier} {Name Courier} {Location 0,8,-0.2}")
        courier.sync()
        wait_for(lambda: "Courier" in {r.name for r in srv.app.facade.robots()}, what="the courier to stand")
        reply = courier.ask("SET {Type RelayDropper} {Name Relays} {Opcode Drop}", "RES")
        assert "{Status OK}" in reply.text, reply.text
    wait_for(lambda: srv.robot_count() == 2, what="the courier to leave")  # its relay stays
    context = browser.new_context(viewport={"width": 1400, "height": 900})
    try:
        page = context.new_page()
        page.goto(f"http://127.0.0.1:{srv.app.web.port}/")
        page.wait_for_function(
            "window.usarsimConsole.truthRows && window.usarsimConsole.truthRows.some((o) => o.class === 'RadioRelay')",
            timeout=DEFAULT_TIMEOUT * 1000,
        )
        page.wait_for_timeout(500)  # drawn
        rgb = page.evaluate("""() => {
            const map = window.usarsimConsole.map;
            const relay = window.usarsimConsole.truthRows.find((o) => o.class === 'RadioRelay');
            const [sx, sy] = map.toScreen(relay.location[0], relay.location[1]);
            const d = map.canvas.getContext('2d').getImageData(Math.round(sx * map.dpr), Math.round(sy * map.dpr), 1, 1).data;
            return [relay.name, d[0], d[1], d[2]];
        }""")
        assert rgb == ["Courier-Relay1", 255, 140, 0]  # #ff8c00
    finally:
        context.close()
