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


def test_range_excess_counts_rows_beyond_per_axis_and_by_how_much():
    from ftcal.io import range_excess

    loads = np.array([[1.0, 0.0, 5.0], [2.0, -4.0, 22.0], [3.0, 0.5, -11.0], [0.5, 0.0, 9.0]])
    found = range_excess(loads, [0.0, 0.0, -10.0], [10.0, 1.0, 10.0], names=("Fx", "Fy", "Fz"))
    assert found.mask.tolist() == [False, True, True, False]
    fx, fy, fz = found.axes
    assert (fx.n_beyond, fy.n_beyond, fz.n_beyond) == (0, 1, 2)
    assert fy.opposite_sign == 1 and fy.largest_factor == pytest.approx(4.0)  # -4 N against a 0..1 N range
    assert fz.largest_factor == pytest.approx(2.2) and fz.opposite_sign == 0
    assert found.beyond() == (fy, fz)
    assert found.to_dict()["rows_beyond"] == 2
    halves = type(found).combined([range_excess(loads[:2], [0, 0, -10], [10, 1, 10]),
                                   range_excess(loads[2:], [0, 0, -10], [10, 1, 10])])
    assert [a.n_beyond for a in halves.axes] == [0, 1, 2] and halves.mask.tolist() == found.mask.tolist()
    assert halves.axes[2].largest_factor == pytest.approx(2.2)


def test_evaluate_says_how_far_the_loads_go_beyond_the_calibrated_range(fitted, tmp_path):
    """A validation session whose loads reach 2.5 x the calibrated range on Fz: ``evaluate`` names the axis, the
    rows and the factor (from the wrench range the model file keeps), and so do its metrics."""
    import json

    train = ftcal.CalibrationDataset.load(fitted / "data" / "train.csv")
    model = ftcal.load_model(fitted / "models" / "linear.model.npz")
    rng = np.random.default_rng(1)
    wrench = train.wrench[rng.choice(train.n_samples, 18, replace=False)].copy()
    fz = list(train.axes).index("Fz")
    top = train.wrench[:, fz].max()
    wrench[:14, fz] = np.linspace(1.1, 2.5, 14) * top  # 14 of 18 rows beyond, the largest 2.5 x
    raw = np.linalg.lstsq(model.predict(np.eye(train.n_channels)) - model.predict(np.zeros((1, train.n_channels))),
                          (wrench - model.predict(np.zeros((1, train.n_channels)))).T, rcond=None)[0].T
    ftcal.CalibrationDataset(raw=raw, wrench=wrench).save(tmp_path / "validation.csv")
    proc = _cli("evaluate", tmp_path / "validation.csv", fitted / "models" / "linear.model.npz", "--no-plots",
                "--out", tmp_path / "eval")
    assert proc.returncode == 0, proc.stderr
    line = next(x for x in proc.stderr.splitlines() if "beyond the loads" in x)
    assert f"Fz: 14 of 18 rows beyond" in line and f"up to {1.5 * top:.3g} N past the high edge" in line
    facts = json.loads((tmp_path / "eval" / "metrics.json").read_text())["models"]["linear"]["extrapolation"]
    assert facts["loads"]["rows_beyond"] == 14
    assert "beyond the readings" in proc.stderr  # the raw readings, as predict --range counts them
