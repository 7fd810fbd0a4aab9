"""No line, however broken, makes the protocol codec raise anything but ProtocolError, and
no byte stream breaks the line framing (issue: reliability, hostile input).  Lines are
generated from the protocol's own vocabulary mixed with garbage: unbalanced braces, NaN,
infinities, huge and tiny numbers, control characters, invalid UTF-8 replaced, very long
words."""

from __future__ import annotations

import random

from hypothesis import given, settings
from hypothesis import strategies as st
from stress_scale import scaled

from usarsim.errors import ProtocolError
from usarsim.protocol import LineBuffer, parse_command

COMMANDS = [
    "INIT",
    "DRIVE",
    "MULTIDRIVE",
    "SET",
    "GETGEO",
    "GETCONF",
    "GETSTARTPOSES",
    "MISPKG",
    "CAMERA",
    "STEP",
    "GETSTA",
    "CONTROL",
    "drive",
    "Init",
    "",
    "X",
    "DRIVE{",
    "{",
    "}",
]
KEYS = [
    "ClassName",
    "Name",
    "Location",
    "Rotation",
    "Start",
    "Left",
    "Right",
    "Speed",
    "FrontSteer",
    "RearSteer",
    "Light",
    "Flip",
    "Normalized",
    "Type",
    "Opcode",
    "Params",
    "Robot",
    "Client",
    "Config",
    "Viewport1",
    "Link",
    "Value",
    "Order",
    "Zoom",
    "Time",
    "WheelNumber",
    "WheelSpeed",
    "WheelSteer",
    "LinearVelocity",
    "LateralVelocity",
    "RotationalVelocity",
    "AltitudeVelocity",
    "Propeller",
    "",
    "{",
    "}",
]
VALUES = [
    "0",
    "1",
    "-1",
    "1.5",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "Infinity",
    "1e308",
    "1e999",
    "-1e999",
    "1e-320",
    "0x10",
    "1,2,3",
    "1,2",
    "1,,3",
    "1 2 3",
    "True",
    "false",
    "USARBot.P2AT",
    "P2AT",
    "PlayerStart1",
    "Camera",
    "Zoom",
    "\x00",
    "\t",
    "é",
    "\ufffd",
    "}",
    "{",
    "{{",
    "}}",
    "9" * 400,
    "a" * 2000,
    "",
]


def random_line(rng: random.Random) -> str:
    parts = [rng.choice(COMMANDS)]
    for _ in range(rng.randint(0, 8)):
        r = rng.random()
        if r < 0.7:
            parts.append("{%s %s}" % (rng.choice(KEYS), rng.choice(VALUES)))
        elif r < 0.8:
            parts.append("{%s}" % rng.choice(KEYS + VALUES))
        elif r < 0.9:
            parts.append(rng.choice(VALUES))
        else:
            parts.append("".join(chr(rng.randint(0, 0x2FF)) for _ in range(rng.randint(1, 12))))
    sep = rng.choice([" ", "", "  ", "\t"])
    return sep.join(parts)


def test_generated_lines_never_break_the_codec():
    rng = random.Random(20261121)
    n = scaled(30_000, 300_000)
    parsed = refused = 0
    for _ in range(n):
        line = random_line(rng)
        try:
            parse_command(line)
            parsed += 1
        except ProtocolError:
            refused += 1
    assert parsed + refused == n and parsed > n // 20 and refused > n // 20


@settings(max_examples=scaled(300, 5_000), deadline=None)
@given(st.text(max_size=200))
def test_any_text_is_parsed_or_refused(text):
    try:
        parse_command(text)
    except ProtocolError:
        pass


def test_any_bytes_are_framed_into_bounded_lines():
    rng = random.Random(7)
    buf = LineBuffer(max_line_bytes=8192)
    total = 0
    for _ in range(scaled(2_000, 20_000)):
        chunk = bytes(rng.randint(0, 255) for _ in range(rng.randint(0, 600)))
        if rng.random() < 0.05:
            chunk += b"x" * 20_000  # over-long
        for line in buf.feed(chunk):
            assert isinstance(line, str) and len(line.encode("utf-8", "surrogatepass")) <= 8192 * 4
            total += 1
    assert total > 0
