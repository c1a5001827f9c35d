"""A first-order load-history term behind any calibrator, for sensors with creep or hysteresis (issue 19).

A soft or viscoelastic sensor reads the same load differently on the way up
and on the way down: part of each reading follows the load with a lag. No
static map of the current reading can undo that; the readings before it can.
:func:`reading_history` summarises them in one feature per channel (the
exponential moving average of the earlier readings, minus the current one),
and :class:`HistoryCalibrator` adds a linear map of those features to what its
calibrator predicts. Readings only: nothing a deployed sensor does not have.

Its rows are **time-ordered samples** (one recording, or recordings one
after another), at ``fit`` and at ``predict``; shuffled rows have no history.
"""

from __future__ import annotations

from collections.abc import Callable
from numbers import Integral, Real

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.signal import lfilter
from sklearn.base import clone
from sklearn.model_selection import GroupKFold, KFold
from sklearn.utils._param_validation import Interval
from sklearn.utils.validation import check_is_fitted

from ..core._exceptions import CalibrationInputError
from ..core._model_selection import simplest_within_one_se
from ..core._validation import check_finite_output, validate_readings
from ..core._wrench import scale_torques
from ._base import BaseCalibrator, GroupsFit
from ._linear import LinearCalibrator
from ._ridge import ridge_least_squares
from ._routing import requests_groups, routed_fit_params, wrapper_routing

__all__ = ["HistoryCalibrator", "reading_history"]

#: Contiguous blocks the rows are cut into for the one-SE rule when no groups are given (neighbouring rows of a
#: time series are not independent errors).
_TIME_BLOCKS = 20


def reading_history(X: ArrayLike, tau_rows: float, *, state: ArrayLike | None = None,
                    return_state: bool = False):
    """Each row's exponential moving average of the readings **before** it, minus the row itself.

    ``m_0 = state`` (default: the first row, a sensor at rest), ``m_{i+1} =
    m_i + (X_i - m_i) / tau_rows``, feature ``h_i = m_i - X_i``. It is zero
    while the readings hold still and follows the recent load path otherwise;
    a constant offset of the readings (a tare) cancels in it.

    Parameters
    ----------
    X : array-like of shape (n, N)
        Readings in time order.
    tau_rows : float >= 1
        Time constant in rows (samples); 1 is the previous row.
    state : array-like of shape (N,) or None
        The moving average before the first row (the ``state`` returned by
        the previous call on the same stream), to continue a stream in chunks.
    return_state : bool, default=False
        Also return the moving average after the last row.

    Returns
    -------
    history : ndarray of shape (n, N)
    state : ndarray of shape (N,), only with ``return_state``

    Examples
    --------
    >>> import numpy as np
    >>> x = np.array([[0.0], [0.0], [2.0], [2.0], [2.0]])
    >>> reading_history(x, 2.0).ravel().tolist()
    [0.0, 0.0, -2.0, -1.0, -0.5]
    >>> first, state = reading_history(x[:3], 2.0, return_state=True)
    >>> reading_history(x[3:], 2.0, state=state).ravel().tolist()   # the same stream in two chunks
    [-1.0, -0.5]
    """
    X = np.asarray(X, dtype=float)
    if isinstance(tau_rows, bool) or not isinstance(tau_rows, Real) or not tau_rows >= 1:
        raise CalibrationInputError(f"tau_rows must be a number >= 1 (a time constant in rows); got {tau_rows!r}.")
    if X.ndim != 2:
        raise CalibrationInputError(f"X must be 2-D (rows in time order x channels); got shape {X.shape}.")
    if len(X) == 0:
        return (X.copy(), np.asarray(state, dtype=float)) if return_state else X.copy()
    start = X[0] if state is None else np.asarray(state, dtype=float).reshape(X.shape[1])
    a = 1.0 / float(tau_rows)
    # e_i = (1 - a) e_{i-1} + a X_i with e_{-1} = start: the average *including* row i; the one before row i is e_{i-1}
    averages = lfilter([a], [1.0, a - 1.0], X, axis=0, zi=((1.0 - a) * start)[None, :])[0]
    before = np.vstack([start[None, :], averages[:-1]])
    history = before - X
    return (history, averages[-1].copy()) if return_state else history


def _rows(groups: NDArray | None, index: NDArray) -> NDArray | None:
    return None if groups is None else groups[index]


