"""Pose planning: icosphere, pitch/yaw, the 155-pose sphere of the thesis."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal.core import KinematicsError
from ftcal.robot import (gravity_directions_in_sensor, gravity_in_sensor_from_pitch_yaw, icosphere, load_robot,
                         pitch_yaw_from_gravity_in_sensor, plan_calibration_poses, sensor_pose_in_base,
                         sensor_rotation_from_pitch_yaw)


@pytest.mark.parametrize("k", [0, 1, 2, 3])
def test_icosphere_counts_unit_and_uniform(k):
    pts = icosphere(k)
    assert len(pts) == 10 * 4**k + 2
    np.testing.assert_allclose(np.linalg.norm(pts, axis=1), 1.0)
    assert np.linalg.norm(pts.mean(axis=0)) < 1e-12  # symmetric: centroid at the origin
    assert len(np.unique(pts.round(9), axis=0)) == len(pts)


def test_thesis_sphere_has_155_directions_and_excludes_tool_face_up():
    g = gravity_directions_in_sensor()
    assert g.shape == (155, 3)
    angle_to_up = np.degrees(np.arccos(np.clip(g @ [0, 0, -1.0], -1, 1)))
    assert angle_to_up.min() > 20.0
    assert len(gravity_directions_in_sensor(excluded_cap_deg=0)) == 162
    with pytest.raises(KinematicsError, match="excluded_cap_deg"):
        gravity_directions_in_sensor(excluded_cap_deg=-1)


def test_pitch_yaw_round_trip_and_meaning():
    g = icosphere(1)
    pitch, yaw = pitch_yaw_from_gravity_in_sensor(g)
    np.testing.assert_allclose(gravity_in_sensor_from_pitch_yaw(pitch, yaw), g, atol=1e-12)
    # The rotation built from pitch/yaw sees gravity (0,0,-1) as g, whatever the heading.
    for p, y, gi in zip(pitch[:10], yaw[:10], g[:10]):
        for heading in (0.0, 1.3):
            R = sensor_rotation_from_pitch_yaw(p, y, heading)
            np.testing.assert_allclose(R.T @ [0, 0, -1.0], gi, atol=1e-12)
    # Tool face down: pitch 180 deg, gravity along +z of the sensor.
    np.testing.assert_allclose(np.degrees(pitch_yaw_from_gravity_in_sensor([[0, 0, 1.0]])[0]), [180.0])


def test_plan_reaches_every_direction_within_limits():
    robot = load_robot("kuka_iiwa14")
    plan = plan_calibration_poses(robot, subdivisions=1, excluded_cap_deg=0)
    assert plan.n_poses == 42 and len(plan.unreachable) == 0
    assert robot.within_limits(plan.q).all()
    R = sensor_pose_in_base(robot, plan.q)[:, :3, :3]
    seen = np.einsum("nji,j->ni", R, [0, 0, -1.0])
    err = np.arccos(np.clip(np.sum(seen * plan.gravity_in_sensor, axis=1), -1, 1))
    assert err.max() < 1.01e-6
    # every planned direction is one of the sphere's
    sphere = gravity_directions_in_sensor(1, excluded_cap_deg=0)
    assert np.all(np.max(plan.gravity_in_sensor @ sphere.T, axis=1) > 1 - 1e-12)


def test_unreachable_directions_are_dropped_and_reported():
    robot = load_robot("kuka_iiwa14")
    plan = plan_calibration_poses(robot, subdivisions=0, excluded_cap_deg=0, anchor_position_in_base=[2.5, 0, 0.5],
                                  max_iterations=40, n_random_seeds=0)
    assert plan.n_poses == 0 and plan.unreachable.shape == (12, 3) and plan.q.shape == (0, 7)
