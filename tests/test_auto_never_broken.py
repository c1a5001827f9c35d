"""auto never ships a broken calibration and never loses to what is free: the stock models are candidates, folds
that cannot judge are replaced, degenerate predictions are refused, and the table says why the winner won."""

from __future__ import annotations

import numpy as np
import pytest

import ftcal
from ftcal import AutoCalibrator, LinearCalibrator, PolynomialCalibrator
from ftcal.core import CalibrationInputError
from ftcal.model_selection._selection import (DegenerateCalibrationError, calibration_folds, check_not_degenerate,
                                         degenerate_reason, simplest_within_one_se, unseen_outputs)
from ftcal.compose._auto import with_stock_candidates
from ftcal.calibrators._baselines import StockCalibrator
from ftcal.simulation._field_sensors import make_dead_weight_dataset


def validation_rmse(model, validation, alpha):
    return ftcal.core.wrench_rmse(validation.wrench, model.predict(validation.raw), alpha=alpha)


# ------------------------------------------------------------------ one group per loaded axis, 15 rows
@pytest.mark.parametrize("axes, channels", [(3, 3), (6, 6)])
def test_one_group_per_loaded_axis_gives_a_model_as_good_as_the_ltm_at_twice_the_range(axes, channels):
    calibration, validation = make_dead_weight_dataset(15, loaded_axes=axes, n_channels=channels, random_state=0)
    assert np.unique(calibration.group).size == axes
    alpha = calibration.meta["alpha"]
    auto = AutoCalibrator(random_state=0).fit(calibration.raw, calibration.wrench, groups=calibration.group)
    # the grouped folds leave each loaded axis unseen in training: said, and replaced by folds over the rows
    assert auto.comparison_["folds"].startswith("replaced") and "cannot judge" in auto.comparison_["folds"]
    assert auto.fold_plan_.kind == "replaced" and auto.fold_plan_.units_name == "fold"
    ltm = LinearCalibrator().fit(calibration.raw, calibration.wrench)
    assert validation_rmse(auto, validation, alpha) <= 1.1 * validation_rmse(ltm, validation, alpha)
    predictions = auto.predict(validation.raw)
    assert np.ptp(predictions[:, :axes], axis=0).min() > 1.0  # never a constant model [N]


def test_grouped_folds_that_leave_an_output_unseen_are_detected():
    y = np.array([[1.0, 0], [2, 0], [0, 1], [0, 2]])
    assert unseen_outputs(y, calibration_folds(4, [0, 0, 1, 1], 2), names=("Fx", "Fy")) == ["Fx", "Fy"]
    assert unseen_outputs(y, calibration_folds(4, None, 2, 0)) in ([], ["output 0"], ["output 1"],
                                                                    ["output 0", "output 1"])
    mixed = np.array([[1.0, 0], [2, 1], [0, 1], [1, 2]])
    assert unseen_outputs(mixed, calibration_folds(4, [0, 0, 1, 1], 2)) == []


def test_repeated_rows_stay_together_in_the_folds():
    calibration, validation = make_dead_weight_dataset(15, loaded_axes=3, n_channels=3, random_state=0)
    raw, wrench = np.vstack([calibration.raw] * 3), np.vstack([calibration.wrench] * 3)
    auto = AutoCalibrator(random_state=0).fit(raw, wrench)
    assert "15 distinct rows" in auto.comparison_["folds"]
    # a flexible model that interpolates the copies would win on split copies; on distinct rows it is not judged
    skipped = dict(zip(auto.comparison_["name"], auto.comparison_["status"]))["gaussian_process"]
    assert skipped.startswith("skipped: training folds of 12 rows")
    ltm = LinearCalibrator().fit(raw, wrench)
    alpha = calibration.meta["alpha"]
    assert validation_rmse(auto, validation, alpha) <= 1.1 * validation_rmse(ltm, validation, alpha)


