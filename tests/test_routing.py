"""``groups`` reach every calibrator that asks for them through scikit-learn's metadata routing.

The calibrator that receives them here is a real one: a :class:`~ftcal.LinearCalibrator` subclass that fits
as usual and keeps the groups its ``fit`` was given (and is registered, so it is saved like any calibrator).
"""

from __future__ import annotations


import numpy as np
import pytest
from sklearn import config_context
from sklearn.base import clone
from sklearn.model_selection import GridSearchCV, GroupKFold, cross_validate
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import FunctionTransformer

from ftcal import (AutoCalibrator, AxisNonlinearCalibrator, CalibrationDataset, EnsembleCalibrator,
                   GaussianProcessCalibrator, LinearCalibrator, PolynomialCalibrator,
                   TemperatureCompensatedCalibrator, load_model)
from ftcal.compose import search_calibrator
from ftcal.compose._routing import requests_groups
from ftcal.compose import _registry

from conftest import affine_sensor_data


class GroupRecordingCalibrator(LinearCalibrator):
    """The LTM, keeping the ``groups`` its ``fit`` received (``None`` when none were routed to it)."""

    __metadata_request__fit = {"groups": True}
    _fitted_state = ("groups_seen_",)

    def fit(self, X, y, groups=None):
        super().fit(X, y)
        self.groups_seen_ = None if groups is None else np.asarray(groups).copy()
        return self


@pytest.fixture
def registered_recorder():
    _registry.register_calibrator("group_recorder", GroupRecordingCalibrator)
    yield "group_recorder"
    _registry._FACTORIES.pop("group_recorder")
    _registry._SCHEDULES.pop("group_recorder")


def grouped_data(n_groups=6, per_group=12, seed=0):
    raw, wrench, _, _ = affine_sensor_data(n_samples=n_groups * per_group, seed=seed)
    groups = np.repeat(np.arange(n_groups) * 10 + 3, per_group)  # labels that are not row positions
    temperature = np.random.default_rng(seed).uniform(15.0, 35.0, len(raw))
    return raw, wrench, groups, temperature


def test_wrappers_route_groups_to_their_inner_calibrator():
    raw, wrench, groups, temperature = grouped_data()
    ensemble = EnsembleCalibrator(GroupRecordingCalibrator(), n_members=2, random_state=0).fit(raw, wrench,
                                                                                             groups=groups)
    for member in ensemble.estimators_:
        np.testing.assert_array_equal(member.groups_seen_, groups)
    compensated = TemperatureCompensatedCalibrator(GroupRecordingCalibrator()).fit(
        np.column_stack([raw, temperature]), wrench, groups=groups)
    np.testing.assert_array_equal(compensated.estimator_.groups_seen_, groups)
    without = TemperatureCompensatedCalibrator(GroupRecordingCalibrator()).fit(np.column_stack([raw, temperature]),
                                                                               wrench)
    assert without.estimator_.groups_seen_ is None


def test_a_wrapper_accepts_groups_its_inner_calibrator_does_not_use():
    raw, wrench, groups, temperature = grouped_data()
    EnsembleCalibrator(LinearCalibrator(), n_members=2).fit(raw, wrench, groups=groups)  # was a TypeError
    TemperatureCompensatedCalibrator().fit(np.column_stack([raw, temperature]), wrench, groups=groups)


def test_a_calibrator_that_declines_groups_does_not_get_them():
    raw, wrench, groups, _ = grouped_data()
    with config_context(enable_metadata_routing=True):
        inner = GroupRecordingCalibrator().set_fit_request(groups=False)
        ensemble = EnsembleCalibrator(inner, n_members=1).fit(raw, wrench, groups=groups)
    assert ensemble.estimators_[0].groups_seen_ is None


