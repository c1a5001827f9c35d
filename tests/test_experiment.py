"""Load / no-load pairing, R_delta (eq. 17), alignment and dataset preparation."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal.experiment._virtual_experiment import JITTER_TRUNCATION

from ftcal.core import LogFormatError
from ftcal.simulation import VirtualSensor
from ftcal.experiment import fit_no_load_model, prepare_dataset, rotation_delta, simulate_experiment
from ftcal.robot import load_robot, plan_calibration_poses, sensor_pose_in_base
from ftcal.io import read_run_log, write_run_log


@pytest.fixture(scope="module")
def iiwa():
    return load_robot("kuka_iiwa14")


@pytest.fixture(scope="module")
def small_plan(iiwa):
    return plan_calibration_poses(iiwa, subdivisions=1, excluded_cap_deg=0)


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def test_rotation_delta_recovers_a_known_small_rotation(iiwa):
    q = np.array([0.2, 0.5, -0.3, -1.1, 0.4, 0.0, 0.0])
    delta = np.deg2rad(0.3)
    q7, q6 = q.copy(), q.copy()
    q7[6] += delta  # joint 7 turns the sensor about its own z axis
    q6[5] += delta  # with q7 = 0, joint 6 turns it about its own y axis
    P0 = sensor_pose_in_base(iiwa, q)
    Rd = rotation_delta(np.stack([P0, P0]), sensor_pose_in_base(iiwa, np.stack([q7, q6])))
    np.testing.assert_allclose(Rd[0], _rz(delta), atol=1e-12)
    np.testing.assert_allclose(Rd[1], _ry(delta), atol=1e-12)


def test_no_load_fit_recovers_an_affine_model():
    rng = np.random.default_rng(0)
    u = rng.normal(size=(30, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    B, z = rng.normal(size=(6, 3)), rng.normal(size=6)
    m = fit_no_load_model(u, u @ B.T + z)
    np.testing.assert_allclose(m.matrix, B, atol=1e-12)
    np.testing.assert_allclose(m.offset, z, atol=1e-12)
    with pytest.raises(LogFormatError, match="do not span 3-D"):
        fit_no_load_model(np.tile([[1.0, 0, 0], [0, 1.0, 0]], (3, 1)), np.zeros((6, 6)))


def largest_jitter_within(limit_deg: float, n_joints: int) -> float:
    """The per-joint jitter std whose pose pairs stay within ``limit_deg`` by construction: the rotation
    between two poses is at most the sum of the joint differences, each truncated at JITTER_TRUNCATION std."""
    return 0.95 * limit_deg / (JITTER_TRUNCATION * n_joints)


def test_perfect_sensor_gives_the_exact_external_load(tmp_path, iiwa, small_plan):
    # No sensor errors, no robot error, but pose differences between the runs (within the pairing limit by
    # construction): the prepared raw must be exactly the sensor's image of the external load's wrench.
    sensor = VirtualSensor(errors="none", zero_offset=np.linspace(-0.5, 0.5, 6))
    jitter = largest_jitter_within(3.0, iiwa.n_joints)
    paths = simulate_experiment(tmp_path, robot=iiwa, plan=small_plan, sensor=sensor, joint_error_max=0.0,
                                load_pose_jitter_deg=jitter, load_mass=3.0, random_state=1)
    ds = prepare_dataset(paths, iiwa, max_pair_rotation_deg=3.0)
    # the poses do differ: the largest of 294 pair rotations (7 joints' differences combined) exceeds one joint's std
    assert ds.raw.shape == (7 * 42, 6) and ds.meta["pair_rotation_deg_max"] > jitter
    expected = sensor.profile.reading_from_wrench(ds.wrench)
    scale = np.abs(expected).max()
    np.testing.assert_allclose(ds.raw, expected, atol=1e-7 * scale)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_alignment_beats_plain_subtraction(tmp_path, iiwa, small_plan, seed):
    limit_deg = 3.0
    jitter_deg = largest_jitter_within(limit_deg, iiwa.n_joints)
    sensor = VirtualSensor(errors="none")
    paths = simulate_experiment(tmp_path, robot=iiwa, plan=small_plan, sensor=sensor, joint_error_max=0.0,
                                load_pose_jitter_deg=jitter_deg, random_state=seed)
    ds = prepare_dataset(paths, iiwa, max_pair_rotation_deg=limit_deg)
    logs = [read_run_log(p) for p in paths]
    naive = np.vstack([logs[i + 1].raw - logs[i].raw for i in range(0, len(logs), 2)])
    expected = sensor.profile.reading_from_wrench(ds.wrench)
    err_aligned = np.abs(ds.raw - expected).max()
    err_naive = np.abs(naive - expected).max()
    assert err_naive > 1e3 * err_aligned


def _pair_logs(tmp_path, iiwa, small_plan, **kw):
    return simulate_experiment(tmp_path, robot=iiwa, plan=small_plan, random_state=0,
                               load_configurations=None, **kw)


def _drop_pose(path, pose):
    lines = path.read_text().splitlines()
    keep = [ln for ln in lines if ln.startswith("#") or ln.split(",")[3] != str(pose)]
    path.write_text("\n".join(keep) + "\n")


def test_unpaired_poses_are_named(tmp_path, iiwa, small_plan):
    paths = _pair_logs(tmp_path, iiwa, small_plan)
    no_load, load = paths[0], paths[1]
    _drop_pose(no_load, 9)  # a no-load pose missing
    # load file: 8 comment lines, the header on line 9, pose p on line 10 + p
    with pytest.raises(LogFormatError, match=r"config0_load.csv:line 19: load pose 9 of config 0 has no no-load"):
        prepare_dataset(paths, iiwa)
    _drop_pose(load, 9)  # now the load pose is gone too -> consistent again
    assert prepare_dataset(paths, iiwa).n_samples == 7 * 42 - 1
    _drop_pose(load, 30)
    # no-load file: 7 comment lines (no load mass), pose p on line 9 + p (pose 9 is gone: 30 is on line 38)
    with pytest.raises(LogFormatError, match=r"config0_no-load.csv:line 38: no-load pose 30 of config 0 has no load"):
        prepare_dataset(paths, iiwa)


def test_shared_no_load_run_and_repeated_samples(tmp_path, iiwa, small_plan):
    sensor = VirtualSensor(errors="none")
    paths = simulate_experiment(tmp_path, robot=iiwa, plan=small_plan, sensor=sensor, joint_error_max=0.0,
                                load_pose_jitter_deg=0.0, samples_per_pose=3, random_state=3)
    shared = read_run_log(paths[0])
    assert shared.n_rows == 3 * 42
    p_shared = tmp_path / "shared_no_load.csv"
    write_run_log(p_shared, timestamp=shared.timestamp, run_kind=shared.run_kind, config=[-1] * shared.n_rows,
                  pose=shared.pose, q=shared.q, raw=shared.raw)
    ds = prepare_dataset([p_shared] + paths[1::2], iiwa)
    assert ds.n_samples == 7 * 42
    np.testing.assert_allclose(ds.raw, sensor.profile.reading_from_wrench(ds.wrench),
                               atol=1e-7 * np.abs(ds.raw).max())


def test_dataset_level_errors(tmp_path, iiwa, small_plan):
    paths = _pair_logs(tmp_path, iiwa, small_plan)
    with pytest.raises(LogFormatError, match=r"load_mass 5 kg but the logs declare \[2.0\] kg"):
        prepare_dataset(paths, iiwa, load_mass=5.0)
    with pytest.raises(LogFormatError, match="load configuration 3 is not among the known ones"):
        prepare_dataset(paths, iiwa, load_configurations={0: [0.1, 0, 0], 1: [0, 0.1, 0], 2: [0.1, 0.1, 0]})
    with pytest.raises(LogFormatError, match="8 expected"):
        prepare_dataset(paths, iiwa, n_channels=8)
    # shift the load run's pose indices by one: pairs now join different poses
    text = paths[3].read_text().splitlines()
    body = [ln.split(",") for ln in text[9:]]
    for f in body:
        f[3] = str((int(f[3]) + 1) % 42)
    paths[3].write_text("\n".join(text[:9] + [",".join(f) for f in body]) + "\n")
    with pytest.raises(LogFormatError, match="do not refer to the same commanded pose"):
        prepare_dataset(paths, iiwa)


def test_logs_of_another_robot_are_refused(tmp_path, iiwa, small_plan):
    paths = _pair_logs(tmp_path, iiwa, small_plan)
    with pytest.raises(LogFormatError, match="7 joint columns but the robot has 6"):
        prepare_dataset(paths, "ur5")
