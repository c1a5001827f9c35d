"""PolynomialCalibrator: degree 1 is the LTM, exact on polynomial sensors, model files, sklearn checks."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal.core import CalibrationInputError
from ftcal import LinearCalibrator, PolynomialCalibrator, load_model, make_calibrator, save_model



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


def offset_sensor(n_groups=8, rows=40, seed=0):
    """An affine 6-channel sensor in ``n_groups`` poses: each pose carries its own load (a tool's weight) plus
    loads varying within it, and shifts all its readings by an offset of its own (the offsets sum to zero over the
    poses, so the mean of the poses' intercepts is the sensor's own); noise-free."""
    rng = np.random.default_rng(seed)
    groups = np.repeat(np.arange(n_groups), rows)
    pose_load = rng.normal(size=(n_groups, 6)) * 3.0
    wrench = pose_load[groups] + rng.normal(size=(len(groups), 6))
    mixing = rng.normal(size=(6, 6)) + 3.0 * np.eye(6)
    offsets = rng.normal(size=(n_groups, 6)) + 0.5 * pose_load  # lined up with the poses' loads: a bias for the LTM
    offsets -= offsets.mean(axis=0)
    raw = wrench @ mixing.T + 2.0 + offsets[groups]
    return raw, wrench, groups, mixing


def test_group_offsets_recover_the_map_that_offsets_bias():
    """Offsets that move with each pose's load bias the plain LTM's slopes; with one intercept per group the map is
    learnt from the variation within poses and is exact (noise-free data, offsets summing to zero)."""
    raw, wrench, groups, mixing = offset_sensor()
    test_wrench = np.random.default_rng(9).normal(size=(50, 6)) * 3.0
    test_raw = test_wrench @ mixing.T + 2.0  # a new pose without offset
    model = PolynomialCalibrator(degree=1, group_offsets=True, alpha=1.0).fit(raw, wrench, groups=groups)
    np.testing.assert_allclose(model.predict(test_raw), test_wrench, atol=1e-8)
    plain = PolynomialCalibrator(degree=1, alpha=1.0).fit(raw, wrench)
    assert np.abs(plain.predict(test_raw) - test_wrench).max() > 0.1  # the bias the offsets cause (O(1) here)


def test_group_offsets_without_groups_warn_and_change_nothing_and_model_files_keep_them(tmp_path):
    raw, wrench, groups, _ = offset_sensor()
    with pytest.warns(UserWarning, match="group_offsets=True but fit.. got no groups"):
        a = PolynomialCalibrator(degree=2, ridge=0.01, group_offsets=True).fit(raw, wrench)
    b = PolynomialCalibrator(degree=2, ridge=0.01).fit(raw, wrench)
    np.testing.assert_array_equal(a.predict(raw), b.predict(raw))
    fitted = PolynomialCalibrator(degree=2, ridge=0.01, group_offsets=True).fit(raw, wrench, groups=groups)
    save_model(fitted, tmp_path / "m.npz")
    loaded = load_model(tmp_path / "m.npz")
    assert loaded.group_offsets is True
    np.testing.assert_array_equal(loaded.predict(raw), fitted.predict(raw))


@pytest.mark.parametrize("make_groups", [lambda g: np.arange(len(g)), lambda g: g],
                         ids=["one_row_per_group", "loads_constant_within_groups"])
def test_group_offsets_refuse_groups_within_which_loads_do_not_vary(make_groups):
    raw, wrench, groups, _ = offset_sensor()
    if make_groups(groups) is groups:  # every pose holds one load only: nothing varies within a pose
        wrench = wrench.copy()
        for g in np.unique(groups):
            wrench[groups == g] = wrench[groups == g][0]
    with pytest.raises(CalibrationInputError, match="loads vary within the .* groups by 0.00%"):
        PolynomialCalibrator(degree=1, group_offsets=True).fit(raw, wrench, groups=make_groups(groups))


def test_group_offsets_tare_is_the_mean_groups_so_a_retare_stays_exact():
    """The estimated tare is the mean group's reading at zero load (the offsets sum to zero here: the sensor's own
    tare, 2.0 on every channel), so the model outputs zero there and a re-tare to readings at zero load is exact."""
    raw, wrench, groups, mixing = offset_sensor()
    model = PolynomialCalibrator(degree=1, group_offsets=True, alpha=1.0).fit(raw, wrench, groups=groups)
    np.testing.assert_allclose(model.zero_reading_, 2.0, atol=1e-8)
    np.testing.assert_allclose(model.predict(model.zero_reading_[None]), 0.0, atol=1e-8)
    shifted = np.full((5, 6), 2.5)  # the sensor later reads 2.5 at zero load
    model.retare(shifted)
    np.testing.assert_allclose(model.predict(shifted), 0.0, atol=1e-8)


def test_group_offsets_take_a_wrench_of_rank_three():
    """One tool at a fixed lever arm gives torques c x F: a wrench of rank 3, loads still varying within every pose."""
    rng = np.random.default_rng(4)
    groups = np.repeat(np.arange(6), 40)
    force = rng.normal(size=(6, 3))[groups] * 5.0 + rng.normal(size=(240, 3))
    wrench = np.hstack([force, np.cross([0.0, 0.0, 0.1], force)])
    raw = wrench @ rng.normal(size=(6, 6)).T + rng.normal(size=(6, 6))[groups] + 0.001 * rng.normal(size=(240, 6))
    model = PolynomialCalibrator(degree=1, group_offsets=True, alpha=1.0).fit(raw, wrench, groups=groups)
    assert np.isfinite(model.predict(raw)).all()
