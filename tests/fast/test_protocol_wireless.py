"""The wireless protocols (protocol.md 12) sans-IO: the ComServer's commands, replies and
SEND framing, the WSS's requests and replies, the ComServerInterface's: exact strings as
the servers send them, round trips, and fuzzing that shows bad input raises nothing but
ProtocolError and that no SEND is delivered in part."""

from __future__ import annotations

import itertools
import math
import subprocess
import sys

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from usarsim.errors import ProtocolError
from usarsim.protocol import wireless as w
from usarsim.protocol.grammar import Segment

# --------------------------------------------------------------------------- strategies

WORD = st.from_regex(r"[A-Za-z0-9_.\-]{1,12}", fullmatch=True)
# a value of a {Key value} segment: words, blanks inside only
VALUE = st.from_regex(r"[A-Za-z0-9_.,\-]([A-Za-z0-9_.,\- ]{0,10}[A-Za-z0-9_.,\-])?", fullmatch=True)
PORT = st.integers(1, 65535)
CENTI_DBM = st.integers(-20_000, 2_000).map(lambda n: n / 100)  # what "%.2f" reads back exactly
SIX_DIGITS = st.floats(-1e6, 1e6, allow_nan=False).map(lambda x: float(f"{x:.6g}"))
METRES = st.integers(-(10**7), 10**7).map(lambda n: n / 10_000)  # what vec4 reads back exactly
REASON = st.from_regex(r"[A-Za-z][A-Za-z.]{0,30}", fullmatch=True)

WCS_REQUESTS = st.one_of(
    st.builds(w.WcsRegister, WORD, WORD),
    st.builds(w.WcsListen, WORD, PORT),
    st.builds(w.WcsOpen, WORD, PORT, WORD, PORT),
    st.builds(w.WcsGetSS, WORD, WORD),
    # an unknown first word (not one of the four), words after it
    st.builds(lambda a, rest: w.WcsUnknown(" ".join(["X" + a, *rest])), WORD, st.lists(WORD, max_size=3)),
)
WCS_REPLIES = st.one_of(st.just(w.WcsOk()), st.builds(w.WcsSignal, CENTI_DBM), st.builds(w.WcsFail, VALUE))
UPPER_WORD = st.from_regex(r"X[A-Z0-9]{0,8}", fullmatch=True)  # never a known request word
SEGMENTS = st.lists(st.builds(Segment, WORD, st.one_of(st.just(""), VALUE)), max_size=3).map(tuple)
WSS_REQUESTS = st.one_of(
    st.builds(w.WssInit, VALUE, st.lists(st.integers(0, 65535), max_size=4).map(tuple)),  # 0: not listening
    st.builds(w.WssGetSS, VALUE),
    st.builds(w.WssDns, VALUE, st.one_of(st.none(), PORT)),
    st.builds(w.WssReverseDns, PORT),
    st.builds(w.WssUnknown, UPPER_WORD, SEGMENTS),
)
OPTIONAL_REASON = st.one_of(st.none(), REASON)
WSS_REPLIES = st.one_of(
    st.builds(w.WssInitReply, WORD),
    st.builds(w.WssSignal, VALUE, SIX_DIGITS, OPTIONAL_REASON),
    st.builds(w.WssDnsReply, VALUE, st.integers(-1, 65535), OPTIONAL_REASON),
    st.builds(w.WssReverseDnsReply, PORT, st.one_of(st.none(), VALUE), OPTIONAL_REASON),
    st.builds(w.WssError, REASON),
)
GETOBS = st.one_of(st.builds(w.GetObsRobots, VALUE, VALUE), st.builds(w.GetObsPoints, VALUE, VALUE))
INTERFACE_REQUESTS = st.one_of(
    st.just(w.GetPos()), GETOBS, st.just(w.GetObsIncomplete()), st.builds(w.InterfaceUnknown, UPPER_WORD, SEGMENTS)
)
INTERFACE_REPLIES = st.one_of(
    st.builds(
        w.Positions,
        st.lists(st.builds(w.RobotPosition, WORD, st.tuples(METRES, METRES, METRES), st.booleans()), max_size=5).map(
            tuple
        ),
    ),
    st.builds(w.NumObs, st.integers(-1, 100), st.one_of(st.none(), GETOBS)),
)


