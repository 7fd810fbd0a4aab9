"""Conversions between the USARSim frame and MuJoCo's.

USARSim reports (protocol.md section 3): X forward, Y right, Z down, angles
(roll, pitch, yaw) applied yaw-pitch-roll (aerospace ZYX), yaw positive clockwise
seen from above.  MuJoCo here uses X forward, Y left, Z up.  The two frames differ
by a half turn about X: (x, y, z)_usar = (x, -y, -z)_mujoco.  Rotations conjugate
the same way: roll is unchanged, pitch and yaw change sign.
"""

from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi


def to_mj_vec(v) -> np.ndarray:
    """A position/direction in the USARSim frame -> MuJoCo frame."""
    return np.array([v[0], -v[1], -v[2]], dtype=float)


def from_mj_vec(v) -> tuple[float, float, float]:
    return (float(v[0]), float(-v[1]), float(-v[2]))


def _euler_rows(roll: float, pitch: float, yaw: float) -> list[list[float]]:
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]


def euler_to_mat(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """ZYX (yaw, then pitch, then roll about body axes) rotation matrix, same frame."""
    return np.array(_euler_rows(roll, pitch, yaw))


def mat_to_euler(m) -> tuple[float, float, float]:
    """Inverse of :func:`euler_to_mat` (pitch in [-pi/2, pi/2])."""
    pitch = math.asin(max(-1.0, min(1.0, -m[2][0])))
    roll = math.atan2(m[2][1], m[2][2])
    yaw = math.atan2(m[1][0], m[0][0])
    return roll, pitch, yaw


def usar_euler_to_mj_mat(rpy) -> np.ndarray:
    """Orientation given in the USARSim frame -> rotation matrix in the MuJoCo frame."""
    return euler_to_mat(rpy[0], -rpy[1], -rpy[2])


def mj_mat_to_usar_euler(mat) -> tuple[float, float, float]:
    m = np.asarray(mat, dtype=float).reshape(3, 3)
    roll, pitch, yaw = mat_to_euler(m)
    return roll, -pitch, -yaw


def _quat_of_rows(m: list[list[float]]) -> np.ndarray:
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = [0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s]
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2
        q = [(m[2][1] - m[1][2]) / s, 0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s]
    elif m[1][1] > m[2][2]:
        s = math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2
        q = [(m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s]
    else:
        s = math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2
        q = [(m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s]
    qa = np.array(q)
    # the numbers of q / np.linalg.norm(q) (which is sqrt(q.dot(q)) for a vector), without its
    # Python: the waving victims' arms are turned with this before every stretch of steps
    return qa / math.sqrt(qa.dot(qa))


def mat_to_quat(m) -> np.ndarray:
    """Rotation matrix -> unit quaternion (w, x, y, z)."""
    return _quat_of_rows(np.asarray(m, dtype=float).reshape(3, 3).tolist())


def usar_euler_to_mj_quat(rpy) -> np.ndarray:
    """Orientation given in the USARSim frame -> unit quaternion in the MuJoCo frame (the
    same numbers as ``mat_to_quat(usar_euler_to_mj_mat(rpy))``, without the arrays between:
    the waving victims' arms are turned with it before every stretch of physics steps)."""
    return _quat_of_rows(_euler_rows(rpy[0], -rpy[1], -rpy[2]))


# An angle this close below 2 pi is reported as 0: a level robot's pitch of -1e-9 rad would
# otherwise read 6.2832 (the protocol prints 4 decimals; 2 pi - 5e-5 is the first value that
# rounds to 6.2832 or prints as 6.2831 only by rounding down).
WRAP_SNAP_RAD = 5e-5


def wrap_2pi(a: float) -> float:
    """Angle into [0, 2 pi), with a hair below 2 pi (WRAP_SNAP_RAD) reported as 0."""
    r = math.fmod(a, TWO_PI)
    if r < 0:
        r += TWO_PI
    if r >= TWO_PI - WRAP_SNAP_RAD:
        r = 0.0
    return r


def wrap_pi(a: float) -> float:
    """Angle into [-pi, pi)."""
    return (a + math.pi) % TWO_PI - math.pi
