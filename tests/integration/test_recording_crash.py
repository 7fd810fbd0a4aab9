"""Recordings that were not closed or were damaged: ``usarsim serve --record`` killed with
SIGKILL leaves a file that ``usarsim replay`` replays up to about a second before the kill,
saying where it ends; a damaged file, a file that is not MCAP and a missing file are each
refused in one line (exit 1, no traceback)."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from mcap.reader import make_reader

from usarsim.client import launch
from usarsim.server.recording.reading import read_mcap
from usarsim.server.recording.transcript import TOPIC, decode_chunk

ENV = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
# The recorder finishes its chunk at least every simulated second and every wall-clock second
# (usarsim.server.recording.recorder.FLUSH_SIM_S, FLUSH_WALL_S); what it had not written yet
# when killed is lost too: a second more on a busy machine.
LOST_AT_MOST_S = 2.0


def replay(*args: str, timeout: float = 180) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "usarsim", "replay", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=ENV,
        stdin=subprocess.DEVNULL,
    )


def _drive_then_kill(path: Path, steps: int, *, lockstep: bool = True) -> float:
    """A P2AT driven over TCP for ``steps`` tenths of a simulated second, then the server
    killed with SIGKILL at once: the simulated time of the kill."""
    with launch(record=path, lockstep=lockstep, speed=1.0) as srv, srv.connect() as world:
        robot = world.spawn("P2AT", name="R1")
        if lockstep:
            for k in range(steps):
                robot.drive(left=1.0, right=1.5 if k < steps // 2 else 1.0)
                world.step(0.1)
        else:
            robot.drive(left=1.0, right=1.5)
            time.sleep(steps / 10)
        t_kill = world.time if lockstep else world.truth("P2AT")[0].time
        os.kill(srv.proc.pid, signal.SIGKILL)
        assert srv.proc.wait(10) == -signal.SIGKILL
    return t_kill


@pytest.fixture(scope="module")
def killed(tmp_path_factory) -> tuple[Path, float]:
    path = tmp_path_factory.mktemp("crash") / "killed.mcap"
    return path, _drive_then_kill(path, 50)


def test_the_mcap_reader_cannot_read_a_killed_recording_but_usarsim_can(killed):
    """What the kill leaves has no summary (the mcap reader, which starts from the footer,
    fails); read from its first byte it holds the run up to the last second."""
    path, t_kill = killed
    with path.open("rb") as f, pytest.raises(Exception):  # noqa: B017, PT011 (whichever the mcap reader raises)
        list(make_reader(f).iter_messages())
    contents = read_mcap(path)
    assert not contents.complete and "usarsim" in contents.metadata
    assert contents.count > 100
    assert t_kill - LOST_AT_MOST_S <= contents.end_ns / 1e9 <= t_kill + 1e-9
    topics = {topic for topic, _, _ in contents.messages}
    assert {TOPIC, "/R1/pose", "/R1/Scanner1", "/tf", "/usarsim/world"} <= topics
    chunks = [decode_chunk(data) for topic, _, data in contents.messages if topic == TOPIC]
    assert [c.seq for c in chunks] == list(range(len(chunks)))  # a prefix of the transcript, no gap
    steps = [c for c in chunks if c.kind == "in" and c.text.startswith("STEP")]
    assert len(steps) >= 50 - LOST_AT_MOST_S * 10


def test_replay_of_a_killed_recording_replays_what_it_holds_and_says_where_it_ends(killed):
    path, t_kill = killed
    out = replay(str(path), "--check")
    assert out.returncode == 0, out.stdout + out.stderr
    assert "Traceback" not in out.stderr
    warning = re.search(
        r"usarsim replay: warning: the recording ends at t=(\d+\.\d+) s,.*it was not closed", out.stderr
    )
    assert warning, out.stderr
    end = float(warning.group(1))
    assert t_kill - LOST_AT_MOST_S <= end <= t_kill + 1e-9
    # the client lines up to the end were replayed, and the server answered each as it had
    upto = float(re.search(r"client lines up to t=(\d+\.\d+) s", out.stdout).group(1))
    assert t_kill - LOST_AT_MOST_S <= upto <= end
    assert "identical: all" in out.stdout
    assert int(out.stdout.split("identical: all ")[1].split()[0]) > 100


def test_a_real_time_recording_killed_replays_up_to_a_second_or_two_before_the_kill(tmp_path):
    path = tmp_path / "rt.mcap"
    t_kill = _drive_then_kill(path, 40, lockstep=False)
    out = replay(str(path))
    assert out.returncode == 0, out.stdout + out.stderr
    end = float(re.search(r"the recording ends at t=(\d+\.\d+) s", out.stderr).group(1))
    assert t_kill - LOST_AT_MOST_S <= end <= t_kill + 0.5
    assert "replayed 1 connections" in out.stdout or "replayed 2 connections" in out.stdout


# ------------------------------------------------------------------------ damaged files


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> Path:
    """A recording closed as it should be: two seconds of a P2AT."""
    path = tmp_path_factory.mktemp("whole") / "run.mcap"
    with launch(record=path) as srv, srv.connect() as world:
        robot = world.spawn("P2AT", name="R1")
        for _ in range(20):
            robot.drive(left=1.0, right=1.0)
            world.step(0.1)
    return path


def _chunks(path: Path) -> list[tuple[int, int]]:
    """(offset, length) of every chunk record, from the file's own chunk index."""
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    return sorted((ci.chunk_start_offset, ci.chunk_length) for ci in summary.chunk_indexes)


