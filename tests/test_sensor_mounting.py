"""A sensor mounted rotated or offset on the flange, without editing the URDF:
``load_robot(..., sensor_mounting=...)`` and ``--sensor-mounting`` of plan, prepare, identify-load, compensate."""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest

from ftcal import CalibrationDataset
from ftcal.core import KinematicsError
from ftcal.robot import load_robot
from ftcal.cli import main
from ftcal.robot._robot import sensor_mounting_transform, sensor_pose_in_base

MOUNTING = (0.0, 0.0, 90.0, 0.0, 0.0, 0.012)  # turned 90 deg about the flange axis on a 12 mm adapter


def test_mounted_sensor_pose_is_the_urdf_frame_composed_with_the_mounting():
    plain, mounted = load_robot(), load_robot(sensor_mounting=MOUNTING)
    q = np.array([[0.1, 0.5, -0.2, -1.0, 0.3, 1.2, 0.4], [0.0] * 7])
    M = np.eye(4)
    M[:3, :3] = pin.exp3(np.deg2rad([0.0, 0.0, 90.0]))
    M[:3, 3] = [0.0, 0.0, 0.012]
    np.testing.assert_allclose(sensor_pose_in_base(mounted, q), sensor_pose_in_base(plain, q) @ M, atol=1e-12)
    np.testing.assert_allclose(sensor_mounting_transform(M).homogeneous, M, atol=1e-15)


@pytest.mark.parametrize("bad", [(0, 0, 90), (0, 0, 0, 0, 0, 12.0), np.diag([1.0, 1.0, -1.0, 1.0]),
                                 (0, 0, 0, 1e300, 0, 0), (1e300, 0, 0, 0, 0, 0), (0, 0, 400, 0, 0, 0)])
def test_bad_mounting_is_refused(bad):
    # a typing or unit error (mm as m, a huge angle) is refused, naming it, without numpy warnings or SVD failures
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(KinematicsError, match="sensor_mounting"):
            load_robot(sensor_mounting=bad)


def test_prepare_with_mounting_gives_wrenches_in_the_mounted_sensor_frame(tmp_path, capsys):
    mounting = ",".join(str(v) for v in MOUNTING)
    assert main(["simulate", "experiment", "--subdivisions", "0", "--preset", "none", "--sensor-mounting", mounting,
                 "--out", str(tmp_path / "logs"), "-q"]) == 0
    assert main(["prepare", str(tmp_path / "logs"), "--sensor-mounting", mounting, "--out", str(tmp_path / "m"),
                 "-q"]) == 0
    # the logs name the frame they were recorded with: prepared without the mounting, they are refused ...
    assert main(["prepare", str(tmp_path / "logs"), "--out", str(tmp_path / "p"), "-q"]) == 2
    refused = capsys.readouterr().err.strip()
    assert len(refused.splitlines()) == 1 and "'ftcal_mounted_sensor'" in refused and "'ft_sensor'" in refused
    # ... and, the frame comment removed, read as if recorded at the URDF's frame: the wrenches turn by R
    (tmp_path / "bare").mkdir()
    for log in (tmp_path / "logs").glob("*.csv"):
        lines = log.read_text().splitlines(keepends=True)
        (tmp_path / "bare" / log.name).write_text("".join(ln for ln in lines if not ln.startswith("# sensor_frame:")))
    assert main(["prepare", str(tmp_path / "bare"), "--out", str(tmp_path / "p"), "-q"]) == 0
    mounted = CalibrationDataset.load(tmp_path / "m" / "dataset.csv")
    plain = CalibrationDataset.load(tmp_path / "p" / "dataset.csv")
    R = pin.exp3(np.deg2rad([0.0, 0.0, 90.0]))
    # the same gravity load, seen from a frame turned by R: F_urdf_frame = R F_mounted_frame
    np.testing.assert_allclose(plain.wrench[:, :3], mounted.wrench[:, :3] @ R.T, atol=1e-6)
    assert not np.allclose(plain.wrench[:, :3], mounted.wrench[:, :3], atol=1e-3)
    code = main(["plan", "--sensor-mounting", "0,0,90", "--out", str(tmp_path / "plan")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "rx,ry,rz" in err
