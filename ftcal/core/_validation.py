"""Input validation shared by every calibrator.

All checks raise :class:`~ftcal.core.CalibrationInputError` (a ``ValueError``) with
a message that names the array, its shape or the first offending row, and
says how to fix it. Shape and dtype handling goes through scikit-learn's
``validate_data`` so ``n_features_in_`` and the feature-count check at
``predict`` follow the scikit-learn conventions.
"""

from __future__ import annotations

import numbers

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.utils._param_validation import InvalidParameterError, Interval, validate_parameter_constraints
from sklearn.utils.validation import check_array, check_consistent_length, validate_data

from ._columns import DTYPE_KIND_NAMES
from ._exceptions import CalibrationInputError, TooFewSamplesError

__all__ = ["check_all_finite", "check_zero_reading", "validate_training_data", "validate_readings",
           "min_training_samples", "check_identifiable", "check_finite_output", "check_magnitude", "check_bool",
           "check_arguments", "refuse_bool_numbers", "check_quiet", "FLOAT64_OVERFLOW"]



def check_all_finite(a: NDArray[np.float64], name: str, fix: str) -> None:
    """Raise if ``a`` holds NaN or inf, naming the first bad row and column.

    Examples
    --------
    >>> check_all_finite(np.array([[1.0, 2.0], [np.nan, 0.0]]), "X", "drop that row")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.CalibrationInputError: X contains NaN or inf: first at row 1, column 0 (value nan). Fix: drop that row.
    """
    bad = ~np.isfinite(a)
    if bad.any():
        where = np.argwhere(bad)[0]
        row = int(where[0])
        col = int(where[1]) if where.size > 1 else 0
        value = a[tuple(where)]
        raise CalibrationInputError(
            f"{name} contains NaN or inf: first at row {row}, column {col} (value {value}). Fix: {fix}.",
            parameter=name.split()[0], value=value,
        )


#: Largest magnitude of a training value: the least-squares fits square and sum values, which overflows float64
#: (~1.8e308) from ~1e154 on; no sensor reading or wrench in any unit comes near.
MAX_TRAINING_MAGNITUDE = 1e100


def check_magnitude(a: NDArray[np.float64], name: str) -> None:
    """Raise when a value of ``a`` exceeds :data:`MAX_TRAINING_MAGNITUDE` (a unit or parsing error, not data).

    Examples
    --------
    >>> check_magnitude(np.array([[1.0, 2e200]]), "X")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.CalibrationInputError: X holds 2e+200 at row 0, column 1, beyond the 1e+100 ftcal's fits can square without overflow. Fix: check the units and the file (a parsing error?).
    """
    big = np.abs(a) > MAX_TRAINING_MAGNITUDE
    if big.any():
        where = np.argwhere(big)[0]
        row, col = int(where[0]), int(where[1]) if where.size > 1 else 0
        raise CalibrationInputError(
            f"{name} holds {a[tuple(where)]:.6g} at row {row}, column {col}, beyond the {MAX_TRAINING_MAGNITUDE:g} "
            "ftcal's fits can square without overflow. Fix: check the units and the file (a parsing error?).",
            parameter=name.split()[0],
        )


#: The kinds the calibrators refuse by that name (complex has its own message, objects go to validate_data).
_NOT_MEASUREMENTS = "bMmUSV"


