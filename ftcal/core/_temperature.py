"""Temperature: simulated thermal drift of a sensor, and its compensation.

Strain gauges drift with temperature in two ways, both specified per channel
in load-cell and F/T sensor data sheets:

* **zero (offset) drift**: the unloaded reading moves, typically 0.01-0.05 %
  of the full-scale reading per deg C (load-cell data sheets give ±0.02 % RO/°C;
  iCub's FT sensors read Fx 12.66 N at 25 °C and 13.37 N at 39 °C, 0.05 N/°C);
* **span (gain) drift**: the sensitivity changes, typically 0.01-0.03 %/°C.

Over a 20 °C range that is a zero shift of up to 1 % of full scale, i.e. the
10-30 N drifts robot users report. The model of both, per channel ``c``, with
``ΔT = T - reference_temperature``::

    raw_c(T) = raw_c(T0) · (1 + g_c ΔT) + o_c ΔT

:class:`ThermalDrift` simulates it; :class:`~ftcal.TemperatureCompensatedCalibrator`
(:mod:`ftcal.compose._temperature_compensation`) learns ``g`` and ``o`` from calibration data recorded over a temperature
range (the iCub approach: per-axis temperature coefficients) and undoes them
before any calibrator sees the readings.

**Creep** (thesis II-A-b, eq. 11) is modelled in the thesis as a constant
relative gain change ``C' = C (1 + δ)`` of a dataset: it carries no time, so
it is indistinguishable from the calibration matrix itself, every calibrator
(the LTM included) absorbs it, and a time-aware model has nothing left to
recover. Creep that grows with the time under load would need the load
history as an input, which neither the thesis' data nor ftcal's logs carry.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._exceptions import CalibrationInputError

__all__ = ["ThermalDrift", "check_temperature", "TemperatureValueError", "REFERENCE_TEMPERATURE",
           "PLAUSIBLE_TEMPERATURE"]

#: Temperature [deg C] at which drift is zero by convention (room temperature).
REFERENCE_TEMPERATURE = 25.0
#: Temperatures outside this range [deg C] are refused as implausible for a strain-gauge sensor.
PLAUSIBLE_TEMPERATURE = (-60.0, 200.0)


class TemperatureValueError(CalibrationInputError):
    """A temperature that is not a usable value in deg C; ``row`` is the offending row (None for a shape error)."""

    def __init__(self, message: str, row: int | None = None, **fields) -> None:
        super().__init__(message, row=row, **fields)


def check_temperature(temperature: ArrayLike, n_rows: int, name: str = "temperature") -> NDArray[np.float64]:
    """Validate temperatures [deg C]: one finite value per row, within :data:`PLAUSIBLE_TEMPERATURE`.

    Examples
    --------
    >>> check_temperature([20.0, 25.5], 2)
    array([20. , 25.5])
    >>> check_temperature([20.0, 2500.0], 2)
    Traceback (most recent call last):
    ...
    ftcal.core._temperature.TemperatureValueError: temperature row 1 is 2500 deg C, outside -60..200 deg C: is it in kelvin, or in tenths of a degree? Give deg C.
    """
    t = np.asarray(temperature)
    if np.iscomplexobj(t) or t.dtype.kind not in "iuf":
        raise CalibrationInputError(f"{name} must hold numbers in deg C; got dtype {t.dtype}.")
    t = t.astype(float)
    if t.shape != (n_rows,):
        raise CalibrationInputError(f"{name} must have shape ({n_rows},), one value per row; got {t.shape}.")
    bad = ~np.isfinite(t)
    if bad.any():
        row = int(np.argmax(bad))
        raise TemperatureValueError("{row} is NaN or inf; repair or drop that reading.", row, parameter=name)
    low, high = PLAUSIBLE_TEMPERATURE
    out = (t < low) | (t > high)
    if out.any():
        i = int(np.argmax(out))
        raise TemperatureValueError(
            f"{{row}} is {t[i]:g} deg C, outside {low:g}..{high:g} deg C: is it in kelvin, or in tenths of a degree? "
            "Give deg C.", i, parameter=name, value=float(t[i])
        )
    return t


@dataclass(frozen=True)
class ThermalDrift:
    """Per-channel thermal offset and gain drift of a sensor (simulation).

    Attributes
    ----------
    offset_per_deg : ndarray of shape (N,)
        Zero drift ``o`` [raw unit / deg C].
    gain_per_deg : ndarray of shape (N,)
        Span drift ``g`` [1 / deg C].
    reference_temperature : float
        ``T0`` [deg C] where the drift is zero.

    Examples
    --------
    >>> drift = ThermalDrift(offset_per_deg=np.array([0.01, 0.0]), gain_per_deg=np.array([0.0, 1e-3]))
    >>> drift.apply(np.array([[1.0, 2.0]]), np.array([35.0]))
    array([[1.1 , 2.02]])
    """

    offset_per_deg: NDArray[np.float64]
    gain_per_deg: NDArray[np.float64]
    reference_temperature: float = REFERENCE_TEMPERATURE

    @classmethod
    def typical(cls, full_scale_reading: ArrayLike, *, zero_pct_per_deg: float = 0.03,
                span_pct_per_deg: float = 0.02, random_state=None) -> "ThermalDrift":
        """Random drift of data-sheet magnitude: zero drift ±``zero_pct_per_deg`` % of each channel's full-scale
        reading per deg C, span drift ±``span_pct_per_deg`` %/deg C (signs and sizes drawn per channel,
        magnitudes uniform in [0.5, 1] of the bound)."""
        fs = np.abs(np.asarray(full_scale_reading, dtype=float))
        rng = np.random.default_rng(random_state)

        def draw():
            return rng.choice([-1.0, 1.0], size=fs.size) * rng.uniform(0.5, 1.0, size=fs.size)

        return cls(offset_per_deg=draw() * zero_pct_per_deg / 100 * fs,
                   gain_per_deg=draw() * span_pct_per_deg / 100)

    def apply(self, raw: ArrayLike, temperature: ArrayLike) -> NDArray[np.float64]:
        """Readings at ``temperature`` [deg C] (n,) of a sensor whose readings at ``T0`` are ``raw`` (n, N)."""
        raw = np.asarray(raw, dtype=float)
        dt = check_temperature(temperature, len(raw)) - self.reference_temperature
        return raw * (1.0 + np.outer(dt, self.gain_per_deg)) + np.outer(dt, self.offset_per_deg)
