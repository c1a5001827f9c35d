"""Inverse kinematics of calibration poses: targets reached within tolerance, limits kept."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal.core import KinematicsError
from ftcal.robot import (frame_pose_in_base, load_robot, sensor_pose_in_base, sensor_rotation_from_pitch_yaw,
                         solve_gravity_direction_ik, solve_orientation_ik)
from ftcal.robot._ik import DEFAULT_LIMIT_MARGIN_RAD

ORIENTATION_TOL = 1e-6  # [rad]
POSITION_TOL = 1e-5  # [m]


@pytest.fixture(scope="module")
def iiwa():
    return load_robot("kuka_iiwa14")


def _angle(a, b):
    return float(np.arccos(np.clip(np.dot(a, b) / np.linalg.norm(a) / np.linalg.norm(b), -1, 1)))


@pytest.mark.parametrize("g_sensor", [[0, 0, 1.0], [1.0, 0, 0], [0, -1.0, 0], [0.3, 0.4, -0.5], [-1.0, 0.2, 0.1]])
def test_gravity_direction_reached_wrist_fixed_limits_kept(iiwa, g_sensor):
    res = solve_gravity_direction_ik(iiwa, g_sensor)
    assert res.success
    R = sensor_pose_in_base(iiwa, res.q)[:3, :3]
    achieved = R.T @ np.array([0, 0, -1.0])  # gravity seen in the sensor frame
    assert _angle(achieved, g_sensor) < ORIENTATION_TOL * 1.01
    home_wrist = frame_pose_in_base(iiwa, iiwa.home_configuration, "iiwa_link_6")[:3, 3]
    assert np.linalg.norm(frame_pose_in_base(iiwa, res.q, "iiwa_link_6")[:3, 3] - home_wrist) < POSITION_TOL
    margin = DEFAULT_LIMIT_MARGIN_RAD - 1e-12
    assert np.all(res.q >= iiwa.lower_limits + margin) and np.all(res.q <= iiwa.upper_limits - margin)


def test_full_orientation_target(iiwa):
    R_t = sensor_rotation_from_pitch_yaw(np.deg2rad(120), np.deg2rad(40), heading=np.deg2rad(-20))
    res = solve_orientation_ik(iiwa, R_t)
    assert res.success
    R = sensor_pose_in_base(iiwa, res.q)[:3, :3]
    angle = np.arccos(np.clip((np.trace(R_t.T @ R) - 1) / 2, -1, 1))
    assert angle < 1.01 * ORIENTATION_TOL
    assert iiwa.within_limits(res.q)[0]


def test_limit_is_respected_when_the_target_needs_it():
    # Joint 7 alone cannot spin the tool past +-175 deg; with a tight margin the
    # solver must stay inside and use the other joints or fail, never exceed.
    ur5 = load_robot("ur5")
    R_home = sensor_pose_in_base(ur5, ur5.home_configuration)[:3, :3]
    c, s = np.cos(np.pi * 0.9), np.sin(np.pi * 0.9)
    R_t = R_home @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    res = solve_orientation_ik(ur5, R_t, limit_margin=np.deg2rad(5))
    assert np.all(res.q >= ur5.lower_limits + np.deg2rad(5) - 1e-12)
    assert np.all(res.q <= ur5.upper_limits - np.deg2rad(5) + 1e-12)
    assert res.success


def test_unreachable_position_reports_failure(iiwa):
    res = solve_gravity_direction_ik(iiwa, [1.0, 0, 0], anchor_position_in_base=[3.0, 0.0, 0.5], n_random_seeds=1,
                                     max_iterations=50)
    assert not res.success and res.position_error > 1.0
    assert iiwa.within_limits(res.q)[0]


def test_bad_targets_raise(iiwa):
    with pytest.raises(KinematicsError, match="non-zero 3-vector"):
        solve_gravity_direction_ik(iiwa, [0, 0, 0])
    with pytest.raises(KinematicsError, match="rotation matrix"):
        solve_orientation_ik(iiwa, np.ones((3, 3)))
    with pytest.raises(KinematicsError, match="anchor_position_in_base"):
        solve_gravity_direction_ik(iiwa, [0, 0, 1], anchor_position_in_base=[np.nan, 0, 0])
