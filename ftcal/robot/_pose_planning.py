"""Calibration pose planning (thesis IV-B-c): a geodesic sphere of gravity directions.

Each calibration pose is defined by the direction of gravity in the sensor
frame, a unit vector ``g_s``. The directions are the vertices of an icosphere
(an icosahedron whose faces are split ``subdivisions`` times and pushed onto the
unit sphere: ``10 * 4**k + 2`` vertices, 162 for ``k = 2``). Each direction is
written as **pitch** and **yaw** and turned into a joint configuration by
inverse kinematics (:func:`ftcal.solve_gravity_direction_ik`) with the arm's
wrist centre held at one point, inside the joint limits. Directions without an
IK solution are dropped and reported.

Pitch and yaw
-------------
``g_s = (sin(pitch) cos(yaw), -sin(pitch) sin(yaw), -cos(pitch))``, which is
gravity ``(0, 0, -1)`` seen from a sensor whose rotation in the base frame is
``R = Rz(heading) @ Ry(pitch) @ Rz(yaw)``: pitch [rad] tilts the sensor's z axis
away from straight up (0: tool face up, pi: tool face down) and yaw [rad] spins
the sensor about its own z axis. The heading about the vertical does not
change ``g_s``; the IK chooses it freely.

Why 155 poses per sphere
------------------------
The thesis reports 155 orientations per sphere without giving the rule. The
nearest icosphere is ``k = 2`` with 162 vertices. We assume the 7 directions
nearest **tool face straight up** were left out (``g_s`` near ``-z``: the
load and its 186 mm lever arm would hang above the sensor, over the robot's
own wrist and the sensor cable). The sphere is rotated so that one of its
six-valent vertices lies on that direction, and the vertices within
``excluded_cap_deg = 20`` degrees of it (that vertex and its ring of 6
neighbours, 15.9-18.0 degrees away; the next ring starts at 30.4 degrees) are
removed: ``162 - 7 = 155``. This is an assumption; ``excluded_cap_deg=0``
keeps all 162. With the built-in iiwa all 155 are reachable.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import KinematicsError
from ._ik import DEFAULT_LIMIT_MARGIN_RAD, anchor_configuration, solve_gravity_direction_ik
from ._robot import RobotModel, sensor_pose_in_base

__all__ = [
    "icosphere",
    "gravity_directions_in_sensor",
    "pitch_yaw_from_gravity_in_sensor",
    "gravity_in_sensor_from_pitch_yaw",
    "sensor_rotation_from_pitch_yaw",
    "CalibrationPlan",
    "plan_calibration_poses",
    "THESIS_SUBDIVISIONS",
    "THESIS_EXCLUDED_CAP_DEG",
]

#: Icosphere subdivision level of the thesis' spheres (162 vertices).
THESIS_SUBDIVISIONS: int = 2
#: Half-angle of the cap of directions around "tool face up" left out [deg] (162 -> 155).
THESIS_EXCLUDED_CAP_DEG: float = 20.0


def icosphere(subdivisions: int = THESIS_SUBDIVISIONS) -> NDArray[np.float64]:
    """Vertices of a geodesic sphere, unit vectors of shape (10 * 4**k + 2, 3).

    The first 12 rows are the icosahedron's vertices (five neighbours each);
    every later vertex has six neighbours.

    Examples
    --------
    >>> [len(icosphere(k)) for k in range(4)]
    [12, 42, 162, 642]
    """
    if not isinstance(subdivisions, (int, np.integer)) or not 0 <= subdivisions <= 6:
        raise KinematicsError(f"subdivisions must be an integer in 0..6; got {subdivisions!r}.")
    t = (1.0 + 5**0.5) / 2.0
    verts = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
             [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5),
             (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    pts = [np.array(v, dtype=float) / np.linalg.norm(v) for v in verts]
    for _ in range(int(subdivisions)):
        cache: dict[tuple[int, int], int] = {}

        def mid(i: int, j: int) -> int:
            key = (min(i, j), max(i, j))
            if key not in cache:
                m = pts[i] + pts[j]
                pts.append(m / np.linalg.norm(m))
                cache[key] = len(pts) - 1
            return cache[key]

        new_faces = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new_faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new_faces
    return np.array(pts)


def _rotation_onto(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Smallest rotation matrix turning unit vector ``a`` onto unit vector ``b``."""
    v, c = np.cross(a, b), float(np.dot(a, b))
    if c < -1 + 1e-12:
        perp = np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0])
        perp /= np.linalg.norm(perp)
        return 2 * np.outer(perp, perp) - np.eye(3)
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + K + K @ K / (1 + c)