@pytest.mark.parametrize("case", ["one group", "constant outputs"])
def test_bad_input_gets_a_clear_error(case):
    calibration, _ = make_dead_weight_dataset(15, loaded_axes=3, n_channels=3, random_state=0)
    raw, wrench, groups = calibration.raw, calibration.wrench, calibration.group
    if case == "one group":
        groups = np.zeros(15, dtype=int)
        match = "one group only"
    else:
        wrench = np.zeros_like(wrench)
        match = "same in all 15 rows"
    with pytest.raises(CalibrationInputError, match=match):
        AutoCalibrator().fit(raw, wrench, groups=groups)


# ------------------------------------------------------------------ degenerate predictions are refused
def test_degenerate_predictions_are_named():
    y = np.random.default_rng(0).normal(size=(40, 6))
    assert degenerate_reason(y, np.zeros_like(y)) == "it predicts 0 for every reading"
    assert degenerate_reason(y, np.tile(y[0], (40, 1))) == "it predicts the same wrench for every reading"
    assert "no better than predicting the mean" in degenerate_reason(y, y[::-1])
    assert degenerate_reason(y, y + 0.01) is None
    with pytest.raises(DegenerateCalibrationError, match="^refusing the LTM: it predicts 0 for every reading"):
        check_not_degenerate(y, np.zeros_like(y), what="the LTM")
    assert issubclass(DegenerateCalibrationError, CalibrationInputError)  # one line on the CLI, exit 2


class ZeroCalibrator(LinearCalibrator):
    """The LTM that answers 0 for every reading (what the broken stack saved)."""

    def _predict_wrench(self, X):
        return np.zeros((len(X), 6))


def test_auto_refuses_a_degenerate_candidate_and_says_why():
    rng = np.random.default_rng(0)
    w = rng.uniform(-1, 1, size=(60, 6))
    raw = w @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(60, 6))
    auto = AutoCalibrator(candidates=[("zero", ZeroCalibrator()), ("linear", LinearCalibrator())], baselines=False,
                          stack=False).fit(raw, w)
    assert auto.best_name_ == "linear"
    assert auto.comparison_["status"][0] == "refused: it predicts 0 for every reading"
    with pytest.raises(DegenerateCalibrationError, match="no candidate could be fitted and judged"):
        AutoCalibrator(candidates=[("zero", ZeroCalibrator())], baselines=False, stack=False).fit(raw, w)


# ------------------------------------------------------------------ never lose to what is free
def cubic(n=240, seed=0):
    rng = np.random.default_rng(seed)
    w = rng.uniform(-1, 1, size=(n, 6))
    raw = (w + 0.3 * w**3) @ rng.normal(size=(6, 6)) + 0.005 * rng.normal(size=(n, 6))
    return raw, w


def test_a_stock_model_is_chosen_when_it_is_clearly_the_best():
    raw, w = cubic()
    # ftcal's candidates here cannot fit the cubic term; the stock cubic polynomial can
    auto = AutoCalibrator(candidates=[("linear", LinearCalibrator()), ("quadratic", PolynomialCalibrator(degree=2))],
                          stack=False, random_state=0).fit(raw, w)
    assert auto.best_name_ == "sk_poly3"
    assert isinstance(auto.best_estimator_, StockCalibrator)
    stock = [r for r, k in zip(auto.comparison_["rmse"], auto.comparison_["kind"]) if k == "stock" and r]
    assert auto.comparison_["rmse"][auto.comparison_["name"].index("sk_poly3")] == min(stock)
    assert "It is the best stock model itself (sk_poly3)" in auto.comparison_["why"]


def test_stock_models_take_their_place_in_the_complexity_order():
    stock = [(name, StockCalibrator(baseline=name)) for name in ("sk_linear", "sk_poly2", "sk_gp")]
    pairs = with_stock_candidates([("linear", LinearCalibrator()), ("quadratic", PolynomialCalibrator(degree=2)),
                                   ("gp", ftcal.GaussianProcessCalibrator())], stock)
    assert [name for name, _ in pairs] == ["linear", "sk_linear", "quadratic", "sk_poly2", "gp", "sk_gp"]
    from ftcal.compose._auto import complexity_ranks
    assert complexity_ranks(pairs, 7).tolist() == [0, 0, 2, 2, 4, 4, 6]


