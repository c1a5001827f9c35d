"""Inverse kinematics for calibration poses: orient the sensor, hold a point fixed.

The calibration experiment only cares about the direction of gravity in the
sensor frame (two degrees of freedom); the heading about the vertical is free.
:func:`solve_gravity_direction_ik` therefore solves a 5-D task with damped least
squares on the Pinocchio model:

* orientation (primary): rotate the sensor so that the unit vector
  ``g_sensor_target`` (given in the sensor frame) points along gravity in the
  base frame. The error is the rotation vector taking the current image
  ``R g_sensor_target`` onto the gravity direction [rad];
* position: the anchor frame (a wrist centre, or the sensor frame) stays at a
  fixed point in the base frame [m].

Joint limits are handled as an active set: a joint that sits on its limit
(minus a safety margin) and would be pushed further out is frozen for that
step. A posture term in the null space of the task pulls toward the seed so
that solutions stay close to it. Unconverged seeds are retried from further
seeds; a target that no seed reaches is reported as unreachable.

:func:`solve_orientation_ik` does the same for a full target rotation.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import KinematicsError
from ._robot import RobotModel

__all__ = ["IKResult", "solve_gravity_direction_ik", "solve_orientation_ik", "DEFAULT_LIMIT_MARGIN_RAD"]

#: Distance kept from every joint limit by the IK [rad] (1 degree).
DEFAULT_LIMIT_MARGIN_RAD: float = float(np.deg2rad(1.0))

_WORLD = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class IKResult:
    """Outcome of an inverse-kinematics solve.

    Attributes
    ----------
    q : ndarray of shape (n_joints,)
        The last iterate [rad] (inside the limits minus the margin).
    success : bool
        Whether both errors fell below their tolerances.
    orientation_error : float
        Remaining orientation error [rad].
    position_error : float
        Remaining distance of the anchor frame from its target [m].
    iterations : int
        Iterations used, over all seeds tried.
    """

    q: NDArray[np.float64]
    success: bool
    orientation_error: float
    position_error: float
    iterations: int


def _unit(v: ArrayLike, name: str) -> NDArray[np.float64]:
    a = np.asarray(v, dtype=float).reshape(-1)
    n = float(np.linalg.norm(a)) if a.shape == (3,) else 0.0
    if a.shape != (3,) or not np.isfinite(n) or n < 1e-12:
        raise KinematicsError(f"{name} must be a finite non-zero 3-vector; got {np.asarray(v).tolist()!r}.")
    return a / n


def _rotation_between(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rotation vector [rad] (base frame) turning unit vector ``a`` onto unit vector ``b``."""
    axis = np.cross(a, b)
    s, c = float(np.linalg.norm(axis)), float(np.dot(a, b))
    if s < 1e-12:
        if c > 0:
            return np.zeros(3)
        perp = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
        return np.pi * perp / np.linalg.norm(perp)
    return axis / s * np.arctan2(s, c)


# A task maps the sensor rotation (base <- sensor) to (error [rad], 3x3 projector on the angular Jacobian).
_Task = Callable[[NDArray[np.float64]], tuple[NDArray[np.float64], NDArray[np.float64]]]


