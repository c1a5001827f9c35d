"""The stock scikit-learn models a user would try first: the baselines every ftcal table shows.

They are **baselines to beat, not ftcal's models**: ten lines of scikit-learn each, built exactly as a
user would write them, so that every results table states ftcal's margin over what is free.

==================  =====================================================================================
name                model
==================  =====================================================================================
``sk_linear``       ``LinearRegression()`` (ordinary least squares with an intercept)
``sk_poly2``        ``StandardScaler() + PolynomialFeatures(2) + RidgeCV(alphas=logspace(-6, 3, 10))``
``sk_poly3``        the same with degree 3
``sk_kernel_ridge`` ``StandardScaler() + KernelRidge(kernel="rbf")``, ``alpha`` and ``gamma`` tuned by
                    3-fold ``GridSearchCV``
``sk_gp``           ``StandardScaler() + GaussianProcessRegressor(ConstantKernel() * RBF(ones(n)) +
                    WhiteKernel(), normalize_y=True)``
==================  =====================================================================================

The kernel models cost O(n^2) memory and O(n^3) time, so on large data they are fitted on a random
subset of ``max_kernel_samples`` rows (:class:`SubsampledRegressor`), as a user would have to; the
subset is part of the baseline and is reported with it.

:class:`StockCalibrator` makes each of them a calibrator: :class:`~ftcal.AutoCalibrator` can then choose
one (never losing to what is free by construction), and a model file stores it as the arrays its
prediction needs (no pickle, bounded by the kernel models' subsample).
"""

from __future__ import annotations

from collections.abc import Callable
from math import comb
from numbers import Integral, Real
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, clone
from sklearn.utils._param_validation import Interval
from sklearn.utils.validation import check_is_fitted, has_fit_parameter, validate_data

from ._base import BaseCalibrator, calibration_tags, declare
from ..core._exceptions import CalibrationInputError, ModelFileError
from ..core._memory import check_allocation
from ..core._validation import check_arguments
from ..core._wrench import scale_torques, unscale_torques

__all__ = ["STOCK_BASELINE_NAMES", "stock_baselines", "SubsampledRegressor", "KERNEL_SAMPLES", "StockCalibrator",
           "as_calibrator"]

#: Rows the stock kernel baselines are fitted on at most by default: ``GaussianProcessCalibrator``'s
#: ``max_samples`` (a test checks they agree), the one budget of every comparison (auto, ``ftcal benchmark``,
#: the report, the artificial benchmark).
KERNEL_SAMPLES = 1000

#: Names of :func:`stock_baselines`' models, in order of complexity.
STOCK_BASELINE_NAMES: tuple[str, ...] = ("sk_linear", "sk_poly2", "sk_poly3", "sk_kernel_ridge", "sk_gp")

#: Bytes of the widest temporary of :meth:`StockCalibrator.predict` per block of rows (the polynomial powers, the
#: kernel matrix): prediction runs in row blocks of this size, so its memory does not grow with the rows beyond
#: the input and the output.
PREDICT_BLOCK_BYTES = 8 * 2**20


class SubsampledRegressor(RegressorMixin, BaseEstimator):
    """Fit ``estimator`` on at most ``max_samples`` rows drawn at random (without replacement).

    Parameters
    ----------
    estimator : regressor
        Cloned at fit.
    max_samples : int or None, default=1000
        Rows used for the fit; ``None`` uses every row.
    random_state : int, default=0
        Seed of the subset.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn.linear_model import LinearRegression
    >>> X = np.arange(20.0).reshape(10, 2); y = X @ [1.0, 2.0]
    >>> SubsampledRegressor(LinearRegression(), max_samples=5).fit(X, y).predict(X[:1])
    array([2.])
    """

    def __init__(self, estimator: Any, *, max_samples: int | None = KERNEL_SAMPLES, random_state: int = 0):
        self.estimator = estimator
        self.max_samples = max_samples
        self.random_state = random_state

    def fit(self, X, y):
        X, y = validate_data(self, X, y, multi_output=True, y_numeric=True)
        n = X.shape[0]
        rows = np.arange(n)
        if self.max_samples is not None and n > self.max_samples:
            rng = np.random.default_rng(self.random_state)
            rows = np.sort(rng.choice(n, size=int(self.max_samples), replace=False))
        self.n_fit_samples_ = rows.size
        self.sample_rows_ = rows
        self.estimator_ = clone(self.estimator).fit(X[rows], y[rows])
        return self

    def predict(self, X):
        check_is_fitted(self)
        X = validate_data(self, X, reset=False)
        return self.estimator_.predict(X)