def split_all(data: bytes, sizes) -> list[bytes]:
    """``data`` cut into pieces of the given sizes (cycled), for feeding in chunks."""
    out, i = [], 0
    for n in itertools.cycle(sizes):
        if i >= len(data):
            return out
        out.append(data[i : i + n])
        i += n
    return out


# --------------------------------------------------------------------------- ComServer commands

WCS_LINES = [
    ("REGISTER A0 127.0.0.1", w.WcsRegister("A0", "127.0.0.1")),
    ("LISTEN B0 4000", w.WcsListen("B0", 4000)),
    ("OPEN A0 4001 B0 4000", w.WcsOpen("A0", 4001, "B0", 4000)),
    ("GETSS A6 B6", w.WcsGetSS("A6", "B6")),
    ("HELLO again", w.WcsUnknown("HELLO again")),
]


@pytest.mark.parametrize("text, cmd", WCS_LINES)
def test_comserver_commands_parse_and_format_exactly(text, cmd):
    assert w.parse_wcs_request(text) == cmd
    assert w.format_wcs_request(cmd) == text + ";"


@pytest.mark.parametrize(
    "text, cmd",
    [
        ("register A0 10.0.0.1", w.WcsRegister("A0", "10.0.0.1")),  # the word in any case
        ("  Listen\tB0  0400 ", w.WcsListen("B0", 400)),
        (" \xff\xfe\x00", w.WcsUnknown("\xff\xfe\x00")),
    ],
)
def test_comserver_commands_are_read_as_robots_write_them(text, cmd):
    assert w.parse_wcs_request(text) == cmd


@pytest.mark.parametrize(
    "text",
    [
        "OPEN A0 1",
        "register A0",
        "GETSS A0",
        "LISTEN A0 port",
        "LISTEN A0 0",
        "OPEN A0 1 B0 99999",
        "LISTEN A0 \u00b2",
        "LISTEN A0 -5",
        "REGISTER a b c",
        " ",
        "",
    ],
)
def test_malformed_comserver_commands_raise_protocol_error(text):
    with pytest.raises(ProtocolError):
        w.parse_wcs_request(text)


def test_the_command_word_names_a_kind_of_bad_command():
    assert w.wcs_request_word(" open A0 1") == "OPEN" and w.wcs_request_word("  ") == ""


@pytest.mark.parametrize(
    "cmd",
    [
        w.WcsRegister("A 0", "ip"),
        w.WcsRegister("A;", "ip"),
        w.WcsListen("A", 0),
        w.WcsOpen("A", 1, "", 2),
        w.WcsUnknown("X;Y"),
        w.WcsUnknown(" "),
    ],
)
def test_commands_that_cannot_be_read_back_are_not_formatted(cmd):
    with pytest.raises(ProtocolError):
        w.format_wcs_request(cmd)


@given(WCS_REQUESTS, st.lists(st.integers(1, 9), min_size=1, max_size=4))
def test_comserver_commands_round_trip_through_the_splitter(cmd, sizes):
    splitter = w.CommandSplitter()
    data = w.format_wcs_request(cmd).encode()
    texts = [t for chunk in split_all(data, sizes) for t in splitter.feed(chunk)]
    assert [w.parse_wcs_request(t) for t in texts] == [cmd]


# --------------------------------------------------------------------------- ComServer replies

WCS_REPLY_TEXTS = [
    (w.WcsOk(), "OK;"),
    (w.WcsSignal(-60.57), "OK:-60.57;"),
    (w.WcsSignal(-97.6249), "OK:-97.62;"),
    (w.WcsSignal(-0.001), "OK:0.00;"),  # never -0.00
    (w.WcsSignal(0.0), "OK:0.00;"),
    (w.FAIL_UNKNOWN_MESSAGE, "Fail: Unknown Message;"),
    (w.FAIL_INCORRECT_MESSAGE, "Fail: Incorrect Message;"),
    (w.FAIL_TOO_MANY_REGISTERED, "Fail: Too many robots registered;"),
    (w.FAIL_TOO_MANY_LISTENING, "Fail: Too many robots listening;"),
    (w.FAIL_NO_CONNECTION, "Fail: Could not establish connection;"),
    (w.FAIL_THIRD_PARTY, "Fail: Server does not accept third party requests;"),
    (w.FAIL_NO_SIGNAL, "Fail: Could not calculate signal strength;"),
    (w.WcsFail.already_registered("A0"), "Fail: Robot with name A0 already registered;"),
    (w.WcsFail.not_registered("Nobody"), "Fail: Robot Nobody not registered;"),
    (w.WcsFail.already_listening("B0", 7), "Fail: Robot with name B0 already listening at port 7;"),
    (w.WcsFail.not_listening("B0", 2), "Fail: B0 not listening on port 2;"),
    (w.WcsFail.cannot_connect("B6"), "Fail: Cannot connect to B6;"),
]


