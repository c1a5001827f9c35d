"""EnsembleCalibrator: the mean of its seeded members, reproducible, registry and model files, sklearn checks."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal.core import CalibrationInputError
from ftcal import (ComparativeCalibrator, DirectionalCalibrator, EnsembleCalibrator, LinearCalibrator, load_model,
                   make_calibrator, save_model)

from conftest import TINY_SCHEDULE, affine_sensor_data


@pytest.fixture(scope="module")
def data():
    raw, wrench, _, _ = affine_sensor_data(n_samples=80, seed=21)
    return raw, wrench


@pytest.fixture(scope="module")
def fitted(data):
    return EnsembleCalibrator(DirectionalCalibrator(**TINY_SCHEDULE), n_members=3, random_state=0).fit(*data)


def test_prediction_is_the_mean_of_the_members(fitted, data):
    raw = data[0]
    members = np.stack([m.predict(raw) for m in fitted.estimators_])
    np.testing.assert_allclose(fitted.predict(raw), members.sum(axis=0) / 3, rtol=1e-12)
    assert len({tuple(m.predict(raw[:1]).ravel()) for m in fitted.estimators_}) == 3  # members really differ


def test_members_are_seeded_from_random_state(fitted, data):
    again = EnsembleCalibrator(DirectionalCalibrator(**TINY_SCHEDULE), n_members=3, random_state=0).fit(*data)
    np.testing.assert_array_equal(again.predict(data[0]), fitted.predict(data[0]))
    assert [m.random_state for m in fitted.estimators_] == [int(s) for s in fitted.member_seeds_]
    assert len(set(fitted.member_seeds_)) == 3
    assert fitted.alpha_ == fitted.estimators_[0].alpha_ and fitted.n_features_in_ == data[0].shape[1]


def test_registry_names_route_the_schedule_to_the_members():
    ens = make_calibrator("directional_ensemble", schedule="short", random_state=1, n_members=4, alpha=50.0)
    assert ens.n_members == 4 and ens.random_state == 1
    assert ens.estimator.phase1_epochs == 150 and ens.estimator.alpha == 50.0  # the "short" directional schedule
    assert isinstance(make_calibrator("comparative_ensemble").estimator, ComparativeCalibrator)


def test_model_file_round_trip(fitted, data, tmp_path):
    loaded = load_model(save_model(fitted, tmp_path / "ensemble.npz"))
    assert isinstance(loaded, EnsembleCalibrator) and len(loaded.estimators_) == 3
    assert loaded.estimator.get_params() == fitted.estimator.get_params()
    np.testing.assert_array_equal(loaded.predict(data[0]), fitted.predict(data[0]))


@pytest.mark.parametrize(
    "kwargs, match",
    [(dict(n_members=0), "n_members"), (dict(n_members=2.5), "n_members"), (dict(estimator="directional"), "estimator")],
)
def test_bad_parameters_raise_clear_errors(data, kwargs, match):
    with pytest.raises(CalibrationInputError, match=match):
        EnsembleCalibrator(**kwargs).fit(*data)


def test_ensemble_of_deterministic_models_equals_the_model(data):
    ens = EnsembleCalibrator(LinearCalibrator(), n_members=2, random_state=0).fit(*data)
    np.testing.assert_allclose(ens.predict(data[0]), LinearCalibrator().fit(*data).predict(data[0]), rtol=1e-12)


def test_an_ensemble_too_large_for_memory_is_refused_before_any_member_is_built():
    from ftcal.core._memory import MemoryLimitError

    raw, w = np.random.default_rng(0).normal(size=(40, 6)), np.random.default_rng(1).normal(size=(40, 6))
    member = DirectionalCalibrator(phase1_epochs=1, plateau_epochs=0, max_recover_epochs=0, hidden_layer_sizes=(512, 512))
    with pytest.raises(MemoryLimitError, match=r"1000000 x DirectionalCalibrator.*use fewer members"):
        EnsembleCalibrator(member, n_members=10**6).fit(raw, w)
    with pytest.raises(ValueError, match="n_jobs"):
        EnsembleCalibrator(member, n_members=2, n_jobs=0).fit(raw, w)