def _one_line_refusal(out: subprocess.CompletedProcess, *said: str) -> str:
    assert out.returncode == 1, out.stdout + out.stderr
    assert "Traceback" not in out.stderr and out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1, out.stderr
    for s in said:
        assert s in lines[0], lines[0]
    return lines[0]


def test_a_flipped_byte_inside_a_compressed_chunk_is_refused_in_one_line(recording, tmp_path):
    offset, length = _chunks(recording)[1]
    data = bytearray(recording.read_bytes())
    for k in range(offset + length // 2, offset + length // 2 + 16):  # the middle of its zstd data
        data[k] ^= 0xFF
    bad = tmp_path / "flipped.mcap"
    bad.write_bytes(bytes(data))
    line = _one_line_refusal(replay(str(bad)), f"{bad} is damaged at byte {offset} (")
    assert "does not decompress" in line or "checksum does not match" in line
    # what to do: replay what comes before, cut there
    assert f"head -c {offset} {bad} > part.mcap" in line
    part = tmp_path / "part.mcap"
    part.write_bytes(bytes(data[:offset]))
    out = replay(str(part))
    assert out.returncode == 0 and "the recording ends at t=" in out.stderr, out.stdout + out.stderr


def test_the_traceback_goes_to_the_log_at_v_only(recording, tmp_path):
    offset, length = _chunks(recording)[0]
    data = bytearray(recording.read_bytes())
    data[offset + length - 40 : offset + length - 8] = bytes(32)
    bad = tmp_path / "zeroed.mcap"
    bad.write_bytes(bytes(data))
    out = replay(str(bad), "-v")
    assert out.returncode == 1
    assert "Traceback" in out.stderr and "is damaged at byte" in out.stderr


def test_garbage_over_a_record_is_refused_in_one_line(recording, tmp_path):
    offset, _ = _chunks(recording)[1]
    data = bytearray(recording.read_bytes())
    data[offset : offset + 64] = bytes((200 + k) % 256 for k in range(64))
    bad = tmp_path / "garbage.mcap"
    bad.write_bytes(bytes(data))
    _one_line_refusal(replay(str(bad)), f"{bad} is damaged at byte {offset} (a record of no MCAP kind, opcode 0xc8)")


def test_a_garbled_metadata_record_is_refused_in_one_line(recording, tmp_path):
    data = bytearray(recording.read_bytes())
    at = data.index(b"usarsim", 8) - 4 - 9  # the metadata record named usarsim: its opcode
    assert data[at] == 0x0C
    data[at + 9 : at + 13] = (1 << 30).to_bytes(4, "little")  # its name's length: beyond the record
    bad = tmp_path / "garbled.mcap"
    bad.write_bytes(bytes(data))
    _one_line_refusal(replay(str(bad)), f"is damaged at byte {at} (a record that does not parse")


@pytest.mark.parametrize("cut", ["mid-chunk", "mid-header", "after-a-chunk", "zeros-after"])
def test_a_recording_cut_short_replays_what_it_holds(recording, tmp_path, cut):
    """A file cut anywhere (a copy that stopped, a full disk, blocks of zeros a file system had
    not filled when the machine stopped) is not damaged: what comes before the cut replays,
    with a warning."""
    chunks = _chunks(recording)
    offset, length = chunks[len(chunks) // 2]
    keep = {
        "mid-chunk": offset + length // 2,
        "mid-header": offset + 5,
        "after-a-chunk": offset,
        "zeros-after": offset,
    }[cut]
    part = tmp_path / f"{cut}.mcap"
    part.write_bytes(recording.read_bytes()[:keep] + (bytes(4096) if cut == "zeros-after" else b""))
    size = part.stat().st_size
    contents = read_mcap(part)
    assert not contents.complete and contents.end == offset  # the last whole record ends there
    out = replay(str(part), "--check")
    assert out.returncode == 0, out.stdout + out.stderr
    assert "Traceback" not in out.stderr
    assert re.search(rf"the recording ends at t=\d+\.\d+ s, byte {offset} of {size} \(it was not closed", out.stderr), (
        out.stderr
    )
    assert "replayed 2 connections" in out.stdout and "identical: all" in out.stdout


def test_a_closed_recording_reads_as_the_mcap_reader_reads_it(recording):
    contents = read_mcap(recording)
    with recording.open("rb") as f:
        reader = make_reader(f)
        expected = [
            (channel.topic, msg.log_time, msg.data) for _, channel, msg in reader.iter_messages(log_time_order=False)
        ]
        stats = reader.get_summary().statistics
    assert contents.complete and contents.end == contents.size == recording.stat().st_size
    assert contents.messages == expected and contents.count == stats.message_count > 100
    assert contents.end_ns == stats.message_end_time and contents.salvaged == 0
    assert read_mcap(recording, topics=[TOPIC]).messages == [m for m in expected if m[0] == TOPIC]


def test_a_file_that_is_not_mcap_is_refused_in_one_line(tmp_path):
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not an mcap file at all, " * 20)
    _one_line_refusal(replay(str(junk)), "is not an MCAP file", "usarsim serve --record")
    empty = tmp_path / "empty.mcap"
    empty.write_bytes(b"")
    _one_line_refusal(replay(str(empty)), "is empty")


def test_a_missing_file_is_refused_in_one_line(tmp_path):
    _one_line_refusal(replay(str(tmp_path / "missing.mcap")), "missing.mcap: no such file")
    _one_line_refusal(replay(str(tmp_path)), "is a folder")
