"""Whole workflows through ``ftcal.cli.main``: simulate -> fit -> evaluate -> predict, the robot
pipeline (plan, virtual experiment logs -> prepare -> fit -> evaluate -> predict), demo, benchmark."""

from __future__ import annotations

import hashlib
import math
import io
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import ftcal
from ftcal import CalibrationDataset
from ftcal.cli import main

from conftest import SMALL_NET_CLI



def digest(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.glob("*.csv"))}


def predict_csv(argv: list[str], capsys) -> np.ndarray:
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0] == "Fx,Fy,Fz,Tx,Ty,Tz"
    return np.loadtxt(io.StringIO(out), delimiter=",", skiprows=1, ndmin=2)


# ------------------------------------------------------------------ artificial path
def test_simulate_dataset_spheres_seed_and_force(tmp_path):
    out = tmp_path / "data"
    argv = ["simulate", "dataset", "--n-per-sphere", "10", "--n-test", "15", "--seed", "4", "--out", str(out), "-q"]
    assert main(argv) == 0
    train = CalibrationDataset.load(out / "train.csv")
    test = CalibrationDataset.load(out / "test.csv")
    assert train.raw.shape == (40, 6) and test.raw.shape == (15, 6)
    # the thesis sensor (2000 N, 40 N·m, alpha 50): spheres of radius 400, 800, 1200, 1600 N (IV-A-a)
    scaled = np.hstack([train.wrench[:, :3], 50.0 * train.wrench[:, 3:]])
    np.testing.assert_allclose(np.sort(np.unique(np.linalg.norm(scaled, axis=1).round(6))), [400, 800, 1200, 1600])
    info = json.loads((out / "info.json").read_text())
    assert info["datasets"][0]["preset"] == "thesis" and info["datasets"][0]["noise_floor"] > 0
    assert (out / "coverage.png").read_bytes()[:4] == b"\x89PNG"
    # same seed, --force: identical files; without --force: refused, untouched
    before = digest(out)
    assert main(argv) == 2
    assert main(argv + ["--force"]) == 0
    assert digest(out) == before
    assert main(argv[:-3] + ["--seed", "5", "--out", str(tmp_path / "other"), "-q"]) == 0
    assert digest(tmp_path / "other") != before


def test_simulate_several_datasets_go_to_subfolders(tmp_path):
    argv = ["simulate", "dataset", "--n-datasets", "2", "--n-per-sphere", "3", "--n-test", "4",
            "--preset", "asymmetric", "--format", "npz", "--out", str(tmp_path), "-q"]
    assert main(argv) == 0
    for k in ("00", "01"):
        assert CalibrationDataset.load(tmp_path / f"dataset_{k}" / "train.npz").n_samples == 12
    a = CalibrationDataset.load(tmp_path / "dataset_00" / "test.npz").raw
    b = CalibrationDataset.load(tmp_path / "dataset_01" / "test.npz").raw
    assert not np.allclose(a, b)


