"""Noise and output ranges a sensor declares, applied by the framework to what it senses.

A sensor plugin says what it is corrupted by with its class attribute ``NOISE`` (a
:class:`Noise`); :meth:`usarsim.sensors.base.Sensor.measure` hands the true values of its
:meth:`~usarsim.sensors.base.Sensor.sense` to the noise, then the corrupted ones to its
:meth:`~usarsim.sensors.base.Sensor.reading`.  The draws come from the sensor's own seeded
generator (:meth:`~usarsim.sensors.base.Sensor.uniform`), in the order the values come, so
that the same seed gives the same readings to the bit.

* :data:`RANGES`: a range finder's distances (Sonar, IR, RangeScanner, RangeScanner3D);
* :data:`RELATIVE`: every value times 1 + u, u uniform within the configured noise (the
  ``Noise`` of protocol.md 7.1; the Tachometer).

Noise that belongs to a sensor's own model is a named :class:`Noise` declared in that
sensor's module, where its source is cited: the GPS's error from the satellites in view
(``SatelliteNoise``), the IMU's and the INU's Gaussian errors (``ImuNoise``, ``InuNoise``),
the encoder's counting error and the INS's drift (``EncoderCountNoise``, ``InsDrift``,
:mod:`usarsim.sensors.motion`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from usarsim.sensors.base import Sensor


class Noise:
    """What corrupts a sensor's true values (see the module's description)."""

    def apply(self, sensor: Sensor[Any], true: Any) -> Any:
        raise NotImplementedError


class RangeNoise(Noise):
    """Distances of a range finder (its settings' ``min_range_m``, ``max_range_m`` and
    ``noise``): a distance beyond reach (infinite, or past the sensor's MaxRange) reads MaxRange;
    one within it gets the relative noise (uniform, within +- ``noise`` of it, protocol.md 7.1);
    every value is held to [MinRange, MaxRange].  ``true``: one distance, or an array of them
    (a sweep, whose rays are cast no farther than MaxRange: a finite one is within reach)."""

    def apply(self, sensor: Sensor[Any], true: Any) -> Any:
        cfg = sensor.config
        if isinstance(true, float):
            value = sensor.relative_noise_scalar(true) if true <= cfg.max_range_m else cfg.max_range_m
            return min(max(value, cfg.min_range_m), cfg.max_range_m)
        hit = np.isfinite(true)
        values = np.full(len(true), cfg.max_range_m)
        if hit.any():
            values[hit] = sensor.relative_noise(true[hit])
        np.clip(values, cfg.min_range_m, cfg.max_range_m, out=values)
        return values


class RelativeNoise(Noise):
    """Every value times 1 + u, u uniform within +- the settings' ``noise``; ``true``: an
    array, or a tuple of arrays (corrupted in their order)."""

    def apply(self, sensor: Sensor[Any], true: Any) -> Any:
        if isinstance(true, tuple):
            return tuple(sensor.relative_noise(v) for v in true)
        return sensor.relative_noise(true)


RANGES = RangeNoise()
RELATIVE = RelativeNoise()

__all__ = ["RANGES", "RELATIVE", "Noise", "RangeNoise", "RelativeNoise"]
