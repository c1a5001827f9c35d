"""Robot models and forward kinematics: the iiwa URDF against hand-derived DH poses."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import ftcal

from ftcal.core import KinematicsError
from ftcal.robot import example_robot_data_dir, frame_pose_in_base, load_robot, sensor_pose_in_base

REPO = Path(__file__).resolve().parents[1]
# Manufacturer dimensions [m] and the mount of Fig. 4 (robots/README.md).
D_SHOULDER, D_UPPER, D_FORE, D_FLANGE = 0.36, 0.42, 0.40, 0.126
PLATE, SENSOR_ORIGIN = 0.030, 0.040
FLANGE_TO_SENSOR = PLATE + SENSOR_ORIGIN
# Standard DH of the iiwa (a = 0): d and alpha per joint.
DH_D = [D_SHOULDER, 0.0, D_UPPER, 0.0, D_FORE, 0.0, D_FLANGE + FLANGE_TO_SENSOR]
DH_ALPHA = [-np.pi / 2, np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, np.pi / 2, 0.0]


def dh_pose(q: np.ndarray) -> np.ndarray:
    """Sensor pose from the standard-DH product, written independently of the URDF and Pinocchio."""
    T = np.eye(4)
    for theta, d, alpha in zip(q, DH_D, DH_ALPHA):
        ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
        T = T @ np.array([[ct, -st * ca, st * sa, 0.0], [st, ct * ca, -ct * sa, 0.0], [0, sa, ca, d], [0, 0, 0, 1.0]])
    return T


@pytest.fixture(scope="module")
def iiwa():
    return load_robot("kuka_iiwa14")


def test_builtin_urdf_is_this_folders_file():
    # one copy: robots/ is installed as the data package ftcal.robots
    assert not (REPO / "ftcal" / "data").exists()
    loaded = ftcal.robot.load_robot("kuka_iiwa14").urdf_path
    assert Path(loaded).read_bytes() == (REPO / "robots" / "kuka_iiwa14_ft.urdf").read_bytes()


def test_iiwa_joints_and_limits_match_the_datasheet(iiwa):
    assert iiwa.n_joints == 7
    limits_deg = np.array([170, 120, 170, 120, 170, 120, 175.0])
    np.testing.assert_allclose(np.degrees(iiwa.upper_limits), limits_deg)
    np.testing.assert_allclose(np.degrees(iiwa.lower_limits), -limits_deg)


def test_zero_configuration_is_upright(iiwa):
    P = sensor_pose_in_base(iiwa, np.zeros(7))
    np.testing.assert_allclose(P[:3, :3], np.eye(3), atol=1e-12)
    height = D_SHOULDER + D_UPPER + D_FORE + D_FLANGE + FLANGE_TO_SENSOR  # 1.376 m
    np.testing.assert_allclose(P[:3, 3], [0, 0, height], atol=1e-12)


def test_shoulder_at_90_deg_lays_the_arm_along_x(iiwa):
    q = np.zeros(7)
    q[1] = np.pi / 2  # A2 about +y: the arm tips forward, its z axis becomes base +x
    P = sensor_pose_in_base(iiwa, q)
    reach = D_UPPER + D_FORE + D_FLANGE + FLANGE_TO_SENSOR
    np.testing.assert_allclose(P[:3, 3], [reach, 0, D_SHOULDER], atol=1e-12)
    np.testing.assert_allclose(P[:3, 2], [1, 0, 0], atol=1e-12)


def test_elbow_at_minus_90_deg(iiwa):
    q = np.zeros(7)
    q[3] = -np.pi / 2  # A4 about -y: minus 90 deg bends the forearm toward +x
    P = sensor_pose_in_base(iiwa, q)
    np.testing.assert_allclose(P[:3, 3], [D_FORE + D_FLANGE + FLANGE_TO_SENSOR, 0, D_SHOULDER + D_UPPER], atol=1e-12)


def test_batched_fk_matches_dh_at_random_configurations(iiwa):
    rng = np.random.default_rng(3)
    q = rng.uniform(iiwa.lower_limits, iiwa.upper_limits, size=(20, 7))
    P = sensor_pose_in_base(iiwa, q)
    assert P.shape == (20, 4, 4)
    for qi, Pi in zip(q, P):
        np.testing.assert_allclose(Pi, dh_pose(qi), atol=1e-12)


def test_wrist_frame_is_the_wrist_centre(iiwa):
    q = np.array([0.3, -0.5, 0.2, 1.0, 0.0, 0.0, 0.0])
    wrist = frame_pose_in_base(iiwa, q, "iiwa_link_6")[:3, 3]
    q2 = q.copy()
    q2[4:] = [1.0, -0.7, 2.0]  # wrist joints leave the wrist centre in place
    np.testing.assert_allclose(frame_pose_in_base(iiwa, q2, "iiwa_link_6")[:3, 3], wrist, atol=1e-12)


@pytest.mark.parametrize("name, frame, n_joints", [("panda", "panda_link8", 7), ("ur5", "tool0", 6)])
def test_example_robot_data_arms_load_by_name_and_path(name, frame, n_joints):
    by_name = load_robot(name)
    assert by_name.n_joints == n_joints and by_name.sensor_frame == frame
    urdf = {"panda": "panda_description/urdf/panda.urdf", "ur5": "ur_description/urdf/ur5_robot.urdf"}[name]
    by_path = load_robot(example_robot_data_dir() / urdf, sensor_frame=frame)
    assert by_path.n_joints == n_joints  # fingers of the Panda are locked away
    q = by_path.home_configuration
    np.testing.assert_allclose(sensor_pose_in_base(by_path, q), sensor_pose_in_base(by_name, q))
    P = sensor_pose_in_base(by_path, np.zeros((3, n_joints)))
    np.testing.assert_allclose(P[:, :3, :3] @ P[:, :3, :3].transpose(0, 2, 1), np.broadcast_to(np.eye(3), (3, 3, 3)),
                               atol=1e-12)


def test_loading_errors_are_clear(tmp_path):
    with pytest.raises(KinematicsError, match="no frame named 'nope'"):
        load_robot(example_robot_data_dir() / "ur_description/urdf/ur5_robot.urdf", sensor_frame="nope")
    with pytest.raises(KinematicsError, match="sensor_frame"):
        load_robot(example_robot_data_dir() / "ur_description/urdf/ur5_robot.urdf")
    with pytest.raises(KinematicsError, match="neither a built-in"):
        load_robot("kuka_iiwa7")
    with pytest.raises(KinematicsError, match="no such URDF"):
        load_robot(tmp_path / "missing.urdf", sensor_frame="x")
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'>")
    with pytest.raises(KinematicsError, match=r"bad.urdf: line 1, column 32: not valid XML \(no element found\)"):
        load_robot(bad, sensor_frame="a")  # the library names where the XML breaks (urdfdom only says it failed)
    empty = tmp_path / "empty.urdf"
    empty.write_text("")
    with pytest.raises(KinematicsError, match="empty.urdf: the URDF file is empty"):
        load_robot(empty, sensor_frame="a")


def test_fk_rejects_bad_joint_vectors(iiwa):
    with pytest.raises(KinematicsError, match=r"shape \(7,\) or \(n, 7\)"):
        sensor_pose_in_base(iiwa, np.zeros(6))
    with pytest.raises(KinematicsError, match="NaN"):
        sensor_pose_in_base(iiwa, [0, 0, np.nan, 0, 0, 0, 0])
