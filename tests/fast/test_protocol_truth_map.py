"""``{Map}`` on the ground-truth service (our extension, docs/protocol.md): the request, its
limits, and the answer's lines, each under 4096 bytes, read back to the same bytes."""

from __future__ import annotations

import os
import zlib

import pytest

from usarsim.errors import ProtocolError
from usarsim.protocol.truth import (
    END,
    MapHeader,
    MapRequest,
    format_map_answer,
    format_map_request,
    parse_map_answer,
    parse_truth_request,
)


def test_a_map_request_and_its_defaults():
    assert parse_truth_request("{Map}").map == MapRequest(0.05, 0.3)
    assert parse_truth_request("{map} {resolution 0.1} {height 0.5}").map == MapRequest(0.1, 0.5)
    assert parse_truth_request(format_map_request(0.2, 0.25)).map == MapRequest(0.2, 0.25)
    assert parse_truth_request("{Class Victim}").map is None


@pytest.mark.parametrize(
    "line", ["{Map} {Resolution 0}", "{Map} {Resolution 50}", "{Map} {Height -1}", "{Map} {Resolution x}"]
)
def test_a_map_request_out_of_range_is_refused(line):
    with pytest.raises(ProtocolError):
        parse_truth_request(line)


def test_the_answer_reads_back_and_every_line_is_short():
    cells = os.urandom(300 * 200)  # incompressible: many {Data} lines
    payload = zlib.compress(cells)
    header = MapHeader("DM-USAR_yellow", 17, 0.05, (-20.0, -11.0), 300, 200, 0.3)
    text = format_map_answer(header, payload)
    assert text.endswith(END)
    lines = text.split("\r\n")[:-2]  # without {End} and the empty tail
    assert lines[0].startswith("{Map DM-USAR_yellow} {Variant 17} {Resolution 0.0500} {Origin -20.0000,-11.0000}")
    assert all(len(line) + 2 < 4096 for line in lines) and len(lines) > 10
    back_header, back = parse_map_answer(lines)
    assert back_header == header and zlib.decompress(back) == cells
    with pytest.raises(ProtocolError):
        parse_map_answer([])
    with pytest.raises(ProtocolError):
        parse_map_answer([lines[0], "{Name x}"])
