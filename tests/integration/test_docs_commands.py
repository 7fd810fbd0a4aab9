"""Every command shown in the README and the pages it links runs as printed.

The commands are the lines of the pages' ```bash blocks, run in page order (the README first), in
one working folder (``examples`` and ``tools`` are there, as in a clone; ``bash scripts/...`` runs the
clone's script), with the shell ``scripts/test.sh`` leaves behind (the virtual environment's
``usarsim`` first on PATH).  What a line means, as a reader would take it:

* ``cmd &``: started in the background, as the shell does; the block's next lines run beside it
  once it says it is listening, and it is stopped at the end of the block;
* ``usarsim serve ...``, ``bash scripts/serve.sh ...`` or ``cmd  # terminal 1 ...``: a server in a
  terminal of its own, started the same way;
* ``cmd  # terminal 2 ...``: runs beside that server;
* any other line first stops a server still running (Ctrl-C: it must exit 0), then runs and must
  exit 0;
* ``<!-- file: NAME -->`` just before a fenced block writes the block to NAME first (the files a
  page has the reader write);
* not run: ``bash scripts/test.sh`` (the suite that runs this test), ``. .venv/bin/activate``
  (this is that environment) and ``pip install`` (every extra is installed here).

Blocks tagged otherwise (```python, ```yaml, untagged transcripts and outputs) are not commands.
It uses the default ports, so no other test of its own does: ``scripts/test.sh`` runs it (marked
``ports``) in a process of its own beside the shared phase, whose tests use free ports (port 0).
"""

from __future__ import annotations

import os
import re
import selectors
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FENCE = re.compile(
    r"(?:<!-- file: (?P<file>[\w./-]+) -->\s*\n)?^(?P<indent>[ \t]*)```(?P<lang>\w*)\n(?P<body>.*?)^(?P=indent)```",
    re.S | re.M,
)
LINK = re.compile(r"\]\((docs/[\w-]+\.md)(?:#[\w-]*)?\)")
NOT_RUN = (
    re.compile(r"^bash scripts/test\.sh\b"),
    re.compile(r"^(\.|source) \.venv/bin/activate$"),
    re.compile(r"^(python -m )?pip install\b"),
)
COMMENT = re.compile(r"\s#\s?")
SERVER = re.compile(r"^(usarsim serve|bash scripts/serve\.sh)\b")
LISTENING = re.compile(r"usarsim: control listening on|listening on \S+:\d+")
# The pages' commands run beside the shared phase of the suite (scripts/test.sh), which slows them
# down up to five times on two cores: the README's sample sweep takes 50 s alone and 5 min there.
COMMAND_TIMEOUT_S = 600


class PortGuard:
    """The default ports, held (bound on every address, not listening) while no command of a
    page runs: a test of the shared phase beside this one binds free ports (port 0), and so do
    Ray and the browser, and the kernel would otherwise be free to give one of them a default
    port (the WSS's 50000 is inside Linux's range of free ports) just before a page's server
    needs it."""

    def __init__(self) -> None:
        from usarsim.cli import DEFAULT_PORTS, FOXGLOVE_PORT

        self.ports = sorted({*DEFAULT_PORTS.values(), FOXGLOVE_PORT})
        self.held: list[socket.socket] = []

    def hold(self) -> None:
        for port in self.ports:
            s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            try:
                s.bind(("0.0.0.0", port))
            except OSError:  # a server of the page still closing, or another program's
                s.close()
                continue
            self.held.append(s)

    def release(self) -> None:
        for s in self.held:
            s.close()
        self.held = []


@pytest.fixture(scope="module")
def port_guard():
    guard = PortGuard()
    guard.hold()
    yield guard
    guard.release()


def pages() -> list[str]:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    linked = sorted(set(LINK.findall(readme)))
    return ["README.md", *linked]


