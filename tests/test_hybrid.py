"""AxisNonlinearCalibrator (the hybrid): LTM on affine data, exact for sign-dependent gains, better with
intra-axis nonlinearity, linear extrapolation in magnitude, model files, sklearn checks."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal.calibrators._axis_nonlinear import one_standard_error_choice
from ftcal import AxisNonlinearCalibrator, LinearCalibrator, load_model, save_model
from ftcal.core import CalibrationInputError, wrench_rmse


ALPHA = 1.0  # the synthetic wrenches below share one unit


def _spheres(radii, n_per_sphere: int, rng) -> np.ndarray:
    v = rng.standard_normal((n_per_sphere * len(radii), 6))
    return v / np.linalg.norm(v, axis=1, keepdims=True) * np.repeat(radii, n_per_sphere)[:, None]


class _Sensor:
    """Independent synthetic sensor: sign gains -> crosstalk -> intra-axis power law -> gauges (+ noise)."""

    def __init__(self, seed: int, asymmetric: bool, gamma: float, noise: float = 0.0):
        rng = np.random.default_rng(seed)
        self.rng = rng
        self.gauges = np.linalg.inv(np.eye(6) + 0.3 * rng.normal(size=(6, 6)))
        self.mix = np.eye(6) + 0.05 * rng.normal(size=(6, 6))
        self.gain_pos = 1 + (rng.uniform(0.03, 0.08, 6) if asymmetric else 0)
        self.gain_neg = 1 - (rng.uniform(0.03, 0.08, 6) if asymmetric else 0)
        self.gamma = gamma * rng.uniform(0.5, 1.0, 6)
        self.noise = noise
        self.offset = rng.normal(size=6) * 0.1

    def read(self, w: np.ndarray) -> np.ndarray:
        e = np.where(w > 0, self.gain_pos, self.gain_neg) * w
        e = e @ self.mix.T
        e = e * (1 + self.gamma * np.abs(e) ** 1.5)
        e = e + self.noise * self.rng.standard_normal(e.shape)
        return e @ self.gauges.T + self.offset


def _train_test(sensor: _Sensor, seed: int):
    rng = np.random.default_rng(seed)
    train = _spheres([0.2, 0.4, 0.6, 0.8], 300, rng)  # like the thesis' four spheres
    test = _spheres(rng.uniform(0.05, 1.0, 600), 1, rng)  # continuous, 20 % beyond the outer sphere
    return sensor.read(train), train, sensor.read(test), test


def test_reduces_to_the_ltm_on_affine_data():
    sensor = _Sensor(seed=1, asymmetric=False, gamma=0.0, noise=0.01)
    raw, w, raw_t, w_t = _train_test(sensor, seed=2)
    hybrid = wrench_rmse(w_t, AxisNonlinearCalibrator(alpha=ALPHA).fit(raw, w).predict(raw_t), ALPHA)
    ltm = wrench_rmse(w_t, LinearCalibrator(alpha=ALPHA).fit(raw, w).predict(raw_t), ALPHA)
    assert hybrid <= 1.03 * ltm


def test_exact_on_noise_free_affine_data():
    sensor = _Sensor(seed=3, asymmetric=False, gamma=0.0)
    raw, w, raw_t, w_t = _train_test(sensor, seed=4)
    np.testing.assert_allclose(AxisNonlinearCalibrator(alpha=ALPHA).fit(raw, w).predict(raw_t), w_t, atol=1e-9)


def test_exact_for_direction_dependent_gains():
    # + and - loads see different gains on every axis (then crosstalk): a positively homogeneous,
    # nonlinear sensor; the LTM cannot fit it, the hybrid must recover it to rounding error.
    sensor = _Sensor(seed=5, asymmetric=True, gamma=0.0)
    raw, w, raw_t, w_t = _train_test(sensor, seed=6)
    hybrid = AxisNonlinearCalibrator(alpha=ALPHA, ridge=0.0).fit(raw, w)
    np.testing.assert_allclose(hybrid.predict(raw_t), w_t, atol=1e-7)
    assert wrench_rmse(w_t, LinearCalibrator(alpha=ALPHA).fit(raw, w).predict(raw_t), ALPHA) > 1e-2


def test_beats_the_ltm_with_sign_gains_and_intra_axis_nonlinearity():
    sensor = _Sensor(seed=7, asymmetric=True, gamma=0.08, noise=0.002)
    raw, w, raw_t, w_t = _train_test(sensor, seed=8)
    hybrid = wrench_rmse(w_t, AxisNonlinearCalibrator(alpha=ALPHA).fit(raw, w).predict(raw_t), ALPHA)
    ltm = wrench_rmse(w_t, LinearCalibrator(alpha=ALPHA).fit(raw, w).predict(raw_t), ALPHA)
    assert hybrid < 0.3 * ltm


def test_extrapolates_linearly_in_magnitude():
    sensor = _Sensor(seed=9, asymmetric=True, gamma=0.05)
    raw, w, _, _ = _train_test(sensor, seed=10)
    model = AxisNonlinearCalibrator(alpha=ALPHA).fit(raw, w)
    direction = np.random.default_rng(11).standard_normal(6)
    # far beyond the training spheres along one ray, in the *reading* space: equal steps, equal increments
    zero = model.zero_reading_
    reading_dir = sensor.read(direction[None] * 0.8)[0] - zero
    k = np.array([200.0, 300.0, 400.0, 500.0])  # every loaded axis beyond its training range
    pred = model.predict(zero + k[:, None] * reading_dir)
    second_difference = pred[2:] - 2 * pred[1:-1] + pred[:-2]
    assert np.abs(second_difference).max() < 1e-9 * np.abs(pred).max()


def test_infinite_ridge_is_the_ltm():
    sensor = _Sensor(seed=20, asymmetric=True, gamma=0.05, noise=0.01)
    raw, w, raw_t, _ = _train_test(sensor, seed=21)
    hybrid = AxisNonlinearCalibrator(alpha=ALPHA, ridge=np.inf).fit(raw, w)
    ltm = LinearCalibrator(alpha=ALPHA).fit(raw, w)
    np.testing.assert_allclose(hybrid.predict(raw_t), ltm.predict(raw_t), rtol=0, atol=1e-9 * np.abs(w).max())


def test_one_standard_error_rule():
    base = np.random.default_rng(22).uniform(1.0, 2.0, 400)
    sign = np.tile([1.0, -1.0], 200)
    # candidates from flexible to simple; paired differences to candidate 0 with known mean and standard error:
    # candidate 1: mean 0; candidate 2: mean 0.002, standard error 0.1 / sqrt(400) = 0.005
    errors = np.stack([base, base + 0.01 * sign, base + 0.1 * sign + 0.002])
    assert one_standard_error_choice(errors) == 2  # within one standard error: the simplest wins
    worse = errors.copy()
    worse[2] += 0.5
    assert one_standard_error_choice(worse) == 1  # the simplest is clearly worse; the next one is not
    better = errors.copy()
    better[0] -= 0.5
    assert one_standard_error_choice(better) == 0  # the flexible one wins by many standard errors


def test_auto_ridge_follows_the_evidence():
    # cross-validation inside fit: heavy penalty (or the LTM itself, inf) where the nonlinear terms only fit
    # noise, a light one where they pay
    affine = _Sensor(seed=16, asymmetric=False, gamma=0.0, noise=0.02)
    raw, w, _, _ = _train_test(affine, seed=17)
    assert AxisNonlinearCalibrator(alpha=ALPHA).fit(raw, w).ridge_ >= 1e-2
    nonlinear = _Sensor(seed=18, asymmetric=True, gamma=0.1)
    raw, w, _, _ = _train_test(nonlinear, seed=19)
    assert AxisNonlinearCalibrator(alpha=ALPHA).fit(raw, w).ridge_ <= 1e-4


@pytest.mark.parametrize(
    "params", [dict(ridge="fast"), dict(powers=(0.0,)), dict(powers=1.5), dict(ridge=-1.0), dict(ridge=float("nan")),
               dict(n_refinements=-1),
               dict(n_refinements=1.5)],
)
def test_bad_parameters_raise_clear_errors(params):
    sensor = _Sensor(seed=12, asymmetric=False, gamma=0.0)
    raw, w, _, _ = _train_test(sensor, seed=13)
    with pytest.raises(CalibrationInputError, match="powers|ridge|n_refinements"):
        AxisNonlinearCalibrator(**params).fit(raw, w)


def test_model_file_round_trip(tmp_path):
    sensor = _Sensor(seed=14, asymmetric=True, gamma=0.05)
    raw, w, raw_t, _ = _train_test(sensor, seed=15)
    model = AxisNonlinearCalibrator(powers=(1.0, 2.0), n_refinements=2).fit(raw, w)
    loaded = load_model(save_model(model, tmp_path / "hybrid.npz"), model_type=AxisNonlinearCalibrator)
    assert loaded.get_params() == model.get_params()
    np.testing.assert_array_equal(loaded.predict(raw_t), model.predict(raw_t))


def test_model_file_round_trip_of_the_ltm_fallback(tmp_path):
    sensor = _Sensor(seed=16, asymmetric=False, gamma=0.0, noise=0.02)
    raw, w, raw_t, _ = _train_test(sensor, seed=17)
    model = AxisNonlinearCalibrator(ridge=np.inf).fit(raw, w)
    loaded = load_model(save_model(model, tmp_path / "hybrid.npz"))
    assert loaded.ridge_ == model.ridge_ == np.inf
    np.testing.assert_array_equal(loaded.predict(raw_t), model.predict(raw_t))
