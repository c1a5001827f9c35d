"""A first-order load-history term behind any calibrator, for sensors with creep or hysteresis.

A soft or viscoelastic sensor reads the same load differently on the way up
and on the way down: part of each reading follows the load with a lag. No
static map of the current reading can undo that; the readings before it can.
:func:`reading_history` summarises them in one feature per channel (the
exponential moving average of the earlier readings, minus the current one),
and :class:`HistoryCalibrator` adds a linear map of those features to what its
calibrator predicts. Readings only: nothing a deployed sensor does not have.

Its rows are **time-ordered samples** (one recording, or recordings one
after another, at one sampling rate: the time constant is counted in rows),
at ``fit`` and at ``predict``; shuffled rows have no history.
"""

from __future__ import annotations

from collections.abc import Callable
from numbers import Integral, Real

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.signal import lfilter
from sklearn.base import clone
from sklearn.utils._param_validation import Interval
from sklearn.utils.validation import check_is_fitted

from ..core._exceptions import NO_SETTING, CalibrationInputError, TooFewSamplesError
from ..core._memory import check_allocation
from ..model_selection._selection import calibration_folds, simplest_within_one_se
from ..core._validation import check_bool
from ..core._wrench import scale_torques
from ..calibrators._base import BaseCalibrator, GroupsFit, calibration_tags, declare
from ..calibrators._ridge import ridge_least_squares
from ._routing import requests_groups, routed_fit_params
from ._wrapper import CalibratorWrapper, reads_history, refuse_history_inside

__all__ = ["HistoryCalibrator", "reading_history", "reads_history", "refuse_history_inside", "spread_flags"]

#: Contiguous blocks the rows are cut into for the one-SE rule when no groups are given (neighbouring rows of a
#: time series are not independent errors).
_TIME_BLOCKS = 20
#: Most time constants one fit tries: each costs ``cv`` fits of the estimator, so a longer list is a mistake (a
#: grid over rows, not over time constants) that would run for hours; a log-spaced grid needs a dozen.
MAX_TAUS = 64


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
    X = _real_array(X, "X")
    if isinstance(tau_rows, bool) or not isinstance(tau_rows, Real) or not (np.isfinite(float(tau_rows))
                                                                             and tau_rows >= 1):
        raise CalibrationInputError(f"tau_rows must be a finite number >= 1 (a time constant in rows); got "
                                    f"{tau_rows!r}.")
    if X.ndim != 2 or len(X) == 0:
        raise CalibrationInputError(f"X must hold at least one row of readings, 2-D (rows in time order x channels); "
                                    f"got shape {X.shape}.", parameter="X")
    if not np.isfinite(X).all():
        r, c = (int(v) for v in np.argwhere(~np.isfinite(X))[0])
        raise CalibrationInputError(f"X[{r}, {c}] = {X[r, c]}: readings must be finite (a NaN would poison every "
                                    "later row's history); drop or repair that row.", parameter="X")
    start = None
    if state is not None:
        start = _real_array(state, "state")
        if start.shape != (X.shape[1],):
            raise CalibrationInputError(f"state must be the moving average of the previous chunk, shape "
                                        f"({X.shape[1]},); got shape {start.shape}.")
        if not np.isfinite(start).all():
            raise CalibrationInputError(f"state holds a non-finite value ({start[~np.isfinite(start)][0]}); pass the "
                                        "state returned by the previous chunk, or None to start at rest.")
    history, end = _history(X, float(tau_rows), start)
    return (history, end) if return_state else history


