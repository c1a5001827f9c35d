"""Load configurations (Table I) and the reference wrench (eq. 15-16), checked by hand."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal.core import KinematicsError
from ftcal.robot import (STANDARD_GRAVITY, load_robot, reference_wrench, reference_wrench_at_joints,
                         thesis_load_configurations)

G = STANDARD_GRAVITY


def test_table_one_configurations():
    cfgs = thesis_load_configurations()
    assert [c.config_id for c in cfgs] == list(range(7))
    pos = {c.name: np.array(c.position_in_sensor) * 1000 for c in cfgs}  # [mm]
    np.testing.assert_allclose(pos["centre"], [186, 0, 79])
    np.testing.assert_allclose(pos["+x"], [186 + 161, 93, 79])
    np.testing.assert_allclose(pos["-x"], [186 - 161, 93, 79])
    np.testing.assert_allclose(pos["+y"], [186, 29, 79])
    np.testing.assert_allclose(pos["-y"], [186, -42, 79])
    np.testing.assert_allclose(pos["+z"], [186, 0, 79 + 15])
    np.testing.assert_allclose(pos["-z"], [186, 0, 79 - 48])


def test_reference_wrench_tool_face_down_by_hand():
    # Sensor rotated 180 deg about base x (R = diag(1, -1, -1)): tool face down.
    R = np.diag([1.0, -1.0, -1.0])
    m, r = 2.0, np.array([0.186, 0.0, 0.079])
    w = reference_wrench(R, m, r)[0]
    # Gravity (0,0,-g) in the sensor frame is R^T (0,0,-g) = (0,0,+g): F = (0, 0, 2g).
    F = np.array([0.0, 0.0, 2 * G])
    # tau = r x F = (ry Fz - rz Fy, rz Fx - rx Fz, rx Fy - ry Fx) = (0, -0.186*2g, 0)
    np.testing.assert_allclose(w, [0, 0, 2 * G, 0, -0.186 * 2 * G, 0], atol=1e-12)
    np.testing.assert_allclose(w[3:], np.cross(r, F))


def test_reference_wrench_tilted_90_deg_about_y():
    c, s = 0.0, 1.0  # Ry(90 deg): sensor z -> base x, sensor x -> base -z
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    w = reference_wrench(R, 1.0, [0.0, 0.1, 0.0])[0]
    # R^T (0,0,-g) = (g, 0, 0): gravity along sensor +x; tau = (0,0.1,0) x (g,0,0) = (0, 0, -0.1 g)
    np.testing.assert_allclose(w, [G, 0, 0, 0, 0, -0.1 * G], atol=1e-12)


def test_batched_and_from_joints():
    robot = load_robot()
    q = np.zeros((2, 7))
    q[1, 1] = np.pi / 2  # arm laid along x: sensor z = base x
    w = reference_wrench_at_joints(robot, q, 1.5, [0.0, 0.0, 0.2])
    np.testing.assert_allclose(w[0], [0, 0, -1.5 * G, 0, 0, 0], atol=1e-12)
    # Ry(90 deg): sensor x is base -z, so R^T (0,0,-g) = (g, 0, 0); tau = (0,0,0.2) x (1.5g,0,0) = (0, 0.3g, 0)
    np.testing.assert_allclose(w[1], [1.5 * G, 0, 0, 0, 0.2 * 1.5 * G, 0], atol=1e-12)


def test_reference_wrench_rejects_bad_input():
    with pytest.raises(KinematicsError, match="load_mass"):
        reference_wrench(np.eye(3), -1.0, [0, 0, 0])
    with pytest.raises(KinematicsError, match="load_position_in_sensor"):
        reference_wrench(np.eye(3), 1.0, [0, 0])
    with pytest.raises(KinematicsError, match="sensor_rotation_in_base"):
        reference_wrench(np.eye(4), 1.0, [0, 0, 0])
