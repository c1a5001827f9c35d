"""ftcal's GP against the stock scikit-learn GP: parity when set to the stock structure, and the choice of mean,
kernel, bounds and start by held-out error (closed-form leave-one-out / leave-one-group-out), not by likelihood."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from sklearn.model_selection import GroupKFold, KFold, cross_val_predict

from ftcal import GaussianProcessCalibrator
from ftcal.core import wrench_rmse
from ftcal.calibrators._gaussian_process import _left_out, _mean_basis, _regressor, make_kernel
from ftcal.core._wrench import scale_torques
from ftcal.calibrators import stock_baselines


def correlated_sensor(n_rows: int, n_channels: int, seed: int, torque_in_nmm: bool):
    """Readings of ``n_channels`` correlated channels (shared load components, scales 1e-4..1e4, offsets) that
    respond smoothly nonlinearly to a 6-axis load; the wrench in N and N·m or N·mm."""
    rng = np.random.default_rng(seed)
    load = rng.uniform(-1, 1, size=(n_rows, 6))
    mixing = rng.normal(size=(6, n_channels)) + 2.0 * rng.normal(size=(1, n_channels))  # a common component
    response = np.tanh(load @ mixing / 3.0) + 0.01 * rng.normal(size=(n_rows, n_channels))
    scales = np.logspace(-4, 4, n_channels)[rng.permutation(n_channels)]
    raw = response * scales + rng.normal(size=n_channels) * scales
    wrench = load * [10, 10, 30, 0.2, 0.2, 0.1] + 0.05 * rng.normal(size=(n_rows, 6)) * [10, 10, 30, 0.2, 0.2, 0.1]
    if torque_in_nmm:
        wrench[:, 3:] *= 1000.0
    return raw, wrench


@pytest.mark.parametrize("n_rows, n_channels, torque_in_nmm", [(20, 3, True), (300, 8, False), (1000, 2, True)])
def test_set_to_the_stock_structure_it_predicts_as_the_stock_gp(n_rows, n_channels, torque_in_nmm):
    raw, wrench = correlated_sensor(n_rows, n_channels, seed=n_rows, torque_in_nmm=torque_in_nmm)
    ours = GaussianProcessCalibrator(mean="none", kernel="rbf", per_output=False, kernel_bounds="stock",
                                     max_samples=1000, random_state=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # convergence warnings of both (the stock GP's bounds are reached)
        ours.fit(raw, wrench)
        stock = stock_baselines(n_channels, max_kernel_samples=None)["sk_gp"].fit(raw, wrench)
    rng = np.random.default_rng(1)
    new = raw[rng.choice(n_rows, size=min(n_rows, 50), replace=False)] * (1 + 0.01 * rng.normal(size=(1, n_channels)))
    for X in (raw, new):
        difference = np.abs(ours.predict(X) - stock.predict(X))
        # optimiser tolerance: both run the same L-BFGS on inputs equal up to rounding
        assert np.all(difference <= 1e-5 * wrench.std(axis=0) + 1e-9), difference.max(axis=0)
    gp = stock.estimator_[-1]
    np.testing.assert_allclose(ours.theta_[0], gp.kernel_.theta, atol=1e-4)


@pytest.mark.parametrize("family", ["rbf", "matern52", "rbf+linear", "matern52+linear"])
@pytest.mark.parametrize("n_rows, n_channels, n_outputs", [(60, 1, 1), (100, 8, 6), (80, 3, 2)])
def test_the_likelihood_gradient_from_matrix_products_is_scikit_learns(family, n_rows, n_channels, n_outputs):
    """ftcal's regressor computes eq. 5.9 without scikit-learn's kernel-gradient tensor: the same value and gradient
    (to rounding), and a kernel of another form takes scikit-learn's own path."""
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, WhiteKernel

    rng = np.random.default_rng(n_rows)
    X = rng.normal(size=(n_rows, n_channels))
    y = np.tanh(X).sum(axis=1, keepdims=True) * rng.normal(size=(1, n_outputs)) + 0.1 * rng.normal(
        size=(n_rows, n_outputs))
    for bounds in ("ftcal", "stock"):
        kernel = make_kernel(family, n_channels, bounds)
        ours = _regressor(kernel, 0, optimizer=None).fit(X, y)
        theirs = GaussianProcessRegressor(kernel, normalize_y=True, optimizer=None).fit(X, y)
        for theta in rng.uniform(np.log(1e-2), np.log(1e2), size=(4, kernel.n_dims)):
            value, gradient = ours.log_marginal_likelihood(theta, eval_gradient=True)
            expected, expected_gradient = theirs.log_marginal_likelihood(theta, eval_gradient=True)
            np.testing.assert_allclose(value, expected, rtol=1e-9)
            np.testing.assert_allclose(gradient, expected_gradient, rtol=1e-7,
                                       atol=1e-9 * np.abs(expected_gradient).max())
    # clusters of near-duplicate rows, short length scales, almost no noise: terms that nearly cancel
    clustered = np.repeat(X[:10], 6, axis=0) + 1e-4 * rng.normal(size=(60, n_channels))
    target = np.tanh(clustered).sum(axis=1, keepdims=True) + 0.01 * rng.normal(size=(60, 1))
    kernel = make_kernel(family, n_channels)
    theta = kernel.theta.copy()
    theta[1:1 + n_channels], theta[-1] = np.log(1e-2), np.log(1e-8)
    ours = _regressor(kernel, 0, optimizer=None).fit(clustered, target)
    theirs = GaussianProcessRegressor(kernel, normalize_y=True, optimizer=None).fit(clustered, target)
    expected_gradient = theirs.log_marginal_likelihood(theta, eval_gradient=True)[1]
    np.testing.assert_allclose(ours.log_marginal_likelihood(theta, eval_gradient=True)[1], expected_gradient,
                               rtol=1e-6, atol=1e-8 * np.abs(expected_gradient).max())
    other = RBF(np.ones(n_channels)) + WhiteKernel()  # not make_kernel's form: scikit-learn computes it
    ours = _regressor(other, 0, optimizer=None).fit(X, y)
    theirs = GaussianProcessRegressor(other, normalize_y=True, optimizer=None).fit(X, y)
    np.testing.assert_array_equal(ours.log_marginal_likelihood(other.theta, eval_gradient=True)[1],
                                  theirs.log_marginal_likelihood(other.theta, eval_gradient=True)[1])


