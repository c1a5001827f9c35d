"""Bad input gets a clear error naming what is wrong and how to fix it (never NaN, never a torch trace)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from skorch.callbacks import EpochTimer
from sklearn.base import clone
from sklearn.exceptions import NotFittedError

import ftcal
from ftcal import CalibrationDataset, DirectionalCalibrator, LinearCalibrator
from ftcal.core import CalibrationInputError, DatasetFileError

from conftest import affine_sensor_data


@pytest.fixture
def data():
    raw, wrench, _, _ = affine_sensor_data(n_samples=40, seed=21)
    return raw, wrench


def test_nan_in_x_names_x_and_first_row(tiny_calibrator, data):
    raw, wrench = data
    raw[7, 2] = np.nan
    raw[9, 0] = np.nan
    with pytest.raises(CalibrationInputError, match=r"X \(raw readings\) contains NaN or inf: first at row 7, column 2"):
        tiny_calibrator.fit(raw, wrench)


def test_inf_in_y_names_y_and_first_row(tiny_calibrator, data):
    raw, wrench = data
    wrench[3, 4] = -np.inf
    with pytest.raises(CalibrationInputError, match=r"y \(reference wrenches\) contains NaN or inf: first at row 3"):
        tiny_calibrator.fit(raw, wrench)


def test_nan_at_predict_is_an_error_not_a_nan_result(tiny_calibrator, data):
    raw, wrench = data
    model = tiny_calibrator.fit(raw, wrench)
    bad = raw[:5].copy()
    bad[1, 1] = np.inf
    with pytest.raises(CalibrationInputError, match="row 1"):
        model.predict(bad)


@pytest.mark.parametrize("shape", [(40, 5), (40,), (40, 7)])
def test_targets_of_another_width_are_plain_regression(tiny_calibrator, data, shape):
    """A calibrator is a regressor of any targets; only a 6-wide y is a wrench with torques to scale."""
    raw, wrench = data
    y = wrench[:, :5] if shape == (40, 5) else wrench[:, 0] if shape == (40,) else np.hstack([wrench, wrench[:, :1]])
    model = tiny_calibrator.fit(raw, y)
    assert model.predict(raw).shape == shape  # a 1-D y gives 1-D predictions, as in scikit-learn
    assert model.n_outputs_ == (1 if len(shape) == 1 else shape[1])
    if not hasattr(model, "net_") and not hasattr(model, "estimators_"):  # exact models: an affine target fits
        np.testing.assert_allclose(model.predict(raw), y, atol=1e-6 * np.abs(y).max())


def test_channel_count_mismatch_at_predict(tiny_calibrator, data):
    raw, wrench = data
    model = tiny_calibrator.fit(raw, wrench)
    with pytest.raises(ValueError, match=f"X has 5 features, but {type(model).__name__} is expecting 6 features"):
        model.predict(raw[:, :5])


def test_predict_before_fit(tiny_calibrator, data):
    with pytest.raises(NotFittedError, match="not fitted yet"):
        tiny_calibrator.predict(data[0])


def test_fewer_samples_than_the_ltm_needs(tiny_calibrator):
    raw, wrench, _, _ = affine_sensor_data(n_samples=8, n_channels=8, seed=1)  # needs 8 + 1 = 9
    with pytest.raises(CalibrationInputError, match=r"X has 8 sample\(s\), but \w+ needs at least 9.*record more"):
        tiny_calibrator.fit(raw, wrench)


def test_fewer_than_three_channels_are_refused_where_calibration_data_enter(data):
    raw, wrench = data
    with pytest.raises(DatasetFileError, match=r"raw has 2 channel\(s\).*at least 3 raw channels"):
        CalibrationDataset(raw=raw[:, :2], wrench=wrench)
    with pytest.raises(DatasetFileError, match=r"wrench must have shape \(n_samples, n_axes\), 1 to 6 axes"):
        CalibrationDataset(raw=raw, wrench=np.hstack([wrench, wrench[:, :1]]))  # a seventh axis
    with pytest.raises(DatasetFileError, match=r"axes \('Fx', 'Fy', 'Tz', 'Fz'\) must name"):
        CalibrationDataset(raw=raw, wrench=wrench[:, :4], axes=("Fx", "Fy", "Tz", "Fz"))


def test_mismatched_lengths(tiny_calibrator, data):
    raw, wrench = data
    with pytest.raises(ValueError, match="inconsistent numbers of samples"):
        tiny_calibrator.fit(raw, wrench[:-1])


def test_zero_reading_of_wrong_shape(tiny_calibrator, data):
    raw, wrench = data
    # an ensemble passes the tare on to its members
    key = "zero_reading" if "zero_reading" in tiny_calibrator.get_params(deep=False) else "estimator__zero_reading"
    model = clone(tiny_calibrator).set_params(**{key: np.zeros(5)})
    with pytest.raises(CalibrationInputError, match=r"zero_reading must have shape \(6,\).*got shape \(5,\)"):
        model.fit(raw, wrench)


@pytest.mark.parametrize("alpha", [-1.0, 0.0, np.nan, "50", 1e200, 5e-324, np.inf])
def test_bad_alpha(data, alpha):
    # the parameter table (_parameter_constraints): named parameter, allowed range (lever arms 1 µm - 1 km),
    # value given
    with pytest.raises(CalibrationInputError, match=r"The 'alpha' parameter of LinearCalibrator must be a float in the "
                                                     r"range \[0\.001, 1000000\.0\] or None\. Got .* instead"):
        LinearCalibrator(alpha=alpha).fit(*data)


@pytest.mark.parametrize("alpha", [-1.0, 0.0, np.nan, np.inf, "50", True, None])
def test_metrics_refuse_a_bad_alpha(alpha):
    y = np.zeros((3, 6))
    for call in (lambda: ftcal.core.wrench_rmse(y, y, alpha), lambda: ftcal.core.per_sample_rmse(y, y, alpha),
                 lambda: ftcal.core.scale_torques(y, alpha), lambda: ftcal.core.unscale_torques(y, alpha)):
        with pytest.raises(CalibrationInputError, match=r"alpha must be a finite torque scale > 0 \[1/m\].*got"):
            call()


def test_metrics_say_when_alpha_overflows_instead_of_returning_inf():
    # 1e200 N·m·(1/m) of torque error squared exceeds float64's ~1.8e308: an error naming alpha, no inf, no warning
    y = np.zeros((2, 6))
    p = y + np.array([0, 0, 0, 1.0, 0, 0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(CalibrationInputError, match=r"the RMSE overflows float64.*alpha = 1e\+200"):
            ftcal.core.wrench_rmse(y, p, 1e200)
        with pytest.raises(CalibrationInputError, match=r"by alpha = 1e\+308 1/m overflows float64"):
            ftcal.core.scale_torques(p * 10, 1e308)
        with pytest.raises(CalibrationInputError, match=r"dividing the torques .* overflows"):
            ftcal.core.unscale_torques(p, 5e-324)


@pytest.mark.parametrize("make, kind", [
    (lambda X: X > 0, "booleans"), (lambda X: X.astype("datetime64[us]"), "dates"),
    (lambda X: X.astype("timedelta64[s]"), "time spans"), (lambda X: X.astype(str), "text"),
])
def test_non_measurement_dtypes_are_refused_not_converted(data, make, kind):
    raw, wrench = data
    with pytest.raises(CalibrationInputError, match=rf"X has dtype .* \({kind}\) and shape \({len(raw)}, 6\)"):
        LinearCalibrator().fit(make(raw), wrench)
    with pytest.raises(CalibrationInputError, match=rf"y has dtype .* \({kind}\)"):
        LinearCalibrator().fit(raw, make(wrench))
    model = LinearCalibrator().fit(raw, wrench)
    with pytest.raises(CalibrationInputError, match=rf"X has dtype .* \({kind}\)"):
        model.predict(make(raw))


def test_masked_values_are_refused_an_unmasked_array_is_used(data):
    raw, wrench = data
    masked = np.ma.masked_array(raw, mask=np.zeros(raw.shape, bool))
    masked.mask[3, 2] = True
    with pytest.raises(CalibrationInputError, match=r"X is a masked array with 1 masked value\(s\).*drop the masked rows"):
        LinearCalibrator().fit(masked, wrench)
    plain = LinearCalibrator().fit(np.ma.masked_array(raw), wrench)  # nothing masked: the values are the data
    np.testing.assert_array_equal(plain.predict(raw), LinearCalibrator().fit(raw, wrench).predict(raw))


def test_a_given_tare_far_outside_the_training_readings_is_refused(data):
    raw, wrench = data
    tare = np.median(raw, axis=0)
    LinearCalibrator(zero_reading=tare).fit(raw, wrench)  # a reading among the training ones: accepted
    tare[2] = 1e6 * np.abs(raw).max()
    with pytest.raises(CalibrationInputError, match=r"zero_reading\[2\] = .* lies far outside the readings channel s2"):
        LinearCalibrator(zero_reading=tare).fit(raw, wrench)


@pytest.mark.parametrize(
    "params, message",
    [
        (dict(hidden_layer_sizes=()), "hidden_layer_sizes must be a non-empty tuple"),
        (dict(hidden_layer_sizes=(8, 0)), "each entry of it an integer >= 1"),
        (dict(callbacks=[42]), "callbacks must hold skorch callbacks"),
        (dict(callbacks=[("p", "progress")]), "callbacks must hold skorch callbacks"),
        (dict(callbacks=[()]), "callbacks must hold skorch callbacks"),
        (dict(callbacks=[(1, EpochTimer())]), "callbacks must hold skorch callbacks"),
        (dict(callbacks=[(EpochTimer(),)]), "callbacks must hold skorch callbacks"),
        (dict(phase1_epochs=0), r"'phase1_epochs' parameter of DirectionalCalibrator must be an int in the range \[1, inf\) or None\. "
                             "Got 0 instead"),
        (dict(lr=-0.1), r"'lr' parameter of DirectionalCalibrator must be a float in the range \(0(\.0)?, inf\)\. "
                        "Got -0.1 instead"),
        (dict(validation_fraction=0.9), r"'validation_fraction' parameter .* range \(0(\.0)?, 0\.5\] or None\. Got 0\.9"),
        (dict(min_relative_magnitude=2.0), r"'min_relative_magnitude' parameter .* range \[0(\.0)?, 1(\.0)?\]\. Got 2\.0"),
        (dict(phase1_epochs=True), r"'phase1_epochs' parameter .* Got True instead"),
    ],
)
def test_bad_network_parameters(data, params, message):
    with pytest.raises(CalibrationInputError, match=message):
        DirectionalCalibrator(**params).fit(*data)


def test_bad_ridge(data):
    with pytest.raises(CalibrationInputError, match=r"The 'ridge' parameter of LinearCalibrator must be a float in the "
                                                     r"range \[0(\.0)?, inf\)\. Got -1\.0 instead"):
        LinearCalibrator(ridge=-1.0).fit(*data)


def test_only_zero_load_rows(data):
    raw, wrench = data
    with pytest.raises(CalibrationInputError, match="nothing to calibrate from"):
        DirectionalCalibrator(zero_reading=np.zeros(6)).fit(np.zeros_like(raw), wrench)
    one_load = np.zeros_like(wrench)
    one_load[0] = wrench[0]  # the readings vary, but only one row carries a load
    with pytest.raises(CalibrationInputError, match="directional model needs loaded samples"):
        DirectionalCalibrator(zero_reading=np.zeros(6)).fit(raw, one_load)


def test_containers_scikit_learn_refuses_with_a_typeerror_get_an_input_error(data):
    # a ValueError subclass naming X and the fix, not numpy's or scikit-learn's TypeError
    import pandas as pd
    import scipy.sparse as sp

    raw, wrench = data
    cases = {
        "is None; pass the raw readings": None,
        "is not a rectangular table": [list(r) for r in raw[:-1]] + [list(raw[-1, :3])],
        "is an np.matrix": np.asmatrix(raw),
        "Sparse data was passed for X \\(csr_matrix": sp.csr_matrix(raw),
        "X's column names mix text and other types": pd.DataFrame(raw, columns=[0, 1, 2, "a", "b", "c"]),
    }
    for message, X in cases.items():
        with pytest.raises(CalibrationInputError, match=f"^X {message}|^{message}"):
            LinearCalibrator().fit(X, wrench)
    model = LinearCalibrator().fit(raw, wrench)
    with pytest.raises(CalibrationInputError, match="^X is None"):
        model.predict(None)


def test_a_derived_alpha_stays_in_the_range_a_given_one_must_meet(data):
    # loads through the sensor's origin: torques that are noise next to the forces; auto passes the derived alpha to
    # its candidates as their parameter, so it must meet the parameter's range
    from ftcal import AutoCalibrator

    raw, wrench = data
    wrench = wrench.copy()
    wrench[:, 3:] *= 1e-9
    assert LinearCalibrator().fit(raw, wrench).alpha_ == 1e6
    wrench[:, 3:] *= 1e18
    wrench[:, :3] *= 1e-9
    assert LinearCalibrator().fit(raw, wrench).alpha_ == 1e-3
    auto = AutoCalibrator(candidates=[("linear", LinearCalibrator())], baselines=False, stack=False, cv=3)
    assert auto.fit(raw, wrench).alpha_ == 1e-3


def test_unscaling_multiplies_by_the_reciprocal_bit_for_bit():
    # every simulated dataset and cached benchmark record (their data fingerprints) was made with torques times
    # 1 / alpha; dividing by alpha differs in the last bit and made every cached record "of other data"
    rng = np.random.default_rng(0)
    w = rng.normal(size=(1000, 6)) * 37.0
    for alpha in (50.0, 3.0, 7.1, 1e-3, 1e6):
        np.testing.assert_array_equal(ftcal.core.unscale_torques(w, alpha)[:, 3:], w[:, 3:] * (1.0 / alpha))
        np.testing.assert_array_equal(ftcal.core.scale_torques(w, alpha)[:, 3:], w[:, 3:] * alpha)
