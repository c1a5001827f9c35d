"""Artificial datasets of the thesis (IV-A) and the noise floor."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ftcal import CalibrationDataset, LinearCalibrator, make_artificial_dataset
from ftcal.core import CalibrationInputError, wrench_rmse
from ftcal.simulation import ErrorModel, SensorProfile, VirtualSensor
from ftcal.core._wrench import scale_torques


@pytest.fixture(scope="module")
def thesis_data():
    return make_artificial_dataset("thesis", random_state=7)


def test_train_spheres_have_exact_radii_before_errors(thesis_data):
    train, _, info = thesis_data
    assert train.n_samples == 5000
    assert np.bincount(train.group).tolist() == [1250] * 4
    radius = np.linalg.norm(scale_torques(train.wrench, 50.0), axis=1)
    for sphere, expected in enumerate([400.0, 800.0, 1200.0, 1600.0]):  # steps of 400 N / 8 N·m
        np.testing.assert_allclose(radius[train.group == sphere], expected, rtol=1e-12)
    # the torque part alone: 8 N·m per 400 N step at most
    assert np.linalg.norm(train.wrench[train.group == 0, 3:], axis=1).max() <= 8.0 + 1e-9


def test_test_points_are_continuous_and_in_range(thesis_data):
    _, test, _ = thesis_data
    assert test.n_samples == 1250
    assert np.abs(test.wrench[:, :3]).max() <= 2000.0
    assert np.abs(test.wrench[:, 3:]).max() <= 40.0
    radius = np.linalg.norm(scale_torques(test.wrench, 50.0), axis=1)
    assert radius.max() <= 2000.0
    # uniform in [0, 2000]: every 400 N band holds about a fifth of the points
    counts = np.histogram(radius, bins=5, range=(0, 2000))[0]
    assert counts.min() > 0.15 * 1250


def test_box_test_distribution_stays_in_range():
    _, test, _ = make_artificial_dataset("none", random_state=0, n_per_sphere=2, n_test=500, test_distribution="box")
    assert np.abs(test.wrench[:, :3]).max() <= 2000.0 and np.abs(test.wrench[:, 3:]).max() <= 40.0
    assert np.abs(test.wrench[:, 3:]).max() > 35.0  # reaches the corners of the box


def test_same_seed_same_data_other_seed_other_data():
    a = make_artificial_dataset("asymmetric", random_state=3, n_per_sphere=20, n_test=30)
    b = make_artificial_dataset("asymmetric", random_state=3, n_per_sphere=20, n_test=30)
    c = make_artificial_dataset("asymmetric", random_state=4, n_per_sphere=20, n_test=30)
    for x, y in zip(a[:2], b[:2]):
        np.testing.assert_array_equal(x.raw, y.raw)
        np.testing.assert_array_equal(x.wrench, y.wrench)
    assert a[2]["errors"] == b[2]["errors"]
    assert not np.allclose(a[0].raw, c[0].raw)


def test_without_errors_the_raw_readings_invert_the_calibration_matrix():
    profile = SensorProfile.default()
    offset = np.linspace(-0.2, 0.3, 6)
    train, test, info = make_artificial_dataset("none", random_state=0, n_per_sphere=10, n_test=10, zero_offset=offset)
    for ds in (train, test):
        np.testing.assert_allclose((ds.raw - offset) @ profile.calibration_matrix.T, ds.wrench, atol=1e-9)
    assert info["noise_floor"] == 0.0


def test_noise_floor_matches_the_configured_sigma():
    model = ErrorModel(noise=0.01, spread=0.0)
    _, test, info = make_artificial_dataset(model, random_state=1)
    # E[(w_i η_i)^2] = σ² E[w_i²]: the floor is σ times the RMS of the torque-scaled test wrench
    expected = 0.01 * np.sqrt(np.mean(scale_torques(test.wrench, 50.0) ** 2))
    assert info["noise_floor"] == pytest.approx(expected, rel=0.05)


def test_a_linear_calibrator_is_exact_without_errors_and_cannot_beat_the_noise_floor(thesis_data):
    train, test, _ = make_artificial_dataset("none", random_state=2, n_per_sphere=50, n_test=50)
    ltm = LinearCalibrator(alpha=50.0).fit(train.raw, train.wrench)
    assert wrench_rmse(test.wrench, ltm.predict(test.raw), 50.0) < 1e-6
    train, test, info = thesis_data
    ltm = LinearCalibrator(alpha=50.0).fit(train.raw, train.wrench)
    rmse = wrench_rmse(test.wrench, ltm.predict(test.raw), 50.0)
    assert 0.95 * info["noise_floor"] < rmse < 3 * info["noise_floor"]


def test_info_and_files_are_json_friendly(thesis_data, tmp_path):
    train, test, info = thesis_data
    json.dumps(info)
    assert info["sphere_radii"] == [400.0, 800.0, 1200.0, 1600.0]
    assert 0.0 < info["noise_floor"] < 20.0
    loaded = CalibrationDataset.load(train.save(tmp_path / "train.npz"))
    np.testing.assert_array_equal(loaded.raw, train.raw)
    assert loaded.meta["preset"] == "thesis"


def test_virtual_sensor_reads_fresh_noise_with_fixed_errors():
    s = VirtualSensor(errors="thesis", random_state=0)
    w = np.tile([[500.0, -200, 300, 5, -3, 2]], (3, 1))
    raw = s.read(w)
    assert not np.allclose(raw[0], raw[1])  # noise differs per sample
    clean = s.read(w, noise=False)
    np.testing.assert_array_equal(clean[0], clean[1])
    assert np.abs(raw - clean).max() < 0.05 * np.abs(clean).max()
    with pytest.raises(CalibrationInputError, match="unknown error preset"):
        VirtualSensor(errors="thesys")
    with pytest.raises(CalibrationInputError, match="wrench must have shape"):
        s.read(np.ones((2, 3)))
    with pytest.raises(CalibrationInputError, match="'test_distribution' parameter of make_artificial_dataset .* Got "
                                                    "'cube'"):
        make_artificial_dataset(random_state=0, n_per_sphere=2, n_test=2, test_distribution="cube")


@pytest.mark.parametrize("kwargs, words", [
    (dict(n_test=0), r"'n_test' parameter of make_artificial_dataset must be an int in the range \[1, 1000000\]\. "
                     "Got 0"),
    (dict(n_test=2.5), "'n_test' .* Got 2.5"),  # not silently 2 points
    (dict(n_per_sphere=10**11), "'n_per_sphere' .* Got 100000000000"),  # refused, not a numpy MemoryError
    (dict(n_test=True), "'n_test' .* must be a number, not a bool"),
    (dict(n_spheres=2.0), r"'n_spheres' .* \[1, 4\]\. Got 2.0"),
    (dict(random_state=-1), "'random_state' .* Got -1"),
    (dict(random_state="a"), "'random_state' .* Got 'a'"),
    (dict(profile="x"), "'profile' .*SensorProfile.* Got 'x'"),
    (dict(zero_offset="a"), "zero_offset must be 6 numbers, one raw value per channel; got 'a'"),
])
def test_make_artificial_dataset_refuses_bad_arguments_before_sampling(kwargs, words):
    with pytest.raises(CalibrationInputError, match=words):
        make_artificial_dataset(**{"n_per_sphere": 2, "n_test": 2, **kwargs})


def test_make_artificial_dataset_takes_numpy_integers_and_a_generator():
    a = make_artificial_dataset(random_state=np.int64(3), n_per_sphere=np.int64(2), n_test=np.int64(2))
    b = make_artificial_dataset(random_state=np.random.default_rng(3), n_per_sphere=2, n_test=2)
    np.testing.assert_array_equal(a[0].raw, b[0].raw)  # default_rng(3) either way


def test_ball_test_distribution_fills_the_force_and_torque_balls_independently():
    _, test, info = make_artificial_dataset("none", random_state=1, n_per_sphere=2, n_test=4000,
                                            test_distribution="ball")
    assert info["test_distribution"] == "ball"
    force, torque = np.linalg.norm(test.wrench[:, :3], axis=1), np.linalg.norm(test.wrench[:, 3:], axis=1)
    assert force.max() <= 2000.0 and torque.max() <= 40.0  # the rated balls, never beyond
    assert force.max() > 1900.0 and torque.max() > 38.0  # ... and up to their surface
    # uniform in a 3-D ball: P(|F| <= R/2) = 1/8 (binomial sd 0.005 at n = 4000)
    assert abs(np.mean(force <= 1000.0) - 0.125) < 0.025 and abs(np.mean(torque <= 20.0) - 0.125) < 0.025
    assert abs(np.corrcoef(force, torque)[0, 1]) < 0.1  # drawn independently
    # twice the radial set's size: rms of the torque-scaled norm sqrt(6/5) * 2000 against 2000 / sqrt(3)
    rms = np.sqrt(np.mean(np.sum(scale_torques(test.wrench, 50.0) ** 2, axis=1)))
    assert rms == pytest.approx(np.sqrt(1.2) * 2000.0, rel=0.05)


def test_reconstructed_preset_uses_ball_loads_and_puts_the_ltm_far_above_the_noise_floor():
    train, test, info = make_artificial_dataset("reconstructed", random_state=2, n_per_sphere=250, n_test=1000)
    assert info["test_distribution"] == "ball"
    assert np.count_nonzero(info["errors"]["asymmetry"]) == 6  # the sign-dependent gain on every axis
    rmse = wrench_rmse(test.wrench, LinearCalibrator().fit(train.raw, train.wrench).predict(test.raw), 50.0)
    # A gain 1 ± a/2 adds (a/2)|c| to component c; |c| is uncorrelated with every component (the loads are
    # sign-symmetric), so no affine map removes more than its mean: per component the LTM keeps at least
    # (a/2) sd(|c|). For a component of a uniform 3-D ball of radius R (2000 N torque-scaled),
    # sd(|c|) = R sqrt(19/320) = 487 N; a >= 0.16 (the 20 % mean minus two 10 % spreads) -> >= 39 N.
    bound = 0.08 * 2000.0 * np.sqrt(19 / 320)
    assert rmse > 0.9 * bound
    assert rmse > 4 * info["noise_floor"]  # noise: 1 % of rms |w| / sqrt(6) ≈ 9 N
    # the thesis' own figure (62.3 N) is of this size, not of the noise floor's
    assert 40.0 < rmse < 90.0


def test_fewer_spheres_are_the_outermost_ones():
    train, _, info = make_artificial_dataset("none", random_state=0, n_per_sphere=3, n_test=2, n_spheres=2)
    radius = np.linalg.norm(scale_torques(train.wrench, 50.0), axis=1)
    np.testing.assert_allclose(np.unique(radius.round(6)), [1200.0, 1600.0])
    assert info["sphere_radii"] == [1200.0, 1600.0] and train.group.tolist() == [0, 0, 0, 1, 1, 1]
    for bad in (0, 5, 2.5, True):
        with pytest.raises(CalibrationInputError, match="n_spheres"):
            make_artificial_dataset("none", random_state=0, n_per_sphere=3, n_test=2, n_spheres=bad)


def test_simulate_dataset_cli_takes_the_presets_test_distribution(tmp_path):
    from ftcal.cli import main

    out = tmp_path / "data"
    assert main(["simulate", "dataset", "--preset", "reconstructed", "--n-per-sphere", "5", "--n-test", "50",
                 "--out", str(out), "--quiet"]) == 0
    assert json.loads((out / "info.json").read_text())["datasets"][0]["test_distribution"] == "ball"
    assert main(["simulate", "dataset", "--preset", "reconstructed", "--test-distribution", "radial",
                 "--n-per-sphere", "5", "--n-test", "50", "--out", str(tmp_path / "radial"), "--quiet"]) == 0
    assert json.loads((tmp_path / "radial" / "info.json").read_text())["datasets"][0]["test_distribution"] == "radial"