def commands(page: str) -> list[tuple[str, str, str | None]]:
    """(kind, command, file contents) in page order: kind is "file" (command = its name),
    "run", "background", "beside" or "end" (of a block)."""
    text = (ROOT / page).read_text(encoding="utf-8")
    out: list[tuple[str, str, str | None]] = []
    for m in FENCE.finditer(text):
        body = "\n".join(ln[len(m.group("indent")) :] for ln in m.group("body").splitlines())
        if m.group("file"):
            out.append(("file", m.group("file"), body + "\n"))
        if m.group("lang") != "bash":
            continue
        ampersand = False
        for line in body.replace("\\\n", " ").splitlines():
            command, _, comment = COMMENT.split(line, 1)[0], None, "".join(COMMENT.split(line, 1)[1:])
            command = command.strip()
            if not command or command.startswith("#") or any(p.search(command) for p in NOT_RUN):
                continue
            if command.endswith("&"):
                ampersand = True
                out.append(("background", command.rstrip("&").strip(), None))
            elif SERVER.search(command) or "terminal 1" in comment:
                out.append(("background", command, None))
            elif ampersand or "terminal 2" in comment:
                out.append(("beside", command, None))
            else:
                out.append(("run", command, None))
        out.append(("end", "", None))
    return out


def _env() -> dict[str, str]:
    env = {
        **os.environ,
        "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl"),
        "USARSIM_PYTHON": sys.executable,
        "PYTHONUNBUFFERED": "1",
    }
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    return env


def _as_run(command: str) -> str:
    """The command as the shell runs it here: the clone's scripts by their path."""
    return re.sub(r"(^|\s)bash scripts/", rf"\1bash {shlex.quote(str(ROOT))}/scripts/", command)


class Background:
    def __init__(self, command: str, cwd: Path, log: Path):
        self.command = command
        self.log = log
        with open(log, "wb") as err:
            self.proc = subprocess.Popen(
                ["bash", "-c", "exec " + _as_run(command)],
                cwd=cwd,
                env=_env(),
                stdout=subprocess.PIPE,
                stderr=err,
                start_new_session=True,
            )
        self.out = ""
        sel = selectors.DefaultSelector()
        sel.register(self.proc.stdout, selectors.EVENT_READ)
        deadline = time.monotonic() + 180  # scripts/serve.sh installs first
        try:
            while not LISTENING.search(self.out):
                assert self.proc.poll() is None, f"{command!r} exited {self.proc.returncode}: {log.read_text()[-2000:]}"
                assert time.monotonic() < deadline, f"{command!r} never said it was listening: {self.out[-2000:]}"
                if sel.select(timeout=1.0):
                    self.out += os.read(self.proc.stdout.fileno(), 65536).decode(errors="replace")
        except AssertionError:
            self.kill()
            raise
        finally:
            sel.close()
        time.sleep(1.0)  # every listener up

    def stop(self) -> None:
        """Ctrl-C, as the reader would: it must stop cleanly."""
        os.killpg(self.proc.pid, signal.SIGINT)
        try:
            self.proc.communicate(timeout=60)
            rc = self.proc.returncode
        except subprocess.TimeoutExpired:
            self.kill()
            pytest.fail(f"{self.command!r} did not stop on Ctrl-C within 60 s")
        assert rc in (0, -signal.SIGINT, 130), f"{self.command!r} exited {rc} on Ctrl-C: {self.log.read_text()[-2000:]}"

    def kill(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGKILL)
        self.proc.communicate()


def _run(command: str, cwd: Path) -> None:
    out = subprocess.run(
        ["bash", "-c", _as_run(command)],
        cwd=cwd,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=COMMAND_TIMEOUT_S,
        check=False,
        stdin=subprocess.DEVNULL,
    )
    assert out.returncode == 0, (
        f"{command!r} exited {out.returncode}\n--- stdout\n{out.stdout[-3000:]}\n--- stderr\n{out.stderr[-3000:]}"
    )


def test_the_readme_links_the_reference_pages():
    assert {
        "docs/commands.md",
        "docs/protocol.md",
        "docs/performance.md",
        "docs/recording.md",
        "docs/experiments.md",
    } <= set(pages())
    for page in pages():
        assert (ROOT / page).is_file(), page


def test_the_commands_are_found():
    readme = commands("README.md")
    assert ("background", "bash scripts/serve.sh", None) in readme
    assert ("beside", "python examples/drive_p2at.py", None) in readme
    assert not any("scripts/test.sh" in c for _, c, _ in readme)  # the suite itself: not run here
    built = commands("docs/building-worlds.md")
    assert built[0][:2] == ("file", "MyArena.yaml") and ("run", "usarsim validate MyArena.yaml", None) in built