def _history(X: NDArray[np.float64], tau_rows: float, start: NDArray[np.float64] | None = None
             ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`reading_history` of readings already validated (the calibrator's own calls: ``fit``, ``predict``,
    ``stream``): ``(history, state after the last row)``; ``start`` None: the first row."""
    start = X[0] if start is None else start
    a = 1.0 / tau_rows
    # e_i = (1 - a) e_{i-1} + a X_i with e_{-1} = start: the average *including* row i; the one before row i is e_{i-1}
    averages = lfilter([a], [1.0, a - 1.0], X, axis=0, zi=((1.0 - a) * start)[None, :])[0]
    with np.errstate(over="ignore", invalid="ignore"):
        before = np.vstack([start[None, :], averages[:-1]])
        history = before - X
    if not np.isfinite(history).all():
        raise CalibrationInputError(f"the readings' history overflows (readings up to {np.abs(X).max():.3g}); "
                                    "readings this large are not a sensor's: check the units and the file.")
    return history, averages[-1].copy()


def _real_array(values: ArrayLike, name: str) -> NDArray[np.float64]:
    array = np.asarray(values)
    if array.dtype.kind not in "biuf":
        raise CalibrationInputError(f"{name} must hold real numbers; got an array of dtype {array.dtype} "
                                    f"(shape {array.shape}).")
    return array.astype(float)


#: Weight below which a reading no longer counts in a later row's history (for the range flags).
HISTORY_WEIGHT_FLOOR = 1e-3


def history_reach(tau_rows: float) -> int:
    """How many rows after a reading its weight in their history stays >= :data:`HISTORY_WEIGHT_FLOOR`.

    Examples
    --------
    >>> history_reach(1.0), history_reach(2.0), history_reach(16.0)
    (1, 9, 65)
    """
    a = 1.0 / float(tau_rows)
    return 1 if a >= 1.0 else 1 + int(np.floor(np.log(HISTORY_WEIGHT_FLOOR / a) / np.log(1.0 - a)))


def spread_flags(flags: ArrayLike, reach: int, since: int | None = None) -> tuple[NDArray[np.bool_], int | None]:
    """Flags of readings beyond the calibrated range, spread to the ``reach`` rows after each (whose history holds
    them): ``(flags, since)``, ``since`` the rows from the last flagged one to the end (``None``: none), to pass
    with the next chunk of a stream.

    Examples
    --------
    >>> flags, since = spread_flags([0, 1, 0, 0, 0], 2)
    >>> flags.astype(int).tolist(), since
    ([0, 1, 1, 1, 0], 4)
    >>> spread_flags([0, 0], 5, since=4)[0].astype(int).tolist()   # the next chunk: 4 and 5 rows after the flag
    [1, 1]
    """
    flags = np.asarray(flags, dtype=bool)
    index = np.arange(flags.size, dtype=float)
    last = np.maximum.accumulate(np.where(flags, index, -np.inf)) if flags.size else index
    last = np.maximum(last, -np.inf if since is None else -float(since))
    spread = (index - last) <= reach
    return spread, (None if not flags.size or not np.isfinite(last[-1]) else int(flags.size - last[-1]))


def _predicted(model: BaseCalibrator, X: NDArray[np.float64]) -> NDArray[np.float64]:
    """``model.predict(X)`` as (n, k), whatever the target's width."""
    return np.asarray(model.predict(X), dtype=float).reshape(len(X), -1)


class HistoryCalibrator(GroupsFit, CalibratorWrapper):
    """``estimator`` plus a linear map of the readings' history, its time constant chosen by cross-validation.

    ``fit`` takes readings **in time order**. The model is partially linear:
    the wrench is ``f(X) + H c`` with ``H`` = :func:`reading_history` ``(X,
    tau)``, ``f`` of the form of ``estimator`` and ``c`` a linear map. It is
    fitted by Robinson's partialling out: ``estimator`` is fitted to the
    wrench (``estimator_``) and, with the same tare, to the history columns
    (``history_estimator_``: what of the history the current reading
    already tells), and ``c`` maps what is left of the history onto what is
    left of the wrench. The prediction is ``estimator_(X) + (H -
    history_estimator_(X)) c``. For an unpenalised estimator linear in its
    features (the LTM) that is exactly the joint least-squares fit, however
    strongly the history correlates with the readings; for a lightly
    penalised polynomial it is close to it.

    Cross-validation (contiguous blocks of rows, or whole ``groups`` held
    out) scores the estimator alone and each time constant of ``taus``;
    ftcal's one-SE rule (:func:`~ftcal.model_selection._selection.simplest_within_one_se`)
    keeps a history term only when it beats the estimator alone by more than
    one standard error (among the time constants within it, the shortest):
    on shuffled rows, and usually on a sensor without memory, the result is
    the estimator itself (with noisy readings the moving average can pay as
    a denoiser, and with a misfitting estimator as a patch: ``cv_rmse_``
    tells by how much; with few groups a small gain may be chance).
    ``estimator`` is fitted ``cv * (1 + len(taus)) + 2`` times (32 with the
    defaults); a model-choosing estimator (:class:`~ftcal.AutoCalibrator`)
    is fitted once on all rows first, and the model it chooses is the
    estimator from then on (the static choice is made without the history).
    A flexible estimator that nearly interpolates its training rows (a
    Gaussian process) leaves little of either to map, so its history term
    gains less.

    ``predict`` also takes rows in time order, as one recording starting at
    rest; :meth:`stream` carries the history from one chunk to the next (a
    live sensor). The time constant is counted in rows: deploy at the
    sampling rate of the calibration data. Not exportable to ONNX (the
    graph has no state).

    Parameters
    ----------
    estimator : calibrator or None, default=None
        The static calibrator; ``None``: :class:`~ftcal.LinearCalibrator`.
    taus : array-like of float >= 1, default=(1, 2, 4, 8, 16)
        Time constants tried [rows]: a flat list of at most 64.
    cv : int >= 2, default=5
        Folds: contiguous blocks of rows, or :class:`~sklearn.model_selection.GroupKFold`
        over ``groups`` (sessions, presses: the rows of one group must be
        consecutive in time).
    alpha, zero_reading, random_state
        Given to ``estimator`` when it has them and they are not None (else
        ``estimator``'s own are kept).

    Attributes
    ----------
    estimator_ : calibrator
        ``estimator`` (or the model ``AutoCalibrator`` chose) fitted on all
        rows.
    tau_rows_ : float or None
        The chosen time constant [rows]; ``None``: no history term.
    history_estimator_ : calibrator or None
        ``estimator`` fitted to the history columns.
    history_coef_ : ndarray of shape (N, k) or None
    history_intercept_ : ndarray of shape (k,) or None
    cv_rmse_ : ndarray of shape (1 + len(taus),)
        Held-out RMSE (eq. 18) without a history term, then with each ``tau``.
    static_choice_ : str or None
        The model a model-choosing ``estimator`` chose (its ``best_name_``).
    static_cv_results_ : dict or None
        Its ``comparison_``.

    Examples
    --------
    >>> import ftcal
    >>> d = ftcal.simulation.make_soft_sensor_dataset()
    >>> model = ftcal.HistoryCalibrator(ftcal.PolynomialCalibrator(degree=2, ridge=0.01)).fit(
    ...     d.raw, d.wrench, groups=d.group)
    >>> model.tau_rows_ is not None, model.predict(d.raw[:5]).shape
    (True, (5, 6))
    """

    _fitted_state = ("estimator_", "tau_rows_", "history_estimator_", "history_coef_", "history_intercept_",
                     "cv_rmse_", "static_choice_", "static_cv_results_")
    _fitted_constraints: dict = {"tau_rows_": [Interval(Real, 1, None, closed="left")],  # a time constant [rows]
                                 "cv_rmse_": [Interval(Real, 0, None, closed="left")]}
    # a model file stores no None: these are the values a fit without a history term (or a chooser) leaves
    tau_rows_ = history_estimator_ = history_coef_ = history_intercept_ = static_choice_ = static_cv_results_ = None
    _groups_purpose = ("cross-validating the history term over whole groups",
                       "give no groups (no group column) for contiguous blocks of rows, or more groups")
    _parameter_constraints: dict = {
        **BaseCalibrator._parameter_constraints,
        "estimator": [BaseCalibrator, None],
        "taus": ["array-like"],
        "cv": [Interval(Integral, 2, None, closed="left")],
    }

    def __init__(self, estimator=None, *, taus=(1.0, 2.0, 4.0, 8.0, 16.0), cv=5, alpha=None, zero_reading=None,
                 random_state=None):
        self.estimator = estimator
        self.taus = taus
        self.cv = cv
        super().__init__(alpha=alpha, zero_reading=zero_reading, random_state=random_state)

    def __sklearn_tags__(self):
        return declare(super().__sklearn_tags__(), reads_history=True)

    def _taus(self) -> list:
        """The time constants as a flat list (one number counts as a list of one; a table is checked and refused)."""
        return list(np.atleast_1d(np.asarray(self.taus, dtype=object)))

    def _check_params(self) -> None:
        shape = np.shape(np.asarray(self.taus, dtype=object))
        taus = self._taus()
        bad = [t for t in taus if isinstance(t, bool) or not isinstance(t, Real) or not np.isfinite(float(t)) or t < 1]
        if len(shape) > 1 or not taus or bad or len(taus) > MAX_TAUS:
            why = (f"an array of shape {shape}" if len(shape) > 1 else f"{bad[0]!r} among them" if bad
                   else f"{len(taus)} of them (each costs cv fits)" if taus else "none")
            raise CalibrationInputError(
                f"taus must be a non-empty flat list of at most {MAX_TAUS} time constants >= 1 [rows], e.g. (1, 2, 4, "
                f"8, 16); got {why}: {self.taus!r:.120}.")

    def _fit(self, X: NDArray[np.float64], y: NDArray[np.float64], groups: NDArray | None = None) -> None:
        n, taus = len(X), [float(t) for t in self._taus()]
        if groups is None and n < self.cv:
            raise CalibrationInputError(f"X has {n} rows, fewer than cv={self.cv} folds; lower cv or record more.",
                                        parameter="X", value=n)
        # ftcal's folds, unshuffled: contiguous blocks of rows (a time series), or whole groups
        folds = calibration_folds(n, groups, int(self.cv), shuffle=False)
        template = self._inner()
        refuse_history_inside(template, type(self).__name__)
        static = calibration_tags(template)
        if static.temperature_column:
            raise CalibrationInputError(
                f"HistoryCalibrator cannot wrap {type(template).__name__}: its last column is the temperature, whose "
                "history is not a load's, and the history columns cannot be temperature-compensated.",
                parameter="estimator", fix="calibrate with one of the two ({HistoryCalibrator} or "
                "{TemperatureCompensatedCalibrator})",
                settings={"HistoryCalibrator": NO_SETTING, "TemperatureCompensatedCalibrator": NO_SETTING})
        check_allocation(8.0 * X.size * (len(taus) + 1), f"the history columns of {len(taus)} time constants",
                         "try fewer taus")
        self.static_choice_ = self.static_cv_results_ = None
        if static.chooses_model:  # AutoCalibrator: choose the static model once, on all rows
            chooser = self._new(template).fit(X, y, **routed_fit_params(self, groups))
            template, self.static_choice_ = clone(chooser.best_estimator_), chooser.best_name_
            self.static_cv_results_ = chooser.comparison_.to_dict()  # JSON-able, as the model file keeps it
        histories = [_history(X, tau)[0] for tau in taus]  # over the whole recording: readings only
        held_out = np.empty((1 + len(taus),) + y.shape)
        for train, test in folds:
            try:
                static, maps = self._partial_fit(template, X[train], y[train], [h[train] for h in histories],
                                                 None if groups is None else groups[train])
            except CalibrationInputError as exc:  # said of the fold, the error's class and fields kept
                hint = " (fewer folds, cv, make it larger)" if isinstance(exc, TooFewSamplesError) else ""
                raise exc.located(f"HistoryCalibrator cross-validates over {len(folds)} folds: a training fold holds "
                                  f"{len(train)} of the {n} rows{hint}, and there: ") from None
            held_out[0][test] = _predicted(static, X[test])
            for k, (history, fitted) in enumerate(zip(histories, maps), start=1):
                held_out[k][test] = held_out[0][test] + self._history_term(fitted, X[test], history[test])
        # per row: the mean squared torque-scaled error (eq. 18 over the rows)
        errors = np.array([np.mean(scale_torques(y - p, self.alpha_, self.axes_) ** 2, axis=1) for p in held_out])
        units = groups if groups is not None else np.arange(n) * _TIME_BLOCKS // n
        shortest_first = np.argsort(np.argsort(taus, kind="stable"), kind="stable")  # among the qualified: the shortest
        chosen = simplest_within_one_se(errors, units, complexity=[0, *(1 + shortest_first)])
        self.cv_rmse_ = np.sqrt(errors.mean(axis=1))
        self.tau_rows_ = None if chosen == 0 else taus[chosen - 1]
        kept = [] if chosen == 0 else [histories[chosen - 1]]
        self.estimator_, maps = self._partial_fit(template, X, y, kept, groups)
        self.history_estimator_, self.history_coef_, self.history_intercept_ = maps[0] if maps else (None,) * 3
        self._adopt_fitted(X, y, self.estimator_)

    def _new(self, template: BaseCalibrator, **given) -> BaseCalibrator:
        return self._settled(template, **{"alpha": self.alpha_, **given})

    def _partial_fit(self, template, X, y, histories, groups):
        """Robinson's partialling out: the estimator fitted to ``y``, and for each history ``H``: ``(g, c, b)``, ``g``
        the estimator fitted to ``H`` (same tare, unscaled columns), ``c, b`` the least-squares map of ``H - g(X)``
        onto ``y - f(X)``."""
        routed = {"groups": groups} if groups is not None and requests_groups(template) else {}
        static = self._new(template).fit(X, y, **routed)
        left = y - _predicted(static, X)
        maps = []
        for history in histories:
            g = self._new(template, alpha=1.0, zero_reading=static.zero_reading_).fit(X, history, **routed)
            coef, intercept = ridge_least_squares(history - _predicted(g, X), left, 0.0, n_unpenalised=0)
            maps.append((g, coef, intercept))
        return static, maps

    @staticmethod
    def _history_term(fitted, X, history):
        g, coef, intercept = fitted
        return (history - _predicted(g, X)) @ coef + intercept

    def _predict_wrench(self, X: NDArray[np.float64], history: NDArray | None = None) -> NDArray[np.float64]:
        wrench = _predicted(self.estimator_, X)
        if self.tau_rows_ is None:
            return wrench
        history = _history(X, self.tau_rows_)[0] if history is None else history
        fitted = (self.history_estimator_, self.history_coef_, self.history_intercept_)
        return wrench + self._history_term(fitted, X, history)

    def out_of_range(self, X: ArrayLike, *, margin: float = 0.0, spread: bool = True) -> NDArray[np.bool_]:
        """Rows beyond the calibrated range (see :meth:`~ftcal.calibrators._base.BaseCalibrator.out_of_range`), and
        with ``spread`` the rows after each whose history still holds it (weight >= :data:`HISTORY_WEIGHT_FLOOR`):
        their wrench depends on that reading too. ``spread=False`` flags the rows themselves only, for a caller
        that spreads the flags across the chunks of a stream itself (``ftcal predict``, with
        :func:`spread_flags`).

        Returns
        -------
        ndarray of shape (n,), bool
        """
        flags = super().out_of_range(X, margin=margin)
        if self.tau_rows_ is None or not check_bool(spread, "spread"):
            return flags
        return spread_flags(flags, history_reach(self.tau_rows_))[0]

    def stream(self) -> Callable[[ArrayLike], NDArray[np.float64]]:
        """A ``predict`` for a live stream: each call takes the next chunk of readings (n_i, N), in time order, and
        the history carries from one call to the next.

        Calling it on the chunks of a recording one after another gives what
        :meth:`predict` gives on the whole recording. Each ``stream()`` is a
        new stream, starting at rest.

        Examples
        --------
        >>> import numpy as np, ftcal
        >>> d = ftcal.simulation.make_soft_sensor_dataset()
        >>> model = ftcal.HistoryCalibrator(taus=(2.0,)).fit(d.raw, d.wrench, groups=d.group)
        >>> predict = model.stream()
        >>> parts = [predict(d.raw[:100]), predict(d.raw[100:])]
        >>> bool(np.allclose(np.vstack(parts), model.predict(d.raw)))
        True
        """
        check_is_fitted(self)
        state = [None, None]  # the moving average before the next chunk, and after the one being predicted

        def predict(chunk: ArrayLike) -> NDArray[np.float64]:
            def with_history(X: NDArray[np.float64]) -> NDArray[np.float64]:
                history, state[1] = (None, None) if self.tau_rows_ is None else _history(X, self.tau_rows_, state[0])
                return self._predict_wrench(X, history)

            wrench = self._calibrated_predict(chunk, with_history)
            state[0] = state[1]  # only a chunk that gave wrenches enters the history: a refused one leaves no trace
            return wrench

        return predict
