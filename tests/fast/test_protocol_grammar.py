"""The generic line grammar and value parsers (protocol.md §2)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from usarsim.errors import ProtocolError
from usarsim.protocol.grammar import (
    RawMessage,
    Segment,
    format_segment,
    parse_bool,
    parse_float,
    parse_int,
    parse_line,
    parse_vector,
)


def test_type_and_segments() -> None:
    raw = parse_line("INIT {ClassName USARBot.P2AT} {Name Robot1} {Location 4.5,1.9,1.8}")
    assert raw == RawMessage(
        "INIT",
        (
            Segment("ClassName", "USARBot.P2AT"),
            Segment("Name", "Robot1"),
            Segment("Location", "4.5,1.9,1.8"),
        ),
    )


def test_type_is_upper_cased_and_keys_kept_as_written() -> None:
    raw = parse_line("Drive {left 1} {RIGHT 1}")
    assert raw.type == "DRIVE"
    assert [s.key for s in raw.segments] == ["left", "RIGHT"]


def test_type_only() -> None:
    assert parse_line("GETSTARTPOSES") == RawMessage("GETSTARTPOSES", ())
    assert parse_line("  getstartposes  ") == RawMessage("GETSTARTPOSES", ())


def test_no_space_after_type_and_between_segments() -> None:
    assert parse_line("NFO{A 1}") == RawMessage("NFO", (Segment("A", "1"),))
    raw = parse_line("NFO {StartPoses 1}{PlayerStart 1,2,3 0,0,0}")
    assert raw.segments == (
        Segment("StartPoses", "1"),
        Segment("PlayerStart", "1,2,3 0,0,0"),
    )


def test_several_spaces_and_tabs_between_segments() -> None:
    raw = parse_line("DRIVE   {Left 1}\t{Right  2 }  ")
    assert raw.segments == (Segment("Left", "1"), Segment("Right", "2"))


def test_repeated_keys_kept_in_order() -> None:
    raw = parse_line("CONF {Type Sonar} {Name F1} {MaxRange 5} {Name F2} {MaxRange 4}")
    assert raw.get_all("name") == ["F1", "F2"]
    assert raw.get_all("MAXRANGE") == ["5", "4"]
    assert raw.get("Name") == "F1"


def test_value_with_spaces_and_commas() -> None:
    raw = parse_line("SET {Type RFID} {Opcode Write} {Params 11137 hello  big world}")
    assert raw.get("params") == "11137 hello  big world"
    raw = parse_line("INIT {Location 0, 0, 0}")
    assert raw.get("Location") == "0, 0, 0"


def test_packed_segment_value() -> None:
    raw = parse_line("SEN {Type Sonar} {Name F1 Range 2.5098}")
    assert raw.segments[1] == Segment("Name", "F1 Range 2.5098")


def test_bare_segment_has_empty_value() -> None:
    raw = parse_line("SET {Opcode Zoom} {0.87} {None}")
    assert raw.segments[1:] == (Segment("0.87", ""), Segment("None", ""))


def test_get_is_case_insensitive_with_default() -> None:
    raw = parse_line("X {ClassName a}")
    assert raw.get("classname") == "a"
    assert raw.get("CLASSNAME") == "a"
    assert raw.get("missing") is None
    assert raw.get("missing", "d") == "d"
    assert raw.get_all("missing") == []
    assert raw.has("CLASSNAME") and not raw.has("Name")


@pytest.mark.parametrize(
    ("line", "fragment"),
    [
        ("", "empty line"),
        ("   \t ", "empty line"),
        ("{Left 1}", "no message type"),
        ("DRIVE {Left 1", "unclosed"),
        ("DRIVE {Left 1} {Right", "unclosed"),
        ("DRIVE {Left {1}}", "cannot nest"),
        ("DRIVE {Left 1}}", "without a matching"),
        ("DRIVE} {Left 1}", "without a matching"),
        ("DRIVE {Left 1} Right 1", "text outside braces"),
        ("DRIVE Left 1", "text outside braces"),
        ("DRIVE {Left 1} {}", "empty segment"),
        ("DRIVE {   }", "empty segment"),
    ],
)
def test_malformed_lines(line: str, fragment: str) -> None:
    with pytest.raises(ProtocolError, match=fragment):
        parse_line(line)


def test_error_message_names_the_type() -> None:
    with pytest.raises(ProtocolError, match="^DRIVE: "):
        parse_line("DRIVE {Left 1")


def test_format_segment() -> None:
    assert format_segment("Name", "F1") == "{Name F1}"
    assert format_segment("On", "") == "{On}"


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("1,2,3", (1.0, 2.0, 3.0)),
        ("1, 2, 3", (1.0, 2.0, 3.0)),
        ("1 ,2 , 3", (1.0, 2.0, 3.0)),
        ("1.5 1.0 0.2", (1.5, 1.0, 0.2)),
        ("  -0.5,\t2e-3,  .25 ", (-0.5, 0.002, 0.25)),
    ],
)
def test_parse_vector_separators(text: str, expected: tuple[float, ...]) -> None:
    assert parse_vector(text) == expected


@pytest.mark.parametrize("text", ["1,2", "1,2,3,4", "1,,2", "1,2,", "", "a,b,c", "1;2;3"])
def test_parse_vector_rejects(text: str) -> None:
    with pytest.raises(ProtocolError, match="3 numbers"):
        parse_vector(text)


def test_parse_vector_any_count() -> None:
    assert parse_vector("1,2", n=2) == (1.0, 2.0)
    assert parse_vector("1,2,3,4,5", n=None) == (1.0, 2.0, 3.0, 4.0, 5.0)
    with pytest.raises(ProtocolError):
        parse_vector("", n=None)


@pytest.mark.parametrize(
    ("text", "expected"),
    [("1", 1.0), ("-2.5", -2.5), ("+.5", 0.5), ("3.", 3.0), ("1e-3", 0.001), (" 4 ", 4.0)],
)
def test_parse_float(text: str, expected: float) -> None:
    assert parse_float(text) == expected


def test_parse_float_returns_non_finite_values() -> None:
    assert math.isnan(parse_float("NaN"))
    assert parse_float("inf") == math.inf
    assert parse_float("-Infinity") == -math.inf


@pytest.mark.parametrize("text", ["", "abc", "1_000", "0x10", "1.2.3", "\u0661", "1,5", "--1"])
def test_parse_float_rejects(text: str) -> None:
    with pytest.raises(ProtocolError, match="expected a number"):
        parse_float(text)


@pytest.mark.parametrize(("text", "expected"), [("0", 0), ("-331", -331), ("+7", 7), ("2.0", 2), ("1e3", 1000)])
def test_parse_int(text: str, expected: int) -> None:
    assert parse_int(text) == expected


@pytest.mark.parametrize("text", ["", "1.5", "x", "nan", "inf", "9" * 5000, "1e400"])
def test_parse_int_rejects(text: str) -> None:
    with pytest.raises(ProtocolError, match="integer"):
        parse_int(text)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("True", True),
        ("true", True),
        ("TRUE", True),
        ("1", True),
        ("False", False),
        ("false", False),
        ("fAlSe", False),
        ("0", False),
    ],
)
def test_parse_bool(text: str, expected: bool) -> None:
    assert parse_bool(text) is expected


@pytest.mark.parametrize("text", ["", "yes", "2", "T", "on"])
def test_parse_bool_rejects(text: str) -> None:
    with pytest.raises(ProtocolError, match="boolean"):
        parse_bool(text)


_word = st.text(
    alphabet=st.characters(min_codepoint=33, max_codepoint=126, blacklist_characters="{}"),
    min_size=1,
    max_size=12,
)
_value = st.text(
    alphabet=st.characters(min_codepoint=32, max_codepoint=126, blacklist_characters="{}"),
    max_size=20,
).map(str.strip)


@given(
    msg_type=_word,
    segments=st.lists(st.tuples(_word, _value), max_size=8),
    gap=st.sampled_from(["", " ", "  ", "\t"]),
)
def test_formatted_segments_parse_back(msg_type: str, segments: list[tuple[str, str]], gap: str) -> None:
    line = msg_type + gap + gap.join(format_segment(k, v) for k, v in segments)
    raw = parse_line(line)
    assert raw.type == msg_type.upper()
    assert raw.segments == tuple(Segment(k, v) for k, v in segments)


@given(st.text(alphabet=st.sampled_from(list("AB {}\t,.1x")), max_size=40) | st.text(max_size=40))
def test_parse_line_raises_only_protocol_error(text: str) -> None:
    try:
        raw = parse_line(text)
    except ProtocolError:
        return
    assert raw.type
    for seg in raw.segments:
        assert seg.key and "{" not in seg.key and "}" not in seg.key
