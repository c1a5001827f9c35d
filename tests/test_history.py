"""The load-history term: ``reading_history`` and ``HistoryCalibrator``, on sensors whose physics is known.

The sensor of these tests creeps: each reading sees the load plus ``k`` times the lag of the load behind its
exponential moving average (time constant 3 rows), ``raw = A (w + k (m - w))`` with ``m - w`` =
``reading_history(w, 3)``. To first order in ``k`` the wrench is then ``A^-1 raw - k A^-1 reading_history(raw, 3)``:
a linear map plus a linear history term, which ``HistoryCalibrator(LinearCalibrator())`` can represent up to
``O(k^2)``, while the LTM alone keeps the whole ``k (m - w)``.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from sklearn.model_selection import GroupKFold

import ftcal
import ftcal.calibrators._base
from ftcal.core import CalibrationInputError
from ftcal import HistoryCalibrator, LinearCalibrator
from ftcal.compose import reading_history
from ftcal.cli import main
from ftcal.compose._auto import StackedCalibrator

TAU_TRUE = 3.0
CREEP = 0.2  # k: 20 % of the lag shows in the readings


def creeping_sensor(n_presses=30, rows_per_press=20, noise=0.01, seed=0, creep=CREEP, tau=TAU_TRUE):
    """Readings, wrenches, press labels and the LTM error the creep causes, of a linear sensor with creep."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, np.pi, rows_per_press)
    loads = [np.outer(np.sin(t) ** 2, rng.normal(size=6) * [10, 10, 10, 0.5, 0.5, 0.5]) for _ in range(n_presses)]
    wrench = np.vstack(loads)
    groups = np.repeat(np.arange(n_presses), rows_per_press)
    A = rng.normal(size=(8, 6)) / np.array([10, 10, 10, 0.5, 0.5, 0.5])
    raw = (wrench + creep * reading_history(wrench, tau)) @ A.T + noise * rng.normal(size=(len(wrench), 8))
    return raw, wrench, groups


def held_out_rmse(make, raw, wrench, groups, alpha):
    pred = np.empty_like(wrench)
    for train, test in GroupKFold(5).split(raw, groups=groups):
        model = make()
        model.fit(raw[train], wrench[train], **({"groups": groups[train]} if isinstance(model, HistoryCalibrator)
                                                else {}))
        pred[test] = model.predict(raw[test])
    return ftcal.core.wrench_rmse(wrench, pred, alpha=alpha)


def test_reading_history_is_the_moving_average_of_the_rows_before_minus_the_row():
    X = np.random.default_rng(1).normal(size=(50, 4))
    for tau in (1.0, 2.5, 10.0):
        expected, mean = np.empty_like(X), X[0].copy()
        for i, row in enumerate(X):  # the definition, one row at a time
            expected[i] = mean - row
            mean = mean + (row - mean) / tau
        np.testing.assert_allclose(reading_history(X, tau), expected, atol=1e-12)
        first, state = reading_history(X[:17], tau, return_state=True)
        np.testing.assert_allclose(np.vstack([first, reading_history(X[17:], tau, state=state)]), expected, atol=1e-12)
    # a constant offset (a tare) cancels; a reading held still has no history
    np.testing.assert_allclose(reading_history(X + 5.0, 2.0), reading_history(X, 2.0), atol=1e-12)
    np.testing.assert_array_equal(reading_history(np.ones((5, 3)), 4.0), np.zeros((5, 3)))
    for bad in (0.5, 0, -1, float("nan"), float("inf"), True, "2"):
        with pytest.raises(CalibrationInputError, match="tau_rows"):
            reading_history(X, bad)
    for bad_x, name in (([["a"]], "X"), (X + 1j, "X"), (np.array([[1e308], [-1e308]]), "overflows"),
                        (np.empty((0, 4)), "at least one row")):
        with pytest.raises(CalibrationInputError, match=name):
            reading_history(bad_x, 2.0)
    for bad_state, message in (("abc", "state must hold real numbers"), ([0.0] * 3, r"shape \(4,\)"),
                               ([np.nan] * 4, "non-finite")):
        with pytest.raises(CalibrationInputError, match=message):
            reading_history(X, 2.0, state=bad_state)