def test_wrappers_route_groups_to_an_inner_auto():
    raw, wrench, groups, temperature = grouped_data()
    auto = AutoCalibrator(candidates=[("recorder", GroupRecordingCalibrator())], cv=3)
    model = TemperatureCompensatedCalibrator(auto).fit(np.column_stack([raw, temperature]), wrench, groups=groups)
    assert model.estimator_.comparison_["folds"] == "group"
    np.testing.assert_array_equal(model.estimator_.best_estimator_.groups_seen_, groups)
    ensemble = EnsembleCalibrator(auto, n_members=1).fit(raw, wrench, groups=groups)
    assert ensemble.estimators_[0].comparison_["folds"] == "group"


def test_routing_declarations():
    assert requests_groups(AxisNonlinearCalibrator()) and requests_groups(AutoCalibrator())
    assert not requests_groups(LinearCalibrator())
    assert requests_groups(TemperatureCompensatedCalibrator(AxisNonlinearCalibrator()))
    assert set(AxisNonlinearCalibrator().get_metadata_routing().fit.requests) == {"groups"}


def test_pipeline_grid_search_and_cross_validate_pass_groups_through():
    raw, wrench, groups, _ = grouped_data()
    with config_context(enable_metadata_routing=True):
        pipe = Pipeline([("identity", FunctionTransformer()),
                         ("cal", EnsembleCalibrator(GroupRecordingCalibrator(), n_members=1))])
        pipe.fit(raw, wrench, groups=groups)
        np.testing.assert_array_equal(pipe[-1].estimators_[0].groups_seen_, groups)

        search = GridSearchCV(EnsembleCalibrator(GroupRecordingCalibrator(), n_members=1), {"n_members": [1, 2]},
                              cv=GroupKFold(n_splits=3)).fit(raw, wrench, groups=groups)
        np.testing.assert_array_equal(search.best_estimator_.estimators_[0].groups_seen_, groups)

        result = cross_validate(TemperatureCompensatedCalibrator(GroupRecordingCalibrator()),
                                np.column_stack([raw, grouped_data()[3]]), wrench,
                                cv=GroupKFold(n_splits=3), params={"groups": groups}, return_estimator=True,
                                return_indices=True)
    for fitted, train in zip(result["estimator"], result["indices"]["train"]):
        np.testing.assert_array_equal(fitted.estimator_.groups_seen_, groups[train])  # each fold's own groups


def test_search_calibrator_routes_each_folds_groups(registered_recorder):
    raw, wrench, groups, _ = grouped_data()
    search = search_calibrator(registered_recorder, raw, wrench, space={"ridge": [0.0, 1e-3]}, cv=3, groups=groups)
    np.testing.assert_array_equal(search.best_estimator_.groups_seen_, groups)  # the refit on all rows
    assert search.best_estimator_.groups_seen_ is not None


def test_cli_fit_with_temperature_routes_the_dataset_groups(registered_recorder, tmp_path):
    """``ftcal fit --temperature`` gives the dataset's groups to the model inside the compensation."""
    from ftcal.cli import main

    raw, wrench, groups, temperature = grouped_data()
    path = CalibrationDataset(raw=raw, wrench=wrench, group=groups, temperature=temperature).save(
        tmp_path / "train.csv")
    assert main(["fit", str(path), "--model", registered_recorder, "--temperature", "--out", str(tmp_path / "m"),
                 "-q"]) == 0
    model = load_model(tmp_path / "m" / f"{registered_recorder}.model.npz")  # the recorder's state is saved too
    np.testing.assert_array_equal(model.estimator_.groups_seen_, groups)