@pytest.mark.parametrize("reply, text", WCS_REPLY_TEXTS)
def test_comserver_replies_are_the_servers_exact_words(reply, text):
    assert w.format_wcs_reply(reply) == text
    assert w.format_wcs_reply(w.parse_wcs_reply(text)) == text


def test_comserver_dbm_has_two_decimals():
    assert [w.fmt_wcs_dbm(x) for x in (-60.5749, -60.575001, -0.004, 3.0)] == ["-60.57", "-60.58", "0.00", "3.00"]


@given(WCS_REPLIES)
def test_comserver_replies_round_trip(reply):
    assert w.parse_wcs_reply(w.format_wcs_reply(reply)) == reply


@pytest.mark.parametrize("text", ["", "OK:", "OK:abc;", "Ok;", "FAIL: x;", "Done;"])
def test_what_is_not_a_comserver_reply_raises_protocol_error(text):
    with pytest.raises(ProtocolError):
        w.parse_wcs_reply(text)


# --------------------------------------------------------------------------- the command splitter


def test_the_splitter_skips_blank_commands_and_keeps_partial_ones():
    s = w.CommandSplitter()
    assert s.feed(b"; HELLO;;  ;REGISTER A0 ") == [" HELLO"]
    assert s.pending_bytes == len(b"REGISTER A0 ")
    assert s.feed(b"1.2.3.4;GET") == ["REGISTER A0 1.2.3.4"]
    assert s.feed(b"SS A B;") == ["GETSS A B"]


@pytest.mark.parametrize("sizes", [[1], [7], [300], [5000]])
def test_an_over_long_command_is_dropped_whole_in_any_split(sizes):
    s = w.CommandSplitter(max_bytes=100)
    data = b"x" * 250 + b";OK 1;" + b"y" * 101 + b";" + b"z" * 100 + b";"
    out = [t for chunk in split_all(data, sizes) for t in s.feed(chunk)]
    assert out == ["OK 1", "z" * 100] and s.dropped_commands == 2
    s.feed(b"q" * 10_000)
    assert s.pending_bytes == 0 and s.dropped_commands == 3  # held bytes stay bounded


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=600), st.lists(st.integers(1, 64), min_size=1, max_size=5))
def test_any_bytes_split_into_bounded_commands_that_parse_or_raise_protocol_error(data, sizes):
    whole = w.CommandSplitter(max_bytes=64)
    chunked = w.CommandSplitter(max_bytes=64)
    out = whole.feed(data)
    assert [t for chunk in split_all(data, sizes) for t in chunked.feed(chunk)] == out
    for text in out:
        assert len(text) <= 64 and ";" not in text and text.split()
        try:
            cmd = w.parse_wcs_request(text)
        except ProtocolError:
            continue
        assert isinstance(cmd, (w.WcsRegister, w.WcsListen, w.WcsOpen, w.WcsGetSS, w.WcsUnknown))


@settings(max_examples=300, deadline=None)
@given(st.text(max_size=120))
def test_any_text_is_a_comserver_command_reply_or_protocol_error(text):
    for parse in (w.parse_wcs_request, w.parse_wcs_reply):
        try:
            parse(text)
        except ProtocolError:
            pass


# --------------------------------------------------------------------------- SEND framing


def feed_all(parser: w.SendParser, data: bytes, sizes) -> list:
    return [ev for chunk in split_all(data, sizes) for ev in parser.feed(chunk)]


