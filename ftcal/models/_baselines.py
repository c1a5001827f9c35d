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
"""

from __future__ import annotations

from numbers import Integral
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, clone
from sklearn.utils._param_validation import Interval
from sklearn.utils.validation import check_is_fitted, validate_data

from ..core._validation import check_arguments

__all__ = ["STOCK_BASELINE_NAMES", "stock_baselines", "SubsampledRegressor", "KERNEL_SAMPLES"]

#: Rows the stock kernel baselines are fitted on at most by default: ``GaussianProcessCalibrator``'s
#: ``max_samples`` (a test checks they agree), the one budget of every comparison (auto, ``ftcal benchmark``,
#: the report, the artificial benchmark).
KERNEL_SAMPLES = 1000

#: Names of :func:`stock_baselines`' models, in order of complexity.
STOCK_BASELINE_NAMES: tuple[str, ...] = ("sk_linear", "sk_poly2", "sk_poly3", "sk_kernel_ridge", "sk_gp")


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