def test_the_history_term_removes_most_of_the_creep_error_and_finds_its_time_constant():
    raw, wrench, groups = creeping_sensor()
    alpha = ftcal.core.alpha_from_wrenches(wrench)
    static = held_out_rmse(lambda: LinearCalibrator(alpha=alpha), raw, wrench, groups, alpha)
    history = held_out_rmse(lambda: HistoryCalibrator(alpha=alpha), raw, wrench, groups, alpha)
    # the floor: the same sensor and noise without creep, calibrated by the LTM
    floor = held_out_rmse(lambda: LinearCalibrator(alpha=alpha), *creeping_sensor(creep=0.0), alpha)
    # what the history term leaves of the creep error is O(k^2), i.e. about k = 20 % of it: demand less than half
    assert history - floor < 0.5 * (static - floor), (static, history, floor)
    model = HistoryCalibrator(alpha=alpha).fit(raw, wrench, groups=groups)
    assert model.tau_rows_ in (2.0, 4.0)  # the grid's neighbours of the true 3 rows
    assert model.cv_rmse_[0] > model.cv_rmse_[1:].min()


@pytest.mark.parametrize("inner", ["linear", "cubic"])
def test_a_long_time_constant_is_found_with_a_linear_or_a_flexible_estimator(inner):
    """True time constant 12 rows: the grid's neighbours are 8 and 16. Partialling out is exact for estimators
    linear in their features (the LTM, a polynomial), however strongly the history correlates with the readings."""
    raw, wrench, groups = creeping_sensor(rows_per_press=60, creep=0.3, tau=12.0)
    estimator = LinearCalibrator() if inner == "linear" else ftcal.PolynomialCalibrator(degree=3, ridge=0.01)
    model = HistoryCalibrator(estimator).fit(raw, wrench, groups=groups)
    assert model.tau_rows_ in (8.0, 16.0)
    # the history term removes most of the creep error in the cross-validation that chose it
    assert model.cv_rmse_[1:].min() < 0.5 * model.cv_rmse_[0]


def test_with_the_ltm_inside_it_is_the_joint_least_squares_fit():
    """Partialling out (Frisch-Waugh-Lovell) gives the joint least-squares fit of [X, H, 1] exactly."""
    raw, wrench, groups = creeping_sensor()
    model = HistoryCalibrator(taus=(4.0,)).fit(raw, wrench, groups=groups)
    assert model.tau_rows_ == 4.0
    design = np.column_stack([raw, reading_history(raw, 4.0), np.ones(len(raw))])
    joint = design @ np.linalg.lstsq(design, wrench, rcond=None)[0]
    np.testing.assert_allclose(model.predict(raw), joint, atol=1e-9 * np.abs(wrench).max())
    assert model.history_estimator_.alpha == 1.0  # the history columns are readings: no torque scale
    np.testing.assert_array_equal(model.history_estimator_.zero_reading_, model.estimator_.zero_reading_)


def test_of_time_constants_within_noise_of_the_best_the_shortest_is_kept_in_any_order():
    """3.0 and 3.1 rows fit the creep (true 3) equally well, within the one-SE rule's tie: the shorter one is kept
    whichever comes first in ``taus`` (by length, not by position), even where 3.1 scores a hair better."""
    raw, wrench, groups = creeping_sensor(noise=0.05)
    for taus in [(3.0, 3.1), (3.1, 3.0)]:
        model = HistoryCalibrator(taus=taus).fit(raw, wrench, groups=groups)
        assert model.tau_rows_ == 3.0
        assert abs(model.cv_rmse_[1] - model.cv_rmse_[2]) < 0.005 * model.cv_rmse_[1:].min()  # a tie indeed