def test_send_frames_are_formatted_binary_safe():
    assert w.format_send(b"a;\r\n") == b"SEND 4 a;\r\n;" and w.CLOSE_FRAME == b"CLOSE;"
    assert w.SendParser().feed(w.format_send(b"a;\r\n") + w.CLOSE_FRAME) == [b"a;\r\n", w.SendParser.CLOSE]


def test_dropped_frames_say_why_and_their_kind():
    out = w.SendParser(max_bytes=10).feed(b"HELLO;SEND x;SEND 11 y;SEND 3 abcd;CLOSE x;")
    assert [(p.kind, str(p)) for p in out] == [
        ("unknown", "unknown message b'HELLO'..."),
        ("no-length", "SEND without a length"),
        ("too-long", "SEND of 11 bytes, more than 10"),
        ("wrong-length", "SEND of 3 bytes not followed by ';' (a wrong length)"),
        ("close", "CLOSE not followed by ';'"),
    ]
    assert all(isinstance(p, w.SendProblem) and isinstance(p, str) for p in out)


SEPARATORS = st.sampled_from([b"", b" ", b"\r\n", b" \t "])


@given(
    st.lists(st.tuples(st.binary(max_size=40), SEPARATORS), max_size=6),
    st.booleans(),
    st.lists(st.integers(1, 17), min_size=1, max_size=4),
)
def test_send_frames_round_trip_in_any_split(frames, close, sizes):
    data = b"".join(sep + w.format_send(p) for p, sep in frames) + (w.CLOSE_FRAME if close else b"")
    parser = w.SendParser()
    assert feed_all(parser, data, sizes) == [p for p, _ in frames] + ([w.SendParser.CLOSE] if close else [])
    assert not parser.partial


@given(st.lists(st.tuples(st.binary(max_size=40), SEPARATORS), min_size=1, max_size=6), st.data())
def test_a_stream_cut_anywhere_delivers_only_whole_messages(frames, data):
    """The end of a connection in the middle of a frame: every message before it is
    delivered, the cut one never, and the parser says a frame was begun."""
    stream, spans = b"", []
    for payload, sep in frames:
        stream += sep
        start = len(stream)
        stream += w.format_send(payload)
        spans.append((start, len(stream), payload))
    cut = data.draw(st.integers(0, len(stream)), label="cut")
    parser = w.SendParser()
    got = feed_all(parser, stream[:cut], data.draw(st.lists(st.integers(1, 13), min_size=1, max_size=3)))
    assert got == [p for s, e, p in spans if e <= cut]
    assert parser.partial == any(s < cut < e for s, e, _ in spans)


@given(st.binary(max_size=60).filter(lambda b: b";" not in b), st.lists(st.binary(max_size=20), max_size=4))
def test_after_garbage_the_stream_recovers_at_the_next_semicolon(garbage, payloads):
    data = b"X" + garbage + b";" + b"".join(w.format_send(p) for p in payloads)
    out = w.SendParser().feed(data)
    assert isinstance(out[0], w.SendProblem) and out[1:] == payloads


@settings(max_examples=300, deadline=None)
@given(
    st.lists(
        st.one_of(
            st.sampled_from(
                [b"SEND ", b"CLOSE", b";", b" ", b"\r\n", b"12 ", b"3 ", b"0 ", b"99999999999 ", b"SEN", b"CLO"]
            ),
            st.binary(max_size=12),
        ),
        max_size=30,
    ),
    st.lists(st.integers(1, 11), min_size=1, max_size=4),
)
def test_any_bytes_give_the_same_events_in_any_split_and_never_raise(parts, sizes):
    """(A dropped frame's text quotes what had arrived of it; its kind does not vary.)"""
    data = b"".join(parts)
    whole = w.SendParser(max_bytes=20).feed(data)

    def kinds(events):
        return [(ev.kind,) if isinstance(ev, w.SendProblem) else ev for ev in events]

    assert kinds(feed_all(w.SendParser(max_bytes=20), data, sizes)) == kinds(whole)
    for ev in whole:
        assert isinstance(ev, (bytes, w.SendClose, w.SendProblem))
        if isinstance(ev, bytes):
            assert len(ev) <= 20


# --------------------------------------------------------------------------- WSS requests

