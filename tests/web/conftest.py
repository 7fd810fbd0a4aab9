"""Fixtures of the operator console's tests: a simulator running in real time with its
console, a headless Chromium driven through Playwright (the system's Chromium, from
Debian's package), and a screenshot of the console after each browser test, kept in
tests/artifacts/."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from helpers import DEFAULT_TIMEOUT, ServerThread
from webtools import chromium_path

ARTIFACTS = Path(__file__).resolve().parent.parent / "artifacts"


@pytest.fixture(scope="module")
def console_server(yellow_world):
    """DM-USAR_yellow in real time with its console on a free port (one per test module)."""
    srv = ServerThread(yellow_world, seed=1, lockstep=False, speed=1.0).start()
    yield srv
    srv.stop()


@pytest.fixture(scope="session")
def browser():
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.skip("Playwright is not installed (pip install -e '.[test]')")
    exe = chromium_path()
    if exe is None:
        pytest.skip("no Chromium on this machine (Debian: apt-get install chromium; scripts/test.sh installs it)")
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=exe, args=["--no-sandbox"])
        yield b
        b.close()


class Page:
    """A browser tab on the console, with every console error and uncaught exception it logs."""

    def __init__(self, page, url: str):
        self.page = page
        self.url = url
        self.errors: list[str] = []
        page.on("console", lambda m: self.errors.append(f"console.{m.type}: {m.text}") if m.type == "error" else None)
        page.on("pageerror", lambda e: self.errors.append(f"uncaught: {e}"))

    def open(self) -> Page:
        self.page.goto(self.url)
        # the world, the robot classes and the first ground truth have arrived
        self.page.wait_for_function(
            "document.querySelectorAll('#spawn-class option').length > 0"
            " && document.querySelectorAll('#spawn-start option').length > 0"
            " && document.getElementById('sim-time').textContent !== '–'",
            timeout=DEFAULT_TIMEOUT * 1000,
        )
        return self

    def spawn(self, cls: str, start: str, name: str) -> None:
        p = self.page
        p.select_option("#spawn-class", cls)
        p.check('input[name="spawn-at"][value="start"]')
        p.select_option("#spawn-start", start)
        p.fill("#spawn-name", name)
        p.click("#spawn-button")
        # the robot is alive: its controls are enabled
        p.wait_for_selector("#wheels:not([disabled])", timeout=DEFAULT_TIMEOUT * 1000)


@pytest.fixture
def console_page(browser, console_server, request):
    context = browser.new_context(viewport={"width": 1400, "height": 900})
    page = context.new_page()
    page.set_default_timeout(DEFAULT_TIMEOUT * 1000)
    wrapped = Page(page, f"http://127.0.0.1:{console_server.app.web.port}/")
    yield wrapped
    ARTIFACTS.mkdir(exist_ok=True)
    try:
        page.screenshot(path=str(ARTIFACTS / f"console-{request.node.name}.png"))
    finally:
        context.close()
        # the page's connections are closed: wait until its robots are gone
        deadline = time.monotonic() + DEFAULT_TIMEOUT
        while console_server.robot_count() and time.monotonic() < deadline:
            time.sleep(0.05)