def test_a_sensor_without_memory_rarely_gets_a_history_term():
    """Rows in time order, a rigid linear sensor, reference noise only: the history has nothing to explain. Over
    8 sensors at most one may keep a term by chance (the one-SE rule compares the best of 5 time constants)."""
    kept = 0
    for seed in range(8):
        raw, wrench, groups = creeping_sensor(creep=0.0, noise=0.0, seed=seed)
        noisy = wrench + np.random.default_rng(seed).normal(size=wrench.shape) * np.array([0.1] * 3 + [0.005] * 3)
        kept += HistoryCalibrator().fit(raw, noisy, groups=groups).tau_rows_ is not None
    assert kept <= 1


def test_rows_without_a_time_order_get_no_history_term():
    raw, wrench, _ = creeping_sensor(noise=0.05)
    order = np.random.default_rng(2).permutation(len(raw))  # shuffled rows: their "history" is noise
    shuffled = raw[order]  # the creep stays in the readings, but no row follows its predecessor in time
    model = HistoryCalibrator().fit(shuffled, wrench[order])
    assert model.tau_rows_ is None and model.history_coef_ is None
    plain = LinearCalibrator().fit(shuffled, wrench[order])
    np.testing.assert_allclose(model.predict(shuffled), plain.predict(shuffled), atol=1e-9)


def test_stream_carries_the_history_across_chunks_and_the_model_file_keeps_everything(tmp_path):
    raw, wrench, groups = creeping_sensor()
    model = HistoryCalibrator(taus=(2.0, 4.0)).fit(raw, wrench, groups=groups)
    predict = model.stream()
    parts = [predict(raw[:1]), predict(raw[1:77]), predict(raw[77:])]
    np.testing.assert_allclose(np.vstack(parts), model.predict(raw), atol=1e-12)
    loaded = ftcal.load_model(ftcal.save_model(model, tmp_path / "h.model.npz"))
    assert loaded.tau_rows_ == model.tau_rows_
    np.testing.assert_array_equal(loaded.predict(raw), model.predict(raw))
    np.testing.assert_array_equal(loaded.cv_rmse_, model.cv_rmse_)


def test_a_refused_chunk_leaves_the_stream_as_it_was_and_range_flags_follow_the_history():
    raw, wrench, groups = creeping_sensor()
    model = HistoryCalibrator(ftcal.PolynomialCalibrator(degree=2, ridge=0.01), taus=(4.0,)).fit(
        raw, wrench, groups=groups)
    predict = model.stream()
    predict(raw[:100])
    with pytest.raises(ValueError):
        predict(np.full((1, raw.shape[1]), 1e200))  # a glitch the polynomial refuses (non-finite wrench)
    clean = model.stream()
    clean(raw[:100])
    np.testing.assert_array_equal(predict(raw[100:110]), clean(raw[100:110]))
    # a reading far beyond the range is flagged, and so are the rows whose history still holds it (weight >= 1e-3)
    glitch = raw.copy()
    glitch[50] = 1e3
    flags = model.out_of_range(glitch)
    reach = 1 + int(np.floor(np.log(1e-3 / 0.25) / np.log(0.75)))  # a (1 - a)^k >= 1e-3, a = 1 / tau
    assert flags[50:51 + reach].all() and not flags[51 + reach:].any() and not flags[:50].any()
    assert np.flatnonzero(model.out_of_range(glitch, spread=False)).tolist() == [50]  # the row itself only
    with pytest.raises(CalibrationInputError, match="spread must be True or False"):
        model.out_of_range(glitch, spread="no")