def test_left_out_errors_are_those_of_refits_without_the_rows():
    """Eq. 5.12 with the constant mean refitted: the closed form equals refitting (hyperparameters fixed) without
    each row, and without each group."""
    raw, wrench = correlated_sensor(40, 3, seed=5, torque_in_nmm=False)
    u = (raw - raw.mean(axis=0)) / raw.std(axis=0)
    gp = _regressor(make_kernel("rbf", 3), 0).fit(u, wrench)
    y = (wrench - gp._y_train_mean) / gp._y_train_std
    K = gp.kernel_(u)
    groups = np.repeat(np.arange(8), 5)
    for g in (None, groups):
        errors, _ = _left_out(gp, np.ones((40, 1)), g)
        for left in ([3], [17]) if g is None else (np.flatnonzero(groups == 2), np.flatnonzero(groups == 6)):
            rest = np.setdiff1d(np.arange(40), left)
            K_inv = np.linalg.inv(K[np.ix_(rest, rest)])
            ones = np.ones(len(rest))
            beta = (ones @ K_inv @ y[rest]) / (ones @ K_inv @ ones)  # the constant mean refitted (GLS)
            prediction = beta + K[np.ix_(left, rest)] @ K_inv @ (y[rest] - beta)
            np.testing.assert_allclose(errors[left], (y[left] - prediction) * gp._y_train_std, rtol=1e-6, atol=1e-9)


def refit_errors(K, basis, y, left):
    """``y[left]`` less the prediction of a GP (covariance ``K``, hyperparameters fixed) refitted without the
    rows ``left``: the mean's coefficients by generalised least squares (QR of the whitened basis), then the
    posterior mean of what it leaves."""
    from scipy.linalg import cho_factor, cho_solve, solve_triangular

    rest = np.setdiff1d(np.arange(len(y)), left)
    L = np.linalg.cholesky(K[np.ix_(rest, rest)])
    Q, R = np.linalg.qr(solve_triangular(L, basis[rest], lower=True))
    beta = np.linalg.solve(R, Q.T @ solve_triangular(L, y[rest], lower=True))
    weights = cho_solve(cho_factor(K[np.ix_(rest, rest)], lower=True), y[rest] - basis[rest] @ beta)
    return y[left] - (basis[left] @ beta + K[np.ix_(left, rest)] @ weights)


