"""`ftcal fit` and `ftcal fit --report` judge a model on the same fold plan, so they give the same verdict; auto's
fold plan is the one FoldPlan.for_data makes, kept with the model; auto prints each candidate as it finishes."""

from __future__ import annotations

import numpy as np
import pytest

import ftcal
from ftcal.cli import main
from ftcal.model_selection import FoldPlan
from ftcal.simulation._field_sensors import make_dead_weight_dataset


@pytest.fixture(scope="module")
def one_axis_per_group(tmp_path_factory):
    """72 dead-weight rows, each group loading one axis only (as a dead-weight session records them)."""
    calibration, _ = make_dead_weight_dataset(72, loaded_axes=6, n_channels=6, random_state=0)
    path = tmp_path_factory.mktemp("data") / "dead_weight.csv"
    calibration.save(path)
    return calibration, path


def test_the_grouped_folds_cannot_judge_and_the_plan_replaces_them(one_axis_per_group):
    calibration, _ = one_axis_per_group
    plan = FoldPlan.for_data(calibration.raw, calibration.wrench, calibration.group)
    assert plan.kind == "replaced" and "cannot judge" in plan.note


def test_fit_and_fit_with_report_give_the_same_verdict(one_axis_per_group, tmp_path, capsys):
    _, path = one_axis_per_group
    plain = main(["fit", str(path), "--model", "linear", "--out", str(tmp_path / "a"), "-q"])
    reported = main(["fit", str(path), "--model", "linear", "--report", "--out", str(tmp_path / "b"), "-q"])
    assert plain == reported == 0, capsys.readouterr().err
    assert (tmp_path / "a" / "linear.model.npz").exists() and (tmp_path / "b" / "linear.model.npz").exists()


def test_auto_keeps_its_fold_plan_through_the_model_file(one_axis_per_group, tmp_path):
    calibration, _ = one_axis_per_group
    auto = ftcal.AutoCalibrator(candidates=[("linear", ftcal.LinearCalibrator()),
                                            ("quadratic", ftcal.PolynomialCalibrator(degree=2))], random_state=0)
    auto.fit(calibration.raw, calibration.wrench, groups=calibration.group)
    plan = FoldPlan.for_data(calibration.raw, calibration.wrench, calibration.group)
    assert auto.fold_plan_.same_folds(plan)  # the certificate compares its own plan with the model's
    ftcal.save_model(auto, tmp_path / "auto.model.npz")
    loaded = ftcal.load_model(tmp_path / "auto.model.npz")
    assert loaded.fold_plan_.same_folds(plan) and loaded.fold_plan_.kind == "replaced"
    assert loaded.comparison_.chosen == auto.best_name_
    assert [r.status for r in loaded.comparison_.rows] == [r.status for r in auto.comparison_.rows]
    np.testing.assert_allclose(loaded.held_out_predictions_, auto.held_out_predictions_)
    assert loaded.summary().splitlines()[0] == auto.summary().splitlines()[0]


def test_cli_auto_prints_each_candidate_as_it_finishes_and_q_keeps_quiet(one_axis_per_group, tmp_path, capsys):
    _, path = one_axis_per_group
    args = ["fit", str(path), "--model", "auto", "--jobs", "1", "--param", "baselines=false",
            "--param", "stack=false"]
    assert main(args + ["--out", str(tmp_path / "a")]) == 0
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.startswith("  linear ")]
    assert lines and "scored, RMSE" in lines[0] and lines[0].endswith(" s)")
    assert main(args + ["--out", str(tmp_path / "b"), "-q"]) == 0
    assert capsys.readouterr().err == ""


@pytest.fixture
def memorizer():
    """A costly model (unknown cost: a user's regressor) that repeats its training rows exactly: perfect on them,
    worse than the mean wrench on every held-out row of wrenches that the readings do not determine."""
    from sklearn.neighbors import KNeighborsRegressor

    from ftcal.calibrators import StockCalibrator, calibration_tags

    def factory(random_state=None, **params):
        return StockCalibrator(baseline=KNeighborsRegressor(n_neighbors=1), random_state=random_state, **params)

    assert calibration_tags(factory()).cost not in ("closed_form", "kernel")
    ftcal.register_calibrator("memorizer", factory)
    yield "memorizer"
    ftcal.compose._registry._FACTORIES.pop("memorizer")


def test_fit_judges_a_costly_model_held_out_with_or_without_the_report(memorizer, tmp_path, capsys):
    rng = np.random.default_rng(0)
    path = ftcal.CalibrationDataset(raw=rng.normal(size=(60, 6)), wrench=rng.normal(size=(60, 6))).save(
        tmp_path / "noise.csv")
    data = ftcal.CalibrationDataset.load(path)
    model = ftcal.make_calibrator(memorizer).fit(data.raw, data.wrench)
    np.testing.assert_allclose(model.predict(data.raw), data.wrench)  # looks perfect on its training rows
    errors = []
    for out, extra in (("a", []), ("b", ["--report"])):
        assert main(["fit", str(path), "--model", memorizer, "--out", str(tmp_path / out), "-q", *extra]) == 2
        errors.append(capsys.readouterr().err.strip())
        assert not (tmp_path / out).exists() or not any((tmp_path / out).iterdir())
    assert errors[0] == errors[1], errors
    assert errors[0].startswith("ftcal: error: ") and "held-out error" in errors[0] \
        and "no better than predicting the mean wrench" in errors[0], errors
    assert len(errors[0].splitlines()) == 1


_FITS = []


def _counting_regressor():
    from sklearn.linear_model import LinearRegression

    class CountingLinearRegression(LinearRegression):
        """A user's regressor of unknown cost that counts its fits (in this process: no worker processes)."""

        def fit(self, X, y, sample_weight=None):
            _FITS.append(len(X))
            return super().fit(X, y, sample_weight=sample_weight)

    return CountingLinearRegression()


def test_calibrate_with_the_certificate_fits_a_costly_model_once_per_fold_plus_once():
    """``ftcal fit --report``'s workflow: the gate judges the certificate's held-out predictions instead of
    refitting the folds again; the verdict is the same with and without the certificate."""
    from ftcal.calibrators import StockCalibrator
    from ftcal.model_selection import DegenerateCalibrationError
    from ftcal.workflow import calibrate

    rng = np.random.default_rng(1)
    wrench = rng.normal(size=(60, 6))
    good = ftcal.CalibrationDataset(raw=wrench @ rng.normal(size=(6, 6)) + 1e-3 * rng.normal(size=(60, 6)),
                                    wrench=wrench)
    noise = ftcal.CalibrationDataset(raw=rng.normal(size=(60, 6)), wrench=wrench)  # nothing to learn
    options = {"baselines": False, "figures": False}
    for data, refused in ((good, False), (noise, True)):
        outcomes = []
        for certify in (False, True):
            _FITS.clear()
            try:
                result = calibrate(data, StockCalibrator(baseline=_counting_regressor()), cv=4, certify=certify,
                                   certificate_options=options)
                outcomes.append(("saved", list(_FITS)))
                assert (result.certificate is not None) == certify
            except DegenerateCalibrationError as exc:
                outcomes.append((str(exc), list(_FITS)))
        # all 60 rows once, then once per fold of 4 (45 training rows each), with or without the certificate
        assert outcomes[0] == outcomes[1] and outcomes[0][1] == [60, 45, 45, 45, 45], outcomes
        assert (outcomes[0][0] != "saved") == refused and (not refused or "held-out" in outcomes[0][0]), outcomes
