"""``sample_weight`` reaches a regressor of the user's composed into a calibrator (``as_calibrator``), directly
and through an ensemble, and changes the fit exactly as calling the regressor with those weights does."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.linear_model import Ridge
from sklearn.neighbors import KNeighborsRegressor

from ftcal import EnsembleCalibrator
from ftcal.calibrators import StockCalibrator, as_calibrator
from ftcal.core import CalibrationInputError


def _data():
    rng = np.random.default_rng(3)
    w = rng.normal(size=(80, 6)) * [20, 20, 20, 1, 1, 1]
    raw = w @ rng.normal(size=(6, 6)) / 20 + 0.1 * rng.normal(size=(80, 6)) * (np.arange(80) % 2)[:, None]
    weights = np.where(np.arange(80) % 2, 0.05, 5.0)  # the noisy rows count less
    return raw, w, weights


def test_the_weights_change_a_wrapped_ridge_as_they_change_ridge_itself():
    raw, w, weights = _data()
    ridge = Ridge(alpha=3.0)
    direct = Ridge(alpha=3.0).fit(raw, w, sample_weight=weights).predict(raw)
    unweighted = Ridge(alpha=3.0).fit(raw, w).predict(raw)
    assert np.abs(direct - unweighted).max() > 1e-3 * np.abs(w).max()  # the weights matter here
    composed = as_calibrator(ridge).fit(raw, w, sample_weight=weights)
    np.testing.assert_allclose(composed.predict(raw), direct, rtol=1e-12, atol=1e-12 * np.abs(w).max())
    ensemble = EnsembleCalibrator(ridge, n_members=2, random_state=0).fit(raw, w, sample_weight=weights)
    np.testing.assert_allclose(ensemble.predict(raw), direct, rtol=1e-10, atol=1e-10 * np.abs(w).max())


def test_weights_a_regressor_cannot_take_are_refused_by_name():
    raw, w, weights = _data()
    with pytest.raises(CalibrationInputError, match="KNeighborsRegressor.fit takes no sample_weight"):
        as_calibrator(KNeighborsRegressor()).fit(raw, w, sample_weight=weights)
    with pytest.raises(CalibrationInputError, match="'sk_poly2' is fitted unweighted"):
        StockCalibrator(baseline="sk_poly2").fit(raw, w, sample_weight=weights)
