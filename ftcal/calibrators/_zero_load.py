"""The zero-load raw reading (tare) of a sensor.

The directional model needs readings that are zero at zero load (eq. 3-4
take the norm and direction of the reading). Two sources:

* **given** (``zero_reading=array``): the raw reading recorded with nothing
  attached, shape (N,). Best for real sensors, and the only exact choice
  for a sensor whose response to ``+w`` and ``-w`` differs (asymmetric
  gains), where an affine fit is biased.
* **estimated** (``zero_reading=None``) from the calibration data:

  1. if the data contain zero-load rows (torque-scaled wrench norm below
     ``1e-3`` of the largest), the mean raw reading of those rows;
  2. otherwise each raw channel is fitted as a **sign-gated** function of the
     applied wrench, ``raw ≈ A⁺ max(w, 0) + A⁻ min(w, 0) + z`` (least squares,
     ``A⁺`` and ``A⁻`` (N, 6)), and the intercept ``z`` is the reading at
     ``w = 0``. A sensor whose + and - loads see different gains (thesis
     II-A-d) bends at the zero load; the plain affine fit ``raw ≈ A w + z``
     spreads that bend into its intercept (with +/-8 % gains the affine
     intercept is off by a few % of the reading span, which the directional
     model turns into a 6x larger error), while the gated fit is exact for it
     and equal to the affine one for a linear sensor. It needs loads of both
     signs on the axes and at least :data:`GATED_MIN_SAMPLES` rows; with fewer
     the affine fit is used.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sklearn.linear_model import LinearRegression

from ..core._wrench import scale_torques

__all__ = ["estimate_zero_reading", "reading_noise", "forward_design", "ZERO_LOAD_TOLERANCE", "GATED_MIN_SAMPLES"]

#: A row is a zero-load row when its torque-scaled wrench norm is below this
#: fraction of the largest one in the data set.
ZERO_LOAD_TOLERANCE = 1e-3
#: Fewest rows for the sign-gated fit (13 unknowns per channel, four rows per unknown); fewer: the affine fit.
GATED_MIN_SAMPLES = 52


def estimate_zero_reading(
    raw: NDArray[np.float64], wrench: NDArray[np.float64], alpha: float = 1.0, axes=None
) -> NDArray[np.float64]:
    """Raw reading at zero load, shape (N,), estimated from calibration data.

    Parameters
    ----------
    raw : ndarray of shape (n_samples, N)
        Raw channel readings.
    wrench : ndarray of shape (n_samples, 6)
        Applied wrenches in [N] and [N·m].
    alpha : float, default=1.0
        Torque scale [m⁻¹] used to decide which rows are zero-load rows.
    axes : sequence of str, optional
        The wrench's axes (default: Fx..Tz for six columns, else forces only).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(20, 6))
    >>> raw = w @ rng.normal(size=(6, 3)) + [1.0, -2.0, 0.5]
    >>> np.round(estimate_zero_reading(raw, w), 6)
    array([ 1. , -2. ,  0.5])

    Sign-dependent gains (+10 % / -10 %) do not bias it:

    >>> w = rng.normal(size=(400, 6))
    >>> raw = np.where(w > 0, 1.1, 0.9) * w @ rng.normal(size=(6, 8)) + 3.0
    >>> bool(np.allclose(estimate_zero_reading(raw, w), 3.0))
    True
    """
    norm = np.linalg.norm(scale_torques(wrench, alpha, axes), axis=1)
    unloaded = norm <= ZERO_LOAD_TOLERANCE * norm.max()
    if unloaded.any() and norm.max() > 0:
        return raw[unloaded].mean(axis=0)
    coef, _ = _forward_fit(raw, wrench)
    return coef[-1]


def forward_design(wrench: NDArray[np.float64]) -> NDArray[np.float64]:
    """Columns of the forward model ``raw ≈ f(wrench)``, each scaled to at most 1 in magnitude, and a last
    column of ones: ``[max(w, 0), min(w, 0), 1]`` (sign-gated) from :data:`GATED_MIN_SAMPLES` rows on, else
    ``[w, 1]``. The scaling keeps the fit well conditioned when forces [N] and torques [N·m] differ a lot.
    Shared with the temperature compensation, whose drift model multiplies it."""
    gated = [np.maximum(wrench, 0.0), np.minimum(wrench, 0.0)] if wrench.shape[0] >= GATED_MIN_SAMPLES else [wrench]
    design = np.hstack(gated)
    scale = np.max(np.abs(design), axis=0)
    return np.hstack([design / np.where(scale > 0, scale, 1.0), np.ones((wrench.shape[0], 1))])


def _forward_fit(raw: NDArray[np.float64], wrench: NDArray[np.float64]):
    """Least-squares forward model ``raw ≈ f(wrench)`` on :func:`forward_design`'s columns (scikit-learn's
    ``LinearRegression``): the coefficients per design column (the last, the intercept, is the reading at zero
    load, in raw units) and the residuals."""
    design = forward_design(wrench)[:, :-1]
    fit = LinearRegression().fit(design, raw)
    coef = np.vstack([fit.coef_.reshape(raw.shape[1], -1).T, fit.intercept_])
    return coef, raw - fit.predict(design).reshape(raw.shape)


def reading_noise(raw: NDArray[np.float64], wrench: NDArray[np.float64]) -> NDArray[np.float64]:
    """Scatter of each raw channel about the forward model of :func:`estimate_zero_reading`, shape (N,).

    The sensor noise in raw units as the training data show it (an upper
    bound for a nonlinear sensor, whose nonlinearity adds to it); the
    quietness check of :meth:`ftcal.calibrators._base.BaseCalibrator.retare` compares
    new zero-load readings with it.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(2000, 6))
    >>> raw = w @ rng.normal(size=(6, 3)) + 0.1 * rng.normal(size=(2000, 3))
    >>> np.round(reading_noise(raw, w), 2)
    array([0.1, 0.1, 0.1])
    """
    coef, residual = _forward_fit(raw, wrench)
    dof = max(raw.shape[0] - coef.shape[0], 1)
    return np.sqrt((residual**2).sum(axis=0) / dof)
