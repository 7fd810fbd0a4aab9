"""Golden transcripts: client lines replayed against a fresh lock-step server, every server
line compared byte for byte.

Transcript format (``tests/golden/transcripts/*.txt``, UTF-8, LF line ends in the file)::

    # world: DM-USAR_yellow        header: world name (or path), seed, lock-step
    # seed: 7
    # lockstep: true
    # any other '#' line is a comment (kept when the file is rewritten)
    S: NFO {Gametype ...}          a server line (compared as the bytes 'text' + CR LF)
    C: GETSTARTPOSES               a client line, sent with CR LF
    C! b'\\x00\\xffgarbage\\r\\n'      raw client bytes: a Python bytes literal, sent as is
    S: NFO {StartPoses ...}

The ``S:`` lines after a ``C`` entry are the server's whole answer to it.  The runner knows
an answer is complete without waiting on the clock: a ``STEP`` ends with ``STEPPED``; after
that (and after any other entry) it sends a probe ``GETSTARTPOSES`` and reads up to the
probe's reply, which is not recorded.  The lines before the first ``C`` entry are the
greeting sent on connect.

Regenerate after an intended change of output, then review the diff::

    pytest tests/golden --update-golden        (or USARSIM_UPDATE_GOLDEN=1 pytest tests/golden)
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from helpers import Client, ServerThread, segments
from usarsim.errors import ProtocolError
from usarsim.protocol.commands import GetStartPoses, Step, parse_command
from usarsim.protocol.framing import LineBuffer

TRANSCRIPTS = Path(__file__).parent / "transcripts"
PROBE = b"GETSTARTPOSES\r\n"
PROBE_REPLY = "NFO {StartPoses"


@dataclass
class Entry:
    data: bytes  # what the client sends
    source: str  # the entry's line in the file
    comments: list[str] = field(default_factory=list)
    expected: list[str] = field(default_factory=list)


@dataclass
class Transcript:
    path: Path
    header: list[str]
    world: str
    seed: int
    lockstep: bool
    greeting: list[str]
    entries: list[Entry]


def load_transcript(path: Path) -> Transcript:
    header: list[str] = []
    settings: dict[str, str] = {}
    greeting: list[str] = []
    entries: list[Entry] = []
    pending_comments: list[str] = []
    for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        if line.startswith("#"):
            m = re.fullmatch(r"# (world|seed|lockstep): (.+)", line)
            if m and not entries and not greeting:
                settings[m.group(1)] = m.group(2).strip()
            if not entries and not greeting:
                header.append(line)
            else:
                pending_comments.append(line)
        elif line.startswith("C: "):
            entries.append(Entry(line[3:].encode("ascii") + b"\r\n", line, pending_comments))
            pending_comments = []
        elif line.startswith("C! "):
            data = ast.literal_eval(line[3:])
            if not isinstance(data, bytes) or not data.endswith((b"\r", b"\n")):
                raise ValueError(
                    f"{path}:{n}: 'C!' needs a bytes literal ending in a line terminator, such as b'...\\r\\n'"
                )
            entries.append(Entry(data, line, pending_comments))
            pending_comments = []
        elif line.startswith("S: ") or line == "S:":
            (entries[-1].expected if entries else greeting).append(line[3:])
        elif line.strip():
            raise ValueError(f"{path}:{n}: a line must start with '#', 'C: ', 'C! ' or 'S: ', got {line!r}")
    for key in ("world", "seed", "lockstep"):
        if key not in settings:
            raise ValueError(f"{path}: header line '# {key}: ...' is missing")
    return Transcript(
        path,
        header,
        settings["world"],
        int(settings["seed"]),
        settings["lockstep"].lower() == "true",
        greeting,
        entries,
    )


def write_transcript(t: Transcript, greeting: list[bytes], answers: list[list[bytes]]) -> None:
    def s_lines(raws: list[bytes]) -> list[str]:
        out = []
        for raw in raws:
            assert raw.endswith(b"\r\n") and b"\n" not in raw[:-2], raw
            out.append("S: " + raw[:-2].decode("ascii"))
        return out

    lines = list(t.header) + s_lines(greeting)
    for entry, raws in zip(t.entries, answers):
        lines += entry.comments + [entry.source] + s_lines(raws)
    t.path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def commands_in(data: bytes) -> tuple[int, int]:
    """How many GETSTARTPOSES and valid STEP commands the server will see in ``data``."""
    n_poses = n_steps = 0
    for line in LineBuffer().feed(data):
        try:
            cmd = parse_command(line)
        except ProtocolError:
            continue
        n_poses += isinstance(cmd, GetStartPoses)
        n_steps += isinstance(cmd, Step)
    return n_poses, n_steps


def answer(client: Client, data: bytes) -> list[bytes]:
    """Send one entry; return the raw lines of the server's whole answer to it."""
    n_poses, n_steps = commands_in(data)
    start = len(client.history)
    client.send_raw(data)
    for _ in range(n_steps):
        client.wait_line("STEPPED ")
    client.send_raw(PROBE)
    seen = 0
    while True:
        line = client.wait_line(PROBE_REPLY)
        seen += 1
        if seen > n_poses:
            break
    got = client.history[start:]
    assert got[-1] is line
    return [ln.raw for ln in got[:-1]]


