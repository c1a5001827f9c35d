"""The calibration report's held-out figures come from ftcal's one fold plan (:class:`FoldPlan`) and one held-out
engine (``held_out_predictions``), and it takes ``auto``'s own comparison and out-of-fold predictions only when
``auto`` was scored on the very same plan (same folds, same rows)."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.linear_model import LinearRegression

from ftcal import AutoCalibrator, CalibrationDataset, LinearCalibrator, calibration_certificate
from ftcal.model_selection import FoldPlan
from ftcal.model_selection._selection import calibration_folds, held_out_predictions


def _sensor(seed: int = 0, n_groups: int = 8, per_group: int = 10) -> CalibrationDataset:
    rng = np.random.default_rng(seed)
    wrench = rng.uniform(-1, 1, size=(n_groups * per_group, 6)) * [200, 200, 400, 3, 3, 3]
    raw = wrench @ (rng.normal(size=(6, 6)) / [200, 200, 400, 3, 3, 3]).T + 0.3
    raw += 0.002 * rng.normal(size=raw.shape)
    return CalibrationDataset(raw=raw, wrench=wrench, group=np.repeat(np.arange(n_groups), per_group))


def test_the_reports_held_out_predictions_are_the_engines_on_the_one_fold_plan():
    data = _sensor()
    model = LinearCalibrator().fit(data.raw, data.wrench)
    cert = calibration_certificate(model, data, cv=4, baselines=False, figures=False, random_state=3)
    plan = FoldPlan.for_data(data.raw, data.wrench, data.group, cv=4, seed=3)
    assert cert.validation["plan"] == plan.to_dict()
    folds = list(plan.folds)
    _, expected = held_out_predictions(LinearCalibrator(), data.raw, data.wrench, groups=data.group, folds=folds)
    np.testing.assert_array_equal(cert.held_out_predictions, expected)
    # and that is each group predicted by a calibration fitted without it (an independent fold loop)
    for train, test in folds:
        assert not np.isin(data.group[test], data.group[train]).any()
        reference = LinearCalibrator().fit(data.raw[train], data.wrench[train])
        np.testing.assert_allclose(expected[test], reference.predict(data.raw[test]), rtol=1e-12, atol=1e-12)


def test_the_engine_caps_training_rows_and_predicts_in_blocks_without_changing_a_prediction():
    rng = np.random.default_rng(1)
    X = rng.normal(size=(90, 3))
    y = X @ rng.normal(size=(3, 2)) + 0.1 * rng.normal(size=(90, 2))
    folds = calibration_folds(90, None, 3, 0)
    _, capped = held_out_predictions(LinearRegression(), X, y, folds=folds, max_train_rows=20, random_state=5,
                                     chunk_rows=7)
    for train, test in folds:  # each fold fitted on 20 of its rows, drawn with the seed
        rows = np.sort(np.random.default_rng(5).choice(train, size=20, replace=False))
        np.testing.assert_allclose(capped[test], LinearRegression().fit(X[rows], y[rows]).predict(X[test]),
                                   rtol=1e-12, atol=1e-12)
    _, full = held_out_predictions(LinearRegression(), X, y, folds=folds)
    assert not np.allclose(full, capped)  # the cap is real: 20 rows fit another map than 60


def test_the_engine_gives_the_std_only_when_every_folds_model_has_one():
    from ftcal import GaussianProcessCalibrator
    from ftcal.compose._auto import provides_std

    data = _sensor(n_groups=5, per_group=8)
    folds = calibration_folds(40, data.group, 3, 0)
    _, _, std = held_out_predictions(GaussianProcessCalibrator(random_state=0), data.raw, data.wrench,
                                     groups=data.group, folds=folds, has_std=provides_std)
    assert std.shape == data.wrench.shape and np.all(std > 0)
    _, _, none = held_out_predictions(LinearCalibrator(), data.raw, data.wrench, folds=folds, has_std=provides_std)
    assert none is None


class _CountingLinear(LinearCalibrator):
    """The LTM, counting its fits in a class attribute (the report runs in this process)."""

    fits = 0

    def fit(self, X, y):
        type(self).fits += 1
        return super().fit(X, y)


def test_the_report_of_auto_reuses_its_comparison_on_the_same_plan_and_not_on_rows_grouped_otherwise():
    from ftcal import PolynomialCalibrator

    data = _sensor(seed=2)
    auto = AutoCalibrator(candidates=[("counted", _CountingLinear()), ("quadratic", PolynomialCalibrator(degree=2))],
                          cv=4, stack=False, n_jobs=1).fit(data.raw, data.wrench, groups=data.group)
    assert auto.best_name_ == "counted"  # an affine sensor: the LTM, the simplest within noise
    _CountingLinear.fits = 0
    cert = calibration_certificate(auto, data, cv=4, figures=False)
    assert cert.validation["reused_auto_comparison"] is True and cert.validation["reused_auto_predictions"] is True
    assert _CountingLinear.fits == 0  # no fold refitted, no stock model scored again
    np.testing.assert_array_equal(cert.held_out_predictions, auto.held_out_predictions_)
    rows = cert.comparison["rows"]
    assert rows[0]["rmse"] == pytest.approx(auto.comparison_.row("counted").rmse, rel=1e-12)
    stock = [r.name for r in auto.comparison_.rows if r.kind in ("stock", "baseline")]
    assert [r["model"] for r in rows[1:]] == stock and stock
    assert cert.comparison["paired_se"] >= 0 and cert.comparison["best_stock"] in stock
    # the same rows in other groups make other folds: nothing is reused
    regrouped = CalibrationDataset(raw=data.raw, wrench=data.wrench, group=np.repeat(np.arange(10), 8))
    other = calibration_certificate(auto, regrouped, cv=4, figures=False, baselines=False)
    assert other.validation["reused_auto_predictions"] is False and _CountingLinear.fits > 0


def test_a_loaded_auto_gives_the_same_held_out_figures_as_the_fitted_one(tmp_path):
    from ftcal import PolynomialCalibrator, load_model, save_model

    data = _sensor(seed=5)
    auto = AutoCalibrator(candidates=[("linear", LinearCalibrator()), ("quadratic", PolynomialCalibrator(degree=2))],
                          cv=4, n_jobs=1).fit(data.raw, data.wrench, groups=data.group)
    save_model(auto, tmp_path / "auto.model.npz")
    loaded = load_model(tmp_path / "auto.model.npz")
    fitted_cert, loaded_cert = (calibration_certificate(m, data, cv=4, figures=False) for m in (auto, loaded))
    assert loaded_cert.validation["reused_auto_predictions"] is True
    np.testing.assert_array_equal(loaded_cert.held_out_predictions, fitted_cert.held_out_predictions)
    # the file keeps the stock rows' figures, not their errors per row: the loaded one scores them again, alike
    assert loaded_cert.validation["reused_auto_comparison"] is False
    fitted_rows, loaded_rows = fitted_cert.comparison["rows"], loaded_cert.comparison["rows"]
    assert [r["model"] for r in fitted_rows] == [r["model"] for r in loaded_rows]
    for a, b in zip(fitted_rows, loaded_rows):
        if a["rmse"] is not None and b["rmse"] is not None:
            assert a["rmse"] == pytest.approx(b["rmse"], rel=1e-6)
