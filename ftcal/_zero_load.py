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
  2. otherwise each raw channel is fitted as an affine function of the
     applied wrench, ``raw ≈ A w + z`` (least squares, ``A`` (N, 6)), and
     the intercept ``z`` is the reading at ``w = 0``. This is exact for a
     linear sensor; it needs loads that are not all collinear.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._wrench import scale_torques

__all__ = ["estimate_zero_reading", "ZERO_LOAD_TOLERANCE"]

#: A row is a zero-load row when its torque-scaled wrench norm is below this
#: fraction of the largest one in the data set.
ZERO_LOAD_TOLERANCE = 1e-3


def estimate_zero_reading(
    raw: NDArray[np.float64], wrench: NDArray[np.float64], alpha: float = 1.0
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

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(20, 6))
    >>> raw = w @ rng.normal(size=(6, 3)) + [1.0, -2.0, 0.5]
    >>> np.round(estimate_zero_reading(raw, w), 6)
    array([ 1. , -2. ,  0.5])
    """
    norm = np.linalg.norm(scale_torques(wrench, alpha), axis=1)
    unloaded = norm <= ZERO_LOAD_TOLERANCE * norm.max()
    if unloaded.any() and norm.max() > 0:
        return raw[unloaded].mean(axis=0)
    design = np.hstack([wrench, np.ones((wrench.shape[0], 1))])
    # Column scaling keeps the fit well conditioned when forces [N] and torques [N·m] differ a lot.
    scale = np.max(np.abs(design), axis=0)
    scale[scale == 0.0] = 1.0
    coef, *_ = np.linalg.lstsq(design / scale, raw, rcond=None)
    return coef[-1] / scale[-1]