WSS_LINES = [
    ("INIT {Robot A0} {Port 5,6}", w.WssInit("A0", (5, 6))),
    ("INIT {Robot A0}", w.WssInit("A0")),
    ("GETSS {Robot B5}", w.WssGetSS("B5")),
    ("DNS {Robot B0}", w.WssDns("B0")),
    ("DNS {Robot B0} {Port 4000}", w.WssDns("B0", 4000)),
    ("REVERSEDNS {Port 50123}", w.WssReverseDns(50123)),
    ("FLY {To Moon} {Now}", w.WssUnknown("FLY", (Segment("To", "Moon"), Segment("Now", "")))),
]


@pytest.mark.parametrize("line, req", WSS_LINES)
def test_wss_requests_parse_and_format_exactly(line, req):
    assert w.parse_wss_request(line + "\r\n") == req
    assert w.format_wss_request(req) == line + "\r\n"


@pytest.mark.parametrize(
    "line, req",
    [
        ("init {robot A0} {port 5, 6 ,7}", w.WssInit("A0", (5, 6, 7))),
        ("INIT {Robot A0} {Port 5,,6,}", w.WssInit("A0", (5, 6))),
        # the reference WSS reads INIT's list as unsigned integers: 0 is accepted (protocol.md 12.2)
        ("INIT {Robot r} {Port 0}", w.WssInit("r", (0,))),
        ("INIT {Robot r} {Port 0,5}", w.WssInit("r", (0, 5))),
        ("INIT {Robot r} {Port 65536}", w.WssInvalid("INIT", w.REASON_PORTS_NOT_INTEGER)),
        ("INIT {Robot r} {Port -1}", w.WssInvalid("INIT", w.REASON_PORTS_NOT_INTEGER)),
        ("DNS {Robot B0} {Port 0}", w.WssDns("B0")),  # 0: the default port, as the reference reads it
        ("INIT {Robot H1} {Port a,b}", w.WssInvalid("INIT", w.REASON_PORTS_NOT_INTEGER)),
        ("INIT {Robot} {Port 1}", w.WssInvalid("INIT", w.REASON_EMPTY_NAME)),
        ("INIT {Port x}", w.WssInvalid("INIT", w.REASON_PORTS_NOT_INTEGER)),  # the ports are checked first
        ("GETSS {Robot}", w.WssInvalid("GETSS", w.REASON_EMPTY_NAME)),
        ("GETSS", w.WssInvalid("GETSS", w.REASON_EMPTY_NAME)),
        ("DNS {Robot H2} {Port x}", w.WssInvalid("DNS", w.REASON_PORT_NOT_INTEGER)),
        ("DNS {Port 0}", w.WssInvalid("DNS", w.REASON_EMPTY_NAME)),  # port 0 is valid (the default)
        ("DNS {Port 7}", w.WssInvalid("DNS", w.REASON_EMPTY_NAME)),
        ("REVERSEDNS {Port -3}", w.WssInvalid("REVERSEDNS", w.REASON_PORT_NOT_INTEGER)),
        ("REVERSEDNS", w.WssInvalid("REVERSEDNS", w.REASON_PORT_NOT_INTEGER)),
    ],
)
def test_wss_requests_with_bad_values_name_the_wss_error(line, req):
    assert w.parse_wss_request(line) == req


@pytest.mark.parametrize("line", ["INIT {Robot", "}}{{ \x01", "", "GETSS {Robot {B}}"])
def test_malformed_wss_lines_raise_protocol_error(line):
    with pytest.raises(ProtocolError):
        w.parse_wss_request(line)


@pytest.mark.parametrize(
    "req",
    [
        w.WssGetSS("a}"),
        w.WssGetSS(" a"),
        w.WssDns("", 5),
        w.WssInit("A", (70000,)),
        w.WssReverseDns(70000),
        w.WssUnknown("A B"),
    ],
)
def test_wss_requests_that_cannot_be_read_back_are_not_formatted(req):
    with pytest.raises(ProtocolError):
        w.format_wss_request(req)
    with pytest.raises(TypeError):
        w.format_wss_request(w.WssInvalid("INIT", w.REASON_EMPTY_NAME))


@given(WSS_REQUESTS)
def test_wss_requests_round_trip(req):
    assert w.parse_wss_request(w.format_wss_request(req)) == req


# --------------------------------------------------------------------------- WSS replies

