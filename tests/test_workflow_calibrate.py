"""The library workflow `calibrate`: what `ftcal fit` does, as one public call."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal import CalibrationDataset, LinearCalibrator, PolynomialCalibrator
from ftcal.model_selection import Comparison, DegenerateCalibrationError, FoldPlan
from ftcal.simulation._field_sensors import make_dead_weight_dataset
from ftcal.workflow import Calibration, calibrate


def data(n=120, seed=0, groups=True):
    rng = np.random.default_rng(seed)
    w = rng.uniform(-1, 1, size=(n, 6))
    raw = w @ rng.normal(size=(6, 6)) + 0.05 * (w @ rng.normal(size=(6, 6))) ** 2 + 0.01 * rng.normal(size=(n, 6))
    return CalibrationDataset(raw=raw, wrench=w, group=np.repeat(np.arange(6), n // 6) if groups else None)


def test_auto_returns_the_model_its_comparison_and_the_plan_it_chose_on():
    d = data()
    result = calibrate(d, "auto", candidates=[("linear", LinearCalibrator()),
                                              ("quadratic", PolynomialCalibrator(degree=2))], baselines=False)
    assert isinstance(result, Calibration) and isinstance(result.summary, Comparison)
    assert result.summary.chosen == result.model.best_name_
    assert result.plan is result.model.fold_plan_ and result.plan.kind == "group"
    assert result.plan.same_folds(FoldPlan.for_data(d.raw, d.wrench, d.group))


def test_an_estimator_is_fitted_in_place_and_judged_on_the_one_plan():
    model = LinearCalibrator()
    result = calibrate(data(groups=False), model)
    assert result.model is model and model.n_features_in_ == 6 and result.summary is None
    with pytest.raises(TypeError, match="for a model given by name"):
        calibrate(data(), LinearCalibrator(), ridge=1.0)


def test_the_gate_is_the_one_fold_plan_s():
    # one group per loaded axis: grouped folds cannot judge; the plan replaces them and the LTM passes
    calibration, _ = make_dead_weight_dataset(72, loaded_axes=6, n_channels=6, random_state=0)
    result = calibrate(calibration, "linear")
    assert result.plan.kind == "replaced"
    rng = np.random.default_rng(1)  # readings that say nothing of the wrench: refused
    noise = CalibrationDataset(raw=rng.normal(size=(60, 6)), wrench=rng.normal(size=(60, 6)))
    with pytest.raises(DegenerateCalibrationError, match="no better than predicting the mean"):
        calibrate(noise, "linear")


def test_auto_choosing_on_a_subsample_returns_a_plan_of_every_row_of_the_dataset():
    # auto's own plan indexes its choice's subsample; the plan the workflow returns must index the dataset
    d = data(n=300)
    result = calibrate(d, "auto", candidates=[("linear", LinearCalibrator())], baselines=False, stack=False,
                       choice_samples=120)
    assert result.model.fold_plan_.n_rows == 120 and result.plan.n_rows == 300
    assert result.plan.same_folds(FoldPlan.for_data(d.raw, d.wrench, d.group))
    every = np.sort(np.concatenate([test for _, test in result.plan.folds]))
    assert np.array_equal(every, np.arange(300))


def test_a_wrapper_around_auto_says_it_chooses_its_model_as_auto_does():
    # the held-out check before saving trusts a model that judged itself on held-out folds (auto) instead of
    # refitting it on every fold; a wrapper around auto (history, temperature, ensemble) is such a model too
    from ftcal import AutoCalibrator, HistoryCalibrator
    from ftcal.calibrators import calibration_tags

    assert calibration_tags(HistoryCalibrator(AutoCalibrator())).chooses_model
    assert not calibration_tags(HistoryCalibrator(LinearCalibrator())).chooses_model
