"""PolynomialCalibrator: degree 1 is the LTM, exact on polynomial sensors, model files, sklearn checks."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal import CalibrationInputError, LinearCalibrator, PolynomialCalibrator, load_model, make_calibrator, save_model



def _noisy_sensor(seed: int, n: int = 300, n_channels: int = 6):
    rng = np.random.default_rng(seed)
    raw = rng.normal(size=(n, n_channels)) * 50.0 + 7.0
    wrench = raw @ rng.normal(size=(6, n_channels)).T + rng.normal(size=(n, 6))
    return raw, wrench


@pytest.mark.parametrize("ridge", [0.0, 10.0])
@pytest.mark.parametrize("n_channels", [6, 8])
def test_degree_one_equals_the_ltm(ridge, n_channels):
    raw, wrench = _noisy_sensor(1, n_channels=n_channels)
    poly = PolynomialCalibrator(degree=1, ridge=ridge).fit(raw, wrench)  # linear terms are never penalised
    ltm = LinearCalibrator().fit(raw, wrench)
    query = _noisy_sensor(2, n_channels=n_channels)[0]
    expected = ltm.predict(query)
    np.testing.assert_allclose(poly.predict(query), expected, rtol=1e-8, atol=1e-8 * np.abs(expected).max())


def test_recovers_a_cubic_sensor_exactly():
    # wrench = A u + B u³ (element-wise cube) of the tare-corrected reading: a degree-3 polynomial
    rng = np.random.default_rng(3)
    tare = rng.normal(size=6)
    u = rng.uniform(-1, 1, size=(400, 6))
    a, b = rng.normal(size=(6, 6)), rng.normal(size=(6, 6))
    wrench = u @ a.T + (u**3) @ b.T
    model = PolynomialCalibrator(degree=3, ridge=0.0, zero_reading=tare).fit(u + tare, wrench)
    test_u = rng.uniform(-1, 1, size=(100, 6))
    np.testing.assert_allclose(model.predict(test_u + tare), test_u @ a.T + (test_u**3) @ b.T, atol=1e-8)
    assert LinearCalibrator().fit(u + tare, wrench).predict(test_u + tare).std() > 0  # sanity: data are nonlinear


def test_predict_in_chunks_matches_row_by_row():
    raw, wrench = _noisy_sensor(4)
    model = PolynomialCalibrator(degree=2).fit(raw, wrench)
    big = np.repeat(raw[:3], 3000, axis=0)  # 9000 rows: more than one prediction chunk
    out = model.predict(big)
    np.testing.assert_allclose(out[::3000], model.predict(raw[:3]), rtol=1e-12)
    np.testing.assert_allclose(out[-1], model.predict(raw[2:3])[0], rtol=1e-12)


@pytest.mark.parametrize("params", [dict(degree=0), dict(degree=6), dict(degree=2.0), dict(ridge=-1.0),
                                    dict(ridge=float("nan"))])
def test_bad_parameters_raise_clear_errors(params):
    raw, wrench = _noisy_sensor(5)
    with pytest.raises(CalibrationInputError, match="degree|ridge"):
        PolynomialCalibrator(**params).fit(raw, wrench)


def test_model_file_round_trip_and_registry(tmp_path):
    raw, wrench = _noisy_sensor(6)
    model = make_calibrator("polynomial", degree=4, ridge=1e-2).fit(raw, wrench)
    loaded = load_model(save_model(model, tmp_path / "poly.npz"))
    assert isinstance(loaded, PolynomialCalibrator) and loaded.degree == 4
    np.testing.assert_array_equal(loaded.predict(raw), model.predict(raw))