WSS_REPLY_TEXTS = [
    (w.WssInitReply(), "INITREPLY {Status OK}"),
    (w.WssSignal("B5", -73.1234567), "SS {Robot B5} {Strength -73.1235}"),
    (w.WssSignal("B6", -93.7), "SS {Robot B6} {Strength -93.7}"),
    (w.WssSignal("A0", math.inf, w.SS_TO_SELF), "SS {Robot A0} {Strength INF} {Error SS.To.Self}"),
    (w.WssSignal("B5", math.nan, w.SS_NO_ROBOT), "SS {Robot B5} {Strength NaN} {Error Robot.Does.Not.Exist}"),
    (w.WssSignal("H2", math.nan, w.SS_MODEL_NAN), "SS {Robot H2} {Strength NaN} {Error Model.Returned.NaN}"),
    (w.WssDnsReply("B0", 40123), "DNSREPLY {Robot B0} {Port 40123}"),
    (w.WssDnsReply("Nobody", -1, w.DNS_NO_ROBOT), "DNSREPLY {Robot Nobody} {Port -1} {Error NoSuchRobot}"),
    (
        w.WssDnsReply("H2", -1, w.DNS_NOT_LISTENING),
        "DNSREPLY {Robot H2} {Port -1} {Error RobotDoesNotListenOnThisPort}",
    ),
    (w.WssReverseDnsReply(40123, robot="A0"), "REVERSEDNSREPLY {Port 40123} {Robot A0}"),
    (w.WssReverseDnsReply(1, error=w.REVERSEDNS_UNKNOWN_PORT), "REVERSEDNSREPLY {Port 1} {Error UnknownOrIllegalPort}"),
    (w.WssError(w.REASON_INIT_FIRST), "ERROR {Reason Must.Use.INIT.Method.First}"),
    (w.WssError(w.REASON_PORTS_NOT_INTEGER), "ERROR {Reason Ports.List.Must.Be.Integer}"),
    (w.WssError(w.REASON_EMPTY_NAME), "ERROR {Reason Robot.Name.Must.Not.Be.Empty}"),
    (w.WssError(w.REASON_ROBOT_EXISTS), "ERROR {Reason Robot.Alread.Exists}"),
    (w.WssError(w.REASON_PORT_NOT_INTEGER), "ERROR {Reason Port.Must.Be.Integer}"),
    (w.WssError(w.REASON_NO_RELAY_PORT), "ERROR {Reason Could.Not.Allocate.Port}"),
    (w.WssError(w.REASON_UNKNOWN_METHOD), "ERROR {Reason Method.Unknown.Or.Can.INIT.only.once}"),
]


@pytest.mark.parametrize("reply, line", WSS_REPLY_TEXTS)
def test_wss_replies_are_the_servers_exact_words(reply, line):
    assert w.format_wss_reply(reply) == line + "\r\n"
    assert w.format_wss_reply(w.parse_wss_reply(line)) == line + "\r\n"


def test_wss_strength_has_six_significant_digits():
    assert [w.fmt_wss_dbm(x) for x in (-73.1234567, -60.0, -0.0001234567, -1234567.0, math.nan, -math.inf)] == [
        "-73.1235",
        "-60",
        "-0.000123457",
        "-1.23457e+06",
        "NaN",
        "-INF",
    ]


@given(WSS_REPLIES)
def test_wss_replies_round_trip(reply):
    assert w.parse_wss_reply(w.format_wss_reply(reply)) == reply


@pytest.mark.parametrize(
    "line",
    [
        "SS {Robot A}",
        "DNSREPLY {Robot A} {Port x}",
        "INITREPLY",
        "ERROR {Why x}",
        "HELLO {A 1}",
        "REVERSEDNSREPLY {Robot A}",
        "SS {Robot A} {Strength loud}",
    ],
)
def test_what_is_not_a_wss_reply_raises_protocol_error(line):
    with pytest.raises(ProtocolError):
        w.parse_wss_reply(line)


# --------------------------------------------------------------------------- ComServerInterface