def _solve(
    robot: RobotModel,
    task: _Task,
    q_seed: ArrayLike | None,
    anchor_position_in_base: ArrayLike | None,
    orientation_tol: float,
    position_tol: float,
    max_iterations: int,
    damping: float,
    limit_margin: float,
    n_random_seeds: int,
    random_state: int,
    *,
    position_weight: float = 1.0,
    posture_gain: float = 0.05,
    max_step: float = 0.2,
    stall_iterations: int = 15,
) -> IKResult:
    model, data = robot.model, robot.data
    seeds = _seeds(robot, q_seed, n_random_seeds, random_state)
    anchor_position = anchor_configuration(robot, anchor_position_in_base)
    lo = robot.lower_limits + limit_margin
    hi = robot.upper_limits - limit_margin
    if np.any(lo > hi):
        raise KinematicsError(f"limit_margin {limit_margin} rad leaves no room inside the joint limits of {robot.name!r}.")
    sid, aid = robot.sensor_frame_id, robot.anchor_frame_id
    best: tuple | None = None  # (summed error, q, orientation error, position error) of the best failed seed
    total = 0
    for seed in seeds:
        q = np.clip(seed, lo, hi)
        rest = q.copy()
        best_err, stalled = np.inf, 0
        for it in range(max_iterations + 1):
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacements(model, data)
            err_o, proj = task(data.oMf[sid].rotation)
            e_o = float(np.linalg.norm(err_o))
            err_p = anchor_position - data.oMf[aid].translation
            e_p = float(np.linalg.norm(err_p))
            J = np.vstack([proj @ pin.getFrameJacobian(model, data, sid, _WORLD)[3:],
                           position_weight * pin.getFrameJacobian(model, data, aid, _WORLD)[:3]])
            err = np.concatenate([err_o, position_weight * err_p])
            if e_o < orientation_tol and e_p < position_tol:
                total += it
                return IKResult(q.copy(), True, e_o, e_p, total)
            stalled = stalled + 1 if e_o + e_p > 0.999 * best_err else 0
            best_err = min(best_err, e_o + e_p)
            if it == max_iterations or stalled >= stall_iterations:
                break
            free = np.ones(q.size, dtype=bool)
            for _ in range(q.size):
                Jf = J * free
                JJt = Jf @ Jf.T + damping**2 * np.eye(Jf.shape[0])
                dq = Jf.T @ np.linalg.solve(JJt, err)
                null = np.eye(q.size) - np.linalg.pinv(Jf, rcond=1e-6) @ Jf
                dq += (null @ (posture_gain * (rest - q))) * free
                blocked = free & (((q >= hi - 1e-12) & (dq > 0)) | ((q <= lo + 1e-12) & (dq < 0)))
                if not blocked.any():
                    break
                free &= ~blocked
            step = float(np.max(np.abs(dq)))
            if step > max_step:
                dq *= max_step / step
            q = np.clip(q + dq, lo, hi)
        total += it
        if best is None or e_o + e_p < best[0]:
            best = (e_o + e_p, q.copy(), e_o, e_p)
    return IKResult(best[1], False, best[2], best[3], total)


def _seeds(robot: RobotModel, q_seed: ArrayLike | None, n_random: int, random_state: int) -> list[NDArray[np.float64]]:
    first = robot.home_configuration if q_seed is None else robot.check_joints(q_seed, "q_seed")[0]
    seeds = [np.asarray(first, dtype=float), robot.home_configuration.copy()]
    rng = np.random.default_rng(random_state)
    lo, hi = robot.lower_limits, robot.upper_limits
    for _ in range(n_random):
        # random postures near home: wide on the distal joints, narrow on the proximal ones
        spread = np.linspace(0.3, 1.0, robot.n_joints) * (hi - lo) / 2
        seeds.append(np.clip(robot.home_configuration + rng.uniform(-1, 1, robot.n_joints) * spread, lo, hi))
    return seeds


