"""The image server's protocol (protocol.md 10) at both ends, without sockets: requests and
pictures read back whole however the bytes are cut, stray bytes skipped, a nonsense length
refused."""

from __future__ import annotations

import struct

import pytest

from usarsim.protocol import upis


@pytest.mark.parametrize("chunk", [1, 2, 3, 17, 1000])
def test_requests_are_read_in_order_however_they_are_cut(chunk):
    wire = b"OK" + b"\r\n" + upis.ask_rect(1, 2, 300, 400) + b"X" + upis.ask_whole() + b"O"
    reader = upis.RequestReader()
    got = []
    for i in range(0, len(wire), chunk):
        got += reader.feed(wire[i : i + chunk])
    assert got == [None, (1, 2, 300, 400), None]  # the trailing O waits for its K
    assert reader.feed(b"K") == [None]
    assert upis.ask_rect(1, 2, 3, 4) == b"U" + struct.pack(">IIII", 1, 2, 3, 4)  # protocol.md 10


@pytest.mark.parametrize("chunk", [1, 4, 5, 6, 64])
def test_pictures_are_read_whole_however_they_are_cut(chunk):
    raw = upis.raw_payload(2, 1, b"\x01\x02\x03\x04\x05\x06")
    wire = upis.frame(upis.RAW, raw) + upis.frame(3, b"\xff\xd8jpeg\xff\xd9")
    assert wire[:5] == bytes([0]) + struct.pack(">I", 10)  # type byte, big-endian length
    reader = upis.FrameReader()
    got = []
    for i in range(0, len(wire), chunk):
        assert reader.wanted() > 0
        got += reader.feed(wire[i : i + chunk])
    assert got == [(0, raw), (3, b"\xff\xd8jpeg\xff\xd9")]
    assert upis.parse_raw(raw) == (2, 1, b"\x01\x02\x03\x04\x05\x06")


def test_a_length_no_picture_has_is_refused():
    with pytest.raises(ValueError, match="not an image server"):
        upis.FrameReader().feed(b"\x03\xff\xff\xff\xff")
