"""Temperature compensation in front of any calibrator; the drift model is in :mod:`ftcal.core._temperature`."""

from __future__ import annotations

from numbers import Integral, Real

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.utils._param_validation import HasMethods, Interval
from sklearn.utils.validation import check_is_fitted

from ..calibrators._base import BaseCalibrator, calibration_tags, declare
from ..core._exceptions import CalibrationInputError
from ..core._temperature import REFERENCE_TEMPERATURE, check_temperature
from ..core._validation import validate_readings
from ..calibrators._zero_load import forward_design
from ._wrapper import CalibratorWrapper

__all__ = ["TemperatureCompensatedCalibrator"]


class TemperatureCompensatedCalibrator(CalibratorWrapper):
    """A calibrator behind per-channel thermal offset and gain compensation (iCub-style temperature coefficients).

    ``X`` holds the raw channels **and, as its last column, the sensor
    temperature [deg C]**. ``fit`` learns, per channel ``c``, the coefficients
    of ``raw_c(T) = raw_c(T0) (1 + g_c ΔT) + o_c ΔT`` from the calibration
    data: a forward model of each channel (the sign-gated least-squares model
    of :mod:`ftcal.calibrators._zero_load`) with temperature terms, solved by a few
    alternating least-squares passes (the equation is bilinear in the gain).
    The readings are then brought to ``reference_temperature``,
    ``raw_c(T0) = (raw_c(T) - o_c ΔT) / (1 + g_c ΔT)``, and ``estimator`` is fitted
    on them; ``predict`` applies the same correction. The calibration data must
    span the temperatures of use (a drift cannot be learned at one temperature).

    Parameters
    ----------
    estimator : calibrator, regressor or None, default=None
        The calibrator fed the compensated readings; ``None``: :class:`~ftcal.LinearCalibrator`. Any
        scikit-learn regressor may be given: it is composed into a calibrator (a
        :class:`~ftcal.calibrators.StockCalibrator` around it: tare, torque scale and range).
    reference_temperature : float, default=25
        ``T0`` [deg C].
    n_iterations : int, default=5
        Alternating least-squares passes.
    alpha : float or None, default=None
        Torque scale; given to ``estimator`` when it has this parameter (``None``: ``estimator``'s own is kept).
    zero_reading : array-like of shape (N,) or None, default=None
        Raw zero-load reading at ``T0``; given to ``estimator`` (``None``: its own is kept; one set on
        ``estimator`` must then be taken at ``reference_temperature``).
    random_state : int or None, default=None
        Given to ``estimator`` (``None``: its own is kept).

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
    >>> from ftcal import TemperatureCompensatedCalibrator
    >>> from ftcal.core import ThermalDrift
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(400, 6)); raw = w @ rng.normal(size=(6, 6))
    >>> T = rng.uniform(15, 35, size=400)
    >>> drift = ThermalDrift(offset_per_deg=np.full(6, 0.02), gain_per_deg=np.full(6, 2e-3))
    >>> X = np.column_stack([drift.apply(raw, T), T])
    >>> model = TemperatureCompensatedCalibrator(alpha=1.0).fit(X, w)
    >>> np.round(model.offset_per_deg_, 3), np.round(model.gain_per_deg_, 4)
    (array([0.02, 0.02, 0.02, 0.02, 0.02, 0.02]), array([0.002, 0.002, 0.002, 0.002, 0.002, 0.002]))
    """

    _fitted_state = ("offset_per_deg_", "gain_per_deg_", "estimator_")
    _parameter_constraints: dict = {
        **BaseCalibrator._parameter_constraints,
        "estimator": [HasMethods(["fit", "predict"]), None],
        "reference_temperature": [Interval(Real, -273.15, None, closed="neither")],
        "n_iterations": [Interval(Integral, 1, None, closed="left")],
    }

    def __init__(self, estimator=None, *, reference_temperature=REFERENCE_TEMPERATURE, n_iterations=5,
                 alpha=None, zero_reading=None, random_state=None):
        self.estimator = estimator
        self.reference_temperature = reference_temperature
        self.n_iterations = n_iterations
        super().__init__(alpha=alpha, zero_reading=zero_reading, random_state=random_state)

    def _split(self, X: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        if X.shape[1] < 2:  # like every calibrator, a regressor of any channel count (the wrench rule is the data's)
            raise CalibrationInputError(
                f"X has {X.shape[1]} feature(s) (columns); TemperatureCompensatedCalibrator needs the raw channels and, last, "
                "the temperature [deg C] (at least 1 + 1 columns).", parameter="X"
            )
        raw, temperature = X[:, :-1], X[:, -1]
        return raw, check_temperature(temperature, len(X), "temperature (the last column of X)")

    def _compensate(self, raw: NDArray[np.float64], temperature: NDArray[np.float64]) -> NDArray[np.float64]:
        dt = (temperature - self.reference_temperature)[:, None]
        return (raw - dt * self.offset_per_deg_) / (1.0 + dt * self.gain_per_deg_)

    def __sklearn_tags__(self):
        # its last input column is the temperature, not a channel; otherwise it is what it wraps
        inner = calibration_tags(self._inner())
        return declare(super().__sklearn_tags__(), temperature_column=True,
                       min_training_rows=lambda n_columns: inner.min_training_rows(max(n_columns - 1, 1)))

    def _fit_inner(self, X, y, inner, routed):
        """Learn the thermal coefficients (unweighted: a property of the sensor), then fit ``inner`` on
        compensated readings; the tare of the wrapper's columns is the inner one at ``reference_temperature``."""
        t0 = float(self.reference_temperature)
        raw, temperature = self._split(X)
        dt = temperature - t0
        if np.ptp(temperature) < 1.0:
            raise CalibrationInputError(
                f"the temperatures span only {np.ptp(temperature):.2g} deg C; a thermal drift can only be learned "
                "from calibration data recorded over the temperature range of use (several deg C)."
            )
        # the forward model of the zero-load estimate, with temperature terms below
        design = forward_design(np.asarray(y, dtype=float))
        gain = np.zeros(raw.shape[1])
        offset = np.zeros(raw.shape[1])
        for _ in range(int(self.n_iterations)):
            for c in range(raw.shape[1]):
                # raw_c = f_c(w) (1 + g ΔT) + o ΔT, with f_c = design @ beta: linear in beta for fixed g ...
                a = design * (1.0 + gain[c] * dt)[:, None]
                beta, *_ = np.linalg.lstsq(np.hstack([a, dt[:, None]]), raw[:, c], rcond=None)
                f = design @ beta[:-1]
                # ... and linear in (g, o) for fixed f
                (gain[c], offset[c]), *_ = np.linalg.lstsq(np.column_stack([f * dt, dt]), raw[:, c] - f, rcond=None)
        self.gain_per_deg_, self.offset_per_deg_ = gain, offset
        self.estimator_ = self._settled(inner).fit(self._compensate(raw, temperature), y, **routed)
        return self.estimator_, np.append(self.estimator_.zero_reading_, t0)

    def retare(self, X_no_load: ArrayLike, *, max_spread: float = 5.0):
        """Re-zero from zero-load readings ``[raw, temperature]`` taken now: compensated first, then passed to
        the inner calibrator's :meth:`~ftcal.calibrators._base.BaseCalibrator.retare`.

        Returns
        -------
        self
        """
        check_is_fitted(self)
        compensated = self._compensate(*self._split(validate_readings(self, X_no_load)))
        self.estimator_.retare(compensated, max_spread=max_spread)
        return self

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.estimator_.predict(self._compensate(*self._split(X)))

    def _emit_onnx(self, g, x: str) -> str:
        n = int(self.n_features_in_)
        raw, temperature = g.columns(x, 0, n - 1), g.columns(x, n - 1, n)
        dt = g.op("Sub", temperature, g.const(float(self.reference_temperature)))
        shifted = g.op("Sub", raw, g.op("Mul", dt, g.const(self.offset_per_deg_)))
        scale = g.op("Add", g.const(1.0), g.op("Mul", dt, g.const(self.gain_per_deg_)))
        return g.calibration(self.estimator_, g.op("Div", shifted, scale))