def test_between_equally_simple_models_a_tie_goes_to_the_earlier():
    errors = np.array([[1.0, 1.0, 1.0, 1.0], [0.999, 0.999, 0.999, 0.999], [0.5, 0.5, 0.5, 0.5]])
    # 0 and 1 as simple, within 0.1 %: the earlier (the LTM before the stock least squares)
    assert simplest_within_one_se(errors[:2], complexity=[0, 0]) == 0
    # clearly lower error among the equally simple: it wins
    assert simplest_within_one_se(errors[[0, 2]], complexity=[0, 0]) == 1


def test_the_table_marks_each_row_and_says_why_the_winner_won():
    rng = np.random.default_rng(1)
    w = rng.uniform(-1, 1, size=(120, 6))
    raw = w @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(120, 6))
    groups = np.repeat(np.arange(6), 20)
    auto = AutoCalibrator(candidates=[("linear", LinearCalibrator()), ("quadratic", PolynomialCalibrator(degree=2)),
                                      ("cubic", PolynomialCalibrator(degree=3))], random_state=0)
    auto.fit(raw, w, groups=groups)
    table = auto.summary()
    verdicts = dict(zip(auto.comparison_["name"], auto.comparison_["verdict"]))
    assert verdicts[auto.best_name_] == "chosen"
    assert set(verdicts.values()) <= {"chosen", "within one SE, more complex", "beyond one SE",
                                      "within one SE, as simple (the lower or earlier wins)"} | {
        s for s in auto.comparison_["status"] if s.split(":")[0] in ("skipped", "failed", "refused")}
    assert table.splitlines()[-1] == auto.comparison_["why"]
    assert auto.comparison_["why"].startswith(f"{auto.best_name_} won: ")
    assert "against the best stock model" in auto.comparison_["why"] or "best stock model itself" in \
        auto.comparison_["why"]


def test_auto_uses_the_cores_by_default_and_its_first_log_line_says_so(caplog):
    import logging

    assert AutoCalibrator().n_jobs == -1
    rng = np.random.default_rng(0)
    w = rng.uniform(-1, 1, size=(40, 6))
    raw = w @ rng.normal(size=(6, 6))
    with caplog.at_level(logging.INFO, logger="ftcal"):
        AutoCalibrator(candidates=[("linear", LinearCalibrator())], baselines=False).fit(raw, w)
    first = [r.getMessage() for r in caplog.records if r.name == "ftcal"][0]
    assert first.startswith("auto: 1 candidates on 40 rows, scored all cores")


def test_check_calibration_refuses_what_must_not_be_saved_and_passes_the_rest():
    from ftcal.compose._auto import check_calibration

    rng = np.random.default_rng(0)
    w = rng.uniform(-1, 1, size=(60, 6))
    raw = w @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(60, 6))
    check_calibration(LinearCalibrator().fit(raw, w), raw, w)
    with pytest.raises(DegenerateCalibrationError, match="refusing the fitted ZeroCalibrator: it predicts 0"):
        check_calibration(ZeroCalibrator().fit(raw, w), raw, w)
    # held-out predictions given (the report's): judged as they are
    with pytest.raises(DegenerateCalibrationError, match="no better than predicting the mean"):
        check_calibration(LinearCalibrator().fit(raw, w), raw, w, predictions=w[::-1])
    # one group per loaded axis: the grouped folds cannot judge the LTM, folds over the rows can; it passes
    calibration, _ = make_dead_weight_dataset(15, loaded_axes=3, n_channels=3, random_state=0)
    check_calibration(LinearCalibrator().fit(calibration.raw, calibration.wrench), calibration.raw,
                      calibration.wrench, groups=calibration.group)


def test_held_out_predictions_is_cross_val_predict_on_ftcals_folds():
    from sklearn.model_selection import cross_val_predict

    from ftcal.model_selection._selection import held_out_predictions

    rng = np.random.default_rng(0)
    w = rng.uniform(-1, 1, size=(60, 6))
    raw = w @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(60, 6))
    groups = np.repeat(np.arange(6), 10)
    folds, pred = held_out_predictions(PolynomialCalibrator(degree=2), raw, w, groups=groups, cv=3)
    assert len(folds) == 3 and all(np.unique(groups[test]).size == 2 for _, test in folds)
    np.testing.assert_allclose(pred, cross_val_predict(PolynomialCalibrator(degree=2), raw, w, cv=folds))


