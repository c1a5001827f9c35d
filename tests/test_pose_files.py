"""Pose files in (quaternion / matrix / roll-pitch-yaw, a wrench in the sensor or the base frame), still poses
found in continuous recordings, and ``ftcal identify-load`` without a calibration model."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

import ftcal
from ftcal.core import LogFormatError
from ftcal.experiment import ToolLoad, find_still_poses
from ftcal.io import read_pose_file
from ftcal.cli import main
from ftcal.experiment._virtual_recording import continuous_recording

TOOL = ToolLoad(mass=1.3, center_of_mass=np.array([0.012, -0.008, 0.065]),
                bias=np.array([1.5, -2.0, 0.7, 0.05, -0.03, 0.02]))
NOISE = np.array([0.15, 0.15, 0.15, 0.006, 0.006, 0.006])  # N, N·m: an Axia80-like sensor


def _write(path, names, *columns):
    rows = np.column_stack(columns)
    path.write_text(",".join(names) + "\n" + "".join(",".join(repr(float(v)) for v in r) + "\n" for r in rows))
    return path


def _static_poses(n, seed):
    rng = np.random.default_rng(seed)
    R = Rotation.random(n, random_state=seed).as_matrix()
    W = TOOL.gravity_wrench(R) + rng.normal(size=(n, 6)) * NOISE
    return R, W


def _in_base(R, W):
    return np.hstack([np.einsum("nij,nj->ni", R, W[:, :3]), np.einsum("nij,nj->ni", R, W[:, 3:])])


def _quat_base_file(path, R, W):
    names = ["qx", "qy", "qz", "qw", "Fx", "Fy", "Fz", "Mx", "My", "Mz"]
    return _write(path, names, Rotation.from_matrix(R).as_quat(), _in_base(R, W))


def _least_squares_tool(R, W):
    """An independent fit of the same model (mass, centre of mass, bias) by nonlinear least squares."""
    g = np.einsum("nji,j->ni", R, TOOL.gravity)

    def residual(p):
        m, c, b = p[0], p[1:4], p[4:]
        return (np.hstack([m * g, np.cross(c, m * g)]) + b - W).ravel()

    p = least_squares(residual, np.r_[1.0, np.zeros(9)]).x
    return ToolLoad(mass=p[0], center_of_mass=p[1:4], bias=p[4:])


def _held_out_force_residual(tool, R, W):
    return float(np.mean(np.linalg.norm(tool.compensate(R, W)[:, :3], axis=1)))


def test_identify_load_from_a_quaternion_pose_file_in_the_base_frame_matches_least_squares(tmp_path, capsys):
    R, W = _static_poses(100, seed=3)
    fit, test = np.arange(12), np.arange(12, 100)
    poses = _quat_base_file(tmp_path / "poses.csv", R[fit], W[fit])
    assert main(["identify-load", str(poses), "--wrench-frame", "base", "--out", str(tmp_path / "t"), "-q"]) == 0
    tool = ToolLoad.load(tmp_path / "t" / "tool.tool.json")
    ours = _held_out_force_residual(tool, R[test], W[test])
    reference = _held_out_force_residual(_least_squares_tool(R[fit], W[fit]), R[test], W[test])
    assert ours <= 1.02 * reference
    # and it is the tool: within a few standard errors of the truth
    assert abs(tool.mass - TOOL.mass) <= 4 * tool.mass_std_error
    assert np.all(np.abs(tool.center_of_mass - TOOL.center_of_mass) <= 4 * tool.center_of_mass_std_error)
    # the wrench was turned back into the sensor frame: read as a sensor-frame wrench it does not turn with the
    # poses, so no tool's weight shows (the bias takes it): refused, naming the base frame, nothing written
    capsys.readouterr()
    assert main(["identify-load", str(poses), "--out", str(tmp_path / "s"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "not distinguishable from zero" in err and "base frame" in err
    assert not (tmp_path / "s" / "tool.tool.json").exists()
    written = (tmp_path / "t" / "tool.poses.csv").read_text().splitlines()
    assert written[1].split(",")[:10] == ["qx", "qy", "qz", "qw", "Fx", "Fy", "Fz", "Tx", "Ty", "Tz"]
    assert len(written) == 2 + 12


def test_the_three_orientation_layouts_and_the_wrench_names_read_alike(tmp_path):
    R, W = _static_poses(20, seed=4)
    quat = _write(tmp_path / "q.csv", ["qx", "qy", "qz", "qw", "Fx", "Fy", "Fz", "Tx", "Ty", "Tz"],
                  Rotation.from_matrix(R).as_quat(), W)
    matrix = _write(tmp_path / "m.csv", [f"R{i}{j}" for i in range(3) for j in range(3)] +
                    ["fx", "fy", "fz", "mx", "my", "mz"], R.reshape(-1, 9), W)
    rpy = Rotation.from_matrix(R).as_euler("xyz")  # fixed axes x, y, z: Rz(yaw) Ry(pitch) Rx(roll)
    euler = _write(tmp_path / "e.csv", ["time", "roll", "pitch", "yaw", "Fx", "Fy", "Fz", "Tx", "Ty", "Tz"],
                   np.arange(20.0), rpy, W)
    for path in (quat, matrix, euler):
        rec = read_pose_file(path)
        np.testing.assert_allclose(rec.rotation, R, atol=1e-12)
        np.testing.assert_allclose(rec.wrench, W)
    # roll, pitch, yaw as URDF writes them: yaw about z applied last
    np.testing.assert_allclose(read_pose_file(euler).rotation[0],
                               Rotation.from_euler("z", rpy[0, 2]).as_matrix()
                               @ Rotation.from_euler("y", rpy[0, 1]).as_matrix()
                               @ Rotation.from_euler("x", rpy[0, 0]).as_matrix(), atol=1e-12)
    assert read_pose_file(euler).time.tolist() == list(np.arange(20.0))


def test_a_pose_file_in_kilonewtons_and_newton_millimetres_is_converted(tmp_path):
    R, W = _static_poses(12, seed=5)
    path = _write(tmp_path / "p.csv", ["qx", "qy", "qz", "qw", "Fx", "Fy", "Fz", "Tx", "Ty", "Tz"],
                  Rotation.from_matrix(R).as_quat(), W[:, :3] / 1000, W[:, 3:] * 1000)
    np.testing.assert_allclose(read_pose_file(path, force_unit="kN", torque_unit="N.mm").wrench, W)


@pytest.mark.parametrize("text, message", [
    ("qx,qy,qz,qw,Fx,Fy,Fz,Tx,Ty,Tz\n0,0,0,2,0,0,1,0,0,0\n", "line 2: the quaternion (qx,qy,qz,qw) has norm 2"),
    ("qx,qy,qz,Fx,Fy,Fz,Tx,Ty,Tz\n0,0,0,0,0,1,0,0,0\n", "it has part of the quaternion"),
    ("qx,qy,qz,qw,Fx,Fy,Fz,Tx,Ty\n0,0,0,1,0,0,1,0,0\n", "the wrench lacks Tz"),
    ("roll,pitch,yaw,Fx,Fy,Fz,Tx,Ty,Tz\n0,90,0,0,0,1,0,0,0\n", "line 2, column pitch: 90 exceeds 2*pi"),
    ("qx,qy,qz,qw,Fx,Fy,Fz,Tx,Ty,Tz\n0,0,0,1,0,0,x,0,0,0\n", "line 2, column Fz: 'x' is not a number"),
    ("time,qx,qy,qz,qw,Fx,Fy,Fz,Tx,Ty,Tz\n1,0,0,0,1,0,0,1,0,0,0\n1,0,0,0,1,0,0,1,0,0,0\n",
     "line 3, column time: 1 s does not follow 1 s on line 2"),
    ("R00,R01,R02,R10,R11,R12,R20,R21,R22,Fx,Fy,Fz,Tx,Ty,Tz\n1,0,0,0,1,0,0,0,-1,0,0,1,0,0,0\n", "a reflection"),
])
def test_a_bad_pose_file_is_one_line_naming_file_line_and_column_and_nothing_is_written(tmp_path, capsys, text,
                                                                                       message):
    path = tmp_path / "poses.csv"
    path.write_text(text)
    with pytest.raises(LogFormatError, match=None) as info:
        read_pose_file(path)
    assert message in str(info.value) and str(path) in str(info.value)
    capsys.readouterr()
    assert main(["identify-load", str(path), "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("ftcal: error: ") and message in err
    assert not (tmp_path / "t").exists()


def _continuous_file(path, rotations, seed, *, settle=1.0, tau=0.6, rate=10.0, noise=NOISE):
    """A continuous recording (time, wrench in the base frame, quaternion) of the tool at ``rotations``."""
    rec = continuous_recording(TOOL.gravity_wrench(rotations), rotations=rotations, still_s=8.0, move_s=3.0,
                               sensor_rate_hz=rate, pose_rate_hz=rate, settle_amplitude=settle, settle_tau_s=tau,
                               noise=noise, random_state=seed, start_time_s=1.7e9)
    names = ["time", "Fx", "Fy", "Fz", "Tx", "Ty", "Tz", "qx", "qy", "qz", "qw"]
    return _write(path, names, rec.sensor_time - 1.7e9, _in_base(rec.rotations, rec.reading),
                  Rotation.from_matrix(rec.rotations).as_quat()), rec


def test_a_continuous_recording_has_its_still_poses_found_settling_dropped_and_the_tool_recovered(tmp_path, capsys):
    R = Rotation.random(14, random_state=7).as_matrix()
    path, rec = _continuous_file(tmp_path / "recording.csv", R, seed=7)
    assert main(["identify-load", str(path), "--wrench-frame", "base", "--out", str(tmp_path / "t")]) == 0
    err = capsys.readouterr().err
    assert "found 14 still poses, kept 14, rejected 0" in err and "from the data" in err
    d = json.loads((tmp_path / "t" / "tool.tool.json").read_text())
    assert d["n_poses"] == 14 and d["still_poses"][0]["found"] == 14
    settle = d["still_poses"][0]["settle_s"]
    assert 0.6 * 2 <= settle <= 0.6 * 9  # the 1 N transient (tau 0.6 s) decays into the 0.15 N noise in ~3 tau
    # each pose's time stamp lies inside its still segment
    times = np.array(d["pose_time_s"])
    assert np.all((times > rec.still_from - 1.7e9) & (times < rec.still_to - 1.7e9))
    tool = ToolLoad.load(tmp_path / "t" / "tool.tool.json")
    assert abs(tool.mass - TOOL.mass) <= 4 * tool.mass_std_error
    assert np.all(np.abs(tool.center_of_mass - TOOL.center_of_mass) <= 4 * tool.center_of_mass_std_error)
    assert np.all(np.abs(tool.bias - TOOL.bias) <= 4 * tool.bias_std_error)


def test_the_settling_from_the_data_removes_the_transient_that_no_settling_keeps():
    R = Rotation.random(10, random_state=8).as_matrix()
    rec = continuous_recording(TOOL.gravity_wrench(R), rotations=R, still_s=8.0, move_s=3.0, sensor_rate_hz=10,
                               pose_rate_hz=10, settle_amplitude=1.0, settle_tau_s=0.6, noise=NOISE, random_state=8)
    truth = TOOL.gravity_wrench(R)
    from scipy.spatial.transform import Slerp  # noqa: F401 - the orientations at the sensor's stamps are the same
    found = find_still_poses(rec.sensor_time, rec.reading, rotations=rec.rotations)
    none = find_still_poses(rec.sensor_time, rec.reading, rotations=rec.rotations, settle_s=0.0)
    error = lambda p: np.abs(p.reading[:, :3] - truth[:, :3]).mean()  # noqa: E731
    # the transient's mean over the first seconds is ~1 N * tau / still time: a bias no averaging removes
    assert error(none) > 2 * error(found)
    assert error(found) <= 3 * NOISE[0] / np.sqrt(found.n_samples.min())


def test_poses_tilted_about_one_axis_are_refused_in_one_line_naming_the_count_and_the_missing_tilt(tmp_path, capsys):
    R = Rotation.from_euler("x", np.linspace(-50, 50, 9)[:, None], degrees=True).as_matrix()
    path, _ = _continuous_file(tmp_path / "recording.csv", R, seed=9)
    assert main(["identify-load", str(path), "--wrench-frame", "base", "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith(str(path)) and "found 9 still poses, kept 9" in err[0]
    assert len(err) == 2 and err[1].startswith("ftcal: error: ")
    assert "the 9 poses do not excite the tool load (they tilt the tool about the sensor's x axis only" in err[1]
    assert "none about y" in err[1] and "Fix: add poses tilted about two axes" in err[1]
    assert not (tmp_path / "t").exists()


def test_a_recording_that_never_stands_still_is_refused(tmp_path, capsys):
    t = np.arange(0, 20, 0.1)
    R = Rotation.from_euler("x", t[:, None] * 10, degrees=True).as_matrix()  # turning at 10 deg/s throughout
    W = TOOL.gravity_wrench(R)
    path = _write(tmp_path / "moving.csv", ["time", "qx", "qy", "qz", "qw", "Fx", "Fy", "Fz", "Tx", "Ty", "Tz"],
                  t, Rotation.from_matrix(R).as_quat(), W)
    assert main(["identify-load", str(path), "--poses", "continuous", "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no still pose in the 200 samples" in err and "the pose moves throughout" in err
    assert "--still-tolerance" not in err  # no looser threshold finds a still pose here: none is advised
    assert not (tmp_path / "t").exists()


def test_an_unsteady_pose_is_rejected_with_its_reason():
    R = Rotation.random(8, random_state=11).as_matrix()
    rec = continuous_recording(TOOL.gravity_wrench(R), rotations=R, still_s=6.0, move_s=2.0, sensor_rate_hz=20,
                               pose_rate_hz=20, noise=NOISE, random_state=11)
    touched = (rec.sensor_time > 3 * 8.0 + 2.5) & (rec.sensor_time < 4 * 8.0 - 0.5)  # someone leans on pose 3
    reading = rec.reading.copy()
    reading[touched, 2] += 5.0 * np.sin(np.arange(touched.sum()))
    poses = find_still_poses(rec.sensor_time, reading, rotations=rec.rotations, settle_s=0.5)
    assert poses.n_found == 8 and poses.n_kept == 7
    assert "unsteady" in poses.rejected[0][1] and 3 * 8.0 < poses.rejected[0][0] < 4 * 8.0
    assert "rejected 1" in poses.summary()


def test_identify_load_without_a_model_refuses_raw_channels_with_the_fix(tmp_path, capsys):
    R, _ = _static_poses(12, seed=6)
    path = _write(tmp_path / "raw.csv", ["qx", "qy", "qz", "qw", "s0", "s1", "s2", "s3", "s4", "s5"],
                  Rotation.from_matrix(R).as_quat(), np.ones((12, 6)))
    assert main(["identify-load", str(path), "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err
    assert "holds raw channels" in err and "--model" in err and not (tmp_path / "t").exists()


def test_a_missing_or_unreadable_input_is_named_before_anything_else(tmp_path, capsys):
    missing = tmp_path / "nosuchfile.csv"
    assert main(["identify-load", str(missing), "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err
    assert f"{missing} does not exist" in err and "--model" not in err and "raw channels" not in err
    assert not (tmp_path / "t").exists()


def test_three_random_poses_are_refused_for_their_count_not_for_their_tilt(tmp_path, capsys):
    R, W = _static_poses(3, seed=11)
    path = _quat_base_file(tmp_path / "three.csv", R, W)
    assert main(["identify-load", str(path), "--wrench-frame", "base", "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"ftcal: error: {path}: 3 poses; at least 4 are needed"), err
    assert "one axis" not in err[0] and not (tmp_path / "t").exists()


def test_torques_in_newton_millimetres_read_as_newton_metres_are_refused_naming_the_unit(tmp_path, capsys):
    R, W = _static_poses(12, seed=12)
    W_nmm = W.copy()
    W_nmm[:, 3:] *= 1000.0  # the factory software wrote N·mm
    path = _quat_base_file(tmp_path / "nmm.csv", R, W_nmm)
    assert main(["identify-load", str(path), "--wrench-frame", "base", "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and "the torques look like N.mm" in err[0], err
    assert "--torque-unit N.mm" in err[0] and not (tmp_path / "t").exists()
    # declared, the same file gives the tool in metres
    assert main(["identify-load", str(path), "--wrench-frame", "base", "--torque-unit", "N.mm",
                 "--out", str(tmp_path / "t"), "-q"]) == 0
    tool = ToolLoad.load(tmp_path / "t" / "tool.tool.json")
    assert np.all(np.abs(tool.center_of_mass - TOOL.center_of_mass) <= 5 * tool.center_of_mass_std_error)
    # both units declared: an unusual arm is the user's to confirm (warned, not refused)
    assert main(["identify-load", str(path), "--wrench-frame", "base", "--force-unit", "N", "--torque-unit", "N.m",
                 "--out", str(tmp_path / "u"), "-q"]) == 0
    assert "ftcal: warning:" in capsys.readouterr().err
