"""Number formatting for the USARSim text protocol (protocol.md §2.4).

Every number the server prints goes through this module, so the precision of each key is
decided in one place:

* ``f2`` / ``f4``: fixed 2 or 4 decimals (UT2004 engine floats printed 2 decimals, the
  USARSim converter 4).  A negative zero (``-0.00``) is printed as ``0.00``.
* ``t4``: 4 decimals, truncated toward zero.  UT2004 printed a scanner resolution of
  0.017453 rad as ``0.0174`` and a field of view of pi as ``3.1415``; clients compute the beam
  count as ``floor(FOV / Resolution) + 1`` and get 181 only from the truncated pair.
* ``angle4``: an angle normalised into [0, 2 pi) at 4 decimals (UT ground truth and INS).
* ``vec2`` / ``vec4`` / ``vec_angle4``: comma-joined sequences without spaces (``x,y,z``).
* ``bool_str``: ``True`` / ``False``.
* ``num``: the shortest text that reads back as exactly the same float, never with an
  exponent; used when formatting client commands, where no precision may be lost.

Inputs are expected to be finite; the simulation guards against NaN before anything is
reported.  A non-finite value is printed as Python prints it (``nan``, ``inf``) rather than
raising, so a formatting call never breaks a connection.

Sequences are formatted with one ``%`` operation on a cached format string per length, which
is about twice as fast as formatting value by value (a 181-beam laser line is formatted many
times a second for every robot).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from decimal import Decimal

__all__ = [
    "TAU",
    "angle4",
    "bool_str",
    "f2",
    "f4",
    "int_str",
    "num",
    "t4",
    "ints",
    "vec2",
    "vec3d",
    "vec4",
    "vec_angle4",
    "vec_t4",
]

TAU = 2.0 * math.pi

_NEG_ZERO_2 = "-0.00"
_NEG_ZERO_3 = "-0.000"
_NEG_ZERO_4 = "-0.0000"
_FULL_TURN_4 = "%.4f" % TAU  # "6.2832": an angle that rounds up to a full turn

# Format strings for comma-joined sequences, cached per length.
_FMT2: dict[int, str] = {}
_FMT3: dict[int, str] = {}
_FMT4: dict[int, str] = {}


def _fmt(cache: dict[int, str], spec: str, n: int) -> str:
    fmt = cache.get(n)
    if fmt is None:
        fmt = ",".join([spec] * n)
        if n <= 4096:  # bound the cache; longer lists are rare and still correct
            cache[n] = fmt
    return fmt


def f2(x: float) -> str:
    """``x`` with 2 decimals (``-0.00`` printed as ``0.00``)."""
    s = "%.2f" % x
    return "0.00" if s == _NEG_ZERO_2 else s


def f4(x: float) -> str:
    """``x`` with 4 decimals (``-0.0000`` printed as ``0.0000``)."""
    s = "%.4f" % x
    return "0.0000" if s == _NEG_ZERO_4 else s


def t4(x: float) -> str:
    """``x`` truncated toward zero to 4 decimals.

    A value that is a 4-decimal number up to binary representation error (``0.0174`` is
    stored as 0.017399999...) keeps its written digits instead of losing the last one.
    """
    if not math.isfinite(x):
        return "%.4f" % x
    scaled = x * 10000.0
    nearest = round(scaled)
    n = nearest if abs(scaled - nearest) < 1e-6 else math.trunc(scaled)
    sign = "-" if n < 0 else ""
    n = abs(n)
    return "%s%d.%04d" % (sign, n // 10000, n % 10000)


def angle4(x: float) -> str:
    """An angle in radians normalised into [0, 2 pi), 4 decimals.

    Values just below 2 pi would print as ``6.2832``; they are printed as ``0.0000``.
    """
    s = "%.4f" % (x % TAU)
    return "0.0000" if s == _FULL_TURN_4 else s


def vec2(v: Sequence[float]) -> str:
    """Comma-joined values with 2 decimals: ``1.00,-2.50,0.00``."""
    s = _fmt(_FMT2, "%.2f", len(v)) % tuple(v)
    return s.replace(_NEG_ZERO_2, "0.00") if _NEG_ZERO_2 in s else s


def vec3d(v: Sequence[float]) -> str:
    """Comma-joined values with 3 decimals (millimetres of a depth picture): ``1.250,0.800``."""
    s = _fmt(_FMT3, "%.3f", len(v)) % tuple(v)
    return s.replace(_NEG_ZERO_3, "0.000") if _NEG_ZERO_3 in s else s


def ints(v: Iterable[int]) -> str:
    """Comma-joined integers: ``320,240``."""
    return ",".join(["%d" % x for x in v])


def vec4(v: Sequence[float]) -> str:
    """Comma-joined values with 4 decimals: ``1.0000,-2.5000,0.0000`` (any length)."""
    s = _fmt(_FMT4, "%.4f", len(v)) % tuple(v)
    # Each number has exactly 4 decimals, so "-0.0000" can only be a whole negative zero.
    return s.replace(_NEG_ZERO_4, "0.0000") if _NEG_ZERO_4 in s else s


def vec_t4(v: Iterable[float]) -> str:
    """Comma-joined values truncated to 4 decimals (see :func:`t4`)."""
    return ",".join(map(t4, v))


def vec_angle4(v: Iterable[float]) -> str:
    """Comma-joined angles normalised into [0, 2 pi), 4 decimals."""
    return ",".join(map(angle4, v))


def bool_str(b: bool) -> str:
    """``True`` or ``False``, as UnrealScript printed booleans."""
    return "True" if b else "False"


def int_str(x: int) -> str:
    """An integer (a float is truncated toward zero)."""
    return "%d" % x


def num(x: float) -> str:
    """The shortest decimal text that reads back as exactly ``x``, without an exponent.

    ``1e-05`` is written ``0.00001``: USARSim servers parse numbers without exponents.
    """
    r = repr(float(x))
    if "e" in r:
        r = format(Decimal(r), "f")
    return r
