"""Input validation shared by every calibrator.

All checks raise :class:`~ftcal.CalibrationInputError` (a ``ValueError``) with
a message that names the array, its shape or the first offending row, and
says how to fix it. Shape and dtype handling goes through scikit-learn's
``validate_data`` so ``n_features_in_`` and the feature-count check at
``predict`` follow the scikit-learn conventions.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.utils.validation import check_array, check_consistent_length, validate_data

from ._exceptions import CalibrationInputError

__all__ = [
    "check_all_finite",
    "check_zero_reading",
    "validate_training_data",
    "validate_readings",
    "min_training_samples",
]

#: Fewest raw channels a calibrator accepts.
MIN_CHANNELS = 3


def check_all_finite(a: NDArray[np.float64], name: str, fix: str) -> None:
    """Raise if ``a`` holds NaN or inf, naming the first bad row and column.

    Examples
    --------
    >>> check_all_finite(np.array([[1.0, 2.0], [np.nan, 0.0]]), "X", "drop that row")
    Traceback (most recent call last):
    ...
    ftcal._exceptions.CalibrationInputError: X contains NaN or inf: first at row 1, column 0 (value nan). Fix: drop that row.
    """
    bad = ~np.isfinite(a)
    if bad.any():
        where = np.argwhere(bad)[0]
        row = int(where[0])
        col = int(where[1]) if where.size > 1 else 0
        value = a[tuple(where)]
        raise CalibrationInputError(
            f"{name} contains NaN or inf: first at row {row}, column {col} (value {value}). Fix: {fix}."
        )


def min_training_samples(n_channels: int) -> int:
    """Fewest samples a fit needs: ``max(n_channels + 1, 7)``.

    The affine LTM has ``n_channels + 1`` unknowns per wrench component, and
    the zero-load estimate (an affine fit of each channel on the 6 wrench
    components) has 7.

    Examples
    --------
    >>> min_training_samples(6), min_training_samples(12)
    (7, 13)
    """
    return max(n_channels + 1, 7)


def validate_training_data(
    estimator, X: ArrayLike, y: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Validate ``fit`` data and set ``estimator.n_features_in_``.

    Returns ``X`` (n, N) and ``y`` (n, 6) as float64. Checks, in order: both
    are numeric 2-D arrays of the same length; no NaN/inf in ``X`` then ``y``;
    ``X`` has at least 3 channels; there are enough samples
    (:func:`min_training_samples`); ``y`` has 6 columns.
    """
    if y is None:
        raise CalibrationInputError(
            f"{type(estimator).__name__} requires y to be passed, but the target y is None. "
            f"Fix: pass the reference wrenches (n_samples, 6)."
        )
    X = validate_data(estimator, X, reset=True, dtype=np.float64, ensure_all_finite=False)
    check_all_finite(X, "X (raw readings)", "remove or repair the rows with missing readings before fitting")
    # y is checked here, not by validate_data, so that NaN/inf get the row-naming message below.
    y = check_array(y, ensure_2d=False, dtype=np.float64, ensure_all_finite=False, input_name="y")
    check_consistent_length(X, y)
    check_all_finite(y, "y (reference wrenches)", "remove or repair the rows with missing reference wrenches")
    n, n_channels = X.shape
    if n_channels < MIN_CHANNELS:
        raise CalibrationInputError(
            f"X has {n_channels} feature(s) (raw channels, shape {X.shape}); a 6-axis calibration needs at least "
            f"{MIN_CHANNELS} raw channels. Fix: pass one column per strain-gauge channel."
        )
    need = min_training_samples(n_channels)
    if n < need:
        raise CalibrationInputError(
            f"X has {n} sample(s), but {type(estimator).__name__} needs at least {need} "
            f"(n_channels + 1 = {n_channels + 1} for the affine calibration, 7 for the zero-load "
            f"estimate). Fix: record more load cases."
        )
    if y.ndim != 2 or y.shape[1] != 6:
        raise CalibrationInputError(
            f"y must have shape (n_samples, 6): the wrench [Fx, Fy, Fz, Tx, Ty, Tz] in [N] and [N·m]; "
            f"got shape {y.shape}. Fix: pass all six reference wrench components per sample."
        )
    return X, y


def validate_readings(estimator, X: ArrayLike) -> NDArray[np.float64]:
    """Validate ``predict`` readings against the fitted channel count; float64 (n, N)."""
    X = validate_data(estimator, X, reset=False, dtype=np.float64, ensure_all_finite=False)
    check_all_finite(X, "X (raw readings)", "remove or repair the rows with missing readings")
    return X


def check_zero_reading(zero_reading: ArrayLike, n_channels: int) -> NDArray[np.float64]:
    """Validate a user-given tare reading: finite, shape (n_channels,).

    Examples
    --------
    >>> check_zero_reading([0.1, 0.2, 0.3], 3)
    array([0.1, 0.2, 0.3])
    """
    z = np.asarray(zero_reading, dtype=np.float64)
    if z.shape != (n_channels,):
        raise CalibrationInputError(
            f"zero_reading must have shape ({n_channels},), one raw value per channel of X; "
            f"got shape {z.shape}. Fix: pass the raw reading recorded at zero load, or None to estimate it."
        )
    check_all_finite(z[None, :], "zero_reading", "pass a finite tare reading or None to estimate it")
    return z