def gravity_directions_in_sensor(
    subdivisions: int = THESIS_SUBDIVISIONS,
    *,
    excluded_direction: ArrayLike = (0.0, 0.0, -1.0),
    excluded_cap_deg: float = THESIS_EXCLUDED_CAP_DEG,
) -> NDArray[np.float64]:
    """Gravity directions of one calibration sphere, in the sensor frame, shape (m, 3).

    Parameters
    ----------
    subdivisions : int, default=2
        Icosphere level: ``10 * 4**k + 2`` candidate directions.
    excluded_direction : array-like of shape (3,), default=(0, 0, -1)
        Centre of the cap of directions left out (default: tool face up).
    excluded_cap_deg : float, default=20
        Half-angle of that cap [deg]; 0 keeps every vertex.

    Examples
    --------
    >>> len(gravity_directions_in_sensor())
    155
    >>> len(gravity_directions_in_sensor(excluded_cap_deg=0))
    162
    """
    pts = icosphere(subdivisions)
    ex = np.asarray(excluded_direction, dtype=float)
    if ex.shape != (3,) or not np.isfinite(ex).all() or np.linalg.norm(ex) == 0:
        raise KinematicsError(f"excluded_direction must be a non-zero 3-vector; got {ex.tolist()!r}.")
    if not np.isfinite(excluded_cap_deg) or not 0 <= excluded_cap_deg < 180:
        raise KinematicsError(f"excluded_cap_deg must be in [0, 180) degrees; got {excluded_cap_deg!r}.")
    ex = ex / np.linalg.norm(ex)
    pivot = pts[12] if len(pts) > 12 else pts[0]  # a six-valent vertex once subdivided
    pts = pts @ _rotation_onto(pivot, ex).T
    keep = np.degrees(np.arccos(np.clip(pts @ ex, -1, 1))) >= excluded_cap_deg
    return pts[keep]


