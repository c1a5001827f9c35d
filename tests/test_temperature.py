"""Temperature columns, simulated thermal drift and its compensation."""

from __future__ import annotations

import json

import numpy as np
import pytest

import ftcal
from ftcal import AxisNonlinearCalibrator, CalibrationDataset, LinearCalibrator, TemperatureCompensatedCalibrator
from ftcal.core import CalibrationInputError, DatasetFileError, LogFormatError, ThermalDrift
from ftcal.cli import main


def test_thermal_drift_follows_the_documented_model():
    drift = ThermalDrift(offset_per_deg=np.array([0.5, -0.2]), gain_per_deg=np.array([1e-3, 2e-3]))
    raw = np.array([[10.0, 20.0], [1.0, 2.0]])
    t = np.array([45.0, 5.0])
    expected = np.array([[10.0 * (1 + 20e-3) + 0.5 * 20, 20.0 * (1 + 40e-3) - 0.2 * 20],
                         [1.0 * (1 - 20e-3) - 0.5 * 20, 2.0 * (1 - 40e-3) + 0.2 * 20]])
    np.testing.assert_allclose(drift.apply(raw, t), expected)


def drifting_dataset(seed=0, preset="thesis", temperature_range=(15.0, 35.0)):
    train, test, info = ftcal.make_artificial_dataset(preset=preset, random_state=seed, n_per_sphere=1000, n_test=1000)
    rng = np.random.default_rng(seed)
    # the upper end of data-sheet drift (zero 0.05 % FS/deg C, span 0.03 %/deg C), so that over 20 deg C the drift
    # stands out of the thesis preset's noise and the share of its error removed can be measured
    drift = ThermalDrift.typical(np.abs(train.raw).max(axis=0), zero_pct_per_deg=0.05, span_pct_per_deg=0.03,
                                 random_state=seed)
    t_train, t_test = rng.uniform(*temperature_range, size=train.n_samples), rng.uniform(*temperature_range, size=test.n_samples)
    return train, test, info, drift, t_train, t_test


@pytest.mark.parametrize("cls", [LinearCalibrator, AxisNonlinearCalibrator])
def test_compensation_removes_at_least_90_percent_of_the_drift_error(cls):
    train, test, info, drift, t_train, t_test = drifting_dataset()
    alpha = info["alpha"]

    def mse(model, X_train, X_test):
        model.fit(X_train, train.wrench)
        return ftcal.core.wrench_rmse(test.wrench, model.predict(X_test), alpha=alpha) ** 2

    clean = mse(cls(alpha=alpha), train.raw, test.raw)
    drifted = mse(cls(alpha=alpha), drift.apply(train.raw, t_train), drift.apply(test.raw, t_test))
    compensated = mse(TemperatureCompensatedCalibrator(cls(), alpha=alpha),
                      np.column_stack([drift.apply(train.raw, t_train), t_train]),
                      np.column_stack([drift.apply(test.raw, t_test), t_test]))
    assert drifted > 1.2 * clean  # the drift matters at data-sheet magnitudes over 20 deg C
    assert compensated - clean <= 0.1 * (drifted - clean)  # the target: >= 90 % of its error removed


def test_compensation_needs_a_temperature_range():
    rng = np.random.default_rng(0)
    w = rng.normal(size=(100, 6))
    X = np.column_stack([w @ rng.normal(size=(6, 6)), np.full(100, 25.0)])
    with pytest.raises(CalibrationInputError, match="span only 0 deg C"):
        TemperatureCompensatedCalibrator().fit(X, w)
    with pytest.raises(CalibrationInputError, match="outside -60..200 deg C"):
        TemperatureCompensatedCalibrator().fit(np.column_stack([X[:, :-1], np.linspace(0, 3000, 100)]), w)


def test_temperature_model_file_round_trip_and_retare(tmp_path):
    train, test, info, drift, t_train, t_test = drifting_dataset(seed=1)
    X = np.column_stack([drift.apply(train.raw, t_train), t_train])
    model = TemperatureCompensatedCalibrator(alpha=info["alpha"]).fit(X, train.wrench)
    X_test = np.column_stack([drift.apply(test.raw, t_test), t_test])
    back = ftcal.load_model(ftcal.save_model(model, tmp_path / "t.model.npz"))
    np.testing.assert_array_equal(back.predict(X_test), model.predict(X_test))
    zero_now = np.column_stack([drift.apply(np.zeros((50, train.n_channels)) + info["zero_offset"], np.full(50, 30.0)),
                                np.full(50, 30.0)]) if info["zero_offset"] is not None else None
    if zero_now is not None:
        model.retare(zero_now)
        assert hasattr(model.estimator_, "tare_reading_")