def test_retare_shifts_both_the_estimator_and_the_range_check(tmp_path, capsys):
    raw, wrench, groups = creeping_sensor()
    model = HistoryCalibrator(taus=(4.0,)).fit(raw, wrench, groups=groups)
    assert model.tau_rows_ == 4.0
    shift = 0.3 * np.ptp(raw, axis=0)  # the sensor's zero moved: every reading shifted by this
    zero = model.zero_reading_ + shift + 1e-4 * np.random.default_rng(0).normal(size=(20, raw.shape[1]))
    before = model.predict(raw)
    model.retare(zero)
    np.testing.assert_allclose(model.predict(raw + shift), before, atol=1e-3 * np.abs(before).max())
    # the range moves with the tare: only rows at a channel's extreme (2 a channel) may flip by the tare's noise
    # (before the flags are spread to the rows whose history holds them)
    assert model.out_of_range(raw + shift, spread=False).sum() <= 2 * raw.shape[1]
    predict = model.stream()
    np.testing.assert_allclose(np.vstack([predict(raw[:50] + shift), predict(raw[50:] + shift)]),
                               model.predict(raw + shift), atol=1e-12)
    # the CLI: fit, re-tare from a file of zero readings, predict
    ftcal.CalibrationDataset(raw=raw, wrench=wrench, group=groups).save(tmp_path / "creep.csv")
    assert main(["fit", str(tmp_path / "creep.csv"), "--model", "linear", "--history", "--out",
                 str(tmp_path / "m"), "--quiet"]) == 0
    np.savetxt(tmp_path / "zero.csv", zero, delimiter=",", header=",".join(f"s{i}" for i in range(raw.shape[1])),
               comments="")
    assert main(["retare", str(tmp_path / "m" / "linear.model.npz"), str(tmp_path / "zero.csv"), "--quiet"]) == 0
    capsys.readouterr()
    fitted = ftcal.load_model(tmp_path / "m" / "linear.model.npz")
    retared = ftcal.load_model(tmp_path / "m" / "linear-retared.model.npz")
    np.testing.assert_allclose(retared.predict(raw + shift), fitted.retare(zero).predict(raw + shift), atol=1e-12)


@pytest.mark.parametrize("width", [1, 3])
def test_other_target_widths_fit_save_and_load(tmp_path, width):
    raw, wrench, groups = creeping_sensor(n_presses=10)
    y = wrench[:, 0] if width == 1 else wrench[:, :width]
    model = HistoryCalibrator(taus=(4.0,)).fit(raw, y, groups=groups)
    assert model.predict(raw).shape == y.shape
    loaded = ftcal.load_model(ftcal.save_model(model, tmp_path / "h.model.npz"))
    np.testing.assert_array_equal(loaded.predict(raw), model.predict(raw))


def test_an_auto_inside_chooses_the_static_model_once():
    raw, wrench, groups = creeping_sensor(n_presses=12)
    auto = ftcal.AutoCalibrator(candidates=[("linear", LinearCalibrator()),
                                            ("polynomial", ftcal.PolynomialCalibrator(degree=2, ridge=1.0))],
                                cv=3, baselines=False)
    model = HistoryCalibrator(auto, taus=(4.0,)).fit(raw, wrench, groups=groups)
    assert model.static_choice_ in ("linear", "polynomial")
    assert not isinstance(model.estimator_, ftcal.AutoCalibrator)