def test_hybrid_inner_cv_gets_the_groups_inside_the_temperature_wrapper():
    """The hybrid's ridge chosen inside the wrapper is the one grouped folds choose, not shuffled ones.

    Each group is a cluster of loads with its own reference error: shuffled folds reward a flexible fit of those
    errors, grouped folds do not.
    """
    rng = np.random.default_rng(7)
    n_groups, per_group = 10, 12
    centers = rng.uniform(-1, 1, size=(n_groups, 6))
    w = centers.repeat(per_group, axis=0) + 0.1 * rng.normal(size=(n_groups * per_group, 6))
    raw = w @ rng.normal(size=(6, 6))
    groups = np.repeat(np.arange(n_groups), per_group)
    wrench = w + 0.1 * rng.normal(size=(n_groups, 6)).repeat(per_group, axis=0) + 0.001 * rng.normal(size=w.shape)
    X = np.column_stack([raw, rng.uniform(15.0, 35.0, len(raw))])
    wrapped = TemperatureCompensatedCalibrator(AxisNonlinearCalibrator(), alpha=1.0).fit(X, wrench, groups=groups)
    compensated = wrapped._compensate(raw, X[:, -1])
    grouped = AxisNonlinearCalibrator(alpha=1.0).fit(compensated, wrench, groups=groups).ridge_
    shuffled = AxisNonlinearCalibrator(alpha=1.0).fit(compensated, wrench).ridge_
    assert grouped != shuffled  # the data tell grouped from shuffled folds apart ...
    assert wrapped.estimator_.ridge_ == grouped  # ... and the wrapped hybrid used the groups


@pytest.mark.parametrize("calibrator", [GaussianProcessCalibrator(max_samples=50, n_restarts_optimizer=0),
                                        AxisNonlinearCalibrator(ridge=0.01), PolynomialCalibrator(degree=2),
                                        PolynomialCalibrator(degree=1, group_offsets=True)],
                         ids=["gaussian_process", "axis_fixed_ridge", "polynomial", "polynomial_group_offsets"])
@pytest.mark.parametrize("groups, message", [
    (np.arange(10), r"groups must have shape \(60,\), one label per row of X; got shape \(10,\)"),
    (np.zeros(60), r"groups holds one group only"),
    (np.full(60, np.nan), r"groups holds NaN"),
])
def test_calibrators_that_take_groups_refuse_bad_groups_before_fitting(calibrator, groups, message):
    """Groups of the wrong length are a caller's bug: refused by every calibrator that takes groups, once X and y are
    checked and before the model is fitted.
    Labels that cannot split (one group, NaN) are refused by those that use them with their parameters (the GP's
    std, the hybrid's ridge="auto", group offsets) and ignored by those that do not (a fixed ridge, no offsets)."""
    raw, w, *_ = affine_sensor_data(n_samples=60)
    uses = not (isinstance(calibrator, PolynomialCalibrator) and not calibrator.group_offsets
                or isinstance(calibrator, AxisNonlinearCalibrator) and calibrator.ridge != "auto")
    if uses or len(groups) != 60:
        with pytest.raises(ValueError, match=message):
            calibrator.fit(raw, w, groups=groups)
        assert not {"coef_", "dual_coef_"} & set(vars(calibrator))  # the model itself was not fitted
    else:
        fitted = clone(calibrator).fit(raw, w, groups=groups)
        np.testing.assert_array_equal(fitted.predict(raw), clone(calibrator).fit(raw, w).predict(raw))


# ------------------------------------------------------------------ one routed fit: auto and every meta-estimator
class FitCountingRecorder(GroupRecordingCalibrator):
    """The recorder, also counting the fits that received groups (in this process: auto's light work)."""

    fits_with_groups = 0
    fits = 0

    def fit(self, X, y, groups=None):
        type(self).fits += 1
        type(self).fits_with_groups += groups is not None
        return super().fit(X, y, groups=groups)


class OtherCountingRecorder(FitCountingRecorder):
    """The same, counted apart."""

    fits_with_groups = 0
    fits = 0


@pytest.fixture
def counting():
    for cls in (FitCountingRecorder, OtherCountingRecorder):
        cls.fits = cls.fits_with_groups = 0
    yield FitCountingRecorder


def _declining():
    with config_context(enable_metadata_routing=True):
        return FitCountingRecorder().set_fit_request(groups=False)


def test_auto_routes_groups_to_a_candidate_that_requests_them(counting):
    raw, wrench, groups, _ = grouped_data()
    auto = AutoCalibrator(candidates=[("recorder", FitCountingRecorder())], baselines=False, stack=False, cv=3)
    auto.fit(raw, wrench, groups=groups)
    assert counting.fits == 4 and counting.fits_with_groups == 4  # 3 folds and the refit
    np.testing.assert_array_equal(auto.best_estimator_.groups_seen_, groups)


