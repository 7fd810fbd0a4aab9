"""LineBuffer: splitting a client byte stream into lines (protocol.md §1)."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usarsim.protocol.framing import LineBuffer


def feed_all(buf: LineBuffer, chunks: list[bytes]) -> list[str]:
    lines: list[str] = []
    for chunk in chunks:
        lines.extend(buf.feed(chunk))
    return lines


def bytewise(data: bytes) -> list[bytes]:
    return [data[i : i + 1] for i in range(len(data))]


@pytest.mark.parametrize("terminator", [b"\r\n", b"\n\r", b"\n", b"\r", b"\r\n\r\n", b"\n\n\n", b"\r\r"])
def test_every_terminator_ends_a_line(terminator: bytes) -> None:
    data = b"GETSTARTPOSES" + terminator + b"DRIVE {Left 1} {Right 1}" + terminator
    assert LineBuffer().feed(data) == ["GETSTARTPOSES", "DRIVE {Left 1} {Right 1}"]


@pytest.mark.parametrize("terminator", [b"\r\n", b"\n\r", b"\n", b"\r"])
def test_byte_by_byte_feeding_gives_the_same_lines(terminator: bytes) -> None:
    data = terminator.join([b"INIT {ClassName USARBot.P2AT}", b"DRIVE {Left 1}", b"X"]) + terminator
    buf = LineBuffer()
    assert feed_all(buf, bytewise(data)) == ["INIT {ClassName USARBot.P2AT}", "DRIVE {Left 1}", "X"]
    assert buf.pending_bytes == 0


def test_several_commands_in_one_read_like_moast() -> None:
    data = b"GETSTARTPOSES\r\nINIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}\r\n"
    assert LineBuffer().feed(data) == [
        "GETSTARTPOSES",
        "INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}",
    ]


def test_mixed_terminators_in_one_stream() -> None:
    data = b"A\r\nB\n\rC\nD\rE\r\n"
    assert LineBuffer().feed(data) == ["A", "B", "C", "D", "E"]


def test_partial_line_is_kept_until_its_terminator() -> None:
    buf = LineBuffer()
    assert buf.feed(b"DRIVE {Le") == []
    assert buf.pending_bytes == len(b"DRIVE {Le")
    assert buf.feed(b"ft 1} {Right 1}") == []
    assert buf.feed(b"\r") == ["DRIVE {Left 1} {Right 1}"]
    assert buf.pending_bytes == 0
    # The LF of a CR LF split across reads is just an empty line.
    assert buf.feed(b"\nSTEP {Time 0.2}\r\n") == ["STEP {Time 0.2}"]


def test_empty_and_blank_lines_are_skipped() -> None:
    assert LineBuffer().feed(b"\r\n\r\n  \r\n\t\nA\r\n\r\n") == ["A"]


def test_empty_feed() -> None:
    buf = LineBuffer()
    assert buf.feed(b"") == []
    assert buf.pending_bytes == 0


def test_line_of_exactly_the_limit_is_kept_and_one_more_byte_is_dropped() -> None:
    buf = LineBuffer(max_line_bytes=10)
    assert buf.feed(b"A" * 10 + b"\n") == ["A" * 10]
    assert buf.feed(b"B" * 11 + b"\nOK\n") == ["OK"]
    assert buf.dropped_lines == 1


def test_over_long_line_in_one_read_is_dropped_and_the_next_survives() -> None:
    buf = LineBuffer(max_line_bytes=16)
    lines = buf.feed(b"DRIVE " + b"x" * 100 + b"\r\nDRIVE {Left 1}\r\n")
    assert lines == ["DRIVE {Left 1}"]
    assert buf.dropped_lines == 1
    assert buf.pending_bytes == 0


def test_over_long_line_over_many_reads_is_dropped_once_including_its_tail() -> None:
    buf = LineBuffer(max_line_bytes=24)
    data = b"SET {Params " + b"y" * 200 + b"}\r\nGETGEO {Type Robot}\r\n"
    lines = feed_all(buf, bytewise(data))
    assert lines == ["GETGEO {Type Robot}"]
    assert buf.dropped_lines == 1
    assert buf.pending_bytes == 0


def test_over_long_line_tail_is_discarded_in_chunks() -> None:
    buf = LineBuffer(max_line_bytes=8)
    assert buf.feed(b"0123456789") == []  # already longer than the limit
    assert buf.discarding
    assert buf.pending_bytes == 0  # nothing of it is kept
    assert buf.feed(b"abcdefghijkl") == []
    assert buf.feed(b"mnop\nnext\n") == ["next"]
    assert not buf.discarding
    assert buf.dropped_lines == 1


def test_dropped_lines_counter_is_monotonic() -> None:
    buf = LineBuffer(max_line_bytes=4)
    counts = []
    for chunk in [b"12345\n", b"ok\n", b"123456789", b"\n", b"abcdefgh\nxy\n"]:
        buf.feed(chunk)
        counts.append(buf.dropped_lines)
    assert counts == [1, 1, 2, 2, 3]


def test_binary_garbage_and_invalid_utf8_never_raise() -> None:
    buf = LineBuffer()
    lines = buf.feed(b"\xff\xfe\x00\x80DRIVE\xc3\x28 {Left 1}\r\n\xe2\x82\r\n")
    assert len(lines) == 2
    assert lines[0] == "\ufffd\ufffd\x00\ufffdDRIVE\ufffd( {Left 1}"
    assert lines[1] == "\ufffd\ufffd"


def test_invalid_max_line_bytes() -> None:
    with pytest.raises(ValueError, match="max_line_bytes"):
        LineBuffer(max_line_bytes=0)


@settings(max_examples=50)
@given(
    lines=st.lists(
        st.text(alphabet=st.characters(min_codepoint=32, max_codepoint=126), min_size=1, max_size=40).filter(
            lambda s: not s.isspace()
        ),
        max_size=12,
    ),
    terminator=st.sampled_from([b"\r\n", b"\n\r", b"\n", b"\r"]),
    cuts=st.lists(st.integers(min_value=0, max_value=600), max_size=10),
)
def test_any_split_of_the_stream_gives_the_same_lines(lines: list[str], terminator: bytes, cuts: list[int]) -> None:
    data = b"".join(line.encode("ascii") + terminator for line in lines)
    points = sorted({min(c, len(data)) for c in cuts} | {0, len(data)})
    chunks = [data[a:b] for a, b in zip(points, points[1:])]
    buf = LineBuffer()
    assert feed_all(buf, chunks) == lines
    assert buf.pending_bytes == 0
    assert buf.dropped_lines == 0


@settings(max_examples=50)
@given(chunks=st.lists(st.binary(max_size=64), max_size=20), limit=st.integers(1, 32))
def test_arbitrary_bytes_never_raise_and_respect_the_limit(chunks: list[bytes], limit: int) -> None:
    buf = LineBuffer(max_line_bytes=limit)
    previous_dropped = 0
    for chunk in chunks:
        for line in buf.feed(chunk):
            assert line and not line.isspace()
            assert "\r" not in line and "\n" not in line
            assert len(line) <= limit
        assert buf.dropped_lines >= previous_dropped
        previous_dropped = buf.dropped_lines
        assert buf.pending_bytes <= limit


# --------------------------------------------------------------------------- DRIVE floods

SPEEDS = "DRIVE {Left 1} {Right 1}"


def drive_buffer() -> LineBuffer:
    return LineBuffer(drop_repeated_drives=True)


def test_a_repeated_drive_is_dropped_and_counted() -> None:
    buf = drive_buffer()
    assert buf.feed(f"{SPEEDS}\r\n{SPEEDS}\r\n{SPEEDS}\r\n".encode()) == [SPEEDS]
    assert buf.repeated_drives == 2


def test_a_repeat_across_two_feeds_is_dropped() -> None:
    buf = drive_buffer()
    assert buf.feed(f"{SPEEDS}\r\n".encode()) == [SPEEDS]
    assert buf.feed(f"{SPEEDS}\r\n".encode()) == []
    assert buf.feed(b"DRIVE {Left 1} ") == []  # a repeat cut in the middle
    assert buf.feed(b"{Right 1}\r\n") == []
    assert buf.repeated_drives == 2


def test_a_drive_another_line_and_the_same_drive_are_all_kept() -> None:
    buf = drive_buffer()
    data = f"{SPEEDS}\r\nGETGEO {{Type Robot}}\r\n{SPEEDS}\r\n".encode()
    assert buf.feed(data) == [SPEEDS, "GETGEO {Type Robot}", SPEEDS]
    assert buf.repeated_drives == 0


@pytest.mark.parametrize(
    "line",
    [
        "DRIVE {Flip True}",
        "DRIVE {Name Arm} {Value 0.1} {Order 10}",
        "DRIVE {ORDER 1} {Name Arm} {Value 1}",
        "DRIVE {flip true}",
    ],
)
def test_a_drive_with_order_or_flip_is_never_dropped(line: str) -> None:
    buf = drive_buffer()
    small = feed_all(buf, [f"{line}\r\n".encode()] * 3)
    big = buf.feed(f"{line}\r\n".encode() * 1000)  # the bytes-level fast path
    assert small == [line] * 3 and big == [line] * 1000
    assert buf.repeated_drives == 0


def test_other_lines_and_other_speeds_are_never_dropped() -> None:
    buf = drive_buffer()
    lines = ["GETGEO {Type Robot}"] * 2 + [SPEEDS, "DRIVE {Left 2} {Right 2}", SPEEDS]
    assert buf.feed("".join(f"{x}\r\n" for x in lines).encode()) == lines
    assert buf.repeated_drives == 0


def test_without_the_option_nothing_is_dropped() -> None:
    assert LineBuffer().feed(f"{SPEEDS}\r\n".encode() * 3) == [SPEEDS] * 3


def test_a_flood_in_one_big_read_collapses_to_one_line() -> None:
    buf = drive_buffer()
    data = f"{SPEEDS}\r\n".encode() * 100_000 + b"DRIVE {Flip True}\r\n" * 2 + f"{SPEEDS}\n".encode() * 3
    assert buf.feed(data) == [SPEEDS, "DRIVE {Flip True}", "DRIVE {Flip True}", SPEEDS]
    assert buf.repeated_drives == 100_000 - 1 + 2


def test_a_big_read_that_begins_inside_a_line_keeps_that_line() -> None:
    """``MISPKG {Name `` held from the read before: the first ``DRIVE}`` of the next read
    ends that line, and the ``DRIVE}`` after it is a line of its own."""
    buf = drive_buffer()
    assert buf.feed(b"MISPKG {Name ") == []
    assert (
        buf.feed(b"DRIVE}\r\n" * 2 + b"GETGEO {Type Robot}\r\n" * 400)
        == ["MISPKG {Name DRIVE}", "DRIVE}"] + ["GETGEO {Type Robot}"] * 400
    )


def test_the_fast_path_gives_the_lines_of_the_line_by_line_rule() -> None:
    from usarsim.protocol.framing import REPEATED_DRIVE

    data = (
        f"{SPEEDS}\r\n".encode() * 1000
        + b"DRIVE {Flip True}\r\n" * 2
        + b"DRIVE {Name Arm} {Value 0.1} {Order 10}\r\n" * 2
        + b"MISPKG {Name DRIVE}\r\nDRIVE}\r\nDRIVE}\r\n"
    )
    assert REPEATED_DRIVE.sub(rb"\1", data) == (
        f"{SPEEDS}\r\n".encode()
        + b"DRIVE {Flip True}\r\n" * 2
        + b"DRIVE {Name Arm} {Value 0.1} {Order 10}\r\n" * 2
        + b"MISPKG {Name DRIVE}\r\nDRIVE}\r\n"
    )


def _reference(lines: list[str]) -> tuple[list[str], int]:
    """The rule line by line: a repeatable DRIVE the same as the line before it is dropped."""
    kept: list[str] = []
    for line in lines:
        if (
            kept
            and line == kept[-1]
            and line.upper().startswith("DRIVE")
            and "order" not in line.lower()
            and "flip" not in line.lower()
        ):
            continue
        kept.append(line)
    return kept, len(lines) - len(kept)


@settings(max_examples=60)
@given(
    runs=st.lists(
        st.tuples(
            st.sampled_from(
                [
                    SPEEDS,
                    "DRIVE {Left 2} {Right 2}",
                    "DRIVE {Flip True}",
                    "DRIVE {Order 1} {Value 2}",
                    "GETGEO {Type Robot}",
                    "drive {Light True}",
                ]
            ),
            st.integers(1, 300),
        ),
        max_size=8,
    ),
    terminator=st.sampled_from([b"\r\n", b"\n"]),
    cuts=st.lists(st.integers(min_value=0, max_value=40_000), max_size=6),
)
def test_any_split_of_a_flood_gives_the_lines_of_the_rule(runs, terminator: bytes, cuts: list[int]) -> None:
    lines = [line for line, n in runs for _ in range(n)]
    data = b"".join(line.encode("ascii") + terminator for line in lines)
    points = sorted({min(c, len(data)) for c in cuts} | {0, len(data)})
    buf = drive_buffer()
    got = feed_all(buf, [data[a:b] for a, b in zip(points, points[1:])])
    assert (got, buf.repeated_drives) == _reference(lines)


def test_empty_lines_are_delivered_when_asked():
    """The ground-truth port answers an empty line: it is kept, one terminator (CR LF, LF CR,
    CR or LF) a line, and a CR LF split between two reads is still one terminator."""
    buf = LineBuffer(empty_lines=True)
    assert buf.feed(b"\r\n") == [""]
    assert buf.feed(b"{Class Robot}\r\n\r\n") == ["{Class Robot}", ""]
    assert buf.feed(b"{Name a}\r") == ["{Name a}"]
    assert buf.feed(b"\n") == []  # the rest of the CR LF
    assert buf.feed(b"\n\r  \n\r") == ["", ""]  # LF CR, then a line of spaces
    assert buf.feed(b"a\nb\n\n") == ["a", "b", ""]
    # by default a run of terminators ends one line and empty lines are skipped
    assert LineBuffer().feed(b"\r\n{Class Robot}\r\n\r\n") == ["{Class Robot}"]
