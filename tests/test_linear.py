"""LinearCalibrator (LTM, eq. 1-2) and the zero-load estimate."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal import LinearCalibrator
from ftcal.calibrators._zero_load import estimate_zero_reading

from conftest import affine_sensor_data


@pytest.mark.parametrize("n_channels", [6, 8, 12])
def test_ltm_recovers_known_matrix_and_offset(n_channels):
    raw, wrench, calibration, offset = affine_sensor_data(n_samples=80, n_channels=n_channels, seed=n_channels)
    model = LinearCalibrator().fit(raw, wrench)
    assert model.calibration_matrix_.shape == (6, n_channels)
    np.testing.assert_allclose(model.calibration_matrix_, calibration, rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(model.offset_, offset, rtol=1e-10, atol=1e-9)


def test_ltm_is_exact_on_affine_data_out_of_sample():
    raw, wrench, calibration, offset = affine_sensor_data(n_samples=50, seed=3)
    new_raw = np.random.default_rng(7).normal(size=(10, 6)) * 3.0
    predicted = LinearCalibrator().fit(raw, wrench).predict(new_raw)
    assert predicted.dtype == np.float64 and predicted.shape == (10, 6)
    np.testing.assert_allclose(predicted, new_raw @ calibration.T + offset, rtol=1e-9, atol=1e-8)


def test_ridge_matches_closed_form_and_shrinks():
    raw, wrench, _, _ = affine_sensor_data(n_samples=40, seed=4)
    ridge = 5.0
    model = LinearCalibrator(ridge=ridge).fit(raw, wrench)
    xc, yc = raw - raw.mean(0), wrench - wrench.mean(0)
    expected = np.linalg.solve(xc.T @ xc + ridge * np.eye(6), xc.T @ yc).T  # (X'X + rI)^-1 X'Y
    np.testing.assert_allclose(model.calibration_matrix_, expected, rtol=1e-9)
    plain = LinearCalibrator().fit(raw, wrench)
    assert np.linalg.norm(model.calibration_matrix_) < np.linalg.norm(plain.calibration_matrix_)


def test_zero_reading_estimated_by_affine_fit_and_given_tare_is_kept():
    rng = np.random.default_rng(5)
    wrench = rng.normal(size=(60, 6)) * [100, 100, 100, 2, 2, 2]
    sensitivity = rng.normal(size=(6, 6)) * 1e-3
    tare = np.array([0.5, -1.0, 2.0, 0.0, 0.25, -0.75])
    raw = wrench @ sensitivity.T + tare
    np.testing.assert_allclose(LinearCalibrator().fit(raw, wrench).zero_reading_, tare, atol=1e-10)
    given = tare + 0.01 * np.arange(6.0)  # a measured tare (one far outside the readings is refused: test_bad_input)
    np.testing.assert_array_equal(LinearCalibrator(zero_reading=given).fit(raw, wrench).zero_reading_, given)


def test_zero_reading_uses_zero_load_rows_when_present():
    # Asymmetric sensor: an affine fit is biased, but recorded zero-load rows give the tare directly.
    rng = np.random.default_rng(6)
    wrench = rng.normal(size=(60, 6))
    raw = np.where(wrench > 0, wrench, 0.5 * wrench) + 3.0
    wrench[:5] = 0.0
    raw[:5] = 3.0 + np.array([1, -1, 1, -1, 0])[:, None] * 1e-3
    np.testing.assert_allclose(estimate_zero_reading(raw, wrench), np.full(6, 3.0 + 0.0), atol=1e-12)


def test_alpha_default_and_given():
    raw, wrench, _, _ = affine_sensor_data(seed=8)
    expected = np.abs(wrench[:, :3]).max() / np.abs(wrench[:, 3:]).max()  # eq. 5 from the data
    assert LinearCalibrator().fit(raw, wrench).alpha_ == pytest.approx(expected)
    assert LinearCalibrator(alpha=50.0).fit(raw, wrench).alpha_ == 50.0