def test_groups_reach_the_inner_calibrator_and_bad_input_is_named():
    raw, wrench, groups = creeping_sensor(n_presses=10)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # group offsets without groups warn: every fit inside must receive them
        HistoryCalibrator(ftcal.PolynomialCalibrator(degree=1, group_offsets=True), taus=(4.0,)).fit(
            raw, wrench, groups=groups)
    with pytest.warns(UserWarning):
        HistoryCalibrator(ftcal.PolynomialCalibrator(degree=1, group_offsets=True), taus=(4.0,)).fit(raw, wrench)
    with pytest.raises(CalibrationInputError, match="groups"):
        HistoryCalibrator().fit(raw, wrench, groups=groups[:-1])
    with pytest.raises(CalibrationInputError, match="taus"):
        HistoryCalibrator(taus=()).fit(raw, wrench)
    with pytest.raises(CalibrationInputError, match="taus"):
        HistoryCalibrator(taus=(0.5, 2.0)).fit(raw, wrench)
    with pytest.raises(CalibrationInputError, match=r"taus must be a non-empty flat list .* got an array of shape "
                                                     r"\(2, 2\)"):
        HistoryCalibrator(taus=[[1.0, 2.0], [4.0, 8.0]]).fit(raw, wrench)  # was flattened silently
    with pytest.raises(CalibrationInputError, match=r"at most 64 time constants .* got 99 of them \(each costs cv "
                                                     r"fits\)"):
        HistoryCalibrator(taus=range(1, 100)).fit(raw, wrench)
    with pytest.raises(CalibrationInputError, match="cv"):
        HistoryCalibrator(cv=1).fit(raw, wrench)
    with pytest.raises(CalibrationInputError, match="training fold holds"):
        HistoryCalibrator(cv=5).fit(raw[:10], wrench[:10])
    with pytest.raises(ftcal.core.ExportError, match="load-history term"):
        ftcal.export_onnx(HistoryCalibrator().fit(raw, wrench, groups=groups), "never-written.onnx")
    with pytest.raises(ftcal.core.ExportError, match="load-history term"):
        ftcal.persistence.linear_calibration_matrix(HistoryCalibrator(taus=(4.0,)).fit(raw, wrench, groups=groups))
    # a history model must be the outermost one: a wrapper would restart its history or shuffle its rows
    warm = np.column_stack([raw, np.linspace(15, 35, len(raw))])
    with pytest.raises(CalibrationInputError, match="use one HistoryCalibrator"):
        HistoryCalibrator(HistoryCalibrator()).fit(raw, wrench)
    for wrapper in (ftcal.EnsembleCalibrator(HistoryCalibrator()),
                    ftcal.TemperatureCompensatedCalibrator(HistoryCalibrator()),
                    ftcal.AutoCalibrator(candidates=[("h", HistoryCalibrator())], baselines=False)):
        with pytest.raises(CalibrationInputError, match="Put the history term outermost"):
            wrapper.fit(warm, wrench)
    with pytest.raises(CalibrationInputError, match="Put the history term outermost"):
        StackedCalibrator(estimators=[HistoryCalibrator()], weights=[1.0]).fit(raw, wrench)
    with pytest.raises(CalibrationInputError, match="last column is the temperature"):
        HistoryCalibrator(ftcal.TemperatureCompensatedCalibrator()).fit(warm, wrench)
    # the inner calibrator's own settings are kept where the wrapper's are None
    inner = ftcal.PolynomialCalibrator(degree=2, ridge=0.01, alpha=3.0, random_state=7)
    model = HistoryCalibrator(inner, taus=(4.0,)).fit(raw, wrench, groups=groups)
    assert model.alpha_ == 3.0 and model.estimator_.alpha == 3.0 and model.estimator_.random_state == 7


def test_cli_fit_history_then_predict_in_chunks_is_the_library_predict(tmp_path, capsys):
    raw, wrench, groups = creeping_sensor(n_presses=12)
    ftcal.CalibrationDataset(raw=raw, wrench=wrench, group=groups).save(tmp_path / "creep.csv")
    assert main(["fit", str(tmp_path / "creep.csv"), "--model", "linear", "--history", "--out", str(tmp_path / "m"),
                 "--quiet"]) == 0
    summary = json.loads((tmp_path / "m" / "linear.fit.json").read_text())
    assert summary["history"] is True and summary["history_tau_rows"] in (2.0, 4.0)
    capsys.readouterr()
    assert main(["predict", str(tmp_path / "m" / "linear.model.npz"), str(tmp_path / "creep.csv"),
                 "--chunk-size", "7", "--output", str(tmp_path / "w.csv")]) == 0
    predicted = np.loadtxt(tmp_path / "w.csv", delimiter=",", skiprows=1)
    model = ftcal.load_model(tmp_path / "m" / "linear.model.npz")
    np.testing.assert_allclose(predicted, model.predict(raw), rtol=1e-8, atol=1e-8)
    temperature = np.random.default_rng(0).uniform(15, 35, len(raw))
    ftcal.CalibrationDataset(raw=raw, wrench=wrench, temperature=temperature).save(tmp_path / "warm.csv")
    assert main(["fit", str(tmp_path / "warm.csv"), "--model", "linear", "--history", "--temperature",
                 "--out", str(tmp_path / "m2")]) == 2
    assert "--history and --temperature cannot be combined" in capsys.readouterr().err
    assert not (tmp_path / "m2").exists()
    assert main(["predict", str(tmp_path / "m" / "linear.model.npz"), str(tmp_path / "creep.csv"), "--std"]) == 2
    assert "--std" in capsys.readouterr().err
    # a glitch beyond the range: its row and those whose history holds it are counted, whatever the chunk size
    glitch = raw.copy()
    glitch[40] = 1e3
    np.savetxt(tmp_path / "glitch.csv", glitch, delimiter=",", comments="",
               header=",".join(f"s{i}" for i in range(raw.shape[1])))
    expected = int(model.out_of_range(glitch).sum())
    assert expected > 1
    for size in ("1", "7", "4096"):
        assert main(["predict", str(tmp_path / "m" / "linear.model.npz"), str(tmp_path / "glitch.csv"),
                     "--chunk-size", size, "--output", str(tmp_path / f"g{size}.csv")]) == 0
        assert f"{expected} of {len(raw)} readings lie beyond" in capsys.readouterr().err