def test_dataset_files_carry_temperature(tmp_path):
    ds = CalibrationDataset(raw=np.eye(8, 6), wrench=np.eye(8, 6), temperature=np.linspace(20, 30, 8))
    for suffix in (".csv", ".npz"):
        back = CalibrationDataset.load(ds.save(tmp_path / f"d{suffix}"))
        np.testing.assert_allclose(back.temperature, ds.temperature)
        np.testing.assert_allclose(back.features(temperature=True)[:, -1], ds.temperature)
    bad = tmp_path / "bad.csv"
    text = (tmp_path / "d.csv").read_text().splitlines()
    fields = text[3].split(",")
    fields[-1] = "nan"
    bad.write_text("\n".join(text[:3] + [",".join(fields)] + text[4:]) + "\n")
    with pytest.raises(DatasetFileError, match="line 4, column temperature: temperature is NaN"):
        CalibrationDataset.load(bad)
    with pytest.raises(DatasetFileError, match="has no temperature column"):
        CalibrationDataset(raw=np.eye(8, 6), wrench=np.eye(8, 6)).features(temperature=True)


def test_run_logs_carry_temperature_into_the_prepared_dataset(tmp_path):
    robot = ftcal.robot.load_robot("kuka_iiwa14")
    paths = ftcal.experiment.simulate_experiment(tmp_path / "logs", robot=robot, subdivisions=0, random_state=0)
    for k, path in enumerate(paths):  # add a temperature column to the virtual logs
        log = ftcal.io.read_run_log(path)
        ftcal.io.write_run_log(path, timestamp=log.timestamp, run_kind=log.run_kind, config=log.config, pose=log.pose,
                            q=log.q, raw=log.raw, load_mass=log.load_mass, overwrite=True,
                            temperature=20.0 + 0.1 * np.arange(log.n_rows) + k)
    assert ftcal.io.read_run_log(paths[1]).temperature is not None
    ds = ftcal.experiment.prepare_dataset(paths, robot)
    assert ds.temperature is not None and ds.temperature.shape == (ds.n_samples,)
    lines = paths[0].read_text().splitlines()
    lines[-1] = lines[-1].rsplit(",", 1)[0] + ",1e9"
    paths[0].write_text("\n".join(lines) + "\n")
    with pytest.raises(LogFormatError, match=r"line \d+, column temperature: temperature is 1e\+09 deg C"):
        ftcal.io.read_run_log(paths[0])


def test_predict_std_of_a_temperature_compensated_model_says_why_not(tmp_path, capsys):
    data, models = tmp_path / "data", tmp_path / "models"
    assert main(["simulate", "dataset", "--temperature-range", "15,35", "--n-per-sphere", "30", "--n-test", "20",
                 "--out", str(data), "-q"]) == 0
    assert main(["fit", str(data / "train.csv"), "--model", "gaussian_process", "--temperature", "--out", str(models),
                 "-q"]) == 0
    capsys.readouterr()
    assert main(["predict", str(models / "gaussian_process.model.npz"), str(data / "test.csv"), "--std"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "temperature-compensated" in err[0] and "fit without --temperature" in err[0]


def test_temperature_workflow_through_the_cli(tmp_path, capsys):
    data, models = tmp_path / "data", tmp_path / "models"
    assert main(["simulate", "dataset", "--temperature-range", "15,35",
                 "--out", str(data), "-q"]) == 0
    info = json.loads((data / "info.json").read_text())
    assert "thermal_drift" in info["datasets"][0]
    assert main(["fit", str(data / "train.csv"), "--model", "linear", "--out", str(models), "-q"]) == 0
    assert main(["fit", str(data / "train.csv"), "--model", "linear", "--temperature", "--name", "linear_t",
                 "--out", str(models), "-q"]) == 0
    capsys.readouterr()
    assert main(["evaluate", str(data / "test.csv"), str(models / "linear.model.npz"),
                 str(models / "linear_t.model.npz"), "--out", str(tmp_path / "eval"), "-q"]) == 0
    table = capsys.readouterr().out
    rmse = {line.split("|")[1].strip(): float(line.split("|")[2]) for line in table.splitlines()
            if line.startswith("| linear")}
    assert rmse["linear_t"] < rmse["linear"]
    # predict reads the temperature column of a dataset file for the compensated model only
    assert main(["predict", str(models / "linear_t.model.npz"), str(data / "test.csv")]) == 0
    assert main(["predict", str(models / "linear.model.npz"), str(data / "test.csv")]) == 0
    assert main(["fit", str(data / "train.csv"), "--model", "linear", "--temperature", "--out",
                 str(tmp_path / "x"), "-q", "--name", "bad", "--tare", "1,2"]) == 2


def test_virtual_experiment_with_thermal_drift_through_the_cli(tmp_path):
    logs, data, models = tmp_path / "logs", tmp_path / "data", tmp_path / "models"
    assert main(["simulate", "experiment", "--subdivisions", "0", "--temperature-range", "15,35", "--out", str(logs),
                 "-q"]) == 0
    log = ftcal.io.read_run_log(logs / "config0_load.csv")
    assert log.temperature is not None and 15 <= log.temperature.min() and log.temperature.max() <= 35
    truth = json.loads((logs / "virtual_experiment.json").read_text())
    assert truth["thermal_drift"]["temperature_range_deg"] == [15.0, 35.0]
    assert main(["prepare", str(logs), "--out", str(data), "-q"]) == 0
    assert CalibrationDataset.load(data / "dataset.csv").temperature is not None
    assert main(["fit", str(data / "dataset.csv"), "--model", "linear", "--temperature", "--out", str(models),
                 "-q"]) == 0
