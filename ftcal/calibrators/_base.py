"""Shared scikit-learn behaviour of every calibrator.

:class:`BaseCalibrator` does what the three calibrators of the thesis have in
common, so each model only implements ``_fit(X, y)`` and
``_predict_wrench(X)``:

* **validation** (``validate_data``): ``X`` (n, N >= 3) raw readings and ``y``
  (n, 6) wrenches, finite; NaN/inf give an error naming ``X`` or ``y`` and
  the first bad row; at ``predict`` the channel count must match ``fit``;
  ``predict`` before ``fit`` raises scikit-learn's ``NotFittedError``;
* **torque scale** ``alpha_`` (eq. 5-6): the ``alpha`` parameter, or
  :func:`~ftcal.core.alpha_from_wrenches` of the training targets when ``None``.
  Models apply it inside their losses; ``predict`` always returns the
  wrench in [N] and [N·m];
* **zero-load reading** ``zero_reading_`` (N,): the ``zero_reading``
  parameter (a known tare reading), or, when ``None``, the mean reading of
  the zero-load rows of the data, or failing those the intercept of an
  affine least-squares fit of the raw channels on the wrench (see
  :func:`ftcal.calibrators._zero_load.estimate_zero_reading`);
* ``score`` is the usual coefficient of determination R² of
  :class:`~sklearn.base.RegressorMixin` (averaged over the 6 components);
  use :func:`ftcal.neg_scaled_rmse` as ``scoring`` for the thesis' eq. 18.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, fields, replace
import numbers
from numbers import Real

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.base import BaseEstimator, RegressorMixin, clone
from sklearn.utils import Tags
from sklearn.utils._param_validation import InvalidParameterError, Interval
from sklearn.utils.validation import check_is_fitted

from ..core._exceptions import CalibrationInputError
from ..model_selection._selection import check_groups
from ..core._threads import limit_threads_here
from ..core._validation import (check_finite_output, check_quiet, check_zero_reading, refuse_bool_numbers, validate_readings,
                                validate_training_data)
from ..core._wrench import ALPHA_RANGE_PER_M, alpha_from_wrenches, target_axes
from ._zero_load import estimate_zero_reading, reading_noise

__all__ = ["BaseCalibrator", "retare_shift", "GroupsFit", "with_settings", "CalibrationTags", "FtcalTags", "calibration_tags", "declare",
           "check_sample_weight"]


#: Kinds of fit by cost, cheapest last: the order ``auto`` schedules its jobs in (the costliest first).
COSTS: tuple[str, ...] = ("kernel", "network", "heavy", "closed_form")


@dataclass
class CalibrationTags:
    """What a calibrator can do, declared once next to its class (``__sklearn_tags__().ftcal``).

    Every part of ftcal that needs to know a capability reads it here, never from the class, an attribute or a
    signature: :class:`~ftcal.AutoCalibrator` (its skipping rule, its job order, how it trains networks, which
    models choose their structure once), the load-history and temperature wrappers, the CLI (a temperature
    column), the ONNX export and model files.

    Attributes
    ----------
    temperature_column : bool
        The last column of ``X`` is the sensor temperature [deg C], not a channel.
    uses_groups : bool
        ``fit`` uses the rows' groups (one offset per group, a grouped choice inside); requested through metadata
        routing by default.
    network : bool
        A neural network trained by skorch; ``stackable``: trainable with others as one stacked module
        (:func:`~ftcal.networks.fit_stacked`).
    stackable : bool
    reads_history : bool
        Reads its rows as a time series (a load-history model): must be the outermost model, no ONNX graph.
    chooses_model : bool
        Chooses a model by cross-validation inside ``fit`` (``best_estimator_``, ``best_name_``, ``comparison_``).
    chooses_structure : bool
        Chooses its structure once (``structure_params()`` gives it): ``auto`` lets it choose on the first training
        fold and cross-validates clones with that structure.
    min_training_rows : callable
        ``n_channels -> rows``: fewest training rows on which a held-out score says something about the model.
    cost : {"closed_form", "kernel", "network", "heavy"}
        What one fit costs: a closed form is light work; a kernel model is cubic in its rows (light on at most
        ``LIGHT_KERNEL_ROWS``); a network trains for epochs; ``heavy`` anything else (a wrapper of unknown cost).
    onnx : bool
        Exportable to an ONNX graph (its class or a parent declares ``_emit_onnx``; a subclass whose ``predict``
        computes something else declares ``onnx=False``).
    provides_std : bool
        ``predict(X, return_std=True)`` gives a standard deviation.
    family : str
        What the model is, for ``auto``'s complexity order: ``"linear"`` (the LTM and its equals),
        ``"polynomial2"``, ``"polynomial3"``, ..., ``"axis_nonlinear"``, ``"kernel"``, ``"network"``; ``""``
        unknown. A stock baseline of a family is as simple as ftcal's model of that family.
    scales_torques : bool
        The model weighs the torques by the torque scale ``alpha_`` itself (ftcal's models, in their losses or
        per-axis fits) or must see the wrench as given (a stock baseline, fitted as a user would). A user's
        regressor without it (:func:`~ftcal.calibrators.as_calibrator`) is fitted on the torque-scaled wrench
        (torques times ``alpha_``, eq. 6) and its predictions are scaled back, so its loss weighs forces and
        torques as ftcal's models do.
    stock_baseline : bool
        One of the named stock scikit-learn baselines (:func:`~ftcal.calibrators.stock_baselines`), fitted as a
        user would: ``auto`` shows it as a free model beside its candidates. A user's own regressor (composed by
        :func:`~ftcal.calibrators.as_calibrator`) is not one: it is a candidate like any calibrator.
    """

    temperature_column: bool = False
    uses_groups: bool = False
    network: bool = False
    stackable: bool = False
    reads_history: bool = False
    chooses_model: bool = False
    chooses_structure: bool = False
    min_training_rows: Callable[[int], int] = field(default_factory=lambda: lambda n_channels: 25 * int(n_channels))
    cost: str = "heavy"
    onnx: bool = False
    provides_std: bool = False
    family: str = ""
    scales_torques: bool = False
    stock_baseline: bool = False


@dataclass
class FtcalTags(Tags):
    """scikit-learn's :class:`~sklearn.utils.Tags` with ftcal's :class:`CalibrationTags` as ``ftcal``."""

    ftcal: CalibrationTags = field(default_factory=CalibrationTags)


def declare(tags: Tags, **capabilities) -> FtcalTags:
    """``tags`` with these :class:`CalibrationTags` fields changed: what a class' ``__sklearn_tags__`` calls.

    Any scikit-learn estimator may declare them too (a user's free model given to ``auto`` as a baseline), from
    its scikit-learn :class:`~sklearn.utils.Tags`.

    Examples
    --------
    >>> from sklearn.linear_model import LinearRegression
    >>> class MyFreeModel(LinearRegression):
    ...     def __sklearn_tags__(self):
    ...         return declare(super().__sklearn_tags__(), cost="closed_form")
    >>> calibration_tags(MyFreeModel()).cost
    'closed_form'
    """
    if not isinstance(tags, FtcalTags):
        tags = FtcalTags(**{f.name: getattr(tags, f.name) for f in fields(tags)})
    tags.ftcal = replace(tags.ftcal, **capabilities)
    return tags


def calibration_tags(estimator) -> CalibrationTags:
    """``estimator``'s :class:`CalibrationTags`; the defaults (a costly model of unknown kind) for any other estimator.

    Examples
    --------
    >>> from ftcal import LinearCalibrator
    >>> calibration_tags(LinearCalibrator()).cost
    'closed_form'
    >>> from sklearn.linear_model import LinearRegression
    >>> calibration_tags(LinearRegression()).cost
    'heavy'
    """
    tags = estimator.__sklearn_tags__() if hasattr(estimator, "__sklearn_tags__") else None
    return getattr(tags, "ftcal", None) or CalibrationTags()


def check_sample_weight(sample_weight: ArrayLike | None, n_samples: int) -> NDArray[np.float64] | None:
    """``sample_weight`` checked as one finite weight >= 0 per row, not all zero; ``None`` passes through.

    The weight of a row multiplies its squared residual in a weighted least-squares fit (a row of weight 2
    counts as two equal rows).

    Examples
    --------
    >>> check_sample_weight([1, 2, 0], 3).tolist()
    [1.0, 2.0, 0.0]
    >>> check_sample_weight([1, -1], 2)
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.CalibrationInputError: sample_weight must be finite and >= 0 (one weight per row of X); got -1 at row 1.
    """
    if sample_weight is None:
        return None
    try:
        w = np.asarray(sample_weight, dtype=np.float64)
    except (TypeError, ValueError):
        raise CalibrationInputError(f"sample_weight must be numbers, one weight per row of X; got {sample_weight!r:.80}.",
                                    parameter="sample_weight") from None
    if w.ndim == 0:
        w = np.full(n_samples, float(w))
    if w.shape != (n_samples,):
        raise CalibrationInputError(f"sample_weight must have shape ({n_samples},), one weight per row of X; got shape "
                                    f"{w.shape}.", parameter="sample_weight")
    bad = np.flatnonzero(~np.isfinite(w) | (w < 0))
    if bad.size:
        raise CalibrationInputError(f"sample_weight must be finite and >= 0 (one weight per row of X); got "
                                    f"{w[bad[0]]:g} at row {bad[0]}.", parameter="sample_weight")
    if not w.any():
        raise CalibrationInputError("sample_weight is zero for every row: nothing is left to fit; give some rows a "
                                    "positive weight.", parameter="sample_weight")
    return w


def calibrated_range(X: NDArray[np.float64]) -> NDArray[np.float64]:
    """Min and max of each channel of the training readings, shape (2, N)."""
    return np.vstack([X.min(axis=0), X.max(axis=0)])


def _refuse_far_outside(X: NDArray[np.float64], reading_range: ArrayLike, name: str, fix: str) -> NDArray[np.float64]:
    """Refuse a zero-load reading (a row of ``X``) far outside the training readings ``reading_range`` (2, N):
    beyond each channel's span widened by ``RETARE_RANGE_MARGIN`` times it on each side. Returns the spans."""
    low, high = np.asarray(reading_range, dtype=float)
    span = high - low
    margin = RETARE_RANGE_MARGIN * np.maximum(span, np.abs(high) + np.abs(low))
    outside = (X < low - margin) | (X > high + margin)
    if outside.any():
        r, c = (int(v) for v in np.argwhere(outside)[0])
        where = f"{name}[{r}, {c}]" if len(X) > 1 or name == "X_no_load" else f"{name}[{c}]"
        raise CalibrationInputError(
            f"{where} = {X[r, c]:.6g} lies far outside the readings channel s{c} gave in training "
            f"([{low[c]:.6g}, {high[c]:.6g}]); a zero-load reading does not. Check the units, the channel "
            f"order and the sensor, or {fix}."
        )
    return span


def resolve_alpha(alpha: float | None, y: NDArray[np.float64], axes=None) -> float:
    if alpha is None:
        # Fmax / Tmax over the axes y has (``axes``: named by y's columns); without names only a 6-component wrench
        # has torques to scale, other targets keep their units (alpha_ = 1)
        if axes is not None:
            return alpha_from_wrenches(y, axes)
        return alpha_from_wrenches(y) if y.shape[1] == 6 else 1.0
    if isinstance(alpha, bool) or not isinstance(alpha, numbers.Real) or not np.isfinite(alpha) or alpha <= 0:
        raise CalibrationInputError(
            f"alpha must be a positive finite number (Fmax / Tmax in [m⁻¹], eq. 5) or None to derive "
            f"it from y; got {alpha!r}."
        )
    return float(alpha)


def with_settings(template: BaseCalibrator, **settings) -> BaseCalibrator:
    """A clone of ``template`` given those of ``settings`` it has as parameters and that are not None (a wrapper's
    ``alpha``, ``zero_reading``, ``random_state``: where the wrapper leaves one None, the inner calibrator's own
    stays)."""
    inner = clone(template)
    params = inner.get_params()
    inner.set_params(**{k: v for k, v in settings.items() if k in params and v is not None})
    return inner


#: A re-tare reading may lie outside the training readings of its channel by at most this fraction of their span.
RETARE_RANGE_MARGIN = 0.5
#: Smallest noise :meth:`BaseCalibrator.retare` assumes, as a fraction of the training readings' span per channel
#: (a 16-bit converter's step is 1.5e-5 of its range; a real sensor's noise a few steps): training data that were
#: averaged or noise-free show ~1e-13 and would otherwise make every real reading "not quiet".
RETARE_NOISE_FLOOR = 1e-4


class BaseCalibrator(RegressorMixin, BaseEstimator):
    """Common base of the calibrators; not meant to be used directly.

    Subclasses implement ``_fit(X, y)`` (``X`` float64 (n, N), ``y`` float64
    (n, 6) in [N] / [N·m]; ``alpha_`` and ``zero_reading_`` already set) and
    ``_predict_wrench(X)`` returning (n, 6) in [N] / [N·m].

    **Parameters** are declared, as in scikit-learn, in a class table
    ``_parameter_constraints`` (name -> allowed types and ranges, see
    ``sklearn.utils._param_validation``), extended by each subclass and
    checked once, at the start of ``fit`` (:meth:`_check_parameters`); a
    bad value raises :class:`~ftcal.core.CalibrationInputError` naming the
    parameter, the allowed values and the value given. Checks a table cannot
    express (the entries of ``hidden_layer_sizes``) follow it in
    ``_check_params`` of the subclass. The parameters every calibrator has
    (``alpha``, ``zero_reading``, ``random_state``) are set by its
    ``__init__``: a subclass lists them in its own signature and passes them
    on (``super().__init__(alpha=alpha, zero_reading=zero_reading,
    random_state=random_state)``); one without parameters of its own needs
    no ``__init__``.
    """

    #: Fitted attributes a model file stores (:func:`ftcal.save_model`); each subclass declares its own
    #: next to its class, and ``_emit_onnx(graph, x)`` for its ONNX graph (:func:`ftcal.export_onnx`).
    _fitted_state: tuple[str, ...] = ("alpha_", "n_features_in_", "feature_names_in_", "n_outputs_", "y_1d_",
                                      "zero_reading_", "reading_noise_", "tare_reading_", "calibrated_range_", "axes_")
    #: The wrench axes ``y``'s columns named at fit (:func:`~ftcal.core._wrench.target_axes`), when not the default
    #: ones of its width (Fx..Tz for six, else forces only): e.g. Fz, Tx, Ty of a plate, whose torques are scaled.
    axes_ = None
    #: Allowed values of fitted attributes, checked when a model file is loaded (with ``_fitted_state``; every numeric
    #: array is also checked finite): scikit-learn's constraint vocabulary, each entry of an array checked.
    _fitted_constraints: dict = {"reading_noise_": [Interval(Real, 0, None, closed="left")]}

    _parameter_constraints: dict = {
        "alpha": [Interval(Real, *ALPHA_RANGE_PER_M, closed="both"), None],  # lever arms 1 µm - 1 km
        "zero_reading": ["array-like", None],
        "random_state": ["random_state"],
    }

    def __init__(self, *, alpha=None, zero_reading=None, random_state=None):
        # the parameters every calibrator shares; a subclass lists them in its own signature and passes them here
        self.alpha = alpha
        self.zero_reading = zero_reading
        self.random_state = random_state

    def _check_parameters(self) -> None:
        """Check every parameter against ``_parameter_constraints`` (and the subclass' ``_check_params``)."""
        try:
            self._validate_params()
        except InvalidParameterError as exc:
            raise CalibrationInputError(str(exc)) from None
        refuse_bool_numbers(type(self).__name__, self._parameter_constraints, self.get_params(deep=False))
        self._check_params()

    def _check_params(self) -> None:
        """Checks beyond the table (none by default)."""

    def fit(self, X: ArrayLike, y: ArrayLike):
        """Fit the calibration on raw readings ``X`` (n, N) and wrenches ``y`` (n, 6).

        Returns
        -------
        self
        """
        return self._checked_fit(X, y)

    def _checked_fit(self, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None,
                     sample_weight: ArrayLike | None = None):
        """``fit``'s body for every calibrator: prepare (:meth:`_prepare_fit`), check the metadata its ``fit``
        takes (:meth:`_fit_metadata`), then the model's own ``_fit``."""
        # one BLAS thread: the least-squares problems are small; threaded OpenBLAS made a 5000-row polynomial fit 20x
        # slower on a busy machine (benchmarks/thread_limits.py). Never another thread's: see limit_threads_here.
        with limit_threads_here(1):
            X, y = self._prepare_fit(X, y)
            self._fit(X, y, **self._fit_metadata(len(X), groups, sample_weight))
        return self

    def _fit_metadata(self, n_samples: int, groups, sample_weight) -> dict:
        """The keyword arguments of ``_fit`` from ``fit``'s metadata (only a class whose ``fit`` takes one gets it)."""
        weights = check_sample_weight(sample_weight, n_samples)
        return {} if weights is None else {"sample_weight": weights}

    def _prepare_fit(self, X: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Everything ``fit`` does before the model's own ``_fit``: check the parameters, validate the data, set
        ``alpha_``, ``zero_reading_`` and ``reading_noise_``, drop a re-tare. Returns the validated ``X``, ``y``.

        Shared with :func:`ftcal.networks.fit_stacked`, which then trains several models' ``_fit`` at once.
        """
        self._check_parameters()
        axes = self._remember_axes(y)
        X, y = validate_training_data(self, X, y)
        given = None if self.zero_reading is None else check_zero_reading(self.zero_reading, X.shape[1])
        if given is not None:
            _refuse_far_outside(given[None, :], calibrated_range(X), "zero_reading",
                                "pass the reading taken at zero load (or None to estimate it)")
        self._record_calibration(X, y, resolve_alpha(self._given_alpha(), y, axes), given, axes)
        return X, y

    def _given_alpha(self) -> float | None:
        """The torque scale the parameters give (``alpha``); None: derived from the training targets."""
        return self.alpha

    def _remember_axes(self, y):
        """``axes_`` from the columns of ``y`` (a table of wrench axes), or None (the default axes of its width)."""
        axes = target_axes(y)
        if axes is None:
            self.__dict__.pop("axes_", None)  # a refit on unnamed targets forgets earlier names
        else:
            self.axes_ = np.asarray(axes, dtype=object)
        return axes

    def out_of_range(self, X: ArrayLike, *, margin: float = 0.0) -> NDArray[np.bool_]:
        """Which rows of raw readings ``X`` (n, N) lie beyond the calibrated range: one bool per row.

        The calibrated range is each channel's span in the training readings
        (``calibrated_range_``, shape (2, N): min and max, re-tare shift
        applied); a row is out of range when any channel is more than
        ``margin`` times that channel's span outside it. Predictions there are
        extrapolations: a flexible model may be far off where the LTM stays
        linear. ``ftcal predict`` reports such rows.

        Examples
        --------
        >>> import numpy as np
        >>> from ftcal import LinearCalibrator
        >>> raw = np.random.default_rng(0).normal(size=(50, 6)); w = raw @ np.eye(6)
        >>> LinearCalibrator().fit(raw, w).out_of_range(np.vstack([raw[:1], 10 * raw[:1]])).tolist()
        [False, True]
        """
        check_is_fitted(self)
        if not hasattr(self, "calibrated_range_"):
            raise CalibrationInputError(
                f"this {type(self).__name__} was saved before ftcal recorded the calibrated range; refit it to "
                "check readings against the range.")
        X = self._retared(validate_readings(self, X))
        low, high = self.calibrated_range_
        slack = margin * (high - low)
        return np.any((X < low - slack) | (X > high + slack), axis=1)

    def retare(self, X_no_load: ArrayLike, *, max_spread: float = 5.0):
        """Re-zero the fitted calibration: readings taken now with no load define the new zero-load reading.

        A sensor's zero moves (a restart, a re-mount, temperature, creep); its
        gain does not. ``retare`` replaces the zero-load reading by the mean of
        ``X_no_load`` without refitting: from then on ``predict`` shifts every
        reading by ``tare_reading_ - zero_reading_`` before the calibration
        sees it, so a reading equal to the new tare gives what the training
        tare gave (zero, up to the model's own offset). Calling it again
        replaces the previous re-tare. Saved and loaded with the model file.
        Its accuracy is bounded by that of the training tare ``zero_reading_``:
        estimated from the data it is known to about ``noise * sqrt(13 / n)``
        per channel; a tare measured at calibration time (``zero_reading=``)
        makes re-taring as exact as the new readings.

        Parameters
        ----------
        X_no_load : array-like of shape (n, N)
            Raw readings with nothing attached beyond what the calibration was
            zeroed with (hold the sensor still).
        max_spread : float, default=5.0
            The readings must be quiet: each channel's standard deviation may be
            at most ``max_spread`` times the noise the training data showed
            (``reading_noise_``, at least :data:`RETARE_NOISE_FLOOR` of the
            channel's training span); more means something touched or moved
            the sensor while they were taken. Each reading must also lie within
            the channel's training readings widened by half their span on each
            side (``calibrated_range_``): a zero-load reading far outside them is
            a wrong unit, channel order or sensor.

        Returns
        -------
        self

        Examples
        --------
        >>> import numpy as np
        >>> from ftcal import LinearCalibrator
        >>> rng = np.random.default_rng(0)
        >>> w = rng.normal(size=(200, 6)); raw = w @ rng.normal(size=(6, 6)) + 1.0
        >>> model = LinearCalibrator().fit(raw + 0.01 * rng.normal(size=raw.shape), w)
        >>> drifted_zero = np.full((10, 6), 1.5) + 0.01 * rng.normal(size=(10, 6))   # the tare moved by +0.5
        >>> bool(np.abs(model.retare(drifted_zero).predict(raw + 0.5) - w).max() < 0.1)
        True
        """
        check_is_fitted(self)
        if isinstance(max_spread, bool) or not isinstance(max_spread, numbers.Real) or not max_spread > 0:
            raise CalibrationInputError(f"max_spread must be a positive number; got {max_spread!r}.")
        X = validate_readings(self, X_no_load)
        if len(X) == 0:
            raise CalibrationInputError("X_no_load holds no readings; pass at least one zero-load reading.")
        reading_range = getattr(self, "calibrated_range_", None)  # the spans of the channels' training readings
        span = None if reading_range is None else _refuse_far_outside(X, reading_range, "X_no_load",
                                                                       "fit the calibration again")
        noise = getattr(self, "reading_noise_", None)
        if noise is not None:
            # floor: noise-free or averaged training data (noise ~ 1e-13) must not refuse every real reading
            floor = RETARE_NOISE_FLOOR * span if span is not None else 0.0
            check_quiet(X, np.maximum(np.asarray(noise, dtype=float), floor), max_spread=max_spread,
                        name="X_no_load", labels=[f"channel s{c}" for c in range(X.shape[1])],
                        noise_words="the noise of the training data")
        self.tare_reading_ = X.mean(axis=0)
        return self

    def predict(self, X: ArrayLike) -> NDArray[np.float64]:
        """Wrench [Fx, Fy, Fz, Tx, Ty, Tz] in [N] and [N·m] for raw readings ``X`` (n, N).

        Returns
        -------
        ndarray of shape (n_samples, 6), float64
            (``(n_samples, k)`` or ``(n_samples,)`` for a calibrator fitted on
            other targets of that shape.)
        """
        if "n_features_in_" not in self.__dict__:  # cheap test first: predict sits in control loops
            check_is_fitted(self)
        return self._calibrated_predict(X, self._predict_wrench)

    def _calibrated_predict(self, X: ArrayLike, predict_wrench: Callable) -> NDArray[np.float64]:
        """The calibration around a model's prediction, for :meth:`predict` and any other (a stream's): readings
        ``X`` validated and shifted back by the re-tare, ``predict_wrench`` of them checked finite, the shape of
        the training targets restored."""
        X = self._retared(validate_readings(self, X))
        with np.errstate(over="ignore", invalid="ignore"):
            wrench = np.asarray(predict_wrench(X), dtype=np.float64)
        check_finite_output(X, wrench, self)
        return wrench[:, 0] if self.__dict__.get("y_1d_") else wrench

    def _retared(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        """``X`` shifted by the re-tare (:meth:`retare`), if any."""
        return X if getattr(self, "tare_reading_", None) is None else X - retare_shift(self, X.shape[1])

    def _fit(self, X: NDArray[np.float64], y: NDArray[np.float64]) -> None:  # pragma: no cover
        raise NotImplementedError

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:  # pragma: no cover
        raise NotImplementedError

    def __sklearn_tags__(self) -> FtcalTags:
        # a subclass declares what it can do; the defaults describe a costly model of unknown kind. Tags are
        # inherited (each class chains super().__sklearn_tags__()): a subclass of an exportable calibrator is
        # exportable, unless it declares ``onnx=False`` (it computes something its parent's graph does not)
        tags = declare(super().__sklearn_tags__(), onnx=callable(getattr(type(self), "_emit_onnx", None)),
                       scales_torques=True)  # a calibrator handles alpha_ itself (or wraps one that does)
        tags.target_tags.required = True
        tags.target_tags.multi_output = True
        tags.target_tags.single_output = False
        tags.input_tags.allow_nan = False
        return tags

    def _record_calibration(self, X: NDArray[np.float64], y: NDArray[np.float64], alpha: float,
                            zero_reading: ArrayLike | None, axes=None) -> None:
        """The one place that records the calibration around a model, for a calibrator's own fit
        (:meth:`_prepare_fit`) and a wrapper's (:meth:`_adopt_fitted`) alike.

        ``alpha_`` the torque scale ``alpha``; ``zero_reading_`` the given one, else estimated from ``X``, ``y``
        (:func:`~ftcal.calibrators._zero_load.estimate_zero_reading` over ``axes``); ``reading_noise_`` and
        ``calibrated_range_`` of ``X`` (n, N) (what :meth:`retare` and :meth:`out_of_range` check readings
        against); a previous re-tare dropped (a refit starts from the training tare). :meth:`predict` undoes the
        re-tare (:meth:`_retared`) before the model sees a reading.
        """
        self.alpha_ = float(alpha)
        self.zero_reading_ = estimate_zero_reading(X, y, self.alpha_, axes) if zero_reading is None else \
            np.asarray(zero_reading, dtype=float)
        self.reading_noise_ = reading_noise(X, y)
        self.calibrated_range_ = calibrated_range(X)
        self.__dict__.pop("tare_reading_", None)

    def _adopt_fitted(self, X: NDArray[np.float64], y: NDArray[np.float64], inner, *,
                      zero_reading: NDArray[np.float64] | None = None) -> None:
        """The calibration of a wrapper around its fitted ``inner`` calibrator (:meth:`_record_calibration`):
        ``inner``'s ``alpha_`` (and ``axes_``, when it has them) and, unless ``zero_reading`` is given, its
        ``zero_reading_``; the noise and the range of the wrapper's own ``X`` (n, N)."""
        if getattr(inner, "axes_", None) is not None:
            self.axes_ = inner.axes_
        if zero_reading is None:
            zero_reading = getattr(inner, "zero_reading_", None)
        self._record_calibration(X, y, inner.alpha_, zero_reading)


class GroupsFit:
    """Mixin of a calibrator that uses the rows' groups inside its ``fit``: ``fit(X, y, groups=None)`` calls
    ``_fit(X, y, groups)`` with the checked labels (None when its parameters do not use them); the groups are
    requested through metadata routing by default, like a group splitter."""

    __metadata_request__fit = {"groups": True}
    #: What the groups are for, and the fix, in the one-group error (see :func:`check_groups`).
    _groups_purpose = ("grouped cross-validation", "pass {groups} for random folds")

    def _uses_groups(self) -> bool:
        """Whether this fit uses the groups with these parameters (else they are only checked for their length)."""
        return True

    def __sklearn_tags__(self) -> FtcalTags:
        return declare(super().__sklearn_tags__(), uses_groups=True)

    def fit(self, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None):
        """Fit on raw readings ``X`` (n, N) and wrenches ``y`` (n, 6).

        Parameters
        ----------
        groups : array-like of shape (n,) or None
            Group of each row (pose, load configuration, recording), used as the class describes; checked after
            ``X`` and ``y`` and before any fitting (their length always, their labels when they are used).

        Returns
        -------
        self
        """
        return self._checked_fit(X, y, groups)

    def _fit_metadata(self, n_samples: int, groups, sample_weight) -> dict:
        uses, (purpose, fix) = self._uses_groups(), self._groups_purpose
        groups = check_groups(groups, n_samples, labels=uses, purpose=purpose, fix=fix)
        return {**super()._fit_metadata(n_samples, None, sample_weight), "groups": groups if uses else None}


def retare_shift(model, n_columns: int | None = None) -> NDArray[np.float64]:
    """How far a re-tare moved the model's zero-load reading [raw units]: ``tare_reading_ - zero_reading_``.

    What :meth:`BaseCalibrator.retare` shifts every reading by before the calibration sees it (``predict``, the
    ONNX graph), and how far the model's calibrated range moves with it. Zero without a re-tare; zero for a column
    past the re-tared ones (a temperature column).

    Parameters
    ----------
    model : fitted calibrator
    n_columns : int, optional
        Width of the result; default the model's ``n_features_in_``.

    Returns
    -------
    ndarray of shape (n_columns,)

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import LinearCalibrator
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(100, 6)); raw = w @ rng.normal(size=(6, 6)) + 1.0
    >>> model = LinearCalibrator(zero_reading=np.ones(6)).fit(raw, w)
    >>> retare_shift(model).tolist() == [0.0] * 6
    True
    >>> np.round(retare_shift(model.retare(np.full((5, 6), 1.001))), 6).tolist()
    [0.001, 0.001, 0.001, 0.001, 0.001, 0.001]
    """
    tare, zero = getattr(model, "tare_reading_", None), getattr(model, "zero_reading_", None)
    moved = np.zeros(0) if tare is None or zero is None else \
        np.asarray(tare, dtype=float).ravel() - np.asarray(zero, dtype=float).ravel()
    shift = np.zeros(int(getattr(model, "n_features_in_", moved.size)) if n_columns is None else int(n_columns))
    shift[:moved.size] = moved[:shift.size]
    return shift