INTERFACE_LINES = [
    ("GETPOS", w.GetPos()),
    ("GETOBS {From A0} {To B0}", w.GetObsRobots("A0", "B0")),
    ("GETOBS {Start -9,10,-1} {End 9,10,-1}", w.GetObsPoints("-9,10,-1", "9,10,-1")),
    ("GETOBS", w.GetObsIncomplete()),
    ("FLY {To Moon}", w.InterfaceUnknown("FLY", (Segment("To", "Moon"),))),
]


@pytest.mark.parametrize("line, req", INTERFACE_LINES)
def test_interface_requests_parse_and_format_exactly(line, req):
    assert w.parse_interface_request(line + "\r\n") == req
    assert w.format_interface_request(req) == line + "\r\n"


@pytest.mark.parametrize(
    "line, req",
    [
        ("getobs {from A0} {to B0} {Start 1,2,3} {End 4,5,6}", w.GetObsRobots("A0", "B0")),  # From/To wins
        ("GETOBS {From A0} {Start 1,2,3} {End 4,5,6}", w.GetObsPoints("1,2,3", "4,5,6")),
        ("GETOBS {From A0} {To}", w.GetObsIncomplete()),
        ("GETOBS {Start 1,2}", w.GetObsIncomplete()),
    ],
)
def test_getobs_takes_the_first_complete_pair(line, req):
    assert w.parse_interface_request(line) == req


def test_getobs_points_are_read_only_when_asked():
    assert w.GetObsPoints("1, 2, 3", "4 5 6").points() == ((1.0, 2.0, 3.0), (4.0, 5.0, 6.0))
    for start, end in [("1,2", "1,2,3"), ("1,2,nan", "1,2,3"), ("a,b,c", "1,2,3"), ("1,2,3", "1e999,0,0")]:
        with pytest.raises(ProtocolError):
            w.GetObsPoints(start, end).points()


@pytest.mark.parametrize("line", ["}{ garbage", "", "GETOBS {From A0"])
def test_malformed_interface_lines_raise_protocol_error(line):
    with pytest.raises(ProtocolError):
        w.parse_interface_request(line)


INTERFACE_REPLY_TEXTS = [
    (w.Positions(), "POSITIONS {Robots 0}"),
    (
        w.Positions((w.RobotPosition("A0", (-10.0, 0.004, -0.00001)), w.RobotPosition("B0", (10.0, 0.0, -0.6), True))),
        (
            "POSITIONS {Robots 2} {Name A0 Location -10.0000,0.0040,0.0000 BatteryEmpty False} "
            "{Name B0 Location 10.0000,0.0000,-0.6000 BatteryEmpty True}"
        ),
    ),
    (w.NumObs(6, w.GetObsRobots("A6", "B6")), "NUMOBS {From A6} {To B6} {ObstCount 6}"),
    (w.NumObs(-1, w.GetObsPoints("1,2", "1,2,3")), "NUMOBS {Start 1,2} {End 1,2,3} {ObstCount -1}"),
    (w.NumObs(-1), "NUMOBS {ObstCount -1}"),
]


@pytest.mark.parametrize("reply, line", INTERFACE_REPLY_TEXTS)
def test_interface_replies_are_the_servers_exact_words(reply, line):
    assert w.format_interface_reply(reply) == line + "\r\n"
    assert w.format_interface_reply(w.parse_interface_reply(line)) == line + "\r\n"


@given(INTERFACE_REQUESTS)
def test_interface_requests_round_trip(req):
    assert w.parse_interface_request(w.format_interface_request(req)) == req


@given(INTERFACE_REPLIES)
def test_interface_replies_round_trip(reply):
    assert w.parse_interface_reply(w.format_interface_reply(reply)) == reply


@pytest.mark.parametrize(
    "line",
    [
        "POSITIONS {Robots 2} {Name A Location 1,2,3 BatteryEmpty False}",
        "POSITIONS {Name A Location 1,2,3 BatteryEmpty False}",
        "POSITIONS {Robots 1} {Name A Location 1,2 BatteryEmpty False}",
        "POSITIONS {Robots 1} {Name A At 1,2,3}",
        "NUMOBS {From A} {To B}",
        "NUMOBS {ObstCount many}",
        "STA {Time 1}",
    ],
)
def test_what_is_not_an_interface_reply_raises_protocol_error(line):
    with pytest.raises(ProtocolError):
        w.parse_interface_reply(line)


