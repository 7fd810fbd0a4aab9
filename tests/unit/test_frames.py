"""USARSim <-> MuJoCo frame conversions (protocol.md section 3).

USARSim: X forward, Y right, Z down; (roll, pitch, yaw) applied yaw-pitch-roll; a positive
yaw turns clockwise seen from above, i.e. from +X towards +Y (right).  MuJoCo here: X forward,
Y left, Z up.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usarsim.sim import frames

finite = st.floats(min_value=-1e3, max_value=1e3, allow_nan=False, allow_infinity=False)
angle = st.floats(min_value=-math.pi + 1e-6, max_value=math.pi - 1e-6)
pitch_angle = st.floats(min_value=-math.pi / 2 + 1e-3, max_value=math.pi / 2 - 1e-3)


def usar_of_mj(v) -> np.ndarray:
    return np.array(frames.from_mj_vec(v))


@given(st.tuples(finite, finite, finite))
def test_vector_round_trip(v):
    back = frames.from_mj_vec(frames.to_mj_vec(v))
    assert back == pytest.approx(v, abs=0.0)


def test_vector_axes():
    # forward stays forward, right (+Y USARSim) is -Y MuJoCo, down (+Z USARSim) is -Z MuJoCo
    assert frames.to_mj_vec((1, 0, 0)).tolist() == [1, 0, 0]
    assert frames.to_mj_vec((0, 1, 0)).tolist() == [0, -1, 0]
    assert frames.to_mj_vec((0, 0, 1)).tolist() == [0, 0, -1]


@settings(max_examples=300)
@given(angle, pitch_angle, angle)
def test_euler_round_trip_through_mujoco_matrix(roll, pitch, yaw):
    m = frames.usar_euler_to_mj_mat((roll, pitch, yaw))
    r, p, y = frames.mj_mat_to_usar_euler(m.reshape(-1))
    assert r == pytest.approx(roll, abs=1e-9)
    assert p == pytest.approx(pitch, abs=1e-9)
    assert y == pytest.approx(yaw, abs=1e-9)


@settings(max_examples=300)
@given(angle, pitch_angle, angle)
def test_quaternion_agrees_with_mujoco(roll, pitch, yaw):
    m = frames.usar_euler_to_mj_mat((roll, pitch, yaw))
    q = frames.usar_euler_to_mj_quat((roll, pitch, yaw))
    assert np.linalg.norm(q) == pytest.approx(1.0)
    back = np.zeros(9)
    mujoco.mju_quat2Mat(back, q)
    np.testing.assert_allclose(back.reshape(3, 3), m, atol=1e-9)


@given(angle, pitch_angle, angle)
def test_rotation_matrix_is_proper(roll, pitch, yaw):
    m = frames.euler_to_mat(roll, pitch, yaw)
    np.testing.assert_allclose(m @ m.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(m) == pytest.approx(1.0)


def test_positive_yaw_turns_forward_towards_right():
    """Yaw +90 degrees: the robot's forward axis points along USARSim +Y (right, east)."""
    m = frames.usar_euler_to_mj_mat((0.0, 0.0, math.pi / 2))
    forward_mj = m @ np.array([1.0, 0.0, 0.0])
    np.testing.assert_allclose(usar_of_mj(forward_mj), [0.0, 1.0, 0.0], atol=1e-12)


def test_positive_yaw_is_clockwise_seen_from_above():
    """Seen from above (MuJoCo +Z towards the viewer) a small positive yaw moves the
    heading clockwise: the z component of (heading0 x heading1) is negative."""
    h0 = frames.usar_euler_to_mj_mat((0, 0, 0.0)) @ [1, 0, 0]
    h1 = frames.usar_euler_to_mj_mat((0, 0, 0.1)) @ [1, 0, 0]
    assert np.cross(h0, h1)[2] < 0


def test_positive_pitch_raises_the_nose():
    """Positive pitch raises the +X end (protocol.md: rotation about +Y by the right-hand rule
    in a Z-down frame lifts the nose, i.e. moves it to smaller USARSim z)."""
    m = frames.usar_euler_to_mj_mat((0.0, 0.3, 0.0))
    nose = usar_of_mj(m @ np.array([1.0, 0.0, 0.0]))
    assert nose[2] < 0  # Z down: negative z is up


