"""scikit-learn compatibility: estimator checks, Pipeline, cross_validate, GridSearchCV, clone, pickle."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.model_selection import GridSearchCV, KFold, cross_validate
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils.estimator_checks import parametrize_with_checks

from ftcal import CalibrationInputError, neg_scaled_rmse

from conftest import TINY_SCHEDULE, affine_sensor_data, tiny_calibrators

# The calibrators take a wrench y of shape (n, 6) and a sensor with >= 3 channels; asking for anything
# else is a user error that must raise (issue 2, "Bad input"). These generic checks fit on y of shape
# (n,) / (n, 1) / (n, 5) or on X with 2 features, so they fail by design. The same properties are
# tested below on wrench-shaped data (clone, pickle, idempotent fit, dtypes, subset invariance, ...).
_Y_SHAPE = "fits on a y of shape (n,), (n, 1) or (n, 5); calibrators require the (n, 6) wrench"
_TWO_FEATURES = "fits on X with 2 features; calibrators require >= 3 raw channels"
_EXPECTED_FAILURES = {
    **dict.fromkeys(
        [
            "check_fit_score_takes_y", "check_dont_overwrite_parameters", "check_n_features_in_after_fitting",
            "check_positive_only_tag_during_fit", "check_estimators_dtypes", "check_dtype_object",
            "check_pipeline_consistency", "check_estimators_nan_inf", "check_estimators_pickle",
            "check_f_contiguous_array_estimator", "check_regressors_train", "check_regressor_data_not_an_array",
            "check_regressor_multioutput", "check_regressors_no_decision_function", "check_regressors_int",
            "check_methods_sample_order_invariance", "check_methods_subset_invariance", "check_dict_unchanged",
            "check_fit2d_predict1d", "check_array_api_input",
        ],
        _Y_SHAPE,
    ),
    **dict.fromkeys(
        [
            "check_readonly_memmap_input", "check_n_features_in", "check_fit_idempotent",
            "check_fit_check_is_fitted", "check_estimators_overwrite_params", "check_estimators_fit_returns_self",
        ],
        _TWO_FEATURES,
    ),
}


@parametrize_with_checks(tiny_calibrators(), expected_failed_checks=lambda est: _EXPECTED_FAILURES, xfail_strict=True)
def test_sklearn_estimator_checks(estimator, check):
    try:
        check(estimator)
    except CalibrationInputError as exc:
        # Our deliberate input errors (the expected failures above): re-raised from here so that pytest
        # does not re-parse the 5000-line estimator_checks.py for every traceback (~0.3 s each).
        raise CalibrationInputError(str(exc)) from None


@pytest.fixture
def data():
    raw, wrench, _, _ = affine_sensor_data(n_samples=60, seed=41)
    return raw, wrench


def test_inside_a_pipeline(tiny_calibrator, data):
    raw, wrench = data
    pipe = make_pipeline(StandardScaler(), tiny_calibrator).fit(raw, wrench)
    assert pipe.predict(raw).shape == (60, 6)
    assert np.isfinite(pipe.score(raw, wrench))


def test_cross_validate_with_the_thesis_metric(tiny_calibrator, data):
    result = cross_validate(tiny_calibrator, *data, cv=KFold(3), scoring={"rmse": neg_scaled_rmse, "r2": "r2"})
    assert result["test_rmse"].shape == (3,) and np.all(result["test_rmse"] <= 0)
    assert np.all(np.isfinite(result["test_r2"]))


def _small_grid(estimator) -> dict:
    params = estimator.get_params()
    if "ridge" in params:
        return {"ridge": [0.0, 1e3]}
    if "hidden_layer_sizes" in params:
        return {"hidden_layer_sizes": [(4,), (8,)]}
    if "max_samples" in params:  # the Gaussian process
        return {"max_samples": [20, 40]}
    if "time_budget" in params:  # auto
        return {"cv": [2, 3]}
    return {"estimator__hidden_layer_sizes": [(4,), (8,)]}  # an ensemble of networks


def test_grid_search(tiny_calibrator, data):
    grid = _small_grid(tiny_calibrator)
    search = GridSearchCV(tiny_calibrator, grid, cv=KFold(2), scoring=neg_scaled_rmse).fit(*data)
    assert search.best_params_.keys() == grid.keys()
    assert search.best_estimator_.predict(data[0]).shape == (60, 6)
    if "ridge" in grid:  # noise-free affine data: no penalty is best
        assert search.best_params_ == {"ridge": 0.0}


def test_clone_and_pickle_round_trip(tiny_calibrator, data):
    raw, wrench = data
    unfitted = clone(tiny_calibrator)
    assert unfitted.get_params().keys() == tiny_calibrator.get_params().keys()
    assert not hasattr(unfitted, "n_features_in_")
    fitted = tiny_calibrator.fit(raw, wrench)
    restored = pickle.loads(pickle.dumps(fitted))
    np.testing.assert_array_equal(restored.predict(raw), fitted.predict(raw))


def test_fit_returns_self_keeps_params_and_is_idempotent(tiny_calibrator, data):
    raw, wrench = data
    params = pickle.dumps(tiny_calibrator.get_params())
    assert tiny_calibrator.fit(raw, wrench) is tiny_calibrator
    assert pickle.dumps(tiny_calibrator.get_params()) == params
    first = tiny_calibrator.predict(raw)
    np.testing.assert_allclose(tiny_calibrator.fit(raw, wrench).predict(raw), first, rtol=1e-6, atol=1e-6)
    assert tiny_calibrator.n_features_in_ == 6


def test_dtypes_lists_and_readonly_inputs(tiny_calibrator, data):
    raw, wrench = data
    reference = clone(tiny_calibrator).fit(raw, wrench).predict(raw)
    readonly = raw.copy()
    readonly.setflags(write=False)
    for x in (raw.astype(np.float32).astype(np.float64), raw.tolist(), readonly, np.asfortranarray(raw)):
        out = clone(tiny_calibrator).fit(x, wrench.tolist()).predict(x)
        assert out.dtype == np.float64
        np.testing.assert_allclose(out, reference, rtol=1e-5, atol=1e-5)
    ints = np.round(raw * 100).astype(np.int64)
    assert clone(tiny_calibrator).fit(ints, wrench).predict(ints).shape == (60, 6)


def test_predictions_do_not_depend_on_batch_composition(tiny_calibrator, data):
    raw, wrench = data
    model = tiny_calibrator.fit(raw, wrench)
    whole = model.predict(raw)
    order = np.random.default_rng(0).permutation(60)
    np.testing.assert_allclose(model.predict(raw[order]), whole[order], rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(np.vstack([model.predict(raw[i : i + 1]) for i in range(5)]), whole[:5],
                               rtol=1e-5, atol=1e-5)


def test_score_is_r2(data):
    raw, wrench = data
    from ftcal import LinearCalibrator

    assert LinearCalibrator().fit(raw, wrench).score(raw, wrench) == pytest.approx(1.0)
    assert TINY_SCHEDULE["max_epochs"] < 10  # the networks in these tests really are tiny