# --------------------------------------------------------------------------- fuzz: lines

TOKENS = [
    "INIT",
    "GETSS",
    "DNS",
    "REVERSEDNS",
    "GETPOS",
    "GETOBS",
    "SS",
    "DNSREPLY",
    "REVERSEDNSREPLY",
    "ERROR",
    "INITREPLY",
    "POSITIONS",
    "NUMOBS",
    "{Robot A0}",
    "{Port 5,6}",
    "{Port x}",
    "{Port 99999}",
    "{Port -1}",
    "{From A}",
    "{To B}",
    "{Start 1,2,3}",
    "{End 1e999,nan,2}",
    "{Strength NaN}",
    "{Strength INF}",
    "{Error x}",
    "{Status OK}",
    "{Robots 1}",
    "{Name A Location 1,2,3 BatteryEmpty False}",
    "{ObstCount 3}",
    "{Reason R}",
    "{",
    "}",
    "{}",
    "{Robot}",
    "\x00",
    "\ufffd",
    " ",
    "9" * 30,
]


@settings(max_examples=500, deadline=None)
@given(st.one_of(st.text(max_size=200), st.lists(st.sampled_from(TOKENS), max_size=10).map(" ".join)))
def test_any_line_is_a_request_reply_or_protocol_error(line):
    parsers = (w.parse_wss_request, w.parse_wss_reply, w.parse_interface_request, w.parse_interface_reply)
    for parse in parsers:
        try:
            parsed = parse(line)
        except ProtocolError:
            continue
        if isinstance(parsed, w.GetObsPoints):
            try:
                parsed.points()
            except ProtocolError:
                pass


@given(st.lists(st.sampled_from(TOKENS), min_size=1, max_size=8).map(" ".join))
def test_parsed_requests_format_back_to_lines_that_parse_the_same(line):
    """What a server parsed, a client can send again (known requests, canonical form)."""
    for parse, fmt in (
        (w.parse_wss_request, w.format_wss_request),
        (w.parse_interface_request, w.format_interface_request),
    ):
        try:
            req = parse(line)
        except ProtocolError:
            continue
        assume(not isinstance(req, (w.WssUnknown, w.WssInvalid, w.InterfaceUnknown)))
        assert parse(fmt(req)) == req


# --------------------------------------------------------------------------- layering


def test_the_wireless_protocols_import_no_asyncio_numpy_simulation_or_server():
    code = (
        "import sys, usarsim.protocol.wireless\n"
        "print(','.join(sorted(m for m in sys.modules if m.split('.')[0] in {'asyncio', 'numpy', 'mujoco'}"
        " or m.startswith(('usarsim.sim', 'usarsim.server', 'usarsim.config')))))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=False)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == ""


def test_getneighbors_and_its_reply_round_trip():
    from usarsim.protocol.wireless import (
        Neighbor,
        WcsFail,
        WcsGetNeighbors,
        WcsNeighbors,
        format_wcs_reply,
        format_wcs_request,
        parse_wcs_neighbors,
        parse_wcs_request,
    )

    assert parse_wcs_request("getneighbors R1") == WcsGetNeighbors("R1")
    assert format_wcs_request(WcsGetNeighbors("R1")) == "GETNEIGHBORS R1;"
    reply = WcsNeighbors((Neighbor("B0", -60.5749, 0.99249), Neighbor("C", -92.996, 0.0801)))
    text = format_wcs_reply(reply)
    assert text == "OK:B0 -60.57 0.992 C -93.00 0.080;"
    assert parse_wcs_neighbors(text) == WcsNeighbors((Neighbor("B0", -60.57, 0.992), Neighbor("C", -93.0, 0.08)))
    assert format_wcs_reply(WcsNeighbors(())) == "OK:;"
    assert parse_wcs_neighbors("OK:;") == WcsNeighbors(())
    assert parse_wcs_neighbors("Fail: Robot X not registered;") == WcsFail("Robot X not registered")
    for bad in ("OK:B0 -60.57;", "OK:B0 x 0.5;", "NEIGHBORS;", ""):
        with pytest.raises(ProtocolError):
            parse_wcs_neighbors(bad)
    with pytest.raises(ProtocolError):
        parse_wcs_request("GETNEIGHBORS A B")