def test_positive_roll_lowers_the_right_side():
    m = frames.usar_euler_to_mj_mat((0.3, 0.0, 0.0))
    right = usar_of_mj(m @ frames.to_mj_vec((0.0, 1.0, 0.0)))
    assert right[2] > 0  # the +Y end goes down (Z down)


def test_yaw_is_applied_before_pitch_and_roll():
    """ZYX: with yaw 90 degrees and pitch 0.3 the nose points right and up."""
    m = frames.usar_euler_to_mj_mat((0.0, 0.3, math.pi / 2))
    nose = usar_of_mj(m @ np.array([1.0, 0.0, 0.0]))
    np.testing.assert_allclose(nose, [0.0, math.cos(0.3), -math.sin(0.3)], atol=1e-12)


@pytest.mark.parametrize(
    "a, expected",
    [
        (0.0, 0.0),
        (-1e-17, 0.0),
        (2 * math.pi, 0.0),
        (-math.pi / 2, 1.5 * math.pi),
        (7.0, 7.0 - 2 * math.pi),
        (-4 * math.pi - 0.25, 2 * math.pi - 0.25),
    ],
)
def test_wrap_2pi(a, expected):
    r = frames.wrap_2pi(a)
    assert 0.0 <= r < 2 * math.pi
    assert r == pytest.approx(expected, abs=1e-12)


@given(st.floats(min_value=-1e4, max_value=1e4))
def test_wrap_2pi_range(a):
    r = frames.wrap_2pi(a)
    assert 0.0 <= r < 2 * math.pi
    # the same angle, but for a hair below 2 pi that reads 0 (frames.WRAP_SNAP_RAD)
    assert math.isclose(math.cos(r), math.cos(a), abs_tol=1e-7 + frames.WRAP_SNAP_RAD)
    assert math.isclose(math.sin(r), math.sin(a), abs_tol=1e-7 + frames.WRAP_SNAP_RAD)


@given(st.floats(min_value=-1e4, max_value=1e4))
def test_wrap_pi_range(a):
    r = frames.wrap_pi(a)
    assert -math.pi <= r < math.pi
    assert math.isclose(math.sin(r), math.sin(a), abs_tol=1e-7)


@pytest.mark.parametrize("angle", [-1e-9, -3e-5, 2 * math.pi - 1e-7, -2 * math.pi - 1e-9])
def test_an_angle_a_hair_below_zero_reads_zero_not_two_pi(angle):
    """A level robot whose pitch is -1e-9 rad reads 0.0000, not 6.2832 (ground truth, INS)."""
    assert frames.wrap_2pi(angle) == 0.0
    assert f"{frames.wrap_2pi(angle):.4f}" == "0.0000"


def test_wrapping_keeps_every_other_angle():
    assert frames.wrap_2pi(-0.001) == pytest.approx(2 * math.pi - 0.001)
    assert frames.wrap_2pi(7.0) == pytest.approx(7.0 - 2 * math.pi)
    assert frames.wrap_2pi(math.pi) == math.pi


@settings(max_examples=300, deadline=None)
@given(angle, pitch_angle, angle, st.floats(min_value=0.0, max_value=1.2))
def test_a_waving_arm_turns_as_its_euler_angles_say(roll, pitch, yaw, lift):
    """The waving victims' arms are turned by cos(lift/2) A + sin(lift/2) B: the rotation of
    (roll, pitch - lift, yaw) in the USARSim frame."""
    from usarsim.sim.entities import _waving_terms

    at_rest, lifting = _waving_terms([(roll, pitch, yaw)])
    q = math.cos(0.5 * lift) * at_rest[0] + math.sin(0.5 * lift) * lifting[0]
    expected = frames.usar_euler_to_mj_quat((roll, pitch - lift, yaw))
    assert np.linalg.norm(q) == pytest.approx(1.0, abs=1e-12)
    assert abs(float(q @ expected)) == pytest.approx(1.0, abs=1e-12)  # the same rotation (q or -q)