@pytest.mark.parametrize("mean", ["none", "linear"])
@pytest.mark.parametrize("grouped", [False, True])
def test_left_out_errors_of_each_mean_are_those_of_refits_on_channels_of_scales_1e_4_to_1e4(mean, grouped):
    """The fitted GP's closed-form held-out errors, its mean's coefficients refitted too, equal refits without
    each row (each group), with the wrench predicted from the raw channels' span, on channels of scales
    1e-4..1e4 (raw channels in the mean's basis made its normal matrix singular to rounding: errors off by
    several N)."""
    raw, wrench = correlated_sensor(60, 4, seed=11, torque_in_nmm=False)
    groups = np.repeat(np.arange(12), 5) if grouped else None
    model = GaussianProcessCalibrator(mean=mean, kernel="rbf", per_output=False, kernel_bounds="ftcal",
                                      random_state=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(raw, wrench, groups=groups)
    assert model.mean_ == mean and model.train_inputs_.shape == (60, 4)
    gp = model.regressors()[0]
    K = gp.kernel_(model.train_inputs_)
    # the brute-force refits take the mean's basis from the raw (tare-corrected) channels, each centred and
    # scaled over the rows it is fitted on: the span of the constant and the raw channels
    xc = raw - model.zero_reading_
    raw_basis = np.hstack([np.ones((60, 1)), (xc - xc.mean(axis=0)) / xc.std(axis=0)]) if mean == "linear" \
        else np.ones((60, 1))
    y = scale_torques(wrench, model.alpha_)  # the GP's target plus the linear mean (which the refit re-estimates)
    folds = [[i] for i in range(60)] if groups is None else [np.flatnonzero(groups == g) for g in range(12)]
    expected = np.empty_like(y)
    for left in folds:
        expected[left] = refit_errors(K, raw_basis, y, left)
    errors, _ = _left_out(gp, _mean_basis(mean, model.train_inputs_), groups)
    # conditioning: K's noise term (>= 1e-8 of its scale) and the whitened basis amplify rounding ~1e8-fold
    np.testing.assert_allclose(errors, expected, rtol=1e-6, atol=1e-6 * np.abs(expected).max())
    rmse = float(np.sqrt(np.mean(expected**2)))
    assert model.held_out_rmse_["final"] == pytest.approx(rmse, rel=1e-6)


def test_the_choice_is_the_combination_of_least_held_out_error_and_beats_the_stock_gp_within_noise():
    raw, wrench = correlated_sensor(150, 4, seed=3, torque_in_nmm=True)
    model = GaussianProcessCalibrator(selection_samples=100, random_state=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(raw, wrench)
    tried = {k: v for k, v in model.held_out_rmse_.items() if k.count("/") == 2}
    assert len(tried) == 8 and {k.split("/")[2] for k in tried} == {"ftcal", "stock"}
    assert f"{model.mean_}/{model.kernel_}/{model.kernel_bounds_}" == min(tried, key=tried.get)
    assert model.structure_params()["kernel_bounds"] == model.kernel_bounds_
    folds = KFold(3, shuffle=True, random_state=0)
    alpha = model.alpha_
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ours = cross_val_predict(GaussianProcessCalibrator(selection_samples=100, random_state=0), raw, wrench,
                                 cv=folds)
        stock = cross_val_predict(stock_baselines(4)["sk_gp"], raw, wrench, cv=folds)
    ours_rmse, stock_rmse = wrench_rmse(wrench, ours, alpha), wrench_rmse(wrench, stock, alpha)
    # within noise: the standard error of an RMSE over 150 x 6 values is ~1/sqrt(2 * 900) of it (~2.4 %)
    assert ours_rmse <= stock_rmse * 1.05, (ours_rmse, stock_rmse)


def test_groups_given_to_fit_choose_by_leave_one_group_out():
    raw, wrench = correlated_sensor(90, 3, seed=8, torque_in_nmm=False)
    groups = np.repeat(np.arange(9), 10)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plain = GaussianProcessCalibrator(mean="none", kernel="rbf", per_output=False, random_state=0).fit(
            raw, wrench)
        grouped = GaussianProcessCalibrator(mean="none", kernel="rbf", per_output=False, random_state=0).fit(
            raw, wrench, groups=groups)
    assert plain.held_out_rmse_.keys() == grouped.held_out_rmse_.keys()
    assert grouped.held_out_rmse_ != plain.held_out_rmse_  # a group left out is not a row left out
    folds = list(GroupKFold(3).split(raw, wrench, groups))
    assert np.isfinite(cross_val_predict(grouped, raw, wrench, cv=folds)).all()
