"""The calibration around a model (torque scale, tare and re-tare, calibrated range), recorded in one place for a
calibrator's own fit and for every wrapper (:class:`ftcal.compose._wrapper.CalibratorWrapper`)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from sklearn.linear_model import Ridge

from ftcal import (EnsembleCalibrator, HistoryCalibrator, LinearCalibrator, PolynomialCalibrator,
                   TemperatureCompensatedCalibrator, load_model)
from ftcal.core import alpha_from_wrenches

V3 = Path(__file__).parent / "data" / "model_files_v3"


def _data(n=120, seed=0):
    rng = np.random.default_rng(seed)
    w = rng.normal(size=(n, 6)) * [50, 50, 50, 1, 1, 1]
    raw = w @ rng.normal(size=(6, 6)) / 50 + 0.3 + 0.001 * rng.normal(size=(n, 6))
    return raw, w


@pytest.mark.parametrize("name", ["ensemble", "history", "stock", "temperature"])
def test_re_tared_wrapper_files_written_before_the_shared_composition_still_load(name):
    """Files written by tests/data/model_files_v3/make_files.py (main at c026f98), each re-tared."""
    model = load_model(V3 / f"{name}.model.npz")
    X = np.load(V3 / f"{name}.readings.npy")
    expected = np.load(V3 / f"{name}.expected.npy")
    # equal to the last few bits, not bit for bit: another machine's BLAS kernel sums in another order and moves the
    # last bit of a ~50 N wrench (~1e-14 N, seen on a fresh machine); a model read wrongly is off by ~0.1 N and more
    np.testing.assert_allclose(model.predict(X), expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    # the re-tare was saved and is applied: the reading it was taken at gives what the training tare gave
    tared = model.estimator_ if name == "temperature" else model  # compensation re-tares the model inside
    at_tare = tared.predict(tared.tare_reading_[None, :])
    del tared.tare_reading_
    np.testing.assert_allclose(at_tare, tared.predict(tared.zero_reading_[None, :]), rtol=1e-9, atol=1e-9)
    assert model.calibrated_range_.shape == (2, X.shape[1])
    assert not model.out_of_range(X).any()


@pytest.mark.parametrize("make", [
    lambda: EnsembleCalibrator(LinearCalibrator(), n_members=2, random_state=0),
    lambda: TemperatureCompensatedCalibrator(LinearCalibrator()),
    lambda: HistoryCalibrator(LinearCalibrator(), taus=(2.0,), cv=3),
], ids=["ensemble", "temperature", "history"])
def test_every_wrapper_takes_the_torque_scale_and_tare_of_what_it_wraps(make):
    raw, w = _data()
    model = make()
    X = raw if not isinstance(model, TemperatureCompensatedCalibrator) else \
        np.hstack([raw, np.random.default_rng(1).uniform(15, 35, size=(len(raw), 1))])
    model.fit(X, w)
    inner = model.estimators_[0] if isinstance(model, EnsembleCalibrator) else model.estimator_
    assert model.alpha_ == inner.alpha_ == pytest.approx(alpha_from_wrenches(w))
    np.testing.assert_array_equal(model.zero_reading_[:6], inner.zero_reading_)
    # the range is the wrapper's own readings' (the temperature column too), not the inner model's
    np.testing.assert_array_equal(model.calibrated_range_, [X.min(axis=0), X.max(axis=0)])


def test_a_wrapper_alpha_and_tare_reach_the_model_inside_and_a_refit_forgets_the_re_tare():
    raw, w = _data()
    zero = raw[np.argmin(np.abs(w).sum(axis=1))]
    model = HistoryCalibrator(PolynomialCalibrator(degree=1), taus=(2.0,), cv=3, alpha=5.0, zero_reading=zero)
    model.fit(raw, w)
    assert model.alpha_ == model.estimator_.alpha_ == 5.0
    np.testing.assert_array_equal(model.zero_reading_, zero)
    np.testing.assert_array_equal(model.estimator_.zero_reading_, zero)
    model.retare(raw[:1].repeat(4, axis=0) + 1e-4 * np.arange(4)[:, None])
    assert hasattr(model, "tare_reading_")
    assert not hasattr(model.fit(raw, w), "tare_reading_")
    # the inner calibrator's own torque scale holds when the wrapper leaves alpha None
    assert HistoryCalibrator(LinearCalibrator(alpha=7.0), taus=(2.0,), cv=3).fit(raw, w).alpha_ == 7.0


def test_an_ensemble_passes_the_wrench_axes_its_targets_name_to_its_members():
    """Fz, Tx, Ty of a plate: the members scale the two torques, as a lone calibrator on the same table does."""
    raw, w = _data()
    y = pd.DataFrame(w[:, 2:5], columns=["Fz", "Tx", "Ty"])
    alone = LinearCalibrator().fit(raw, y)
    model = EnsembleCalibrator(LinearCalibrator(), n_members=2, random_state=0).fit(raw, y)
    assert list(model.axes_) == list(model.estimators_[0].axes_) == ["Fz", "Tx", "Ty"]
    assert model.alpha_ == alone.alpha_ != 1.0
    np.testing.assert_allclose(model.predict(raw), alone.predict(raw))


def test_a_users_regressor_inside_a_wrapper_gets_the_calibration_around_it():
    raw, w = _data()
    model = EnsembleCalibrator(Ridge(alpha=1e-6), n_members=2, random_state=0).fit(raw, w)
    np.testing.assert_allclose(model.predict(raw), Ridge(alpha=1e-6).fit(raw, w).predict(raw), atol=1e-8)
    moved = raw + 0.05  # the zero moved: a re-tare at the new zero brings the training wrenches back
    model.retare(model.zero_reading_[None, :].repeat(4, axis=0) + 0.05 + 1e-4 * np.arange(4)[:, None])
    np.testing.assert_allclose(model.predict(moved), Ridge(alpha=1e-6).fit(raw, w).predict(raw), atol=1e-3 * 50)


class _DeclaredRidge(Ridge):
    """A user's regressor that declares what it is (ftcal tags on a scikit-learn regressor)."""

    def __sklearn_tags__(self):
        from ftcal.calibrators._base import declare

        return declare(super().__sklearn_tags__(), cost="closed_form", family="linear",
                       min_training_rows=lambda n_channels: n_channels + 2)


def test_a_users_regressor_keeps_the_tags_it_declares_through_the_composition():
    from ftcal.calibrators import as_calibrator
    from ftcal.calibrators._base import calibration_tags

    composed = calibration_tags(as_calibrator(_DeclaredRidge()))
    assert (composed.cost, composed.family, composed.min_training_rows(6), composed.onnx) == \
        ("closed_form", "linear", 8, False)
    wrapped = calibration_tags(TemperatureCompensatedCalibrator(_DeclaredRidge()))
    assert (wrapped.cost, wrapped.min_training_rows(7)) == ("closed_form", 8)  # 6 channels + the temperature
    plain = calibration_tags(as_calibrator(Ridge()))  # declares nothing: a costly model of unknown kind
    assert (plain.cost, plain.family) == ("heavy", "")