def pitch_yaw_from_gravity_in_sensor(gravity_in_sensor: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Pitch in [0, pi] and yaw in (-pi, pi] [rad] of gravity directions (n, 3) in the sensor frame.

    Examples
    --------
    >>> pitch, yaw = pitch_yaw_from_gravity_in_sensor([[0.0, 0, 1], [1.0, 0, 0]])
    >>> np.degrees(pitch).round(6), np.degrees(yaw).round(6) + 0.0
    (array([180.,  90.]), array([0., 0.]))
    """
    g = np.asarray(gravity_in_sensor, dtype=float).reshape(-1, 3)
    g = g / np.linalg.norm(g, axis=1, keepdims=True)
    pitch = np.arccos(np.clip(-g[:, 2], -1.0, 1.0))
    yaw = np.arctan2(-g[:, 1], g[:, 0])
    return pitch, yaw


def gravity_in_sensor_from_pitch_yaw(pitch: ArrayLike, yaw: ArrayLike) -> NDArray[np.float64]:
    """Unit gravity directions in the sensor frame, shape (n, 3), from pitch and yaw [rad]."""
    p, y = np.broadcast_arrays(np.asarray(pitch, dtype=float), np.asarray(yaw, dtype=float))
    return np.stack([np.sin(p) * np.cos(y), -np.sin(p) * np.sin(y), -np.cos(p)], axis=-1).reshape(-1, 3)


def sensor_rotation_from_pitch_yaw(pitch: float, yaw: float, heading: float = 0.0) -> NDArray[np.float64]:
    """Sensor rotation in the base frame ``Rz(heading) Ry(pitch) Rz(yaw)`` (3, 3), angles [rad]."""

    def rz(a: float) -> NDArray[np.float64]:
        c, s = np.cos(a), np.sin(a)
        return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])

    c, s = np.cos(pitch), np.sin(pitch)
    ry = np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]])
    return rz(heading) @ ry @ rz(yaw)


@dataclass
class CalibrationPlan:
    """The joint configurations of one calibration sphere, in execution order.

    Attributes
    ----------
    q : ndarray of shape (m, n_joints)
        Joint configurations [rad], inside the limits minus the IK margin.
    gravity_in_sensor : ndarray of shape (m, 3)
        Target gravity direction in the sensor frame of each pose (unit).
    pitch, yaw : ndarray of shape (m,)
        The same directions as angles [rad].
    unreachable : ndarray of shape (k, 3)
        Directions dropped because no IK solution was found.
    anchor_position_in_base : ndarray of shape (3,)
        Where the anchor (wrist) frame stays [m].
    robot_name, sensor_frame, anchor_frame : str
    n_candidates : int
        Directions on the sphere after the cap rule, before IK.
    """

    q: NDArray[np.float64]
    gravity_in_sensor: NDArray[np.float64]
    pitch: NDArray[np.float64]
    yaw: NDArray[np.float64]
    unreachable: NDArray[np.float64]
    anchor_position_in_base: NDArray[np.float64]
    robot_name: str
    sensor_frame: str
    anchor_frame: str
    n_candidates: int
    settings: dict = field(default_factory=dict)

    @property
    def n_poses(self) -> int:
        """Number of reachable poses."""
        return int(self.q.shape[0])


def _travel_order(dirs: NDArray[np.float64], start: NDArray[np.float64]) -> list[int]:
    """Greedy nearest-neighbour tour over directions, from the one nearest ``start``."""
    left = list(range(len(dirs)))
    order: list[int] = []
    cur = start
    while left:
        nxt = max(left, key=lambda i: float(dirs[i] @ cur))
        order.append(nxt)
        left.remove(nxt)
        cur = dirs[nxt]
    return order


def plan_calibration_poses(
    robot: RobotModel,
    *,
    subdivisions: int = THESIS_SUBDIVISIONS,
    excluded_direction: ArrayLike = (0.0, 0.0, -1.0),
    excluded_cap_deg: float = THESIS_EXCLUDED_CAP_DEG,
    gravity_in_base: ArrayLike = (0.0, 0.0, -1.0),
    anchor_position_in_base: ArrayLike | None = None,
    orientation_tol: float = 1e-6,
    limit_margin: float = DEFAULT_LIMIT_MARGIN_RAD,
    max_iterations: int = 200,
    n_random_seeds: int = 6,
) -> CalibrationPlan:
    """Plan one calibration sphere: icosphere directions -> pitch/yaw -> IK joint configurations.

    Directions are visited in a greedy nearest-neighbour order (short robot
    motions); each IK solve starts from the previous pose, falling back to
    the home posture and further seeds.

    Parameters
    ----------
    robot : RobotModel
    subdivisions, excluded_direction, excluded_cap_deg
        See :func:`gravity_directions_in_sensor`.
    gravity_in_base : array-like of shape (3,), default=(0, 0, -1)
        Direction of gravity in the base frame.
    anchor_position_in_base : array-like of shape (3,), optional
        Where the anchor frame (iiwa: the wrist centre) stays [m]; default its
        position at the robot's home posture.
    orientation_tol : float, default=1e-6
        IK orientation tolerance [rad].
    limit_margin : float, default=1 degree
        Distance kept from the joint limits [rad].
    max_iterations, n_random_seeds : int
        IK effort per direction (see :func:`ftcal.solve_gravity_direction_ik`).

    Returns
    -------
    CalibrationPlan

    Examples
    --------
    >>> from ftcal import load_robot
    >>> plan = plan_calibration_poses(load_robot(), subdivisions=0, excluded_cap_deg=0)
    >>> plan.n_poses, plan.q.shape
    (12, (12, 7))
    """
    dirs = gravity_directions_in_sensor(subdivisions, excluded_direction=excluded_direction,
                                        excluded_cap_deg=excluded_cap_deg)
    anchor = anchor_configuration(robot, anchor_position_in_base)
    g_base = np.asarray(gravity_in_base, dtype=float)
    R_home = sensor_pose_in_base(robot, robot.home_configuration)[:3, :3]
    order = _travel_order(dirs, R_home.T @ (g_base / np.linalg.norm(g_base)))
    qs, reached, dropped = [], [], []
    prev = robot.home_configuration
    for i in order:
        res = solve_gravity_direction_ik(robot, dirs[i], q_seed=prev, anchor_position_in_base=anchor,
                                         gravity_in_base=g_base, orientation_tol=orientation_tol,
                                         limit_margin=limit_margin, max_iterations=max_iterations,
                                         n_random_seeds=n_random_seeds)
        if res.success:
            qs.append(res.q)
            reached.append(dirs[i])
            prev = res.q
        else:
            dropped.append(dirs[i])
    g = np.array(reached).reshape(-1, 3)
    pitch, yaw = pitch_yaw_from_gravity_in_sensor(g)
    return CalibrationPlan(
        q=np.array(qs).reshape(-1, robot.n_joints), gravity_in_sensor=g, pitch=pitch, yaw=yaw,
        unreachable=np.array(dropped).reshape(-1, 3), anchor_position_in_base=anchor, robot_name=robot.name,
        sensor_frame=robot.sensor_frame, anchor_frame=robot.anchor_frame, n_candidates=len(dirs),
        settings={"subdivisions": int(subdivisions), "excluded_cap_deg": float(excluded_cap_deg),
                  "excluded_direction": np.asarray(excluded_direction, dtype=float).tolist(),
                  "gravity_in_base": g_base.tolist(), "limit_margin_rad": float(limit_margin)},
    )
