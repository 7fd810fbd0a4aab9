"""Wheel-speed and inertial sensors: Tachometer (protocol.md 7.5), IMU (UDK layout,
protocol.md 6.3) and the old orientation-only INU (protocol.md 6.3).

Frames (protocol.md section 3): every vector is reported in the USARSim frame, X forward,
Y right, Z down, which is MuJoCo's (x, -y, -z); a positive yaw is a clockwise (right) turn
seen from above, so a left turn has a negative yaw rate.

Noise: each sensor senses the true values and declares what corrupts them (its ``NOISE``,
applied by the framework, :mod:`usarsim.sensors.noise`): the Tachometer the relative noise
of protocol.md 7.1 (:data:`~usarsim.sensors.noise.RELATIVE`), the IMU a Gaussian error per
reported quantity (:class:`ImuNoise`), the INU a Gaussian error N(Mean, Sigma) on each angle
(:class:`InuNoise`).  None of them is noisy by default.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from usarsim.readings import ImuReading, OrientationReading, TachometerReading
from usarsim.sensors.base import SENSORS, Sensor, SensorConfig
from usarsim.sensors.noise import RELATIVE, Noise
from usarsim.sim import frames
from usarsim.sim.frames import wrap_2pi

if TYPE_CHECKING:
    from usarsim.config.robot import MountedItem, RobotConfig
    from usarsim.sim.view import WorldView

# MuJoCo -> USARSim component signs of a vector: (x, y, z)_usar = (x, -y, -z)_mujoco
# (protocol.md section 3, usarsim.sim.frames).
_TO_USAR = np.array([1.0, -1.0, -1.0])


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    # np.cross costs ~20 us for two 3-vectors; this is ~1.5 us
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _vec(v: np.ndarray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def _wrapped(angles: np.ndarray) -> tuple[float, float, float]:
    """Each angle into [0, 2 pi), as GroundTruth and INS report them (protocol.md section 3)."""
    return (wrap_2pi(float(angles[0])), wrap_2pi(float(angles[1])), wrap_2pi(float(angles[2])))


# --------------------------------------------------------------------------- Tachometer


@dataclass(frozen=True, kw_only=True)
class TachometerConfig(SensorConfig):
    """A Tachometer's settings in a robot file (protocol.md 7.5): its scan interval and relative noise, none by
    default."""

    # Tachometer ScanInterval 0.2 (protocol.md 7.5).  No noise by default: the UDK
    # Tachometer.uc (listed in protocol.md's Sources) reports the exact wheel values;
    # ``Noise`` (protocol.md 7.1, relative, uniform) may add some.
    scan_interval_s: float = 0.2
    noise: float = 0.0


@SENSORS.register("Tachometer")
class Tachometer(Sensor[TachometerConfig]):
    """Spin speed (rad/s, the wheel joint's instantaneous velocity) and accumulated angle
    (rad, since spawn or the last RESET) of every wheel of the robot, in the robot file's
    wheel order; forward rotation is positive (as for Encoder, protocol.md 7.5).
    ``SET {Type Tachometer} {Opcode RESET}`` zeroes the angles (protocol.md 5.4)."""

    RESETTABLE = True
    NOISE = RELATIVE

    def configure(self, view: WorldView) -> None:
        h = self.handle
        names = [w.name for w in self.robot.wheels]
        self._qpos = np.array([h.joint_qpos[n] for n in names], dtype=np.intp)
        self._qvel = np.array([h.joint_qvel[n] for n in names], dtype=np.intp)

    def reset(self, view: WorldView) -> None:
        self._zero = view.data.qpos[self._qpos].copy()

    def sense(self, view: WorldView) -> tuple[np.ndarray, np.ndarray]:
        d = view.data
        return d.qvel[self._qvel].astype(float), d.qpos[self._qpos] - self._zero

    def reading(self, values: tuple[np.ndarray, np.ndarray]) -> TachometerReading:
        vel, pos = values
        return TachometerReading(self.name, tuple(vel.tolist()), tuple(pos.tolist()))


# --------------------------------------------------------------------------- IMU


@dataclass(frozen=True, kw_only=True)
class ImuConfig(SensorConfig):
    """An IMU's settings in a robot file (UDK layout, protocol.md 6.3): its scan interval, the Gaussian noise of each
    quantity it reports, and whether its acceleration includes gravity."""

    # The UDK IMU.uc (protocol.md Sources) sets no ScanInterval of its own: the sensor
    # base 0.1 s applies (protocol.md 7.1).  It adds no noise either, so every sigma
    # defaults to 0 (exact values); the Gaussian generator of protocol.md 7.1 is
    # available per quantity.
    scan_interval_s: float = 0.1
    acceleration_sigma_m_s2: float = 0.0
    angular_velocity_sigma_rad_s: float = 0.0
    angular_acceleration_sigma_rad_s2: float = 0.0
    orientation_sigma_rad: float = 0.0
    # True: proper acceleration, what a real accelerometer measures (at rest on a level
    # floor (0, 0, -g): the floor pushes up, Z is down).  False: the coordinate
    # acceleration without gravity, as the UDK IMU.uc reported it.
    include_gravity: bool = True

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in (
            "acceleration_sigma_m_s2",
            "angular_velocity_sigma_rad_s",
            "angular_acceleration_sigma_rad_s2",
            "orientation_sigma_rad",
        ):
            v = getattr(self, name)
            if not (v >= 0 and math.isfinite(v)):
                raise ValueError(f"{name} must be a finite number >= 0, got {v}")


@dataclass(frozen=True, slots=True)
class ImuValues:
    """What an IMU senses, in the sensor's USARSim-style axes (see :class:`IMU`): acceleration
    (m/s^2), angular velocity (rad/s), angular acceleration (rad/s^2), and the robot's roll,
    pitch and yaw (rad, not yet wrapped)."""

    acceleration: np.ndarray
    angular_velocity: np.ndarray
    angular_acceleration: np.ndarray
    orientation: np.ndarray


class ImuNoise(Noise):
    """An IMU's Gaussian error per reported quantity (the Gaussian generator of protocol.md 7.1;
    the UDK IMU.uc adds no noise, so every sigma defaults to 0): each component of the
    acceleration, the angular velocity, the angular acceleration and the orientation gets an
    error of mean 0 and the sigma its settings give that quantity (``XYZAccelerationSigma``,
    ``AngularVelSigma``, ``AngularAccelSigma``, ``RotationSigma``), drawn from the sensor's
    generator in that order, three at a time; a quantity whose sigma is 0 draws nothing.
    ``true``: an :class:`ImuValues`."""

    @staticmethod
    def _gauss(sensor: Sensor[Any], sigma: float, k: int = 3) -> np.ndarray | float:
        return sensor.rng.normal(0.0, sigma, k) if sigma > 0 else 0.0

    def apply(self, sensor: Sensor[Any], true: ImuValues) -> ImuValues:
        c: ImuConfig = sensor.config
        acc = true.acceleration + self._gauss(sensor, c.acceleration_sigma_m_s2)
        ang_vel = true.angular_velocity + self._gauss(sensor, c.angular_velocity_sigma_rad_s)
        ang_acc = true.angular_acceleration + self._gauss(sensor, c.angular_acceleration_sigma_rad_s2)
        ori = true.orientation + self._gauss(sensor, c.orientation_sigma_rad)
        return ImuValues(acc, ang_vel, ang_acc, ori)


@SENSORS.register("IMU")
class IMU(Sensor[ImuConfig]):
    """UDK-style IMU: ``XYZAcceleration``, ``AngularVel``, ``AngularAccel``, ``Rotation``.

    * Acceleration (m/s^2) of the sensor point, in the sensor's frame (the robot's body
      frame, X forward, Y right, Z down, for a mount without rotation): the change of
      the point's world velocity between two measurements divided by the time between
      them (the mean acceleration over the scan interval, as UDK IMU.uc computes it),
      minus gravity (proper acceleration, see ``include_gravity``): at rest on a level
      floor it reads (0, 0, -9.81).
    * Angular velocity (rad/s): the body's instantaneous angular velocity in the same
      frame; a left turn gives a negative Z rate (yaw decreases, protocol.md section 3).
    * Angular acceleration (rad/s^2): change of that angular velocity between two
      measurements over the time between them.
    * Rotation: roll, pitch, yaw of the robot in the world, each in [0, 2 pi) like
      GroundTruth.
    The first measurement after spawn has no previous one: it reports zero coordinate
    and angular acceleration.
    Each quantity may carry Gaussian noise (:class:`ImuNoise`), none by default.
    """

    NOISE = ImuNoise()
    ALIASES = {
        # named after the SEN segments (protocol.md 6.3); UDK IMU.uc has no settings
        "XYZAccelerationSigma": "acceleration_sigma_m_s2",
        "AngularVelSigma": "angular_velocity_sigma_rad_s",
        "AngularAccelSigma": "angular_acceleration_sigma_rad_s2",
        "RotationSigma": "orientation_sigma_rad",
        "IncludeGravity": "include_gravity",
    }

    def __init__(self, item: MountedItem, config: ImuConfig, robot: RobotConfig, seed: int) -> None:
        super().__init__(item, config, robot, seed)
        self._offset_mj = frames.to_mj_vec(self.item.location)  # mount, robot body frame (MuJoCo axes)
        self._mount_mj = frames.usar_euler_to_mj_mat(self.item.orientation)  # sensor axes in body axes
        self._last_time: float | None = None

    def _state(self, view: WorldView) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(world velocity of the sensor point, body rotation, body angular velocity in
        body axes), all in MuJoCo's frame, from the current qpos/qvel."""
        h, d = self.handle, view.data
        quat = d.qpos[h.root_qpos + 3 : h.root_qpos + 7]
        flat = np.empty(9)
        mujoco.mju_quat2Mat(flat, quat)
        rot = flat.reshape(3, 3)
        v = d.qvel[h.root_qvel : h.root_qvel + 6]
        # free joint: linear velocity of the body origin in the world frame, angular
        # velocity in the body frame (MuJoCo's convention)
        w_body = np.array(v[3:6], dtype=float)
        v_point = np.array(v[0:3], dtype=float) + rot @ _cross(w_body, self._offset_mj)
        return v_point, rot, w_body

    def reset(self, view: WorldView) -> None:
        v_point, _, w_body = self._state(view)
        self._last_time = view.time
        self._last_v = v_point
        self._last_w = self._mount_mj.T @ w_body

    def sense(self, view: WorldView) -> ImuValues:
        c = self.config
        v_point, rot, w_body = self._state(view)
        w_sensor = self._mount_mj.T @ w_body  # sensor axes (MuJoCo-style)
        if self._last_time is None:
            self._last_time, self._last_v, self._last_w = view.time, v_point, w_sensor
        dt = view.time - self._last_time
        if dt > 1e-9:
            acc_world = (v_point - self._last_v) / dt
            ang_acc = (w_sensor - self._last_w) / dt  # body-fixed axes: d/dt of the components
        else:
            acc_world = np.zeros(3)
            ang_acc = np.zeros(3)
        self._last_time, self._last_v, self._last_w = view.time, v_point, w_sensor
        if c.include_gravity:
            acc_world = acc_world - np.asarray(view.model.opt.gravity, dtype=float)
        acc_sensor = self._mount_mj.T @ (rot.T @ acc_world)
        ori = np.array(self.handle.orientation(view.data))
        return ImuValues(acc_sensor * _TO_USAR, w_sensor * _TO_USAR, ang_acc * _TO_USAR, ori)

    def reading(self, values: ImuValues) -> ImuReading:
        return ImuReading(
            self.name,
            _vec(values.acceleration),
            _vec(values.angular_velocity),
            _vec(values.angular_acceleration),
            _wrapped(values.orientation),
        )


