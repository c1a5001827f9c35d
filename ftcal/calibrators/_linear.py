"""The linear transformation model (LTM) of the thesis, eq. 1-2."""

from __future__ import annotations

from numbers import Real

import numpy as np
from numpy.typing import NDArray
from sklearn.linear_model import LinearRegression, Ridge
from sklearn.utils._param_validation import Interval

from ._base import BaseCalibrator, declare

__all__ = ["LinearCalibrator", "affine_fit"]


def affine_fit(X: NDArray[np.float64], y: NDArray[np.float64], ridge: float = 0.0,
               sample_weight: NDArray[np.float64] | None = None) -> LinearRegression | Ridge:
    """The affine least-squares fit ``y ≈ X C.T + b`` of scikit-learn (``Ridge`` on ``C`` when ``ridge > 0``),
    weighted by ``sample_weight`` (one weight >= 0 per row) when given.

    The one affine fit of ftcal: the LTM, the hybrid's and the GP's linear
    bases, the zero-load forward model. ``coef_`` is ``C`` (k, N) and
    ``intercept_`` is ``b`` (k,); the offset is never penalised.

    Examples
    --------
    >>> X = np.array([[0.0], [1.0], [2.0]])
    >>> fit = affine_fit(X, 3.0 * X + 1.0)
    >>> np.round(fit.coef_, 6).tolist(), np.round(fit.intercept_, 6).tolist()
    ([[3.0]], [1.0])
    """
    return (Ridge(ridge) if ridge > 0 else LinearRegression()).fit(X, y, sample_weight=sample_weight)


class LinearCalibrator(BaseCalibrator):
    """Affine least-squares calibration ``W = C S + b`` (eq. 1-2).

    ``C`` (6 x N) and ``b`` (6,) minimise ``sum_i ||W_i - C S_i - b||²``
    (eq. 2), optionally plus ``ridge * ||C||²`` (the offset is not
    penalised); ``fit(X, y, sample_weight=w)`` weighs row i's squared
    residual by ``w_i`` (weighted least squares). The per-component least-squares solution does not depend on
    the torque scale, so ``alpha_`` only enters the metrics.

    Parameters
    ----------
    ridge : float, default=0.0
        Ridge penalty on ``C``, in the squared units of ``raw`` (0 = plain
        least squares). Raw channels are centred first.
    alpha : float or None, default=None
        Torque scale ``Fmax / Tmax`` [m⁻¹] (eq. 5); ``None`` derives it from
        ``y`` with :func:`~ftcal.core.alpha_from_wrenches`.
    zero_reading : array-like of shape (N,) or None, default=None
        Known raw reading at zero load; ``None`` estimates it from the data
        (affine fit ``raw ≈ A w + z``). The LTM's offset absorbs it; it is
        exposed so every calibrator reports the same quantity.
    random_state : int, RandomState or None, default=None
        Unused (the fit is deterministic); accepted so that all calibrators
        share one signature.

    Attributes
    ----------
    calibration_matrix_ : ndarray of shape (6, N)
        ``C`` in [N] / [N·m] per raw unit.
    offset_ : ndarray of shape (6,)
        ``b`` in [N] / [N·m].
    alpha_ : float
        Torque scale used [m⁻¹].
    zero_reading_ : ndarray of shape (N,)
        Raw reading at zero load.
    n_features_in_ : int
        Number of raw channels N.

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import LinearCalibrator
    >>> rng = np.random.default_rng(0)
    >>> C = rng.normal(size=(6, 6)); b = np.arange(6.0)
    >>> raw = rng.normal(size=(50, 6))
    >>> model = LinearCalibrator().fit(raw, raw @ C.T + b)
    >>> bool(np.allclose(model.calibration_matrix_, C)), bool(np.allclose(model.offset_, b))
    (True, True)
    """

    _fitted_state = ("calibration_matrix_", "offset_")
    _parameter_constraints: dict = {
        **BaseCalibrator._parameter_constraints,
        "ridge": [Interval(Real, 0, None, closed="left")],
    }

    def __init__(self, *, ridge=0.0, alpha=None, zero_reading=None, random_state=None):
        self.ridge = ridge
        super().__init__(alpha=alpha, zero_reading=zero_reading, random_state=random_state)

    #: Takes ``sample_weight`` and asks for it through metadata routing by default (like ``groups``).
    __metadata_request__fit = {"sample_weight": True}

    def fit(self, X, y, sample_weight=None):
        """Fit ``C`` and ``b`` on raw readings ``X`` (n, N) and wrenches ``y`` (n, 6).

        Parameters
        ----------
        sample_weight : array-like of shape (n,) or None
            Weight of each row's squared residual (weighted least squares); ``None``: all rows alike. The
            zero-load reading and the noise estimate stay unweighted (properties of the sensor, not the fit).

        Returns
        -------
        self
        """
        return self._checked_fit(X, y, sample_weight=sample_weight)

    def __sklearn_tags__(self):
        # its coefficients plus one training row
        return declare(super().__sklearn_tags__(), cost="closed_form", family="linear",
                       min_training_rows=lambda n_channels: n_channels + 2)

    def _fit(self, X: NDArray[np.float64], y: NDArray[np.float64], sample_weight=None) -> None:
        fit = affine_fit(X, y, float(self.ridge), sample_weight)
        self.calibration_matrix_, self.offset_ = fit.coef_.reshape(y.shape[1], -1), np.reshape(fit.intercept_, -1)

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        return X @ self.calibration_matrix_.T + self.offset_

    def _emit_onnx(self, g, x: str) -> str:
        return g.affine(x, self.calibration_matrix_.T, self.offset_)
