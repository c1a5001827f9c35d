"""Each error model of the artificial data, switched on alone, is measurable."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal.core import CalibrationInputError
from ftcal.simulation import ErrorModel, SampledErrors, VirtualSensor, error_preset
from ftcal.core._wrench import scale_torques

ALPHA = 50.0
FULL_SCALE = np.array([2000.0] * 3 + [40.0] * 3)


def loads(n=600, seed=0):
    """Wrenches spread over the range, in [N] and [N·m]."""
    return np.random.default_rng(seed).uniform(-1, 1, size=(n, 6)) * FULL_SCALE * 0.8


def fitted_error_map(model: ErrorModel, seed=1):
    """LTM ``A`` with scaled(erroneous) = scaled(true) @ A.T, fitted through the whole sensor pipeline."""
    sensor = VirtualSensor(errors=model, random_state=seed)
    w = loads()
    raw = sensor.read(w, noise=False)
    seen = raw @ sensor.profile.calibration_matrix.T  # back through the calibration matrix
    a_t, *_ = np.linalg.lstsq(scale_torques(w, ALPHA), scale_torques(seen, ALPHA), rcond=None)
    return a_t.T


def test_crosstalk_shows_as_a_k_sized_off_diagonal_of_a_fitted_ltm():
    a = fitted_error_map(ErrorModel(crosstalk=0.05, crosstalk_pairs=1, spread=0.0))
    off = a - np.eye(6)
    j, i = np.unravel_index(np.argmax(np.abs(off)), off.shape)
    assert i != j
    assert off[j, i] == pytest.approx(0.05, abs=1e-9)
    off[j, i] = 0.0
    np.testing.assert_allclose(off, 0.0, atol=1e-9)


def test_crosstalk_pairs_count_and_random_choice_per_dataset():
    model = ErrorModel(crosstalk=0.05, crosstalk_pairs=3)
    maps = [model.sample(FULL_SCALE, ALPHA, np.random.default_rng(s)).crosstalk for s in range(5)]
    assert all(np.count_nonzero(m) == 3 and np.all(np.diag(m) == 0) for m in maps)
    assert len({tuple(np.flatnonzero(m)) for m in maps}) > 1  # different axes in different datasets


def test_creep_is_a_gain_on_the_chosen_axes():
    a = fitted_error_map(ErrorModel(creep=0.003, creep_axes=2, spread=0.0))
    np.testing.assert_allclose(a - np.diag(np.diag(a)), 0.0, atol=1e-9)
    gains = np.sort(np.diag(a))
    np.testing.assert_allclose(gains, [1, 1, 1, 1, 1.003, 1.003], atol=1e-9)


def test_nonlinearity_reaches_gamma_times_full_scale_at_full_scale():
    model = ErrorModel(nonlinearity=0.012, nonlinearity_axes=1, spread=0.0)
    errors = model.sample(FULL_SCALE, ALPHA, np.random.default_rng(0))
    axis = int(np.flatnonzero(errors.nonlinearity_gamma)[0])
    for fraction in (1.0, 0.5, -1.0):
        w = np.zeros((1, 6))
        w[0, axis] = fraction * FULL_SCALE[axis]
        err = errors.apply_deterministic(w)[0, axis] - w[0, axis]
        # eq. 14 normalised: C (1 + γ |C/FS|^1.5) - C = γ FS |f|^1.5 f
        expected = 0.012 * FULL_SCALE[axis] * abs(fraction) ** 1.5 * fraction
        assert err == pytest.approx(expected, rel=1e-12)
    assert abs(errors.apply_deterministic(np.diag(FULL_SCALE))[axis, axis] / FULL_SCALE[axis] - 1) == pytest.approx(0.012)


def test_thesis_nonlinearity_is_about_one_percent_of_full_scale():
    gammas = [error_preset("thesis").sample(FULL_SCALE, ALPHA, np.random.default_rng(s)).nonlinearity_gamma
              for s in range(200)]
    g = np.concatenate([x[x > 0] for x in gammas])
    assert g.mean() == pytest.approx(0.01, rel=0.03)
    assert g.std() == pytest.approx(0.001, rel=0.15)  # 10 % spread
    assert np.quantile(g, 0.975) == pytest.approx(0.012, abs=0.0005)  # "max ~1.2 % FS"


def test_asymmetric_sensitivity_depends_on_the_load_direction():
    errors = ErrorModel(asymmetry=0.02, asymmetry_axes=6, spread=0.0).sample(FULL_SCALE, ALPHA, np.random.default_rng(0))
    w = np.vstack([np.diag(FULL_SCALE) * 0.5, -np.diag(FULL_SCALE) * 0.5])
    out = errors.apply_deterministic(w)
    np.testing.assert_allclose(np.diag(out[:6]) / np.diag(w[:6]), 1.01)  # + loads: gain 1 + a/2
    np.testing.assert_allclose(np.diag(out[6:]) / np.diag(w[6:]), 0.99)  # - loads: gain 1 - a/2


def test_noise_matches_the_configured_sigma():
    errors = ErrorModel(noise=0.01, spread=0.0).sample(FULL_SCALE, ALPHA, np.random.default_rng(0))
    w = loads(4000)
    noisy = errors.apply_noise(w, np.random.default_rng(1))
    eta = (noisy - w) / w
    assert eta.std() == pytest.approx(0.01, rel=0.02)
    assert abs(eta.mean()) < 0.0005
    np.testing.assert_allclose(errors.apply_deterministic(w), w, rtol=1e-14)  # noise only: no deterministic part


def test_spread_is_ten_percent_of_the_mean():
    deltas = np.concatenate([
        (ErrorModel(creep=0.003, creep_axes=6).sample(FULL_SCALE, ALPHA, np.random.default_rng(s)).creep_gain - 1)
        for s in range(300)
    ])
    assert deltas.mean() == pytest.approx(0.003, rel=0.02)
    assert deltas.std() == pytest.approx(0.0003, rel=0.1)


def test_no_errors_is_identity_and_parameters_round_trip():
    errors = ErrorModel().sample(FULL_SCALE, ALPHA, np.random.default_rng(0))
    w = loads(10)
    np.testing.assert_allclose(errors.apply_deterministic(w), w, rtol=1e-14)
    thesis = error_preset("thesis").sample(FULL_SCALE, ALPHA, np.random.default_rng(2))
    again = SampledErrors.from_dict(thesis.to_dict())
    np.testing.assert_array_equal(again.apply_deterministic(w), thesis.apply_deterministic(w))
    d = thesis.to_dict()
    assert len(d["creep_axes"]) == 3 and len(d["crosstalk_pairs"]) == 3 and len(d["nonlinearity_axes"]) == 3


def test_presets_and_bad_values():
    assert error_preset("asymmetric").asymmetry == 0.02 and error_preset("thesis").asymmetry == 0
    assert error_preset("stress").nonlinearity_axes == 6
    with pytest.raises(CalibrationInputError, match="unknown error preset 'nope'.*asymmetric"):
        error_preset("nope")
    with pytest.raises(CalibrationInputError,
                       match=r"ErrorModel.noise must be a number from 0 to 1 \(a relative magnitude, 1 = 100 %\); got "
                             r"-0.1 \(float\)"):
        ErrorModel(noise=-0.1)
    with pytest.raises(CalibrationInputError, match=r"ErrorModel.creep_axes must be an integer from 0 to 6; got 7 \(int\)"):
        ErrorModel(creep_axes=7)


@pytest.mark.parametrize("kwargs, words", [
    (dict(asymmetry=5), "asymmetry must be a number from 0 to 1 .* got 5 "),  # a gain of 1 - 5/2 < 0: a sign flip
    (dict(nonlinearity=1e308), "nonlinearity must be a number from 0 to 1"),  # overflowed into an inf reading
    (dict(noise="0.1"), r"noise must be a number .* got '0.1' \(str\)"),  # was numpy's TypeError
    (dict(spread=float("nan")), "spread must be a number from 0 to 1"),
    (dict(asymmetry_axes=2.5), r"asymmetry_axes must be an integer from 0 to 6; got 2.5 \(float\)"),
    (dict(asymmetry_axes=True), r"asymmetry_axes must be an integer from 0 to 6; got True \(bool\)"),
    (dict(crosstalk_pairs=31), "crosstalk_pairs must be an integer from 0 to 30"),
    (dict(nonlinearity_exponent=0.5), "nonlinearity_exponent must be a number from 1 to 10"),
])
def test_error_model_refuses_values_outside_its_physical_range(kwargs, words):
    with pytest.raises(CalibrationInputError, match=words):
        ErrorModel(**kwargs)
    with pytest.raises(CalibrationInputError, match=r"wrench must have shape \(n_samples, 6\)"):
        ErrorModel().sample(FULL_SCALE, ALPHA, np.random.default_rng(0)).apply_deterministic(np.ones((2, 5)))