def test_the_report_of_a_history_model_keeps_the_rows_in_time_order(tmp_path):
    """Without a group column the report's folds are contiguous blocks, not shuffled rows (which have no history)."""
    raw, wrench, _ = creeping_sensor(n_presses=12)
    dataset = ftcal.CalibrationDataset(raw=raw, wrench=wrench)
    model = HistoryCalibrator(taus=(4.0,)).fit(raw, wrench)
    report = ftcal.calibration_certificate(model, dataset, baselines=False, figures=False)
    assert "contiguous" in report.validation["split"]
    plain = ftcal.calibration_certificate(LinearCalibrator().fit(raw, wrench), dataset, baselines=False,
                                          figures=False)
    assert "shuffled" in plain.validation["split"]


def test_benchmark_dataset_scores_the_closed_forms_with_a_history_term(tmp_path, capsys):
    """``ftcal benchmark dataset --history``: on a creeping sensor the history term is chosen and removes most of
    the LTM's error (the creep is 20 % of the lag; what stays is the reading noise); bad uses are one line. 15
    presses (300 rows): enough for the history term's 200 training rows per fold, and the stock baselines (kernel
    ridge, a GP) that the command also scores cost a fraction of the default 30 presses'."""
    raw, wrench, groups = creeping_sensor(n_presses=15)
    path = tmp_path / "creep.csv"
    ftcal.CalibrationDataset(raw=raw, wrench=wrench, group=groups).save(path)
    out = tmp_path / "bench"
    assert main(["benchmark", "dataset", str(path), "--model", "linear", "--history", "--out", str(out), "-q"]) == 0
    result = json.loads((out / "dataset_results.json").read_text())
    rmse = dict(zip(result["name"], result["rmse"]))
    assert result["chosen"] == "history(linear)"
    assert rmse["history(linear)"] < 0.5 * rmse["linear"]
    capsys.readouterr()
    for argv, words in [(["--folds", "kfold"], "--history: a load history runs along consecutive rows"),
                        (["--model", "gaussian_process"], "--history scores the closed-form models")]:
        assert main(["benchmark", "dataset", str(path), "--history", *argv, "--out", str(tmp_path / "x")]) == 2
        err = capsys.readouterr().err
        assert err.startswith("ftcal: error: --history") and words in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x").exists()


def test_fit_auto_with_a_history_term_through_the_cli_saves_and_says_the_static_choice(tmp_path, capsys):
    # a history wrapper around auto chooses its model (its tags say so): the command must not read auto's own
    # comparison off the wrapper (it crashed with an AttributeError)
    rng = np.random.default_rng(0)
    w = rng.uniform(-1, 1, (120, 6))
    raw = w @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(120, 6))
    path = ftcal.CalibrationDataset(raw=raw, wrench=w, group=np.repeat(np.arange(6), 20)).save(tmp_path / "d.csv")
    assert main(["fit", str(path), "--model", "auto", "--history", "--out", str(tmp_path / "m"), "-q"]) == 0
    fit = json.loads((tmp_path / "m" / "auto.fit.json").read_text())
    assert fit["history"] is True and fit["chosen"] == "linear"  # affine data: the LTM is the static choice
    assert (tmp_path / "m" / "auto.model.npz").is_file()