def test_a_candidate_that_declines_groups_never_sees_them_through_auto(counting):
    raw, wrench, groups, _ = grouped_data()
    auto = AutoCalibrator(candidates=[("declining", _declining())], baselines=False, stack=False, cv=3)
    auto.fit(raw, wrench, groups=groups)
    assert counting.fits == 4 and counting.fits_with_groups == 0
    assert auto.comparison_["folds"] == "group"  # auto itself still holds out whole groups


@pytest.mark.parametrize("how", ["pipeline", "grid_search", "cross_validate"])
def test_a_declining_candidate_never_sees_groups_through_auto_in_scikit_learn(how, counting):
    raw, wrench, groups, _ = grouped_data()
    with config_context(enable_metadata_routing=True):
        auto = AutoCalibrator(candidates=[("declining", FitCountingRecorder().set_fit_request(groups=False)),
                                          ("recorder", OtherCountingRecorder())], baselines=False, stack=False, cv=3)
        if how == "pipeline":
            Pipeline([("scale", FunctionTransformer()), ("auto", auto)]).fit(raw, wrench, groups=groups)
        elif how == "grid_search":
            GridSearchCV(auto, {"cv": [3]}, cv=GroupKFold(2)).fit(raw, wrench, groups=groups)
        else:
            cross_validate(auto, raw, wrench, cv=GroupKFold(2), params={"groups": groups})
    # every fit of the recorder got groups, none of the declining one's
    assert counting.fits >= 3 and counting.fits_with_groups == 0
    assert OtherCountingRecorder.fits >= 3 and OtherCountingRecorder.fits_with_groups == OtherCountingRecorder.fits


def test_auto_declares_its_candidates_in_its_routing():
    auto = AutoCalibrator(candidates=[("declining", _declining()), ("recorder", GroupRecordingCalibrator())],
                          baselines=False)
    routing = auto.get_metadata_routing()
    assert {"declining", "recorder"} <= {name for name, _ in routing}
    with config_context(enable_metadata_routing=True):
        routed = routing.route_params(params={"groups": np.arange(4)}, caller="fit")
    assert "groups" not in routed["declining"].fit and "groups" in routed["recorder"].fit


def test_a_stack_routes_groups_to_its_members_and_takes_fitted_ones_explicitly(counting):
    from ftcal.compose._auto import StackedCalibrator

    raw, wrench, groups, _ = grouped_data()
    stack = StackedCalibrator(estimators=[FitCountingRecorder(), _declining()], weights=[0.5, 0.5])
    stack.fit(raw, wrench, groups=groups)
    assert counting.fits == 2 and counting.fits_with_groups == 1
    fitted = [LinearCalibrator().fit(raw, wrench), LinearCalibrator().fit(raw, 2 * wrench)]
    stack = StackedCalibrator(estimators=[LinearCalibrator(), LinearCalibrator()], weights=[0.5, 0.5])
    stack.fit(raw, wrench, fitted_estimators=fitted)
    assert stack.estimators_[1] is fitted[1]
    np.testing.assert_allclose(stack.predict(raw[:3]), 1.5 * wrench[:3], atol=1e-8)
    assert not any(name.startswith("_fit") for name in vars(stack))  # no hidden fit state


def test_history_routes_groups_to_its_estimator(counting):
    from ftcal import HistoryCalibrator

    raw, wrench, groups, _ = grouped_data()
    HistoryCalibrator(FitCountingRecorder(), taus=(2.0,), cv=3).fit(raw, wrench, groups=groups)
    assert counting.fits > 0 and counting.fits_with_groups == counting.fits
    counting.fits = counting.fits_with_groups = 0
    HistoryCalibrator(_declining(), taus=(2.0,), cv=3).fit(raw, wrench, groups=groups)
    assert counting.fits > 0 and counting.fits_with_groups == 0


# ------------------------------------------------------------------------------------------ sample weights


