"""``neg_scaled_rmse`` finds the fitted calibrator's torque scale through pipelines and searches, or refuses."""

import numpy as np
import pytest
from sklearn.linear_model import LinearRegression
from sklearn.model_selection import GridSearchCV, KFold, cross_validate
from sklearn.pipeline import Pipeline, make_pipeline
from sklearn.preprocessing import StandardScaler

from ftcal.core import CalibrationInputError, wrench_rmse
from ftcal import LinearCalibrator, PolynomialCalibrator, neg_scaled_rmse

ALPHA = 40.0  # 1/m: a torque error of 1 N·m counts as 40 N


@pytest.fixture
def data():
    rng = np.random.default_rng(3)
    wrench = rng.uniform(-1, 1, size=(90, 6)) * [20, 20, 40, 0.5, 0.5, 0.25]
    raw = wrench @ rng.normal(size=(6, 6)) + 0.05 * rng.normal(size=(90, 6))
    return raw, wrench


def test_a_pipeline_is_scored_with_its_final_calibrators_alpha(data):
    raw, wrench = data
    pipe = make_pipeline(StandardScaler(), LinearCalibrator(alpha=ALPHA)).fit(raw, wrench)
    shifted = wrench + [0, 0, 0, 0, 0, 0.1]  # a torque error only
    pred = pipe.predict(raw)
    assert neg_scaled_rmse(pipe, raw, shifted) == pytest.approx(-wrench_rmse(shifted, pred, ALPHA))
    assert neg_scaled_rmse(pipe, raw, shifted) < -wrench_rmse(shifted, pred, 1.0) * 10  # alpha = 1 would be 40x smaller


def test_nested_pipelines_and_a_fitted_search_are_looked_through(data):
    raw, wrench = data
    inner = Pipeline([("scale", StandardScaler()), ("calibrator", LinearCalibrator(alpha=ALPHA))])
    outer = Pipeline([("identity", "passthrough"), ("inner", inner)]).fit(raw, wrench)
    search = GridSearchCV(outer, {"inner__calibrator__ridge": [0.0, 1.0]}, cv=KFold(3),
                          scoring=neg_scaled_rmse).fit(raw, wrench)
    expected = -wrench_rmse(wrench, outer.predict(raw), ALPHA)
    assert neg_scaled_rmse(outer, raw, wrench) == pytest.approx(expected)
    assert neg_scaled_rmse(search, raw, wrench) == pytest.approx(
        -wrench_rmse(wrench, search.predict(raw), ALPHA))


def test_grid_search_over_a_pipeline_scores_each_fold_with_the_fitted_alpha(data):
    """The README's pattern: GridSearchCV(Pipeline([..., calibrator]), scoring=neg_scaled_rmse); alpha derived
    from each fold's y (alpha=None) is the one used, fold by fold."""
    raw, wrench = data
    pipe = Pipeline([("scale", StandardScaler()), ("calibrator", PolynomialCalibrator(degree=1))])
    folds = KFold(3, shuffle=True, random_state=0)
    search = GridSearchCV(pipe, {"calibrator__ridge": [0.0, 10.0]}, scoring=neg_scaled_rmse, cv=folds,
                          error_score="raise").fit(raw, wrench)
    scores = search.cv_results_["mean_test_score"]
    for i, ridge in enumerate([0.0, 10.0]):
        per_fold = []
        for train, test in folds.split(raw):
            fitted = pipe.set_params(calibrator__ridge=ridge).fit(raw[train], wrench[train])
            alpha = fitted[-1].alpha_
            assert alpha != 1.0
            per_fold.append(-wrench_rmse(wrench[test], fitted.predict(raw[test]), alpha))
        assert scores[i] == pytest.approx(np.mean(per_fold), rel=1e-9)


@pytest.mark.parametrize("make", [
    lambda: LinearRegression(),
    lambda: make_pipeline(StandardScaler(), LinearRegression()),
])
def test_an_estimator_without_a_calibrator_is_refused_not_scored_with_alpha_one(make, data):
    raw, wrench = data
    model = make().fit(raw, wrench)
    with pytest.raises(CalibrationInputError, match=r"LinearRegression has none.*make_scorer\(ftcal.core.wrench_rmse"):
        neg_scaled_rmse(model, raw, wrench)
    with pytest.raises(CalibrationInputError, match="alpha_"):
        cross_validate(make(), raw, wrench, cv=KFold(2), scoring=neg_scaled_rmse, error_score="raise")