# --------------------------------------------------------------------------- INU


@dataclass(frozen=True, kw_only=True)
class InuConfig(SensorConfig):
    """An INU's settings in a robot file (protocol.md 6.3): its scan interval and the mean and sigma (rad) of the
    Gaussian noise added to each angle."""

    # The old orientation sensor (protocol.md 6.3, "INU (old)"): no documented settings;
    # the sensor base ScanInterval 0.1 s (protocol.md 7.1).  Gaussian noise with the
    # generator's Mean and Sigma keys (protocol.md 7.1), exact by default.
    scan_interval_s: float = 0.1
    sigma_rad: float = 0.0
    mean_rad: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (self.sigma_rad >= 0 and math.isfinite(self.sigma_rad)):
            raise ValueError(f"sigma_rad must be a finite number >= 0, got {self.sigma_rad}")


class InuNoise(Noise):
    """The old orientation sensor's error (protocol.md 6.3, "INU (old)"): the Gaussian generator
    of protocol.md 7.1 with its Mean and Sigma keys, N(Mean, Sigma) added to each angle (roll,
    pitch, yaw, drawn in that order from the sensor's generator).  With Sigma 0 nothing is drawn:
    a non-zero Mean is then a constant offset of every angle.  ``true``: the three angles (rad)."""

    def apply(self, sensor: Sensor[Any], true: np.ndarray) -> np.ndarray:
        c: InuConfig = sensor.config
        if c.sigma_rad > 0:
            return true + sensor.rng.normal(c.mean_rad, c.sigma_rad, 3)
        if c.mean_rad != 0:
            return true + c.mean_rad
        return true


@SENSORS.register("INU")
class INU(Sensor[InuConfig]):
    """The robot's orientation (roll, pitch, yaw in the world, as GroundTruth), each angle
    plus N(Mean, Sigma) (:class:`InuNoise`), then wrapped into [0, 2 pi)."""

    NOISE = InuNoise()
    ALIASES = {"Sigma": "sigma_rad", "Mean": "mean_rad"}

    def sense(self, view: WorldView) -> np.ndarray:
        return np.array(self.handle.orientation(view.data), dtype=float)

    def reading(self, values: np.ndarray) -> OrientationReading:
        return OrientationReading(self.name, _wrapped(values))