def test_a_file_where_a_dataset_folder_goes_is_named_before_any_work(tmp_path, capsys):
    (tmp_path / "dataset_01").write_text("my notes")
    argv = ["simulate", "dataset", "--n-datasets", "2", "--n-per-sphere", "3", "--n-test", "4", "--out",
            str(tmp_path), "-q"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err == (f"ftcal: error: {tmp_path / 'dataset_01'} is a file, where this run makes a folder (for "
                   f"{tmp_path / 'dataset_01' / 'train.csv'}); move it or choose another --out\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dataset_01"]  # nothing written, the file kept
    assert (tmp_path / "dataset_01").read_text() == "my notes"


def test_end_to_end_artificial(tmp_path, capsys):
    data, models, ev = tmp_path / "data", tmp_path / "models", tmp_path / "eval"
    assert main(["simulate", "dataset", "--n-per-sphere", "30", "--n-test", "40", "--out", str(data), "-q"]) == 0
    assert main(["fit", str(data / "train.csv"), "--model", "linear", "--out", str(models), "-q"]) == 0
    assert main(["fit", str(data / "train.csv"), "--model", "directional", *SMALL_NET_CLI, "--out", str(models), "-q"]) == 0
    assert main(["evaluate", str(data / "test.csv"), str(models / "linear.model.npz"),
                 str(models / "directional.model.npz"), "--out", str(ev), "-q"]) == 0
    table = capsys.readouterr().out
    assert "| linear |" in table and "| directional |" in table and "| noise floor |" in table
    metrics = json.loads((ev / "metrics.json").read_text())
    assert metrics["alpha"] == 50.0  # the simulated sensor's Fmax / Tmax, from the dataset meta
    # predict's CSV, compared by hand with the reference, gives evaluate's RMSE (eq. 18, alpha 50)
    test = CalibrationDataset.load(data / "test.csv")
    for name in ("linear", "directional"):
        wrench = predict_csv(["predict", str(models / f"{name}.model.npz"), str(data / "test.csv")], capsys)
        assert wrench.shape == (40, 6)
        diff = wrench - test.wrench
        diff[:, 3:] *= 50.0
        assert np.sqrt(np.mean(diff**2)) == pytest.approx(metrics["models"][name]["rmse"], rel=1e-6)
    # the linear model sits close to the noise floor on the thesis preset, far below a zero predictor
    assert metrics["models"]["linear"]["rmse"] < 0.05 * np.sqrt(np.mean(np.hstack(
        [test.wrench[:, :3], 50 * test.wrench[:, 3:]]) ** 2))


def test_demo_quick_prints_the_table_and_writes_everything(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--quick", "--out", str(out), "-q"]) == 0
    stdout = capsys.readouterr().out
    rows = [line for line in stdout.splitlines() if line.startswith("| ")]
    assert [r.split("|")[1].strip() for r in rows[1:]] == ["linear", "comparative", "directional", "noise floor"]
    from ftcal.benchmark._demo import demo_files

    for name in demo_files():
        assert (out / name).is_file(), name
    model = ftcal.load_model(out / "models" / "directional.model.npz")
    assert model.predict(CalibrationDataset.load(out / "test.csv").raw).shape == (60, 6)
    assert main(["demo", "--quick", "--out", str(out), "-q"]) == 2  # nothing overwritten without --force


def test_benchmark_artificial_quick(tmp_path, capsys):
    argv = ["benchmark", "artificial", "--quick", "--n-datasets", "1", "--model", "linear",
            "--out", str(tmp_path), "-q"]
    assert main(argv) == 0
    assert "| linear | 1 |" in capsys.readouterr().out
    result = json.loads((tmp_path / "artificial_results.json").read_text())
    assert result["meta"]["models"] == ["linear"] and result["meta"]["n_complete"] == 1
    assert (tmp_path / "artificial_rmse_thesis.png").is_file()


# ------------------------------------------------------------------ robot path
def test_plan_writes_joint_configurations_that_reach_the_directions(tmp_path):
    assert main(["plan", "--subdivisions", "0", "--excluded-cap-deg", "0", "--out", str(tmp_path), "-q"]) == 0
    with open(tmp_path / "poses.csv") as fh:
        header = fh.readline().strip().split(",")
    table = np.loadtxt(tmp_path / "poses.csv", delimiter=",", skiprows=1)
    robot = ftcal.robot.load_robot("kuka_iiwa14")
    assert header[0] == "pose" and header[1:8] == [f"{j}_rad" for j in robot.joint_names]
    assert table.shape == (12, 13)  # an icosahedron: 12 directions, all reachable
    q, g = table[:, 1:8], table[:, 8:11]
    R = ftcal.robot.sensor_pose_in_base(robot, q)[:, :3, :3]
    gravity_in_sensor = np.einsum("nji,j->ni", R, [0.0, 0.0, -1.0])  # R^T g_base
    np.testing.assert_allclose(gravity_in_sensor, g, atol=1e-5)
    assert np.all(q >= robot.lower_limits - 1e-9) and np.all(q <= robot.upper_limits + 1e-9)
    meta = json.loads((tmp_path / "plan.json").read_text())
    assert meta["n_poses"] == 12 and meta["angle_unit"] == "rad"
    assert (tmp_path / "coverage.png").is_file()


def test_end_to_end_logs_prepare_fit_evaluate_predict(tmp_path, capsys):
    logs, data, models, ev = (tmp_path / n for n in ("logs", "data", "models", "eval"))
    assert main(["simulate", "experiment", "--subdivisions", "0", "--seed", "1", "--out", str(logs), "-q"]) == 0
    assert len(list(logs.glob("config*_load.csv"))) == 7 and len(list(logs.glob("config*_no-load.csv"))) == 7
    assert main(["prepare", str(logs), "--out", str(data), "-q"]) == 0
    ds = CalibrationDataset.load(data / "dataset.csv")
    assert sorted(set(ds.group.tolist())) == list(range(7))
    # the reference wrench is the load's weight: |F| = m g for every sample
    mass = json.loads((logs / "virtual_experiment.json").read_text())["load_mass_kg"]
    np.testing.assert_allclose(np.linalg.norm(ds.wrench[:, :3], axis=1), mass * 9.80665, rtol=1e-6)
    assert main(["fit", str(data / "dataset.csv"), "--model", "linear", "--out", str(models), "-q"]) == 0
    assert main(["evaluate", str(data / "dataset.csv"), str(models / "linear.model.npz"), "--out", str(ev), "-q"]) == 0
    capsys.readouterr()
    wrench = predict_csv(["predict", str(models / "linear.model.npz"), str(data / "dataset.csv")], capsys)
    rel = np.linalg.norm(wrench[:, :3] - ds.wrench[:, :3], axis=1) / np.linalg.norm(ds.wrench[:, :3], axis=1)
    assert np.median(rel) < 0.05  # the linear model calibrates the simulated sensor to a few per cent
    # existing logs are not overwritten
    before = digest(logs)
    assert main(["simulate", "experiment", "--subdivisions", "0", "--seed", "2", "--out", str(logs), "-q"]) == 2
    assert digest(logs) == before


def test_prepare_bad_inputs_give_one_line(tmp_path, capsys):
    assert main(["prepare", str(tmp_path / "missing_dir"), "--out", str(tmp_path / "d")]) == 2
    assert "missing_dir does not exist (a run log, or a directory of" in capsys.readouterr().err
    bad = tmp_path / "run.csv"
    bad.write_text("timestamp,run_kind\n0,load\n")
    assert main(["prepare", str(bad), "--out", str(tmp_path / "d"), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("ftcal: error: ") and "run.csv" in err[0]
    # the bag options on run logs would do nothing: refused by name, before any work
    assert main(["prepare", str(bad), "--tf", "base_link,ft_sensor", "--stamps", "receive", "--out",
                 str(tmp_path / "d"), "-q"]) == 2
    assert capsys.readouterr().err == ("ftcal: error: --tf, --stamps read ROS bags, but the inputs are run logs; drop "
                                       "them, or give the recording's bag\n")
    assert not (tmp_path / "d").exists()


def test_prepare_channel_count_is_n_channels_and_the_old_spelling_says_so(tmp_path):
    def ftcal_cli(*argv):
        return subprocess.run([sys.executable, "-m", "ftcal", *map(str, argv)], capture_output=True, text=True)

    logs = tmp_path / "logs"
    assert ftcal_cli("simulate", "experiment", "--subdivisions", "0", "--seed", "1", "--out", logs, "-q").returncode == 0
    assert ftcal_cli("prepare", logs, "--out", tmp_path / "a", "-q").returncode == 0
    n = CalibrationDataset.load(tmp_path / "a" / "dataset.csv").n_channels  # the simulated sensor's bridges
    wrong = ftcal_cli("prepare", logs, "--n-channels", n - 1, "--out", tmp_path / "x", "-q")
    assert wrong.returncode == 2 and f"{n} raw channels (s0..s{n - 1}) but {n - 1} expected" in wrong.stderr
    assert not (tmp_path / "x" / "dataset.csv").exists()
    assert ftcal_cli("prepare", logs, "--n-channels", n, "--out", tmp_path / "a", "--force", "-q").returncode == 0
    spec = ftcal_cli("prepare", logs, "--channels", "g1..g4", "--out", tmp_path / "c")  # a column spec: not here
    err = spec.stderr.strip().splitlines()
    assert spec.returncode == 2 and len(err) == 1 and not (tmp_path / "c").exists()
    assert "--channels is now --n-channels N on prepare" in err[0]


def test_benchmark_real_world_quick(tmp_path, capsys):
    argv = ["benchmark", "real-world", "--quick", "--model", "linear", "--split", "random20", "--out", str(tmp_path), "-q"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "### Split `random20`" in out and "| linear | - |" in out
    result = json.loads((tmp_path / "real_world_results.json").read_text())
    n_test = result["splits"]["random20"]["linear"]["n_test"]
    assert n_test == math.ceil(0.2 * result["dataset"]["n_samples"])  # ShuffleSplit holds out ceil(20 %)
    assert (tmp_path / "real_world_rmse.png").is_file() and any((tmp_path / "logs").iterdir())
    assert main(argv) == 2  # results exist: refused without --force


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_training_progress_bar_on_a_terminal_and_quiet_silences_it(tmp_path, monkeypatch):
    w = np.random.default_rng(0).uniform(-1, 1, size=(40, 6)) * [100, 100, 100, 2, 2, 2]
    CalibrationDataset(raw=w @ np.diag([1, 2, 3, 4, 5, 6.0]) * 1e-3, wrench=w).save(tmp_path / "t.csv")
    # 40 rows are one batch an epoch: 100 epochs to beat the mean wrench (ftcal fit refuses a network that does not)
    argv = ["fit", str(tmp_path / "t.csv"), "--model", "directional", *SMALL_NET_CLI, "--param", "phase1_epochs=100"]
    terminal = _Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    assert main(argv + ["--out", str(tmp_path / "loud")]) == 0
    text = terminal.getvalue()
    assert "directional epochs" in text and "train_loss=" in text and "valid_loss=" in text and "lr=1.0e-03" in text
    model = ftcal.load_model(tmp_path / "loud" / "directional.model.npz")
    assert model.predict(w).shape == (40, 6)
    quiet = _Terminal()
    monkeypatch.setattr("sys.stderr", quiet)
    assert main(argv + ["--out", str(tmp_path / "quiet"), "-q"]) == 0
    assert quiet.getvalue() == ""


def test_a_forced_refit_without_report_keeps_the_old_report_says_so_and_predict_warns_of_a_report_of_another_fit(
        tmp_path, capsys):
    data, out = tmp_path / "d", tmp_path / "m"
    assert main(["simulate", "dataset", "--n-per-sphere", "20", "--n-test", "40", "--out", str(data), "-q"]) == 0
    assert main(["fit", str(data / "train.csv"), "--model", "linear", "--report", "--no-baselines", "--out", str(out),
                 "-q"]) == 0
    old_report = tmp_path / "old.report.json"
    old_report.write_bytes((out / "linear.report.json").read_bytes())
    capsys.readouterr()
    assert main(["fit", str(data / "test.csv"), "--model", "linear", "--out", str(out), "-q", "--force"]) == 0
    # the report certified the replaced model, but a run replaces only what it writes (ftcal cannot tell its own
    # earlier report from a user's file of that name): kept, and said, never deleted
    names = sorted(p.name for p in out.iterdir())
    assert "linear.model.npz" in names and "linear.fit.json" in names and "linear.report.json" in names
    assert f"{out / 'linear.report.json'} was kept as it is" in capsys.readouterr().err
    model = str(out / "linear.model.npz")
    assert main(["predict", model, str(data / "test.csv"), "--range", str(old_report), "-q"]) == 0
    err = capsys.readouterr().err
    assert f"ftcal: warning: --range {old_report} certifies another model file" in err
    # the report of this very model gives no such warning
    assert main(["report", model, str(data / "test.csv"), "--no-baselines", "--out", str(tmp_path / "r"), "-q"]) == 0
    capsys.readouterr()
    assert main(["predict", model, str(data / "test.csv"), "--range", str(tmp_path / "r" / "linear.report.json"),
                 "-q"]) == 0
    assert "certifies another model file" not in capsys.readouterr().err
