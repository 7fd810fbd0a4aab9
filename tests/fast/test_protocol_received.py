"""The direct path's quick reading of messages (usarsim.protocol.received): each rule gives
exactly what a client parses from the printed line, or declines."""

from __future__ import annotations

import math

from hypothesis import example, given, settings
from hypothesis import strategies as st

from usarsim import readings as r
from usarsim.errors import ProtocolError
from usarsim.protocol import messages as m
from usarsim.protocol.received import as_received, covered


def read_back(msg) -> list:
    """What a client of the control port reads of ``msg``: its printed lines, parsed."""
    out = []
    text = m.format_message(msg).encode("ascii", "replace").decode("ascii", "replace")
    for line in text.split("\r\n"):
        if line:
            try:
                out.append(m.parse_message(line))
            except ProtocolError:
                pass
    return out


def same(msg) -> bool:
    """The quick rule (when it answers) gives what reading back gives, to the last bit: compared
    by repr, which tells 0.0 from -0.0 and 1 from 1.0 and True."""
    quick = as_received(msg)
    return quick is None or repr(quick) == repr(read_back(msg))


def ties(scale: int):
    """Numbers at and beside a half of the last printed digit: 1.23445, 1.2344500000000001..."""
    return st.builds(
        lambda k, nudge: (k + 0.5) / scale + nudge,
        st.integers(-(10**7), 10**7),
        st.sampled_from([0.0, 1e-12, -1e-12, 5e-17, -5e-17]),
    )


NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-1e6, 1e6),
    st.floats(-1e-3, 1e-3),
    ties(10_000),
    ties(100),
    st.integers(-1000, 1000).map(float),
)
SMALL = st.one_of(st.floats(-100.0, 100.0), ties(10_000), st.just(-0.0), st.floats(-1e-5, 1e-5))
NAMES = st.one_of(
    st.sampled_from(["Scanner1", "F1", "ECLeft", "GroundTruth", "Odometry", "CameraPanTilt", "GPS"]),
    st.text(max_size=6),
)
INTS = st.one_of(st.integers(-(2**31), 2**31), NUMBERS)


@settings(max_examples=300, deadline=None)
@given(NUMBERS, st.lists(SMALL, max_size=200), NAMES, NAMES)
@example(0.1, [1.00005] * 30, "Scanner1", "RangeScanner")
@example(-0.00001, [-0.00004] * 30 + [math.inf], "Scanner1", "RangeScanner")
def test_a_sweep_reads_back_the_same(t, ranges, name, kind):
    assert same(m.SensorMessage(t, r.RangeScanReading(kind, name, 0.0174532925, math.pi, tuple(ranges))))


@settings(max_examples=300, deadline=None)
@given(st.one_of(st.none(), NUMBERS), st.tuples(NUMBERS, NUMBERS, NUMBERS), st.tuples(NUMBERS, NUMBERS, NUMBERS), NAMES)
@example(1.0, (0.0, -0.0, 1.00005), (-1e-9, 6.28318, -6.2832), "GroundTruth")
def test_a_pose_reads_back_the_same(t, location, orientation, name):
    assert same(m.SensorMessage(t, r.PoseReading("GroundTruth", name, location, orientation)))
    assert same(m.SensorMessage(t, r.PoseReading("INS", name, location, orientation)))


@settings(max_examples=200, deadline=None)
@given(NUMBERS, st.lists(st.tuples(NAMES, NUMBERS, INTS, st.booleans()), max_size=16), NUMBERS, NUMBERS, NUMBERS)
def test_packed_sensors_and_odometry_read_back_the_same(t, items, x, y, theta):
    assert same(m.SensorMessage(t, r.RangeReading("Sonar", tuple(r.RangeItem(n, v) for n, v, _, _ in items))))
    assert same(m.SensorMessage(t, r.EncoderReading(tuple(r.EncoderItem(n, k) for n, _, k, _ in items))))
    assert same(m.SensorMessage(t, r.TouchReading(tuple(r.TouchItem(n, b) for n, _, _, b in items))))
    assert same(m.SensorMessage(t, r.OdometryReading("Odometry", x, y, theta)))


@settings(max_examples=200, deadline=None)
@given(NUMBERS, NAMES, st.booleans(), INTS, NUMBERS, NUMBERS, st.sampled_from("NSEWX"), st.booleans())
def test_gps_rfid_and_victims_read_back_the_same(t, name, fix, satellites, lat, lon, hemisphere, coordinates):
    latitude = (39, lat, hemisphere) if coordinates else None
    longitude = (77, lon, "W") if coordinates else None
    assert same(m.SensorMessage(t, r.GpsReading(name, fix, satellites, latitude, longitude)))
    assert same(m.SensorMessage(t, r.RfidReading(name, ())))
    assert same(m.SensorMessage(t, r.VictimReading(name, ())))


@settings(max_examples=300, deadline=None)
@given(
    NUMBERS,
    st.sampled_from(["GroundVehicle", "AerialVehicle", "LeggedRobot", "Ground Vehicle"]),
    INTS,
    NUMBERS,
    NUMBERS,
    st.lists(st.tuples(NAMES, NUMBERS), max_size=4),
    st.booleans(),
    INTS,
    INTS,
)
def test_a_status_reads_back_the_same(t, kind, battery, front, rear, joints, light, intensity, view):
    status = r.RobotStatus(kind, battery, front, rear, tuple(joints), light, intensity, view)
    assert same(m.StatusMessage(t, status))


@settings(max_examples=200, deadline=None)
@given(NUMBERS, NAMES, st.lists(st.tuples(INTS, NUMBERS, NUMBERS), max_size=4))
def test_a_package_state_and_stepped_read_back_the_same(t, name, links):
    state = r.PackageState(name, tuple(r.PackageLink(k, v, q) for k, v, q in links))
    assert same(m.MisPkgMessage(t, state))
    assert same(m.Stepped(t))


def test_the_rules_answer_for_what_robots_report_and_decline_the_rest():
    """A robot's usual lines are read without printing; anything else is printed and read back."""
    sweep = m.SensorMessage(0.1, r.RangeScanReading("RangeScanner", "Scanner1", 0.0174, 3.1415, (1.23456,) * 181))
    got = as_received(sweep)
    assert got is not None and got[0].reading.ranges_m == (1.2346,) * 181
    assert covered(sweep)
    assert as_received(m.Stepped(-0.00001)) == [m.Stepped(0.0)]
    assert repr(as_received(m.Stepped(-0.00001))) == "[Stepped(time=0.0)]"  # not -0.0, as "0.0000" reads
    # a name with a space, a victim seen, a reply: printed and read back
    assert as_received(m.SensorMessage(0.1, r.OdometryReading("my odometry", 0.0, 0.0, 0.0))) is None
    seen = r.VictimReading("VictSensor", (r.VictimPart("Head", (1.0, 2.0, 0.5)),))
    assert as_received(m.SensorMessage(0.1, seen)) is None
    assert as_received(m.GameInfo(level="DM-USAR_yellow")) is None
    assert not covered(m.GameInfo(level="DM-USAR_yellow"))