def test_the_stack_never_combines_a_model_with_its_own_stock_twin():
    # a saturating sensor: the LTM and sk_linear (the same least squares) score alike and both rank high; a stack
    # of the two splits its weight arbitrarily between two equal columns and combines no other kind of model
    rng = np.random.default_rng(0)
    wrench = rng.uniform(-1, 1, (150, 6)) * [100, 100, 100, 2, 2, 2]
    raw = np.tanh(wrench / [150, 150, 150, 3, 3, 3]) @ rng.normal(size=(6, 6)) + 1e-3 * rng.normal(size=(150, 6))
    auto = AutoCalibrator(candidates=[("linear", LinearCalibrator())], cv=3, random_state=0).fit(raw, wrench)
    c = auto.comparison_
    rmse = dict(zip(c["name"], c["rmse"]))
    assert rmse["sk_linear"] == pytest.approx(rmse["linear"], rel=1e-6)  # twins indeed
    members = c["stack_members"]
    assert "linear" in members and "sk_linear" not in members and len(members) == 3, members


def test_a_stock_model_is_fitted_by_name_through_the_cli_and_predicts_as_the_stock_pipeline(tmp_path):
    from ftcal.cli import main
    from ftcal.calibrators import stock_baselines

    raw, w = cubic(120)
    data = ftcal.CalibrationDataset(raw=raw, wrench=w).save(tmp_path / "d.csv")
    np.savetxt(tmp_path / "r.csv", raw[:7], delimiter=",")
    assert main(["fit", str(data), "--model", "stock", "--param", "baseline=sk_poly3", "--name", "free",
                 "--out", str(tmp_path / "m"), "-q"]) == 0
    model = ftcal.load_model(tmp_path / "m" / "free.model.npz")
    assert isinstance(model, StockCalibrator) and model.baseline == "sk_poly3"
    assert main(["predict", str(tmp_path / "m" / "free.model.npz"), str(tmp_path / "r.csv"),
                 "--output", str(tmp_path / "w.csv")]) == 0
    written = np.loadtxt(tmp_path / "w.csv", delimiter=",", skiprows=1)
    expected = stock_baselines(6)["sk_poly3"].fit(raw, w).predict(raw[:7])
    np.testing.assert_allclose(written, expected, atol=1e-6 * np.abs(w).max())


def test_a_stock_model_of_the_users_regressor_is_refused_at_save_not_written_as_another_model(tmp_path):
    from sklearn.linear_model import Ridge

    from ftcal.core import ModelFileError

    raw, w = cubic(60)
    model = StockCalibrator(baseline=Ridge()).fit(raw, w)
    with pytest.raises(ModelFileError, match="holds a Ridge of the user.s .estimator_."):
        ftcal.save_model(model, tmp_path / "mine.model.npz")
    assert not (tmp_path / "mine.model.npz").exists()


def test_a_stock_model_file_whose_arrays_are_not_its_baselines_is_refused(tmp_path):
    from ftcal.core import ModelFileError

    raw, w = cubic(60)
    model = StockCalibrator(baseline="sk_linear").fit(raw, w)
    model.powers_ = np.eye(6, dtype=np.int64)  # an edited file: monomials in a least-squares map
    ftcal.save_model(model, tmp_path / "edited.model.npz")
    with pytest.raises(ModelFileError, match="not those of baseline='sk_linear'"):
        ftcal.load_model(tmp_path / "edited.model.npz").predict(raw[:3])


def test_a_stock_kernel_fit_over_the_memory_limit_is_refused_before_it_allocates(monkeypatch):
    from ftcal.core._memory import MemoryLimitError

    monkeypatch.setenv("FTCAL_MEMORY_LIMIT_GB", "0.01")  # 10 MB: a 600-row kernel and its gradient need ~29 MB
    raw, w = cubic(600)
    with pytest.raises(MemoryLimitError, match="max_kernel_samples"):
        StockCalibrator(baseline="sk_gp", max_kernel_samples=None).fit(raw, w)
