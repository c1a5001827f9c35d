"""End to end: virtual experiment -> logs on disk -> dataset -> fitted calibrators."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ftcal import DirectionalCalibrator, LinearCalibrator
from ftcal.core import LogFormatError, scale_torques, wrench_rmse
from ftcal.experiment import MountingDevice, prepare_dataset, simulate_experiment
from ftcal.robot import load_robot, plan_calibration_poses, reference_wrench_at_joints
from ftcal.io import read_run_log


@pytest.fixture(scope="module")
def experiment(tmp_path_factory):
    robot = load_robot("kuka_iiwa14")
    plan = plan_calibration_poses(robot, subdivisions=1, excluded_cap_deg=0)
    out = tmp_path_factory.mktemp("virtual")
    paths = simulate_experiment(out, robot=robot, plan=plan, load_mass=2.0, random_state=7)
    return robot, plan, out, paths


def test_logs_on_disk_follow_the_format(experiment):
    robot, plan, out, paths = experiment
    assert [p.name for p in paths[:2]] == ["config0_no-load.csv", "config0_load.csv"]
    assert len(paths) == 14 and all(p.is_file() for p in paths)
    load = read_run_log(paths[1], n_channels=6, n_joints=7)
    no_load = read_run_log(paths[0])
    assert load.load_mass == 2.0 and no_load.load_mass is None
    assert set(load.run_kind) == {"load"} and set(no_load.run_kind) == {"no-load"}
    # load poses differ from the no-load ones by tenths of a degree, not more
    diff = np.degrees(np.abs(load.q - no_load.q))
    assert 0.01 < diff.mean() < 0.3 and diff.max() < 1.0
    truth = json.loads((out / "virtual_experiment.json").read_text())
    assert truth["joint_error_max_rad"] == 0.0055 and truth["n_poses"] == plan.n_poses


def test_refuses_to_overwrite(experiment):
    robot, plan, out, paths = experiment
    before = paths[0].read_text()
    with pytest.raises(LogFormatError, match="exists"):
        simulate_experiment(out, robot=robot, plan=plan)
    assert paths[0].read_text() == before


def test_linear_fit_reaches_the_simulated_noise_level(experiment):
    robot, plan, out, paths = experiment
    ds = prepare_dataset(paths, robot)
    assert ds.raw.shape == (7 * 42, 6) and sorted(set(ds.group.tolist())) == list(range(7))
    rng = np.random.default_rng(0)
    test = rng.permutation(ds.n_samples)[: ds.n_samples // 5]
    train = np.setdiff1d(np.arange(ds.n_samples), test)
    model = LinearCalibrator().fit(ds.raw[train], ds.wrench[train])
    rmse = wrench_rmse(ds.wrench[test], model.predict(ds.raw[test]), model.alpha_)
    # Noise level of the simulation: 1 % of each component of the wrench the sensor
    # carries (eq. 12), once in the load reading (mount + load), once in the no-load one (mount).
    q_load = np.vstack([read_run_log(p).q for p in paths[1::2]])
    mount = MountingDevice()
    w_mount = reference_wrench_at_joints(robot, q_load, mount.mass, mount.center_of_mass_in_sensor)
    var = (0.01 * scale_torques(ds.wrench + w_mount, model.alpha_)) ** 2 + (0.01 * scale_torques(w_mount, model.alpha_)) ** 2
    floor = float(np.sqrt(var[test].mean()))
    assert 0.5 * floor < rmse < 2.0 * floor, (rmse, floor)


def test_tiny_directional_fit_runs_on_the_dataset(experiment):
    robot, plan, out, paths = experiment
    ds = prepare_dataset(paths, robot)
    model = DirectionalCalibrator(hidden_layer_sizes=(32, 32), phase1_epochs=25, plateau_epochs=3, plateau_patience=1,
                                  max_recover_epochs=3, random_state=0).fit(ds.raw, ds.wrench)
    pred = model.predict(ds.raw)
    assert pred.shape == ds.wrench.shape and np.all(np.isfinite(pred))
    # 25 epochs learn well past the best constant (the mean wrench)
    baseline = wrench_rmse(ds.wrench, np.broadcast_to(ds.wrench.mean(axis=0), ds.wrench.shape), model.alpha_)
    assert wrench_rmse(ds.wrench, pred, model.alpha_) < 0.7 * baseline


def test_benchmark_library_side_scores_both_splits_and_plots(tmp_path):
    from ftcal.benchmark import run_real_world_benchmark
    from ftcal.calibrators import STOCK_BASELINE_NAMES

    res = run_real_world_benchmark(models=("linear",), subdivisions=0, log_dir=tmp_path / "logs",
                                   plot_path=tmp_path / "fig6.png")
    assert set(res["splits"]) == {"random20", "leave-one-config-out"}
    lin = res["splits"]["leave-one-config-out"]["linear"]
    assert lin["n_test"] == res["dataset"]["n_samples"] == 77  # every pose predicted once
    assert len(lin["per_sample_rmse"]) == 77 and lin["rmse_mean"] > 0
    # the stock baselines on the same splits, eq. 18's RMSE beside; sk_linear is the LTM
    assert set(STOCK_BASELINE_NAMES) <= set(res["splits"]["random20"])
    assert res["splits"]["random20"]["sk_linear"]["rmse"] == pytest.approx(res["splits"]["random20"]["linear"]["rmse"],
                                                                           rel=1e-6)
    assert (tmp_path / "fig6.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(list((tmp_path / "logs").glob("config*_load.csv"))) == 7