def _predicted(model: BaseCalibrator, X: NDArray[np.float64]) -> NDArray[np.float64]:
    """``model.predict(X)`` as (n, k), whatever the target's width."""
    return np.asarray(model.predict(X), dtype=float).reshape(len(X), -1)


class HistoryCalibrator(GroupsFit, BaseCalibrator):
    """``estimator`` plus a linear map of the readings' history, its time constant chosen by cross-validation.

    ``fit`` takes readings **in time order**. The model is additive: the
    wrench is ``estimator(X)`` plus a linear map of :func:`reading_history`
    ``(X, tau)``, the two fitted jointly by backfitting (``n_iterations``
    alternating fits, each on the other's residual). Cross-validation
    (contiguous blocks of rows, or whole ``groups`` held out) decides in two
    steps: the time constant of ``taus`` whose map, fitted on the estimator's
    residual, predicts the held-out rows best (one estimator fit per fold
    for all of them), then whether that time constant's whole backfitted
    model beats the estimator alone by more than one standard error (ftcal's
    one-SE rule, :func:`~ftcal.core._model_selection.simplest_within_one_se`);
    if not, there is no history term: on a rigid sensor, or on shuffled rows,
    the result is the estimator itself. ``estimator`` is fitted
    ``cv * n_iterations + n_iterations`` times (18 with the defaults); a
    model-choosing estimator (:class:`~ftcal.AutoCalibrator`) is fitted
    once on all rows first, and the model it chooses is the estimator from
    then on (the static choice is made without the history).

    ``predict`` also takes rows in time order, as one recording starting at
    rest; :meth:`stream` carries the history from one chunk to the
    next (a live sensor). Not exportable to ONNX (the graph has no state).

    Parameters
    ----------
    estimator : calibrator or None, default=None
        The static calibrator; ``None``: :class:`~ftcal.LinearCalibrator`.
    taus : tuple of float >= 1, default=(1, 2, 4, 8, 16)
        Time constants tried [rows].
    cv : int >= 2, default=5
        Folds: contiguous blocks of rows, or :class:`~sklearn.model_selection.GroupKFold`
        over ``groups`` (sessions, presses: the rows of one group must be
        consecutive in time).
    n_iterations : int >= 1, default=3
        Backfitting passes (1: the history map fitted once on the estimator's
        residual).
    alpha, zero_reading, random_state
        Given to ``estimator`` when it has them.

    Attributes
    ----------
    estimator_ : calibrator
        ``estimator`` (or the model ``AutoCalibrator`` chose) fitted on all
        rows, jointly with the history map.
    tau_rows_ : float or None
        The chosen time constant [rows]; ``None``: no history term.
    history_coef_ : ndarray of shape (N, 6) or None
    history_intercept_ : ndarray of shape (6,) or None
    static_choice_ : str or None
        The model a model-choosing ``estimator`` chose (its ``best_name_``).
    cv_rmse_ : ndarray of shape (1 + len(taus),)
        Held-out RMSE (eq. 18) without a history term, then with each
        ``tau`` after one backfitting pass (the time constant's choice).
    history_cv_rmse_ : float
        Held-out RMSE of the best time constant's whole backfitted model
        (the keep-or-not decision, against ``cv_rmse_[0]``).

    Examples
    --------
    >>> import ftcal
    >>> d = ftcal.make_soft_sensor_dataset()
    >>> model = ftcal.HistoryCalibrator(ftcal.PolynomialCalibrator(degree=2, ridge=0.01)).fit(
    ...     d.raw, d.wrench, groups=d.group)
    >>> model.tau_rows_ is not None, model.predict(d.raw[:5]).shape
    (True, (5, 6))
    """

    _fitted_state = ("estimator_", "tau_rows_", "history_coef_", "history_intercept_", "cv_rmse_", "history_cv_rmse_",
                     "static_choice_")
    # a model file stores no None: these are the values a fit without a history term (or a chooser) leaves
    tau_rows_ = history_coef_ = history_intercept_ = static_choice_ = None
    _groups_purpose = ("cross-validating the history term over whole groups",
                       "pass groups=None for contiguous blocks of rows")
    _parameter_constraints: dict = {
        **BaseCalibrator._parameter_constraints,
        "estimator": [BaseCalibrator, None],
        "taus": ["array-like"],
        "cv": [Interval(Integral, 2, None, closed="left")],
        "n_iterations": [Interval(Integral, 1, None, closed="left")],
    }

    def __init__(self, estimator=None, *, taus=(1.0, 2.0, 4.0, 8.0, 16.0), cv=5, n_iterations=3, alpha=None, zero_reading=None,
                 random_state=None):
        self.estimator = estimator
        self.taus = taus
        self.cv = cv
        self.n_iterations = n_iterations
        self.alpha = alpha
        self.zero_reading = zero_reading
        self.random_state = random_state

    def _check_params(self) -> None:
        taus = list(np.ravel(np.asarray(self.taus, dtype=object)))
        bad = [t for t in taus if isinstance(t, bool) or not isinstance(t, Real) or not np.isfinite(t) or t < 1]
        if not taus or bad:
            raise CalibrationInputError(
                f"taus must be a non-empty list of time constants >= 1 [rows]; got {self.taus!r}"
                + (f" (bad: {bad[0]!r})" if bad else "") + ".")

    def _inner(self) -> BaseCalibrator:
        return LinearCalibrator() if self.estimator is None else self.estimator

    def get_metadata_routing(self):
        """Routing of ``fit``'s ``groups`` to ``estimator`` (see :mod:`ftcal.calibrators._routing`)."""
        return wrapper_routing(self, self._inner())

    def _new_inner(self) -> BaseCalibrator:
        template = self.__dict__.get("_template")
        inner = clone(self._inner() if template is None else template)
        params = inner.get_params()
        given = {"alpha": self.alpha_, "zero_reading": self.zero_reading, "random_state": self.random_state}
        inner.set_params(**{k: v for k, v in given.items() if k in params})  # one torque scale for every fit
        return inner

    def _folds(self, n: int, groups: NDArray | None) -> list[tuple[NDArray, NDArray]]:
        if groups is None:
            if n < self.cv:
                raise CalibrationInputError(f"X has {n} rows, fewer than cv={self.cv} folds; lower cv or record more.")
            return list(KFold(int(self.cv)).split(np.empty((n, 1))))  # contiguous blocks: the rows are a time series
        return list(GroupKFold(min(int(self.cv), np.unique(groups).size)).split(np.empty((n, 1)), groups=groups))

    def _fit(self, X: NDArray[np.float64], y: NDArray[np.float64]) -> None:
        groups = self._fit_groups
        n, taus = len(X), [float(t) for t in np.ravel(np.asarray(self.taus, dtype=object))]
        folds = self._folds(n, groups)
        self._template = self.static_choice_ = None
        try:
            if getattr(self._inner(), "_chooses_a_model", False):  # AutoCalibrator: choose the static model once
                chooser = self._new_inner().fit(X, y, **routed_fit_params(self, groups))
                self._template = clone(chooser.best_estimator_)
                self.static_choice_ = chooser.best_name_
            self._fit_with_history(X, y, groups, taus, folds)
        finally:
            del self._template

    def _fit_with_history(self, X, y, groups, taus, folds) -> None:
        n = len(X)
        histories = [reading_history(X, tau) for tau in taus]  # over the whole recording: readings only
        # 1. one backfitting pass per fold, shared by every candidate: the estimator alone (no history term), then
        #    each time constant's map fitted on its residual; the best time constant by held-out error
        static, first_pass = [], np.empty((1 + len(taus),) + y.shape)
        for train, test in folds:
            model = self._fold(lambda: self._backfit(X[train], y[train], None, _rows(groups, train)), train, n, folds)[0]
            static.append(model)
            first_pass[0][test] = _predicted(model, X[test])
            residual = y[train] - _predicted(model, X[train])
            for k, history in enumerate(histories, start=1):
                coef, intercept = ridge_least_squares(history[train], residual, 0.0, n_unpenalised=0)
                first_pass[k][test] = first_pass[0][test] + history[test] @ coef + intercept
        pass_errors = np.array([self._row_errors(y - p) for p in first_pass])  # per row: eq. 18 over rows
        best = int(np.argmin(pass_errors[1:].mean(axis=1)))
        # 2. that time constant's whole backfitted model, held out the same way, against the estimator alone
        joint = np.empty_like(y)
        for (train, test), model in zip(folds, static):
            model, coef, intercept = self._fold(lambda: self._backfit(
                X[train], y[train], histories[best][train], _rows(groups, train), first=model), train, n, folds)
            joint[test] = _predicted(model, X[test]) + histories[best][test] @ coef + intercept
        errors = np.vstack([pass_errors[0], self._row_errors(y - joint)])
        units = groups if groups is not None else np.arange(n) * _TIME_BLOCKS // n
        keep = simplest_within_one_se(errors, units) == 1  # the simpler (no history term) wins ties
        self.cv_rmse_ = np.sqrt(pass_errors.mean(axis=1))
        self.history_cv_rmse_ = float(np.sqrt(errors[1].mean()))
        self.tau_rows_ = taus[best] if keep else None
        self.estimator_, self.history_coef_, self.history_intercept_ = self._backfit(
            X, y, histories[best] if keep else None, groups)
        self.zero_reading_ = self.estimator_.zero_reading_

    @staticmethod
    def _fold(fit, train, n, folds):
        """``fit()`` of one training fold, its refusal (too few rows, ...) said to be a fold's."""
        try:
            return fit()
        except CalibrationInputError as exc:
            raise CalibrationInputError(f"HistoryCalibrator cross-validates over {len(folds)} folds: a training fold "
                                        f"holds {len(train)} of the {n} rows, and there: {exc}") from None

    def _backfit(self, X, y, history, groups, first=None):
        """``estimator`` and the history map fitted jointly by backfitting (alternating fits on each other's residual,
        the standard algorithm of additive models): ``(estimator, coef, intercept)``; without a history, the estimator
        alone and ``None, None``. ``first``: the estimator already fitted on ``y`` (the first pass)."""
        routed = {"groups": groups} if groups is not None and requests_groups(self._new_inner()) else {}
        model = first if first is not None else self._new_inner().fit(X, y, **routed)
        coef = intercept = None
        for iteration in range(0 if history is None else int(self.n_iterations)):
            if iteration:
                model = self._new_inner().fit(X, y - (history @ coef + intercept), **routed)
            coef, intercept = ridge_least_squares(history, y - _predicted(model, X), 0.0, n_unpenalised=0)
        return model, coef, intercept

    def _row_errors(self, error: NDArray[np.float64]) -> NDArray[np.float64]:
        scaled = scale_torques(error, self.alpha_) if error.shape[1] == 6 else error
        return np.mean(scaled ** 2, axis=1)

    def retare(self, X_no_load: ArrayLike, *, max_spread: float = 5.0):
        """Re-zero the inner calibrator from zero-load readings taken now (the history term needs none: an offset
        cancels in it). See :meth:`~ftcal.calibrators._base.BaseCalibrator.retare`.

        Returns
        -------
        self
        """
        check_is_fitted(self)
        self.estimator_.retare(validate_readings(self, X_no_load), max_spread=max_spread)
        return self

    def _predict_wrench(self, X: NDArray[np.float64], state: NDArray | None = None) -> NDArray[np.float64]:
        wrench = _predicted(self.estimator_, X)
        if self.tau_rows_ is None:
            return wrench
        return wrench + reading_history(X, self.tau_rows_, state=state) @ self.history_coef_ + self.history_intercept_

    def stream(self) -> Callable[[ArrayLike], NDArray[np.float64]]:
        """A ``predict`` for a live stream: each call takes the next chunk of readings (n_i, N), in time order, and
        the history carries from one call to the next.

        Calling it on the chunks of a recording one after another gives what
        :meth:`predict` gives on the whole recording. Each ``stream()`` is a
        new stream, starting at rest.

        Examples
        --------
        >>> import numpy as np, ftcal
        >>> d = ftcal.make_soft_sensor_dataset()
        >>> model = ftcal.HistoryCalibrator(taus=(2.0,)).fit(d.raw, d.wrench, groups=d.group)
        >>> predict = model.stream()
        >>> parts = [predict(d.raw[:100]), predict(d.raw[100:])]
        >>> bool(np.allclose(np.vstack(parts), model.predict(d.raw)))
        True
        """
        check_is_fitted(self)
        state = [None]

        def predict(chunk: ArrayLike) -> NDArray[np.float64]:
            X = validate_readings(self, chunk)
            wrench = self._predict_wrench(X, state[0])
            check_finite_output(X, wrench, self)
            if self.tau_rows_ is not None and len(X):
                state[0] = reading_history(X, self.tau_rows_, state=state[0], return_state=True)[1]
            return wrench[:, 0] if self.__dict__.get("y_1d_") else wrench

        return predict