def stock_baselines(n_channels: int, *, max_kernel_samples: int | None = KERNEL_SAMPLES,
                    random_state: int = 0) -> dict[str, Any]:
    """The stock scikit-learn baselines for readings with ``n_channels`` columns, by name.

    Parameters
    ----------
    n_channels : int
        Number of raw channels, >= 1 (the stock GP's RBF has one length scale per channel).
    max_kernel_samples : int or None, default=1000
        Rows the kernel models (``sk_kernel_ridge``, ``sk_gp``) are fitted on at most (>= 1; ``None``: all);
        the default is :data:`KERNEL_SAMPLES`, the rows ftcal's own GP is fitted on, so every table compares
        kernel models on the same budget.
    random_state : int, default=0
        Seed (>= 0) of the kernel models' subsets and of the GP optimizer's restarts.

    Raises
    ------
    CalibrationInputError
        An argument of another type or out of its range, named with its value.

    Returns
    -------
    dict
        Name -> unfitted scikit-learn regressor, in the order of :data:`STOCK_BASELINE_NAMES`.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.normal(size=(60, 3)); y = np.c_[X @ [1.0, 2, 3], X[:, 0] ** 2]
    >>> models = stock_baselines(3)
    >>> list(models)
    ['sk_linear', 'sk_poly2', 'sk_poly3', 'sk_kernel_ridge', 'sk_gp']
    >>> float(np.abs(models["sk_poly2"].fit(X, y).predict(X) - y).max()) < 1e-2
    True
    """
    check_arguments("stock_baselines", {
        "n_channels": [Interval(Integral, 1, None, closed="left")],
        "max_kernel_samples": [Interval(Integral, 1, None, closed="left"), None],
        "random_state": [Interval(Integral, 0, None, closed="left")],
    }, n_channels=n_channels, max_kernel_samples=max_kernel_samples, random_state=random_state)
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel
    from sklearn.kernel_ridge import KernelRidge
    from sklearn.linear_model import LinearRegression, RidgeCV
    from sklearn.model_selection import GridSearchCV
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import PolynomialFeatures, StandardScaler

    def poly(degree: int):
        return make_pipeline(StandardScaler(), PolynomialFeatures(degree), RidgeCV(alphas=np.logspace(-6, 3, 10)))

    def subsampled(estimator):
        return SubsampledRegressor(estimator, max_samples=max_kernel_samples, random_state=random_state)

    kernel_ridge = make_pipeline(StandardScaler(), GridSearchCV(
        KernelRidge(kernel="rbf"),
        {"alpha": np.logspace(-6, 0, 7), "gamma": np.logspace(-2, 1, 7) / n_channels}, cv=3))
    gp = make_pipeline(StandardScaler(), GaussianProcessRegressor(
        ConstantKernel() * RBF(np.ones(n_channels)) + WhiteKernel(), normalize_y=True,
        random_state=random_state))
    return {
        "sk_linear": LinearRegression(),
        "sk_poly2": poly(2),
        "sk_poly3": poly(3),
        "sk_kernel_ridge": subsampled(kernel_ridge),
        "sk_gp": subsampled(gp),
    }


#: What each stock baseline is, for ``auto``'s complexity order and its scheduling: the ftcal family it is as
#: flexible as, its cost, and the fewest training rows that judge it (as for that family).
_STOCK_KINDS: dict[str, tuple[str, str, Callable[[int], int]]] = {
    "sk_linear": ("linear", "closed_form", lambda n_channels: n_channels + 2),
    "sk_poly2": ("polynomial2", "closed_form", lambda n_channels: comb(n_channels + 2, 2)),
    "sk_poly3": ("polynomial3", "closed_form", lambda n_channels: comb(n_channels + 3, 3)),
    "sk_kernel_ridge": ("kernel", "kernel", lambda n_channels: 10 * n_channels),
    "sk_gp": ("kernel", "kernel", lambda n_channels: 10 * n_channels),
}


