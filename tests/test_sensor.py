"""Sensor profiles and the default calibration matrix."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal.core import CalibrationInputError
from ftcal.simulation import SensorProfile, VirtualSensor, default_calibration_matrix

VERTICAL, HORIZONTAL = [0, 2, 4], [1, 3, 5]  # channel order V0 H0 V1 H1 V2 H2


def test_default_profile_is_the_thesis_range():
    p = SensorProfile.default()
    assert (p.fmax, p.tmax, p.alpha, p.n_channels) == (2000.0, 40.0, 50.0, 6)
    np.testing.assert_array_equal(p.full_scale, [2000, 2000, 2000, 40, 40, 40])


def test_default_matrix_has_the_three_beam_structure():
    c = default_calibration_matrix()
    # Fz, Tx, Ty come from the vertical bridges, Fx, Fy, Tz from the horizontal ones (misalignment ~1-2 %).
    for row in (2, 3, 4):
        assert np.abs(c[row, HORIZONTAL]).max() < 0.05 * np.abs(c[row, VERTICAL]).max()
    for row in (0, 1, 5):
        assert np.abs(c[row, VERTICAL]).max() < 0.05 * np.abs(c[row, HORIZONTAL]).max()
    # Fz: the three vertical bridges share the load equally (within the ~2 % gain deviations).
    fz = c[2, VERTICAL]
    assert np.ptp(fz) / fz.mean() < 0.05
    # Tz: all three horizontal bridges, same sign.
    assert np.all(c[5, HORIZONTAL] > 0)


def test_default_matrix_gives_about_five_volts_at_full_scale():
    p = SensorProfile.default()
    raw = p.reading_from_wrench(np.diag(p.full_scale))
    # 5 V at the largest beam shear of a single-axis full-scale load, times gains within +-2.1 %.
    assert 4.8 < np.abs(raw).max() < 5.3


def test_user_matrix_with_more_channels_round_trips_through_pseudo_inverse():
    rng = np.random.default_rng(3)
    c = rng.normal(size=(6, 8)) * np.array([100.0] * 3 + [2.0] * 3)[:, None]
    p = SensorProfile(calibration_matrix=c, fmax=500.0, tmax=10.0)
    w = rng.normal(size=(20, 6)) * np.array([300.0] * 3 + [5.0] * 3)
    raw = p.reading_from_wrench(w)
    assert raw.shape == (20, 8)
    np.testing.assert_allclose(p.wrench_from_reading(raw), w, rtol=1e-9, atol=1e-9)


def test_virtual_sensor_accepts_a_6xN_matrix_and_offset():
    rng = np.random.default_rng(4)
    c = rng.normal(size=(6, 9))
    offset = np.arange(9.0)
    s = VirtualSensor(c, errors="none", zero_offset=offset, fmax=100.0, tmax=2.0)
    w = rng.uniform(-1, 1, size=(5, 6))
    raw = s.read(w)
    assert raw.shape == (5, 9)
    np.testing.assert_allclose((raw - offset) @ c.T, w, atol=1e-9)


@pytest.mark.parametrize(
    "matrix, words",
    [
        (np.ones((8, 6)), "Transpose"),
        (np.hstack([np.eye(6)[:, :3]] * 2), "rank 3"),
        (np.full((6, 6), np.nan), "NaN"),
        (np.ones(6), r"shape \(6, n_channels\)"),
    ],
)
def test_bad_matrices_are_rejected_clearly(matrix, words):
    with pytest.raises(CalibrationInputError, match=words):
        SensorProfile(calibration_matrix=matrix, fmax=1.0, tmax=1.0)


def test_bad_ranges_and_offsets_are_rejected():
    with pytest.raises(CalibrationInputError, match="tmax"):
        SensorProfile(calibration_matrix=np.eye(6), fmax=1.0, tmax=0.0)
    with pytest.raises(CalibrationInputError, match=r"zero_offset .*shape \(6,\)"):
        VirtualSensor(errors="none", zero_offset=np.zeros(4))
