"""Number formatting (protocol.md §2.4)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from usarsim.protocol.numbers import (
    TAU,
    angle4,
    bool_str,
    f2,
    f4,
    int_str,
    num,
    t4,
    vec2,
    vec4,
    vec_angle4,
    vec_t4,
)


@pytest.mark.parametrize(
    ("x", "expected"),
    [(5609.45, "5609.45"), (31.2, "31.20"), (-0.001, "0.00"), (-0.0, "0.00"), (-2.675, "-2.67")],
)
def test_f2(x: float, expected: str) -> None:
    assert f2(x) == expected


@pytest.mark.parametrize(
    ("x", "expected"),
    [(2.5098, "2.5098"), (0.0, "0.0000"), (-0.0, "0.0000"), (-0.00004, "0.0000"), (-20, "-20.0000")],
)
def test_f4(x: float, expected: str) -> None:
    assert f4(x) == expected


@pytest.mark.parametrize(
    ("x", "expected"),
    [
        (math.radians(1.0), "0.0174"),
        (math.pi, "3.1415"),
        (math.pi / 2, "1.5707"),
        (0.0174, "0.0174"),  # stored as 0.017399999...: written digits kept
        (0.1, "0.1000"),
        (2.0, "2.0000"),
        (-math.pi, "-3.1415"),
        (-0.00001, "0.0000"),
        (11.30599, "11.3059"),
    ],
)
def test_t4_truncates_toward_zero(x: float, expected: str) -> None:
    assert t4(x) == expected


def test_t4_keeps_the_181_beam_count_of_ut_clients() -> None:
    fov = float(t4(math.pi))
    resolution = float(t4(math.radians(1.0)))
    assert math.floor(fov / resolution) + 1 == 181


@pytest.mark.parametrize(
    ("x", "expected"),
    [
        (0.0, "0.0000"),
        (-0.0, "0.0000"),
        (6.23, "6.2300"),
        (-0.05, "6.2332"),
        (TAU, "0.0000"),
        (TAU - 1e-9, "0.0000"),
        (-1e-17, "0.0000"),
        (7.0, "0.7168"),
        (-TAU - 1.0, "5.2832"),
    ],
)
def test_angle4_normalises_into_zero_two_pi(x: float, expected: str) -> None:
    assert angle4(x) == expected


@given(st.floats(min_value=-1e4, max_value=1e4, allow_nan=False))
def test_angle4_is_never_a_full_turn(x: float) -> None:
    value = float(angle4(x))
    assert 0.0 <= value < 6.2832
    assert not angle4(x).startswith("-")


def test_vectors() -> None:
    assert vec2((4.5, 1.9, 1.8)) == "4.50,1.90,1.80"
    assert vec2((-0.001, 0.0, -1.0)) == "0.00,0.00,-1.00"
    assert vec4((0.145, -0.13, 0.0)) == "0.1450,-0.1300,0.0000"
    assert vec4((-0.0, -0.00001, -10.0, 0.5)) == "0.0000,0.0000,-10.0000,0.5000"
    assert vec4(()) == ""
    assert vec_angle4((0.0, -0.05, TAU)) == "0.0000,6.2332,0.0000"
    assert vec_t4((math.pi, 0.0, math.pi / 2)) == "3.1415,0.0000,1.5707"


@given(st.lists(st.floats(min_value=-1e6, max_value=1e6, allow_nan=False), max_size=200))
def test_vec4_matches_value_by_value_formatting(values: list[float]) -> None:
    assert vec4(values) == ",".join(f4(v) for v in values)
    assert vec2(values) == ",".join(f2(v) for v in values)


def test_bool_and_int() -> None:
    assert bool_str(True) == "True"
    assert bool_str(False) == "False"
    assert int_str(-331) == "-331"


@pytest.mark.parametrize(
    ("x", "expected"), [(1.5, "1.5"), (1e-05, "0.00001"), (1e20, "100000000000000000000"), (-2.0, "-2.0")]
)
def test_num_is_exact_and_without_exponent(x: float, expected: str) -> None:
    assert num(x) == expected


@given(st.floats(allow_nan=False, allow_infinity=False))
def test_num_round_trips(x: float) -> None:
    text = num(x)
    assert "e" not in text and "E" not in text
    assert float(text) == x
