"""Advice is checked before it is given: an option is proposed only where its result is not the same failure."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal.core import CalibrationInputError
from ftcal.experiment._still_poses import find_still_poses


def test_a_looser_still_tolerance_is_advised_only_when_it_finds_still_poses():
    rng = np.random.default_rng(0)
    t = np.arange(0.0, 12.0, 0.01)
    # three poses held 4 s each, with a 1 deg jitter: still, but beyond the default 0.5 deg
    q = np.repeat([[0.0, 0.0], [0.5, 0.2], [1.0, -0.3]], 400, axis=0) + np.radians(0.5) * rng.uniform(-1, 1, (1200, 2))
    reading = rng.normal(size=(1200, 6))
    with pytest.raises(CalibrationInputError) as info:
        find_still_poses(t, reading, joints=q)
    advised = info.value.settings["tolerance_deg"]
    assert advised == 2.0 and "checked: that finds still poses" in str(info.value)
    assert find_still_poses(t, reading, joints=q, tolerance_deg=advised).n_kept == 3
    # a pose moving throughout: no threshold is advised
    moving = np.c_[np.linspace(0.0, 3.0, 1200), np.zeros(1200)]
    with pytest.raises(CalibrationInputError, match="the pose moves throughout") as info:
        find_still_poses(t, reading, joints=moving)
    assert not info.value.settings


def test_a_mat_file_of_structs_only_is_told_to_save_the_fields_not_to_slice_a_struct(tmp_path, capsys):
    import scipy.io

    from ftcal.cli import main

    rng = np.random.default_rng(0)
    w = rng.normal(size=(60, 6))
    path = tmp_path / "s.mat"
    scipy.io.savemat(path, {"data": {"raw": w @ rng.normal(size=(6, 6)), "wrench": w}})
    assert main(["fit", str(path), "--out", str(tmp_path / "o"), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "holds no numeric array, only data (a struct)" in err[0], err
    assert "save(FILE, '-struct', 'data', '-v7')" in err[0] and "[:,0:8]" not in err[0]
    assert not (tmp_path / "o").exists()