def _check_real_2d(X, name: str, what: str, two_d: bool = True) -> None:
    """Complex, boolean, date, text, masked, 1-D or 3-D input gets a short message (scikit-learn's would print
    the whole array, or convert it silently)."""
    if X is None:
        raise CalibrationInputError(f"{name} is None; pass the {what} as an array of shape (n_samples, n_columns).",
                                    parameter=name)
    if not hasattr(X, "__len__") and not hasattr(X, "shape"):
        return  # scalars: validate_data's own message
    if hasattr(X, "format") and hasattr(X, "tocsr"):
        raise CalibrationInputError(
            f"Sparse data was passed for {name} ({type(X).__name__}, shape {X.shape}), but ftcal's calibrators take "
            f"dense {what}. Fix: pass {name}.toarray().", parameter=name,
        )
    if isinstance(X, np.matrix):
        raise CalibrationInputError(f"{name} is an np.matrix (shape {X.shape}); pass np.asarray({name}).",
                                    parameter=name)
    columns = getattr(X, "columns", None)
    if columns is not None and len({type(c) is str for c in columns}) > 1:
        raise CalibrationInputError(
            f"{name}'s column names mix text and other types ({list(columns)[:8]}); name every column with text "
            f"(e.g. s0, s1, ...) or none (pass {name}.to_numpy()).", parameter=name,
        )
    try:
        a = np.asarray(X)
    except (ValueError, TypeError):
        raise CalibrationInputError(
            f"{name} is not a rectangular table: its rows have different lengths (ragged lists?). Fix: give every "
            f"row the same number of {what}.", parameter=name,
        ) from None
    if np.iscomplexobj(a):
        raise CalibrationInputError(
            f"Complex data not supported: {name} has complex dtype {a.dtype} and shape {a.shape}; {what} are real "
            f"numbers. Fix: pass the real part (e.g. {name}.real) if that is what you mean.", parameter=name,
        )
    if a.dtype.kind in _NOT_MEASUREMENTS:
        raise CalibrationInputError(
            f"{name} has dtype {a.dtype} ({DTYPE_KIND_NAMES[a.dtype.kind]}) and shape {a.shape}; {what} are real "
            f"numbers. Fix: convert the measured values to floats first (e.g. {name}.astype(float) after parsing).", parameter=name,
        )
    if isinstance(X, np.ma.MaskedArray) and np.ma.getmaskarray(X).any():
        raise CalibrationInputError(
            f"{name} is a masked array with {int(np.ma.getmaskarray(X).sum())} masked value(s) (shape {a.shape}); "
            f"ftcal would read the values under the mask. Fix: drop the masked rows "
            f"({name}[~{name}.mask.any(axis=1)]) or pass {name}.data if the values are valid.", parameter=name,
        )
    if a.dtype.kind == "O" or not two_d:
        return  # objects: validate_data converts or reports them
    if a.ndim != 2:
        hint = f" Reshape your data: for one reading, use {name}.reshape(1, -1)." if a.ndim == 1 else ""
        raise CalibrationInputError(
            f"{name} must be a 2-D array of {what} (n_samples, n_columns); got a {a.ndim}-D array of shape "
            f"{a.shape}.{hint}", parameter=name,
        )


def _rank(a: NDArray[np.float64]) -> int:
    """Numerical rank of the centred, column-scaled ``a`` (columns that never change count for nothing)."""
    centred = a - a.mean(axis=0)
    scale = np.abs(centred).max(axis=0)
    # a column that varies only by rounding (the mean of identical values is not always exact) is constant
    varies = scale > 1e-12 * np.abs(a).max(axis=0)
    if not np.any(varies):
        return 0
    return int(np.linalg.matrix_rank(centred[:, varies] / scale[varies]))