class StockCalibrator(BaseCalibrator):
    """A stock scikit-learn baseline (:func:`stock_baselines`) as a calibrator that ``auto`` may choose and a model
    file may hold.

    ``fit`` fits exactly the baseline of that name (the same pipeline every ftcal table shows beside its models),
    then keeps only the arrays its prediction needs: the input scaling, the polynomial exponents and the linear
    map, or the kernel model's training inputs (at most ``max_kernel_samples``), dual coefficients and kernel
    parameters. ``predict`` computes the same numbers from those arrays (to rounding), in row blocks of bounded
    memory (:data:`PREDICT_BLOCK_BYTES`), so a model file stores
    them without pickling scikit-learn objects, and its size is bounded by the kernel subsample.

    A regressor of the user's (any scikit-learn regressor) may be given instead of a name: it is fitted on the
    torque-scaled wrench (torques times ``alpha_``, so its loss weighs forces and torques as ftcal's models do;
    not when its tags declare ``scales_torques``) and its predictions are scaled back; ``sample_weight`` reaches
    its ``fit``. A model file cannot hold it (save the named baselines only). What it declares of its cost,
    family and fewest training rows (:func:`~ftcal.calibrators._base.declare`) is the calibrator's too.

    Parameters
    ----------
    baseline : str or regressor, default="sk_linear"
        One of :data:`STOCK_BASELINE_NAMES`, or a scikit-learn regressor (cloned at fit).
    max_kernel_samples : int or None, default=1000
        Rows the kernel baselines are fitted on at most (:data:`KERNEL_SAMPLES`).
    alpha, zero_reading, random_state
        As for every calibrator (the stock fit ignores ``alpha``: it is a baseline, fitted as a user would;
        ``random_state`` seeds the kernel subsample and the GP's optimiser, ``None`` = 0).

    Attributes
    ----------
    input_mean_, input_scale_ : ndarray of shape (N,)
        The standard scaling of the readings (the LTM: 0 and 1).
    powers_ : ndarray of shape (n_features, N) or None
        Exponents of the polynomial features (polynomial baselines).
    coef_ : ndarray of shape (k, n_features) or None
    intercept_ : ndarray of shape (k,) or None
    train_inputs_ : ndarray of shape (m, N) or None
        Scaled training inputs of a kernel baseline.
    dual_coef_ : ndarray of shape (m, k) or None
    length_scale_ : ndarray of shape (N,) or None
        RBF length scales in scaled units (kernel ridge: one, ``1 / sqrt(2 gamma)``, for every channel).
    amplitude_ : float or None
    target_mean_, target_scale_ : ndarray of shape (k,) or None
        The GP's target normalisation (kernel ridge: 0 and 1).
    estimator_ : regressor or None
        A user's regressor, fitted (not saved).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(80, 6)); raw = w @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(80, 6))
    >>> model = StockCalibrator(baseline="sk_poly2").fit(raw, w)
    >>> stock = stock_baselines(6)["sk_poly2"].fit(raw, w)
    >>> bool(np.allclose(model.predict(raw[:5]), stock.predict(raw[:5]), atol=1e-9))
    True
    """

    _fitted_state = ("input_mean_", "input_scale_", "powers_", "coef_", "intercept_", "train_inputs_", "dual_coef_",
                     "length_scale_", "amplitude_", "target_mean_", "target_scale_",
                     "estimator_")  # (a user's regressor: declared so that saving it is refused, never dropped)
    _positive = [Interval(Real, 0, None, closed="neither")]
    #: a scale, a length scale or an amplitude of 0 (or below) divides by zero or flips the kernel; a monomial's
    #: power is a whole number of at most 3 (sk_poly3)
    _fitted_constraints: dict = {"input_scale_": _positive, "length_scale_": _positive, "amplitude_": _positive,
                                 "target_scale_": _positive, "powers_": [Interval(Integral, 0, 3, closed="both")]}
    # a model file stores no None: what a baseline that does not use them leaves
    powers_ = coef_ = intercept_ = train_inputs_ = dual_coef_ = length_scale_ = amplitude_ = None
    target_mean_ = target_scale_ = estimator_ = None
    _transient_params = ()
    _parameter_constraints: dict = {
        **BaseCalibrator._parameter_constraints,
        "baseline": "no_validation",
        "max_kernel_samples": [Interval(Integral, 1, None, closed="left"), None],
    }

    def __init__(self, *, baseline="sk_linear", max_kernel_samples=KERNEL_SAMPLES, alpha=None, zero_reading=None,
                 random_state=None):
        self.baseline = baseline
        self.max_kernel_samples = max_kernel_samples
        super().__init__(alpha=alpha, zero_reading=zero_reading, random_state=random_state)

    #: Takes ``sample_weight`` (for a regressor of the user's, handed to its ``fit`` as calling it directly would)
    #: and asks for it through metadata routing, so that a wrapper or ``auto`` given weights passes them on.
    __metadata_request__fit = {"sample_weight": True}

    def fit(self, X, y, sample_weight=None):
        """Fit the baseline on raw readings ``X`` (n, N) and wrenches ``y`` (n, k).

        Parameters
        ----------
        sample_weight : array-like of shape (n,) or None
            Weight of each row, given to a user's regressor's ``fit`` (one that takes ``sample_weight``); the
            named stock baselines are fitted unweighted and refuse weights.

        Returns
        -------
        self
        """
        return self._checked_fit(X, y, sample_weight=sample_weight)

    def _check_params(self) -> None:
        baseline = self.baseline
        if not (baseline in _STOCK_KINDS if isinstance(baseline, str) else
                hasattr(baseline, "fit") and hasattr(baseline, "predict")):
            raise CalibrationInputError(
                f"baseline must be one of {', '.join(STOCK_BASELINE_NAMES)} or a scikit-learn regressor (with fit "
                f"and predict); got {baseline!r:.80}.")

    def family(self) -> str:
        """The ftcal family this baseline is as flexible as (``"linear"``, ``"polynomial2"``, ``"polynomial3"``,
        ``"kernel"``), or ``"custom"`` for a user's regressor."""
        return _STOCK_KINDS[self.baseline][0] if isinstance(self.baseline, str) and self.baseline in _STOCK_KINDS \
            else "custom"

    def __sklearn_tags__(self):
        family = self.family()
        if family == "custom":  # a user's regressor: no graph, no model file; its declared cost and kind
            own = calibration_tags(self.baseline)
            return declare(super().__sklearn_tags__(), onnx=False, cost=own.cost, family=own.family,
                           min_training_rows=own.min_training_rows)
        _, cost, rows = _STOCK_KINDS[self.baseline]
        return declare(super().__sklearn_tags__(), cost=cost, family=family, min_training_rows=rows,
                       stock_baseline=True)

    def _fit(self, X, y, sample_weight=None) -> None:
        for name in self._fitted_state[2:]:
            self.__dict__.pop(name, None)
        self.input_mean_, self.input_scale_ = np.zeros(X.shape[1]), np.ones(X.shape[1])
        seed = 0 if self.random_state is None else int(self.random_state)
        if not isinstance(self.baseline, str):
            weighted = {} if sample_weight is None else {"sample_weight": sample_weight}
            if weighted and not has_fit_parameter(self.baseline, "sample_weight"):
                raise CalibrationInputError(
                    f"sample_weight was given but {type(self.baseline).__name__}.fit takes no sample_weight; use a "
                    "regressor that weighs its rows (e.g. Ridge) or fit without sample_weight.")
            if not calibration_tags(self.baseline).scales_torques:  # fitted on the torque-scaled wrench (eq. 6)
                y = scale_torques(y, self.alpha_, getattr(self, "axes_", None))
            self.estimator_ = clone(self.baseline).fit(X, y, **weighted)
            return
        if sample_weight is not None:
            raise CalibrationInputError(
                f"sample_weight was given but the stock baseline {self.baseline!r} is fitted unweighted (as the "
                "tables show it); fit it without sample_weight, or weigh the rows with LinearCalibrator, "
                "PolynomialCalibrator or a regressor of your own (StockCalibrator(baseline=Ridge())).")
        if _STOCK_KINDS[self.baseline][1] == "kernel":  # the kernel matrix and the GP's gradient, before fitting
            m = len(X) if self.max_kernel_samples is None else min(len(X), int(self.max_kernel_samples))
            check_allocation(8.0 * m * m * (X.shape[1] + 4), f"the stock {self.baseline}'s kernel and its "
                             f"gradient ({m} rows, {X.shape[1]} channels)", "lower max_kernel_samples (default "
                             f"{KERNEL_SAMPLES})")
        model = stock_baselines(X.shape[1], max_kernel_samples=self.max_kernel_samples,
                                random_state=seed)[self.baseline].fit(X, y)
        if self.baseline == "sk_linear":
            self.coef_, self.intercept_ = np.atleast_2d(model.coef_), np.atleast_1d(model.intercept_)
            return
        if isinstance(model, SubsampledRegressor):
            model = model.estimator_
        scaler, last = model.steps[0][1], model.steps[-1][1]
        self.input_mean_, self.input_scale_ = np.asarray(scaler.mean_), np.asarray(scaler.scale_)
        if self.baseline in ("sk_poly2", "sk_poly3"):
            self.powers_ = np.asarray(model.steps[1][1].powers_, dtype=np.int64)
            self.coef_, self.intercept_ = np.atleast_2d(last.coef_), np.atleast_1d(last.intercept_)
        elif self.baseline == "sk_kernel_ridge":
            best = last.best_estimator_
            self.train_inputs_ = np.asarray(best.X_fit_)
            self.dual_coef_ = np.asarray(best.dual_coef_).reshape(len(self.train_inputs_), -1)
            self.length_scale_ = np.full(X.shape[1], 1.0 / np.sqrt(2.0 * float(best.gamma)))
            self.amplitude_ = 1.0
            self.target_mean_, self.target_scale_ = np.zeros(y.shape[1]), np.ones(y.shape[1])
        else:  # sk_gp: ConstantKernel * RBF + WhiteKernel (no white noise between distinct points), normalize_y
            kernel = last.kernel_
            self.train_inputs_ = np.asarray(last.X_train_)
            self.dual_coef_ = np.asarray(last.alpha_).reshape(len(self.train_inputs_), -1)
            self.length_scale_ = np.broadcast_to(np.asarray(kernel.k1.k2.length_scale, dtype=float),
                                                 (X.shape[1],)).copy()
            self.amplitude_ = float(kernel.k1.k1.constant_value)
            # normalize_y's own mean and scale of the subsample's targets (a scale of 0 made 1)
            self.target_mean_, self.target_scale_ = np.asarray(last._y_train_mean), np.asarray(last._y_train_std)

    def _predict_wrench(self, X):
        if self.estimator_ is not None:
            out = np.asarray(self.estimator_.predict(X), dtype=float).reshape(len(X), -1)
            return out if calibration_tags(self.baseline).scales_torques else \
                unscale_torques(out, self.alpha_, getattr(self, "axes_", None))
        if self.coef_ is None and self.train_inputs_ is None:
            raise CalibrationInputError(
                "this StockCalibrator wrapped a regressor of the user's, which a model file cannot hold; refit it, "
                "or save one of the named stock baselines.")
        self._check_arrays()
        # row blocks whose widest temporary (the n x features monomials, the kernel's n x m matrix) stays within
        # PREDICT_BLOCK_BYTES, whatever the number of rows
        width = len(self.train_inputs_) if self.train_inputs_ is not None else \
            X.shape[1] if self.powers_ is None else len(self.powers_)
        rows = max(1, PREDICT_BLOCK_BYTES // (8 * width))
        out = np.empty((len(X), len(self.intercept_ if self.train_inputs_ is None else self.target_mean_)))
        for start in range(0, len(X), rows):
            out[start:start + rows] = self._predict_block(X[start:start + rows])
        return out

    def _check_arrays(self) -> None:
        """The stored arrays are those of ``baseline`` (a model file may have been edited): else ModelFileError."""
        family = self.family()
        polynomial = self.powers_ is not None and self.coef_ is not None and self.train_inputs_ is None
        wanted = (family == "kernel" and self.train_inputs_ is not None) or (
            family.startswith("polynomial") and polynomial and int(np.max(self.powers_)) <= int(family[-1])) or (
            family == "linear" and self.powers_ is None and self.train_inputs_ is None)
        if not wanted:
            raise ModelFileError(f"the arrays of this StockCalibrator are not those of baseline={self.baseline!r} "
                                 "(one of " + ", ".join(STOCK_BASELINE_NAMES) + "); the model file is damaged or "
                                 "was edited: fit and save the model again.")

    def _emit_onnx(self, g, x: str) -> str:
        """The same prediction as ONNX: the scaled readings' least-squares map, monomials (as
        :class:`~ftcal.PolynomialCalibrator`'s graph) or RBF kernel sum (as the GP's)."""
        self._check_arrays()
        z = g.op("Div", g.op("Sub", x, g.const(self.input_mean_)), g.const(self.input_scale_))
        if self.train_inputs_ is None:
            from ._polynomial import onnx_monomials

            return g.affine(z if self.powers_ is None else onnx_monomials(g, z, self.powers_), self.coef_.T,
                            self.intercept_)
        from ._gaussian_process import onnx_kernel

        kernel = onnx_kernel(g, z, self.train_inputs_, self.length_scale_, self.amplitude_)
        return g.op("Add", g.op("Mul", g.op("MatMul", kernel, g.const(self.dual_coef_)), g.const(self.target_scale_)),
                    g.const(self.target_mean_))

    def _predict_block(self, X):
        """The wrench of a block of rows, from the stored arrays (see :meth:`_predict_wrench`)."""
        z = (X - self.input_mean_) / self.input_scale_
        if self.train_inputs_ is None:
            if self.powers_ is None:
                return z @ self.coef_.T + self.intercept_
            # the monomials channel by channel: z_c ** p_c picked from the channel's powers 0..degree
            by_power = z[:, :, None] ** np.arange(int(self.powers_.max()) + 1)
            features = by_power[:, 0, self.powers_[:, 0]]
            for channel in range(1, z.shape[1]):
                features *= by_power[:, channel, self.powers_[:, channel]]
            return features @ self.coef_.T + self.intercept_
        from sklearn.gaussian_process.kernels import RBF

        kernel = RBF(self.length_scale_)(z, self.train_inputs_)  # exp(-d² / 2), d the distance in length scales
        return self.amplitude_ * (kernel @ self.dual_coef_) * self.target_scale_ + self.target_mean_


def as_calibrator(estimator) -> BaseCalibrator:
    """``estimator`` itself when it is a calibrator, else a user's regressor composed into one: a
    :class:`StockCalibrator` around it, which adds what every calibrator has around its model (the torque scale
    ``alpha_``, the zero-load reading and its re-tare, the calibrated range, the checks of ``predict``: the one
    composition of :meth:`~ftcal.calibrators._base.BaseCalibrator._record_calibration`), and keeps the cost and
    family the regressor declares in its tags.

    What a wrapper (:class:`~ftcal.EnsembleCalibrator`, :class:`~ftcal.TemperatureCompensatedCalibrator`) calls
    on its ``estimator``, so that any scikit-learn regressor can be a member.

    Examples
    --------
    >>> from sklearn.linear_model import Ridge
    >>> type(as_calibrator(Ridge())).__name__, as_calibrator(Ridge()).baseline
    ('StockCalibrator', Ridge())
    >>> from ftcal import LinearCalibrator
    >>> model = LinearCalibrator(); as_calibrator(model) is model
    True
    """
    return estimator if isinstance(estimator, BaseCalibrator) else StockCalibrator(baseline=estimator)