def _weighted_least_squares(X, y, w):
    """``[C.T; b]`` minimising ``sum_i w_i ||y_i - C x_i - b||²``: the weighted normal equations."""
    A = np.hstack([X, np.ones((len(X), 1))])
    return np.linalg.solve(A.T @ (w[:, None] * A), A.T @ (w[:, None] * y))


def _noisy(seed=0, n=80):
    rng = np.random.default_rng(seed)
    raw = rng.normal(size=(n, 6))
    wrench = raw @ rng.normal(size=(6, 6)) + 0.5 * rng.normal(size=(n, 6))  # noise: weights move the fit
    return raw, wrench, rng.uniform(0.0, 3.0, n)


def test_linear_calibrator_with_weights_is_weighted_least_squares():
    raw, wrench, w = _noisy()
    model = LinearCalibrator().fit(raw, wrench, sample_weight=w)
    expected = _weighted_least_squares(raw, wrench, w)
    np.testing.assert_allclose(model.calibration_matrix_, expected[:6].T, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(model.offset_, expected[6], rtol=1e-9, atol=1e-12)
    unweighted = LinearCalibrator().fit(raw, wrench)
    assert np.abs(unweighted.calibration_matrix_ - model.calibration_matrix_).max() > 1e-3  # the weights count
    np.testing.assert_allclose(LinearCalibrator().fit(raw, wrench, sample_weight=np.full(len(raw), 3.0))
                               .calibration_matrix_, unweighted.calibration_matrix_, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("group_offsets", [False, True])
@pytest.mark.parametrize("ridge", [0.0, 1e-3])
def test_polynomial_weights_count_as_repeated_rows(ridge, group_offsets):
    """An integer weight k is the row given k times (the penalty scales with the total weight, as with rows)."""
    raw, wrench, _ = _noisy(seed=1, n=60)
    groups = np.repeat(np.arange(6), 10)
    k = np.r_[np.full(30, 2), np.ones(30, dtype=int), ][np.random.default_rng(2).permutation(60)]
    k[:3] = 0  # zero weight: the row does not count
    make = lambda: PolynomialCalibrator(degree=2, ridge=ridge, group_offsets=group_offsets,  # noqa: E731
                                        zero_reading=np.zeros(6))
    weighted = make().fit(raw, wrench, groups=groups, sample_weight=k.astype(float))
    repeated = make().fit(np.repeat(raw, k, axis=0), np.repeat(wrench, k, axis=0), groups=np.repeat(groups, k))
    np.testing.assert_allclose(weighted.coef_, repeated.coef_, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(weighted.intercept_, repeated.intercept_, rtol=1e-8, atol=1e-10)
    assert np.abs(make().fit(raw, wrench, groups=groups).coef_ - weighted.coef_).max() > 1e-4


def test_wrappers_route_weights_to_their_inner_calibrator():
    raw, wrench, w = _noisy(seed=3)
    direct = LinearCalibrator().fit(raw, wrench, sample_weight=w)
    ensemble = EnsembleCalibrator(LinearCalibrator(), n_members=2, random_state=0).fit(raw, wrench, sample_weight=w)
    for member in ensemble.estimators_:
        np.testing.assert_allclose(member.calibration_matrix_, direct.calibration_matrix_, rtol=1e-12)
    temperature = np.random.default_rng(3).uniform(15.0, 35.0, len(raw))
    X = np.column_stack([raw, temperature])
    compensated = TemperatureCompensatedCalibrator().fit(X, wrench, sample_weight=w)
    inner_X = compensated._compensate(raw, temperature)
    expected = _weighted_least_squares(inner_X, wrench, w)
    np.testing.assert_allclose(compensated.estimator_.calibration_matrix_, expected[:6].T, rtol=1e-8, atol=1e-10)


@pytest.mark.parametrize("wrapper", [
    lambda inner: EnsembleCalibrator(inner, n_members=2, random_state=0),
    lambda inner: TemperatureCompensatedCalibrator(inner),
], ids=["ensemble", "temperature"])
def test_a_wrapper_refuses_weights_its_inner_calibrator_cannot_take(wrapper):
    raw, wrench, w = _noisy(seed=4)
    X = np.column_stack([raw, np.linspace(15.0, 35.0, len(raw))])
    with pytest.raises(ValueError, match="was given sample_weight but AxisNonlinearCalibrator does not take sample "
                                         "weights"):
        wrapper(AxisNonlinearCalibrator()).fit(X, wrench, sample_weight=w)
    with config_context(enable_metadata_routing=True):
        declined = LinearCalibrator().set_fit_request(sample_weight=False)
    with pytest.raises(ValueError, match="but LinearCalibrator does not take sample weights"):
        wrapper(declined).fit(X, wrench, sample_weight=w)
    with pytest.raises(TypeError, match="sample_weight"):  # a calibrator without weights: Python's own error
        AxisNonlinearCalibrator().fit(raw, wrench, sample_weight=w)


@pytest.mark.parametrize("bad, words", [
    (lambda n: np.ones(n - 1), "must have shape"), (lambda n: -np.ones(n), "finite and >= 0"),
    (lambda n: np.r_[np.nan, np.ones(n - 1)], "finite and >= 0"), (lambda n: np.zeros(n), "zero for every row"),
])
def test_bad_weights_get_a_clear_error_before_fitting(bad, words):
    raw, wrench, _ = _noisy(seed=5)
    model = LinearCalibrator()
    with pytest.raises(ValueError, match=words):
        model.fit(raw, wrench, sample_weight=bad(len(raw)))
    assert not hasattr(model, "calibration_matrix_")


def test_pipeline_and_cross_validate_route_weights_to_the_calibrator():
    raw, wrench, w = _noisy(seed=6)
    with config_context(enable_metadata_routing=True):
        pipe = Pipeline([("id", FunctionTransformer()), ("cal", LinearCalibrator())])
        pipe.fit(raw, wrench, sample_weight=w)
    np.testing.assert_allclose(pipe[-1].calibration_matrix_,
                               LinearCalibrator().fit(raw, wrench, sample_weight=w).calibration_matrix_, rtol=1e-12)


# ------------------------------------------------------------------------------------------ users' regressors


def test_a_users_regressor_is_a_member_composed_with_tare_torque_scale_and_range():
    """Any scikit-learn regressor is a member or an inner model: composed into a calibrator (alpha_, the zero-load
    reading, the calibrated range, re-tare) around its own predict."""
    from sklearn.linear_model import Ridge

    raw, wrench, w = _noisy(seed=7)
    ridge = Ridge(alpha=2.0).fit(raw, wrench)
    ensemble = EnsembleCalibrator(Ridge(alpha=2.0), n_members=2, random_state=0).fit(raw, wrench)
    np.testing.assert_allclose(ensemble.predict(raw), ridge.predict(raw), rtol=1e-12, atol=1e-12)
    assert ensemble.alpha_ > 0 and ensemble.calibrated_range_.shape == (2, 6)
    assert ensemble.out_of_range(10 * raw[:1]).tolist() == [True]
    shifted = ensemble.retare(np.tile(ensemble.zero_reading_ + 0.5, (3, 1))).predict(raw + 0.5)
    np.testing.assert_allclose(shifted, ridge.predict(raw), rtol=1e-9, atol=1e-9)  # the re-tare around it

    temperature = np.random.default_rng(7).uniform(15.0, 35.0, len(raw))
    compensated = TemperatureCompensatedCalibrator(Ridge(alpha=2.0)).fit(np.column_stack([raw, temperature]),
                                                                        wrench)
    inner = Ridge(alpha=2.0).fit(compensated._compensate(raw, temperature), wrench)
    np.testing.assert_allclose(compensated.estimator_.predict(raw), inner.predict(raw), rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match="'estimator' parameter of EnsembleCalibrator must be an object "
                                         "implementing 'fit' and 'predict'"):
        EnsembleCalibrator("ridge").fit(raw, wrench)