def solve_gravity_direction_ik(
    robot: RobotModel,
    gravity_in_sensor: ArrayLike,
    *,
    q_seed: ArrayLike | None = None,
    anchor_position_in_base: ArrayLike | None = None,
    gravity_in_base: ArrayLike = (0.0, 0.0, -1.0),
    orientation_tol: float = 1e-6,
    position_tol: float = 1e-5,
    max_iterations: int = 200,
    damping: float = 1e-3,
    limit_margin: float = DEFAULT_LIMIT_MARGIN_RAD,
    n_random_seeds: int = 6,
    random_state: int = 0,
) -> IKResult:
    """Joint configuration in which gravity points along ``gravity_in_sensor`` in the sensor frame.

    Parameters
    ----------
    robot : RobotModel
    gravity_in_sensor : array-like of shape (3,)
        Wanted direction of gravity in the sensor frame (normalised here).
    q_seed : array-like of shape (n_joints,), optional
        First seed [rad]; default the robot's home posture.
    anchor_position_in_base : array-like of shape (3,), optional
        Where the anchor frame must stay [m]; default its position at the
        robot's home posture.
    gravity_in_base : array-like of shape (3,), default=(0, 0, -1)
        Direction of gravity in the base frame (a robot on a flat table).
    orientation_tol : float, default=1e-6
        Angle between achieved and wanted gravity direction accepted [rad].
    position_tol : float, default=1e-5
        Distance of the anchor from its target accepted [m].
    max_iterations : int, default=200
        Iterations per seed.
    damping : float, default=1e-3
        Damping of the least-squares step.
    limit_margin : float, default=1 degree
        Distance kept from every joint limit [rad].
    n_random_seeds : int, default=6
        Extra seeds around the home posture tried when the first ones fail.
    random_state : int, default=0
        Seed of those extra seeds (the solver is deterministic).

    Returns
    -------
    IKResult
        ``success`` is False when no seed reached both tolerances.

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal.robot import load_robot, sensor_pose_in_base
    >>> robot = load_robot()
    >>> res = solve_gravity_direction_ik(robot, [1.0, 0.0, 0.0])
    >>> res.success
    True
    >>> R = sensor_pose_in_base(robot, res.q)[:3, :3]
    >>> (R.T @ [0, 0, -1.0]).round(6) + 0.0
    array([1., 0., 0.])
    """
    target = _unit(gravity_in_sensor, "gravity_in_sensor")
    g_base = _unit(gravity_in_base, "gravity_in_base")

    def task(R: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        a = R @ target
        return _rotation_between(a, g_base), np.eye(3) - np.outer(a, a)

    return _solve(robot, task, q_seed, anchor_position_in_base, orientation_tol, position_tol, max_iterations,
                  damping, limit_margin, n_random_seeds, random_state)


def solve_orientation_ik(
    robot: RobotModel,
    sensor_rotation_in_base: ArrayLike,
    *,
    q_seed: ArrayLike | None = None,
    anchor_position_in_base: ArrayLike | None = None,
    orientation_tol: float = 1e-6,
    position_tol: float = 1e-5,
    max_iterations: int = 200,
    damping: float = 1e-3,
    limit_margin: float = DEFAULT_LIMIT_MARGIN_RAD,
    n_random_seeds: int = 6,
    random_state: int = 0,
) -> IKResult:
    """Joint configuration giving the sensor frame a full target rotation (base <- sensor).

    Same solver and parameters as :func:`solve_gravity_direction_ik`; the
    orientation error is the angle of ``R_target R^T`` [rad].

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal.robot import load_robot
    >>> robot = load_robot()
    >>> R_down = np.diag([-1.0, 1.0, -1.0])  # tool face down, as at home
    >>> solve_orientation_ik(robot, R_down).success
    True
    """
    R_t = np.asarray(sensor_rotation_in_base, dtype=float)
    if R_t.shape != (3, 3) or not np.allclose(R_t.T @ R_t, np.eye(3), atol=1e-6) or np.linalg.det(R_t) < 0:
        raise KinematicsError(f"sensor_rotation_in_base must be a 3x3 rotation matrix; got {R_t.tolist()!r}.")

    def task(R: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        return pin.log3(R_t @ R.T), np.eye(3)

    return _solve(robot, task, q_seed, anchor_position_in_base, orientation_tol, position_tol, max_iterations,
                  damping, limit_margin, n_random_seeds, random_state)


def anchor_configuration(robot: RobotModel, anchor_position_in_base: ArrayLike | None) -> NDArray[np.float64]:
    if anchor_position_in_base is None:
        pin.framesForwardKinematics(robot.model, robot.data, robot.home_configuration)
        return robot.data.oMf[robot.anchor_frame_id].translation.copy()
    p = np.asarray(anchor_position_in_base, dtype=float)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise KinematicsError(f"anchor_position_in_base must be a finite 3-vector [m]; got {p.tolist()!r}.")
    return p
