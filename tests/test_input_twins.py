"""One recording given twice (two names, or twice in a folder) is refused by its content: it would count its poses
twice and put its twins in different folds, so a drift or a model would be judged on its own rows."""

from __future__ import annotations

import shutil

import numpy as np
from scipy.spatial.transform import Rotation

from ftcal.cli import main
from ftcal.experiment import ToolLoad
from ftcal.io._bags import write_bag


def _pose_file(path, seed):
    tool = ToolLoad(mass=1.3, center_of_mass=np.array([0.012, -0.008, 0.065]), bias=np.array([1.5, -2, 0.7, 0, 0, 0]))
    R = Rotation.random(12, random_state=seed).as_matrix()
    W = tool.gravity_wrench(R) + np.random.default_rng(seed).normal(size=(12, 6)) * 0.01
    rows = np.column_stack([Rotation.from_matrix(R).as_quat(), W])
    path.write_text("qx,qy,qz,qw,Fx,Fy,Fz,Tx,Ty,Tz\n" + "".join(",".join(repr(float(v)) for v in r) + "\n"
                                                            for r in rows))
    return path


def test_a_pose_file_given_twice_is_refused_and_two_recordings_are_read(tmp_path, capsys):
    a = _pose_file(tmp_path / "a.csv", 1)
    twin = tmp_path / "renamed.csv"
    shutil.copy(a, twin)
    out = tmp_path / "t"
    assert main(["identify-load", str(a), str(twin), "--out", str(out), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{twin} holds the same pose file as {a} (identical content)" in err[0], err
    assert not out.exists()
    b = _pose_file(tmp_path / "b.csv", 2)
    assert main(["identify-load", str(a), str(b), "--out", str(out), "-q"]) == 0


def test_a_folder_holding_the_same_bag_twice_is_refused(tmp_path, capsys):
    folder = tmp_path / "bags"
    folder.mkdir()
    t = np.arange(0.0, 1.0, 0.01)
    bag = write_bag(folder / "run1", "sqlite3", sensor_time=t, reading=np.ones((100, 6)), pose_time=t,
                    joints=np.c_[t, -t], joint_names=["j1", "j2"])
    shutil.copytree(bag, folder / "run1_copy")
    assert main(["identify-load", str(folder), "--out", str(tmp_path / "t"), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "run1_copy holds the same ROS bag as" in err[0], err