def check_identifiable(X: NDArray[np.float64], y: NDArray[np.float64]) -> None:
    """Refuse data from which no calibration can be identified.

    The readings must vary (not only duplicate rows, a constant or an
    all-zero X), the wrenches must vary, and the readings must span at least
    as many independent directions as the loads do (up to the channel
    count): otherwise two different loads give the same reading, e.g. a dead
    or duplicated channel.

    Examples
    --------
    >>> check_identifiable(np.zeros((10, 6)), np.eye(10, 6))
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.CalibrationInputError: X (raw readings) is the same in all 10 rows (constant or all-zero channels, or only duplicate rows): there is nothing to calibrate from. Fix: record readings under different loads.
    """
    n = X.shape[0]
    rank_x = _rank(X)
    if rank_x == 0:
        raise CalibrationInputError(
            f"X (raw readings) is the same in all {n} rows (constant or all-zero channels, or only duplicate rows): "
            "there is nothing to calibrate from. Fix: record readings under different loads.", parameter="X"
        )
    rank_y = _rank(y)
    if rank_y == 0:
        raise CalibrationInputError(
            f"y (reference wrenches) is the same in all {n} rows: there is no load change to calibrate against. "
            "Fix: record several different loads.", parameter="y"
        )
    need = min(X.shape[1], rank_y)
    if rank_x < need:
        raise CalibrationInputError(
            f"X (raw readings, shape {X.shape}) spans only {rank_x} independent direction(s) but the wrenches y span "
            f"{rank_y}: different loads give the same reading, so no calibration can tell them apart (a dead, "
            "constant or duplicated channel?). Fix: check the channels, or record loads that excite every channel.",
            parameter="X",
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
    """Validate ``fit`` data; set ``n_features_in_``, ``n_outputs_`` and ``y_1d_`` of the estimator.

    Returns ``X`` (n, N) and ``y`` (n, k) as float64. Checks, in order: ``X``
    is a numeric 2-D array and ``y`` a numeric 1-D or 2-D one of the same
    length; no NaN/inf in ``X`` then ``y``; there are enough samples
    (:func:`min_training_samples`); the data identify an affine map.

    A calibrator is a regressor of any outputs: ``y`` is the wrench (n, 6)
    in ftcal's use, and only then are torques scaled (``alpha_``). The
    wrench rule (6 components, at least 3 raw channels) is enforced where
    calibration data enter: :class:`~ftcal.CalibrationDataset` and the CLI.
    A 1-D ``y`` gives 1-D predictions, as in scikit-learn.
    """
    if y is None:
        raise CalibrationInputError(
            f"{type(estimator).__name__} requires y to be passed, but the target y is None. "
            f"Fix: pass the reference wrenches (n_samples, 6)."
        )
    _check_real_2d(X, "X", "raw readings")
    _check_real_2d(y, "y", "reference wrenches", two_d=False)
    X = validate_data(estimator, X, reset=True, dtype=np.float64, ensure_all_finite=False)
    check_all_finite(X, "X (raw readings)", "remove or repair the rows with missing readings before fitting")
    # y is checked here, not by validate_data, so that NaN/inf get the row-naming message below.
    y = check_array(y, ensure_2d=False, dtype=np.float64, ensure_all_finite=False, input_name="y")
    check_consistent_length(X, y)
    check_all_finite(y, "y (reference wrenches)", "remove or repair the rows with missing reference wrenches")
    for a, name in ((X, "X (raw readings)"), (y, "y (reference wrenches)")):
        check_magnitude(a, name)
    n, n_channels = X.shape
    need = min_training_samples(n_channels)
    if n < need:
        raise TooFewSamplesError(
            f"X has {n} sample(s), but {type(estimator).__name__} needs at least {need} "
            f"(n_channels + 1 = {n_channels + 1} for the affine calibration, 7 for the zero-load "
            f"estimate). Fix: record more load cases.", parameter="X", value=n, needed=need,
            estimator=type(estimator).__name__,
        )
    if y.ndim not in (1, 2) or (y.ndim == 2 and y.shape[1] == 0):
        raise CalibrationInputError(
            f"y must have shape (n_samples, 6) (the wrench [Fx, Fy, Fz, Tx, Ty, Tz] in [N] and [N·m]) or, for "
            f"other targets, (n_samples,) or (n_samples, k); got shape {y.shape}.", parameter="y"
        )
    estimator.y_1d_ = y.ndim == 1
    y = y.reshape(n, -1)
    estimator.n_outputs_ = y.shape[1]
    check_identifiable(X, y)
    return X, y


def validate_readings(estimator, X: ArrayLike) -> NDArray[np.float64]:
    """Validate ``predict`` readings against the fitted channel count; float64 (n, N)."""
    # the control-loop case (one float64 reading at a time) skips validate_data: the finite check below is all it
    # would add, at a fraction of its cost
    if not (type(X) is np.ndarray and X.dtype == np.float64 and X.ndim == 2 and X.shape[1] == estimator.n_features_in_
            and X.shape[0] > 0 and not hasattr(estimator, "feature_names_in_")):
        _check_real_2d(X, "X", "raw readings")
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


#: What overflows in a model computing in float64 (what :func:`check_finite_output` says unless the model's class
#: names its own computation in ``_overflow_note``).
FLOAT64_OVERFLOW = "a value of its float64 computation exceeds float64's largest number, ~1.8e308"


def check_finite_output(X: NDArray[np.float64], wrench: NDArray[np.float64], estimator, what: str = "wrench") -> None:
    """Raise when a prediction is NaN or inf, naming the reading that caused it (never print NaN rows).

    The message says what overflowed for that model: the estimator's class attribute ``_overflow_note``
    (e.g. the GP's kernel distances, a network's float32), else :data:`FLOAT64_OVERFLOW`.

    Examples
    --------
    >>> check_finite_output(np.ones((2, 3)), np.array([[0.0] * 6, [np.inf] + [0.0] * 5]), "model")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.CalibrationInputError: X row 1 (largest |value| 1) gives a non-finite wrench with str: ...
    """
    bad = ~np.isfinite(wrench)
    if bad.any():
        row = int(np.argmax(bad.reshape(len(wrench), -1).any(axis=1)))
        big = float(np.abs(X[row]).max()) if X.size else float("nan")
        note = getattr(estimator, "_overflow_note", None) or FLOAT64_OVERFLOW
        raise CalibrationInputError(
            f"{{row}} (largest |value| {big:.3g}) gives a non-finite {what} with {type(estimator).__name__}: "
            f"the reading is outside the range the model can compute ({note}). Fix: check the reading's units, or "
            "remove that row.", parameter="X", value=big, row=row,
        )


def check_bool(value, name: str) -> bool:
    """``value`` as a ``bool`` if it is one (Python or numpy), else a :class:`CalibrationInputError` naming ``name``.

    A flag given as a string or a number (``return_std="no"``, ``1``) is a mistake, not a truth value.

    Examples
    --------
    >>> check_bool(np.True_, "return_std")
    True
    >>> check_bool("no", "return_std")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.CalibrationInputError: return_std must be True or False; got 'no' (str).
    """
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise CalibrationInputError(f"{name} must be True or False; got {value!r} ({type(value).__name__}).")


def check_arguments(caller: str, constraints: dict, **values) -> None:
    """Check a function's arguments against scikit-learn constraints (``Interval``, ``StrOptions``, ``None``, ...).

    The one way ftcal's functions check their arguments: a bad one raises
    :class:`CalibrationInputError` naming the argument, what is allowed and
    the value given. A bool where a number is allowed and a bool is not is
    refused too (scikit-learn's intervals take ``True`` for 1).

    Examples
    --------
    >>> from numbers import Integral
    >>> check_arguments("make_data", {"n_samples": [Interval(Integral, 1, None, closed="left")]}, n_samples=0)
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.CalibrationInputError: The 'n_samples' parameter of make_data must be an int in the range [1, inf). Got 0 instead.
    """
    try:
        validate_parameter_constraints(constraints, values, caller_name=caller)
    except InvalidParameterError as exc:
        raise CalibrationInputError(str(exc)) from None
    refuse_bool_numbers(caller, constraints, values)


def refuse_bool_numbers(owner: str, constraints: dict, values: dict) -> None:
    """Refuse a bool given where a number is allowed and a bool is not.

    scikit-learn's intervals take ``True`` for 1, but a flag where a count or a size belongs is a mistake.
    The one rule of :func:`check_arguments` and of every calibrator's parameter check.

    Parameters
    ----------
    owner : str
        The function or estimator named in the error.
    constraints : dict
        Parameter name -> scikit-learn constraints (a name without constraints is not checked).
    values : dict
        Parameter name -> value.

    Examples
    --------
    >>> from numbers import Integral
    >>> refuse_bool_numbers("fit", {"cv": [Interval(Integral, 2, None, closed="left")]}, {"cv": True})
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.CalibrationInputError: The 'cv' parameter of fit must be a number, not a bool. Got True instead.
    >>> refuse_bool_numbers("fit", {"verbose": [Interval(Integral, 0, None, closed="left"), "boolean"]},
    ...                     {"verbose": True})  # a bool is one of its values
    """
    for name, value in values.items():
        allowed = [c for c in constraints.get(name, []) if c is not None]
        takes_bools = any((isinstance(c, str) and c == "boolean") or c is bool or c is np.bool_ for c in allowed)
        if isinstance(value, (bool, np.bool_)) and not takes_bools and any(isinstance(c, Interval) for c in allowed):
            raise CalibrationInputError(f"The {name!r} parameter of {owner} must be a number, not a bool. Got "
                                        f"{value!r} instead.")


def check_quiet(X: NDArray[np.float64], noise: ArrayLike, *, max_spread: float, name: str, labels: list[str],
                noise_words: str) -> None:
    """Refuse re-tare readings that are not quiet: a column whose standard deviation over the rows of ``X`` is more
    than ``max_spread`` times its ``noise`` means something touched or moved the sensor while they were taken
    (a load on it, a hand), and their mean would be a wrong zero. The one rule of every re-tare (a model's raw
    readings, a tool's wrenches).

    Parameters
    ----------
    X : ndarray of shape (n, k)
        The readings (one row passes: no spread to judge).
    noise : array-like of shape (k,)
        Each column's noise (std), floored at a few ulps of the readings' size.
    max_spread : float
        Positive; how many times the noise a column's std may be.
    name : str
        The argument ``X`` came from (``X_no_load``), named in the message.
    labels : list of str
        Each column's name (``s0``, ``Fx``).
    noise_words : str
        Where the noise comes from (``"the noise of the training data"``).

    Raises
    ------
    CalibrationInputError
        ``max_spread`` not a positive number, or a column that is not quiet (naming it, its std, the limit).

    Examples
    --------
    >>> import numpy as np
    >>> quiet = np.random.default_rng(0).normal(0.0, 0.1, size=(50, 2))
    >>> check_quiet(quiet, [0.1, 0.1], max_spread=5.0, name="X", labels=["Fx", "Fy"], noise_words="the noise")
    >>> loaded = quiet + np.c_[np.zeros(50), np.linspace(-900, 900, 50)]
    >>> check_quiet(loaded, [0.1, 0.1], max_spread=5.0, name="X", labels=["Fx", "Fy"], noise_words="the noise")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.CalibrationInputError: X is not quiet: Fy varies by 535.5 (std) over the 50 readings, more than 5 times the noise (0.1). Was something touching or moving the sensor? Take the readings again, holding it still.
    """
    if isinstance(max_spread, bool) or not isinstance(max_spread, numbers.Real) or not max_spread > 0:
        raise CalibrationInputError(f"max_spread must be a positive number; got {max_spread!r}.")
    if len(X) < 2:
        return
    noise = np.maximum(np.asarray(noise, dtype=float), 16 * np.finfo(float).eps * np.abs(X).max(axis=0))
    spread = X.std(axis=0, ddof=1)
    limit = max_spread * np.maximum(noise, np.finfo(float).tiny)
    bad = np.flatnonzero(spread > limit)
    if bad.size:
        c = int(bad[0])
        raise CalibrationInputError(
            f"{name} is not quiet: {labels[c]} varies by {spread[c]:.4g} (std) over the {len(X)} readings, more "
            f"than {max_spread:g} times {noise_words} ({noise[c]:.4g}). Was something touching or moving the "
            "sensor? Take the readings again, holding it still.")