WORLDS = Path(__file__).parent / "worlds"


def world_of(t: Transcript):
    """A shipped world by name, or a world file of tests/golden/worlds."""
    from usarsim.config.catalog import resolve_world

    if (WORLDS / f"{t.world}.yaml").exists():
        return resolve_world(str(WORLDS / f"{t.world}.yaml"))
    return resolve_world(t.world)


def replay(world, seed: int, lockstep: bool, entries: list[bytes]) -> tuple[list[bytes], list[list[bytes]]]:
    """Run the client entries against a fresh server; return (greeting, answers)."""
    srv = ServerThread(world, seed=seed, lockstep=lockstep).start()
    try:
        client = srv.connect()
        greeting = answer(client, b"")
        answers = [answer(client, data) for data in entries]
        return greeting, answers
    finally:
        srv.stop()


def transcript_paths() -> list[Path]:
    return sorted(TRANSCRIPTS.glob("*.txt"))


@pytest.mark.parametrize("path", transcript_paths(), ids=lambda p: p.stem)
def test_transcript(path: Path, update_golden: bool):
    t = load_transcript(path)
    assert t.lockstep, "golden transcripts must run in lock-step mode to be reproducible"
    greeting, answers = replay(world_of(t), t.seed, t.lockstep, [e.data for e in t.entries])
    if update_golden:
        write_transcript(t, greeting, answers)
        return
    assert [g.decode("ascii") for g in greeting] == [s + "\r\n" for s in t.greeting]
    for entry, got in zip(t.entries, answers):
        expected = [(s + "\r\n").encode("ascii") for s in entry.expected]
        assert got == expected, f"{path.name}: answer to {entry.source!r} differs"


def test_every_transcript_has_a_greeting_and_answers():
    """Guards against an empty or never-generated transcript passing silently."""
    paths = transcript_paths()
    assert len(paths) >= 3
    for path in paths:
        t = load_transcript(path)
        assert t.greeting == ["NFO {Gametype BotDeathMatch} {Level %s} {TimeLimit 0}" % t.world]
        assert any(e.expected for e in t.entries), f"{path.name} holds no server lines; run --update-golden"
        assert any(s.startswith("STEPPED ") for e in t.entries for s in e.expected)


# --------------------------------------------------------------------------- determinism


@pytest.fixture(scope="module")
def session_a():
    return load_transcript(TRANSCRIPTS / "a_session.txt")


def noisy(line: bytes) -> bool:
    text = line.decode("ascii")
    return text.startswith("SEN ") and segments(text).get("Type") in ("Sonar", "RangeScanner", "INS", "Encoder")


def test_same_seed_gives_byte_identical_output(session_a):
    world = world_of(session_a)
    entries = [e.data for e in session_a.entries]
    first = replay(world, session_a.seed, True, entries)
    second = replay(world, session_a.seed, True, entries)
    as_bytes = lambda run: b"".join(run[0]) + b"".join(b"".join(a) for a in run[1])  # noqa: E731
    assert len(as_bytes(first)) > 20_000
    assert as_bytes(first) == as_bytes(second)


def test_another_seed_changes_the_noise_only(session_a):
    world = world_of(session_a)
    entries = [e.data for e in session_a.entries]
    _, a = replay(world, session_a.seed, True, entries)
    _, b = replay(world, session_a.seed + 1, True, entries)
    lines_a = [ln for ans in a for ln in ans]
    lines_b = [ln for ans in b for ln in ans]
    assert len(lines_a) == len(lines_b)
    kinds = lambda ln: (ln.split(b" ")[0], segments(ln.decode()).get("Type"))  # noqa: E731
    assert [kinds(x) for x in lines_a] == [kinds(x) for x in lines_b]
    differing = [(x, y) for x, y in zip(lines_a, lines_b) if x != y]
    assert differing, "a different seed gave the same output"
    assert any(noisy(x) and segments(x.decode())["Type"] == "RangeScanner" for x, _ in differing)
    assert any(noisy(x) and segments(x.decode())["Type"] == "Sonar" for x, _ in differing)
    # replies that carry no noise are the same
    for x, y in zip(lines_a, lines_b):
        if x.startswith((b"NFO ", b"GEO ", b"CONF ", b"STA ", b"STEPPED ")):
            assert x == y
