"""``predict --range`` of a re-tared model: the calibrated range moves with the zero, as the model's own range does."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import ftcal


def _cli(*args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "ftcal", *map(str, args)], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    root = tmp_path_factory.mktemp("retare_range")
    assert _cli("simulate", "dataset", "--n-per-sphere", "25", "--n-test", "100", "--out", root / "data",
                "-q").returncode == 0
    proc = _cli("fit", root / "data" / "train.csv", "--model", "linear", "--out", root / "models", "-q")
    assert proc.returncode == 0, proc.stderr
    return root


@pytest.mark.parametrize("drift_of_span", [0.0, 0.3, -0.6])
def test_range_flags_of_a_retared_model_are_its_own(fitted, tmp_path, drift_of_span):
    """The zero moves by a fraction of each channel's training span; the re-tared model flags the drifted readings
    by its own range, and ``--range`` (the training dataset, recorded before the re-tare) flags the same rows."""
    model = ftcal.load_model(fitted / "models" / "linear.model.npz")
    low, high = model.calibrated_range_
    drift = drift_of_span * (high - low)
    rng = np.random.default_rng(0)
    noise = 1e-3 * (high - low)
    zero_load = model.zero_reading_ + drift + rng.normal(size=(50, len(drift))) * noise
    np.savetxt(tmp_path / "zero.csv", zero_load, delimiter=",")
    retared = tmp_path / "retared.model.npz"
    proc = _cli("retare", fitted / "models" / "linear.model.npz", tmp_path / "zero.csv", "--output", retared, "-q")
    assert proc.returncode == 0, proc.stderr

    test = ftcal.CalibrationDataset.load(fitted / "data" / "test.csv")
    readings = test.raw + drift  # the same loads, measured after the zero moved
    np.savetxt(tmp_path / "live.csv", readings, delimiter=",")
    own = ftcal.load_model(retared).out_of_range(readings)
    proc = _cli("predict", retared, tmp_path / "live.csv", "--range", fitted / "data" / "train.csv",
                "--output", tmp_path / "w.csv")
    assert proc.returncode == 0, proc.stderr
    flags = np.loadtxt(tmp_path / "w.csv", delimiter=",", skiprows=1)[:, -1].astype(bool)
    np.testing.assert_array_equal(flags, own)
    assert 0 < own.sum() < len(own)  # the test's loads reach beyond the training span on some rows only
    assert f"{int(own.sum())} of {len(own)} readings lie beyond the calibrated range" in proc.stderr
