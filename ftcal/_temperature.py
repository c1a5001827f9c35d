"""Temperature: simulated thermal drift of a sensor, and its compensation (issue 15).

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

:class:`ThermalDrift` simulates it; :class:`TemperatureCompensatedCalibrator`
learns ``g`` and ``o`` from calibration data recorded over a temperature
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

import numbers
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.base import clone
from sklearn.utils.validation import check_is_fitted

from ._base import BaseCalibrator
from ._exceptions import CalibrationInputError
from ._linear import LinearCalibrator
from ._validation import validate_readings, validate_training_data
from ._zero_load import GATED_MIN_SAMPLES

__all__ = ["ThermalDrift", "TemperatureCompensatedCalibrator", "check_temperature", "REFERENCE_TEMPERATURE"]

#: Temperature [deg C] at which drift is zero by convention (room temperature).
REFERENCE_TEMPERATURE = 25.0
#: Temperatures outside this range [deg C] are refused as implausible for a strain-gauge sensor.
PLAUSIBLE_TEMPERATURE = (-60.0, 200.0)


def check_temperature(temperature: ArrayLike, n_rows: int, name: str = "temperature") -> NDArray[np.float64]:
    """Validate temperatures [deg C]: one finite value per row, within :data:`PLAUSIBLE_TEMPERATURE`.

    Examples
    --------
    >>> check_temperature([20.0, 25.5], 2)
    array([20. , 25.5])
    >>> check_temperature([20.0, 2500.0], 2)
    Traceback (most recent call last):
    ...
    ftcal._exceptions.CalibrationInputError: temperature row 1 is 2500 deg C, outside -60..200 deg C: is it in kelvin, or in tenths of a degree? Give deg C.
    """
    t = np.asarray(temperature)
    if np.iscomplexobj(t) or t.dtype.kind not in "iuf":
        raise CalibrationInputError(f"{name} must hold numbers in deg C; got dtype {t.dtype}.")
    t = t.astype(float)
    if t.shape != (n_rows,):
        raise CalibrationInputError(f"{name} must have shape ({n_rows},), one value per row; got {t.shape}.")
    bad = ~np.isfinite(t)
    if bad.any():
        raise CalibrationInputError(f"{name} row {int(np.argmax(bad))} is NaN or inf; repair or drop that row.")
    low, high = PLAUSIBLE_TEMPERATURE
    out = (t < low) | (t > high)
    if out.any():
        i = int(np.argmax(out))
        raise CalibrationInputError(
            f"{name} row {i} is {t[i]:g} deg C, outside {low:g}..{high:g} deg C: is it in kelvin, or in tenths "
            "of a degree? Give deg C."
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


class TemperatureCompensatedCalibrator(BaseCalibrator):
    """A calibrator behind per-channel thermal offset and gain compensation (iCub-style temperature coefficients).

    ``X`` holds the raw channels **and, as its last column, the sensor
    temperature [deg C]**. ``fit`` learns, per channel ``c``, the coefficients
    of ``raw_c(T) = raw_c(T0) (1 + g_c ΔT) + o_c ΔT`` from the calibration
    data: a forward model of each channel (the sign-gated least-squares model
    of :mod:`ftcal._zero_load`) with temperature terms, solved by a few
    alternating least-squares passes (the equation is bilinear in the gain).
    The readings are then brought to ``reference_temperature``,
    ``raw_c(T0) = (raw_c(T) - o_c ΔT) / (1 + g_c ΔT)``, and ``estimator`` is fitted
    on them; ``predict`` applies the same correction. The calibration data must
    span the temperatures of use (a drift cannot be learned at one temperature).

    Parameters
    ----------
    estimator : calibrator or None, default=None
        The calibrator fed the compensated readings; ``None``: :class:`~ftcal.LinearCalibrator`.
    reference_temperature : float, default=25
        ``T0`` [deg C].
    n_iterations : int, default=5
        Alternating least-squares passes.
    alpha : float or None, default=None
        Torque scale; given to ``estimator`` when it has this parameter.
    zero_reading : array-like of shape (N,) or None, default=None
        Raw zero-load reading at ``T0``; given to ``estimator``.
    random_state : int or None, default=None
        Given to ``estimator``.

    Attributes
    ----------
    offset_per_deg_ : ndarray of shape (N,)
        Learned ``o`` [raw unit / deg C].
    gain_per_deg_ : ndarray of shape (N,)
        Learned ``g`` [1 / deg C].
    estimator_ : calibrator
        The fitted calibrator on compensated readings.
    alpha_, zero_reading_, n_features_in_
        ``n_features_in_`` counts the temperature column too.

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import TemperatureCompensatedCalibrator, ThermalDrift
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(400, 6)); raw = w @ rng.normal(size=(6, 6))
    >>> T = rng.uniform(15, 35, size=400)
    >>> drift = ThermalDrift(offset_per_deg=np.full(6, 0.02), gain_per_deg=np.full(6, 2e-3))
    >>> X = np.column_stack([drift.apply(raw, T), T])
    >>> model = TemperatureCompensatedCalibrator(alpha=1.0).fit(X, w)
    >>> np.round(model.offset_per_deg_, 3), np.round(model.gain_per_deg_, 4)
    (array([0.02, 0.02, 0.02, 0.02, 0.02, 0.02]), array([0.002, 0.002, 0.002, 0.002, 0.002, 0.002]))
    """

    def __init__(self, estimator=None, *, reference_temperature=REFERENCE_TEMPERATURE, n_iterations=5,
                 alpha=None, zero_reading=None, random_state=None):
        self.estimator = estimator
        self.reference_temperature = reference_temperature
        self.n_iterations = n_iterations
        self.alpha = alpha
        self.zero_reading = zero_reading
        self.random_state = random_state

    def _split(self, X: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        if X.shape[1] < 4:
            raise CalibrationInputError(
                f"X has {X.shape[1]} columns; TemperatureCompensatedCalibrator needs the raw channels and, last, "
                "the temperature [deg C] (at least 3 + 1 columns)."
            )
        raw, temperature = X[:, :-1], X[:, -1]
        return raw, check_temperature(temperature, len(X), "temperature (the last column of X)")

    def _compensate(self, raw: NDArray[np.float64], temperature: NDArray[np.float64]) -> NDArray[np.float64]:
        dt = (temperature - self.reference_temperature)[:, None]
        return (raw - dt * self.offset_per_deg_) / (1.0 + dt * self.gain_per_deg_)

    def fit(self, X: ArrayLike, y: ArrayLike):
        """Learn the thermal coefficients, then fit ``estimator`` on compensated readings.

        Returns
        -------
        self
        """
        t0 = self.reference_temperature
        if isinstance(t0, bool) or not isinstance(t0, numbers.Real) or not np.isfinite(t0):
            raise CalibrationInputError(f"reference_temperature must be a finite number in deg C; got {t0!r}.")
        n_it = self.n_iterations
        if isinstance(n_it, bool) or not isinstance(n_it, numbers.Integral) or n_it < 1:
            raise CalibrationInputError(f"n_iterations must be an integer >= 1; got {n_it!r}.")
        X, y = validate_training_data(self, X, y)
        raw, temperature = self._split(X)
        dt = temperature - t0
        if np.ptp(temperature) < 1.0:
            raise CalibrationInputError(
                f"the temperatures span only {np.ptp(temperature):.2g} deg C; a thermal drift can only be learned "
                "from calibration data recorded over the temperature range of use (several deg C)."
            )
        if len(y) >= GATED_MIN_SAMPLES:
            design = np.hstack([np.maximum(y, 0.0), np.minimum(y, 0.0), np.ones((len(y), 1))])
        else:
            design = np.hstack([y, np.ones((len(y), 1))])
        scale = np.max(np.abs(design), axis=0)
        design = design / np.where(scale > 0, scale, 1.0)
        gain = np.zeros(raw.shape[1])
        offset = np.zeros(raw.shape[1])
        for _ in range(int(n_it)):
            for c in range(raw.shape[1]):
                # raw_c = f_c(w) (1 + g ΔT) + o ΔT, with f_c = design @ beta: linear in beta for fixed g ...
                a = design * (1.0 + gain[c] * dt)[:, None]
                beta, *_ = np.linalg.lstsq(np.hstack([a, dt[:, None]]), raw[:, c], rcond=None)
                f = design @ beta[:-1]
                # ... and linear in (g, o) for fixed f
                (gain[c], offset[c]), *_ = np.linalg.lstsq(np.column_stack([f * dt, dt]), raw[:, c] - f, rcond=None)
        self.gain_per_deg_, self.offset_per_deg_ = gain, offset
        inner = LinearCalibrator() if self.estimator is None else clone(self.estimator)
        params = inner.get_params()
        inner.set_params(**{k: getattr(self, k) for k in ("alpha", "zero_reading", "random_state") if k in params})
        self.estimator_ = inner.fit(self._compensate(raw, temperature), y)
        self.alpha_ = self.estimator_.alpha_
        self.zero_reading_ = np.append(self.estimator_.zero_reading_, t0)
        return self

    def retare(self, X_no_load: ArrayLike, *, max_spread: float = 5.0):
        """Re-zero from zero-load readings ``[raw, temperature]`` taken now: compensated first, then passed to
        the inner calibrator's :meth:`~ftcal._base.BaseCalibrator.retare`.

        Returns
        -------
        self
        """
        check_is_fitted(self)
        raw, temperature = self._split(validate_readings(self, X_no_load))
        self.estimator_.retare(self._compensate(raw, temperature), max_spread=max_spread)
        return self

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        raw, temperature = self._split(X)
        return self.estimator_.predict(self._compensate(raw, temperature))