@pytest.fixture(scope="module")
def clone_folder(tmp_path_factory) -> Path:
    """The reader's folder, one for every page in turn (what a page's commands leave there, a
    later page finds, as in a clone: the sweep the README ran, docs/experiments.md resumes)."""
    folder = tmp_path_factory.mktemp("clone")
    for name in ("examples", "tools"):
        (folder / name).symlink_to(ROOT / name)
    return folder


def pages_with_commands() -> list[str]:
    return [page for page in pages() if any(kind not in ("file", "end") for kind, _, _ in commands(page))]


@pytest.mark.ports
@pytest.mark.parametrize("page", pages_with_commands())
def test_every_command_of_the_page_runs_as_printed(page, clone_folder, port_guard):
    steps = commands(page)
    tmp_path = clone_folder
    server: Background | None = None
    try:
        for i, (kind, command, contents) in enumerate(steps):
            if kind == "end":
                if server is not None:
                    server.stop()
                    server = None
                    port_guard.hold()
                continue
            if kind == "file":
                (tmp_path / command).parent.mkdir(parents=True, exist_ok=True)
                (tmp_path / command).write_text(contents)
                continue
            if kind != "beside" and server is not None:
                server.stop()
                server = None
                port_guard.hold()
            port_guard.release()  # the command takes them; held again once it (or its server) is done
            if kind == "background":
                server = Background(command, tmp_path, tmp_path / f"{Path(page).stem}-background{i}.log")
            else:
                _run(command, tmp_path)
                if server is None:
                    port_guard.hold()
        if server is not None:
            server.stop()
            server = None
    finally:
        if server is not None:
            server.kill()
        port_guard.release()
        port_guard.hold()


@pytest.mark.ports
def test_the_readme_competitions_leaderboard_opens_in_chromium(clone_folder):
    """The README's sample competition ran above (in the reader's folder): its leaderboard page
    opens in a real browser without a console error, with every map shown."""
    page_file = clone_folder / "results" / "rescue_cup" / "leaderboard.html"
    assert page_file.exists(), "the README's usarsim compete examples/rescue_cup.yaml did not write its page"
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.skip("no Chromium on this machine (Debian: apt-get install chromium; scripts/test.sh installs it)")
    from playwright.sync_api import sync_playwright

    errors: list[str] = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=exe, args=["--no-sandbox"])
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            page.on("console", lambda m: errors.append(f"console.{m.type}: {m.text}") if m.type == "error" else None)
            page.on("pageerror", lambda e: errors.append(f"uncaught: {e}"))
            page.goto(page_file.as_uri())
            page.wait_for_load_state("load")
            shown = page.eval_on_selector_all("img", "imgs => imgs.map(i => i.complete && i.naturalWidth > 0)")
            teams = page.eval_on_selector_all("table:first-of-type td.name", "tds => tds.map(t => t.textContent)")
        finally:
            browser.close()
    assert errors == []
    assert sorted(teams) == ["frontier", "victim", "wander"]
    assert len(shown) == 4 + 3 * 4 and all(shown)  # each scenario's ground truth and every team's map of it


INLINE = re.compile(
    r"`(usarsim (?:serve|validate|worlds|robots|bench|replay|sweep|report|ros2|compete|map|score-map)\b[^`]*)`"
)


def test_every_usarsim_command_named_in_the_text_has_options_that_exist(capsys):
    """The commands the pages name inline (``usarsim serve --port-offset 100``) are not run,
    but every option and choice they show must be one the command has."""
    from usarsim.cli import build_parser

    parser = build_parser()
    checked, wrong = 0, []
    for page in pages():
        for m in INLINE.finditer((ROOT / page).read_text(encoding="utf-8")):
            text = m.group(1)
            if re.search(r"[\[\]|]|\.\.\.", text):  # a synopsis, not a command
                continue
            checked += 1
            try:
                parser.parse_args(shlex.split(text)[1:])
            except SystemExit:
                said = capsys.readouterr().err
                if "unrecognized arguments" in said or "invalid choice" in said:
                    wrong.append(f"{page}: {text}: {said.strip()}")
    assert checked > 30
    assert not wrong, "\n".join(wrong)
