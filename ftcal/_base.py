"""Shared scikit-learn behaviour of every calibrator.

:class:`BaseCalibrator` does what the three calibrators of the thesis have in
common, so each model only implements ``_fit(X, y)`` and
``_predict_wrench(X)``:

* **validation** (``validate_data``): ``X`` (n, N >= 3) raw readings and ``y``
  (n, 6) wrenches, finite; NaN/inf give an error naming ``X`` or ``y`` and
  the first bad row; at ``predict`` the channel count must match ``fit``;
  ``predict`` before ``fit`` raises scikit-learn's ``NotFittedError``;
* **torque scale** ``alpha_`` (eq. 5-6): the ``alpha`` parameter, or
  :func:`~ftcal.alpha_from_wrenches` of the training targets when ``None``.
  Models apply it inside their losses; ``predict`` always returns the
  wrench in [N] and [N·m];
* **zero-load reading** ``zero_reading_`` (N,): the ``zero_reading``
  parameter (a known tare reading), or, when ``None``, the mean reading of
  the zero-load rows of the data, or failing those the intercept of an
  affine least-squares fit of the raw channels on the wrench (see
  :func:`ftcal._zero_load.estimate_zero_reading`);
* ``score`` is the usual coefficient of determination R² of
  :class:`~sklearn.base.RegressorMixin` (averaged over the 6 components);
  use :func:`ftcal.neg_scaled_rmse` as ``scoring`` for the thesis' eq. 18.
"""

from __future__ import annotations

import numbers

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted
from threadpoolctl import threadpool_limits

from ._exceptions import CalibrationInputError
from ._validation import check_finite_output, check_zero_reading, validate_readings, validate_training_data
from ._wrench import alpha_from_wrenches
from ._zero_load import estimate_zero_reading

__all__ = ["BaseCalibrator"]


def _resolve_alpha(alpha: float | None, y: NDArray[np.float64]) -> float:
    if alpha is None:
        return alpha_from_wrenches(y)
    if isinstance(alpha, bool) or not isinstance(alpha, numbers.Real) or not np.isfinite(alpha) or alpha <= 0:
        raise CalibrationInputError(
            f"alpha must be a positive finite number (Fmax / Tmax in [m⁻¹], eq. 5) or None to derive "
            f"it from y; got {alpha!r}."
        )
    return float(alpha)


class BaseCalibrator(RegressorMixin, BaseEstimator):
    """Common base of the calibrators; not meant to be used directly.

    Subclasses implement ``_fit(X, y)`` (``X`` float64 (n, N), ``y`` float64
    (n, 6) in [N] / [N·m]; ``alpha_`` and ``zero_reading_`` already set) and
    ``_predict_wrench(X)`` returning (n, 6) in [N] / [N·m].
    """

    def fit(self, X: ArrayLike, y: ArrayLike):
        """Fit the calibration on raw readings ``X`` (n, N) and wrenches ``y`` (n, 6).

        Returns
        -------
        self
        """
        X, y = validate_training_data(self, X, y)
        # One BLAS thread: the least-squares problems are tall and thin; on a busy 2-core machine
        # threaded OpenBLAS made a 5000-sample fit ~300x slower (0.25 s instead of < 1 ms).
        with threadpool_limits(1, user_api="blas"):
            self.alpha_ = _resolve_alpha(self.alpha, y)
            if self.zero_reading is None:
                self.zero_reading_ = estimate_zero_reading(X, y, self.alpha_)
            else:
                self.zero_reading_ = check_zero_reading(self.zero_reading, X.shape[1])
            self._fit(X, y)
        return self

    def predict(self, X: ArrayLike) -> NDArray[np.float64]:
        """Wrench [Fx, Fy, Fz, Tx, Ty, Tz] in [N] and [N·m] for raw readings ``X`` (n, N).

        Returns
        -------
        ndarray of shape (n_samples, 6), float64
        """
        check_is_fitted(self)
        X = validate_readings(self, X)
        with np.errstate(over="ignore", invalid="ignore"):
            wrench = np.asarray(self._predict_wrench(X), dtype=np.float64)
        check_finite_output(X, wrench, self)
        return wrench

    def _fit(self, X: NDArray[np.float64], y: NDArray[np.float64]) -> None:  # pragma: no cover
        raise NotImplementedError

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:  # pragma: no cover
        raise NotImplementedError

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.required = True
        tags.target_tags.multi_output = True
        tags.target_tags.single_output = False
        tags.input_tags.allow_nan = False
        return tags
