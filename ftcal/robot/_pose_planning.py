"""Calibration pose planning (thesis IV-B-c): a geodesic sphere of gravity directions.

Each calibration pose is defined by the direction of gravity in the sensor
frame, a unit vector ``g_s``. The directions are the vertices of an icosphere
(an icosahedron whose faces are split ``subdivisions`` times and pushed onto the
unit sphere: ``10 * 4**k + 2`` vertices, 162 for ``k = 2``). Each direction is
written as **pitch** and **yaw** and turned into a joint configuration by
inverse kinematics (:func:`ftcal.robot.solve_gravity_direction_ik`) with the arm's
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

Fewer poses for the same accuracy: optimal plans
------------------------------------------------
``strategy="d-optimal"`` chooses ``n_poses`` of a dense candidate sphere
(icosphere level ``candidate_subdivisions``, 3 by default: 642 directions
before the cap rule), after dropping the candidates that IK can not reach, so
that they teach the calibration model the most. The physics: at gravity
direction ``u`` (sensor frame) with the load's centre of mass at ``r_c``, the
load's wrench is ``m |g| [u, r_c x u]`` (eq. 15-16), and every load
configuration is run at every pose. The sensor's (load minus no-load) reading
is ``S w`` to first order, so the LTM ``w = C x + b`` has, up to a constant
invertible map, the regressors ``phi = [1, u, r_c x u / l]`` (``l`` the mean
lever arm, a scale that changes no determinant); its information matrix is
``M(P) = sum over poses in P and configurations c of phi phi^T`` (7 x 7) and a
D-optimal plan maximises ``log det M`` (the volume of the joint confidence
ellipsoid of the LTM's coefficients shrinks as ``det M^-1/2``). One pose with
all configurations spans only 3 of the 7 directions (the configurations share
its force ``u``; their torques differ only in the plane normal to ``u``), and
the offset and force part ``[1, u]`` needs 4 directions not on one circle, so
a plan needs at least 4 poses; we ask for at least
``LINEAR_MODEL_PARAMETERS = 7`` (one pose per parameter, so a plan still
identifies the LTM when a load configuration is left out).

A purely D-optimal plan piles poses near a few extreme directions (for a
model linear in ``u`` any design with ``sum u = 0`` and ``sum u u^T ~ I``, an
octahedron, is optimal); a nonlinear model needs the whole sphere. The
**space-filling term** is the D-criterion of a degree-``L`` polynomial in ``u``
(``(L + 1)^2 >= n_poses`` harmonics, ``L <= 8``, orthonormalised on the candidates):
``log det(I + Psi_P^T Psi_P)``, a repulsive kernel determinant whose kernel is
the reproducing kernel of those polynomials (width about ``pi / L``), so it
rewards directions far from the chosen ones. The criterion is

``J(P) = log det(M(P) + eps I) / 7 + space_filling * log det(I + Psi_P^T Psi_P) / q``

(both per dimension; ``eps`` a 1e-9 relative ridge that makes the first steps
defined). It is maximised by a greedy pass (each step adds the candidate of
largest gain, computed for all candidates at once from Cholesky factors:
``log det(I + Phi_k M^-1 Phi_k^T)``, a rank-``n_configurations`` update) and
then Fedorov exchanges (swap a chosen pose for an unchosen one while ``J``
grows). Deterministic: ties go to the lower candidate index. The poses are
then ordered for short robot motions and solved by IK from the previous pose,
as for the geodesic plan. ``strategy="random"`` draws ``n_poses`` reachable
candidates uniformly with ``random_state``.

Which load configurations: ``n_load_configurations=K`` keeps the ``K`` of the
given configurations (the thesis' seven by default) whose design over the
reachable candidates has the largest D-criterion (all subsets when there are
at most 5000, else forward selection), then chooses the poses for them. The
choice is made on the whole candidate sphere, not jointly with the poses: the
D-optimal pose sets are nearly uniform on the sphere, so the two decouple. At
least 3 configurations are needed (two share all torques but one plane's).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..core._exceptions import NO_SETTING, KinematicsError, PlanningError
from ._ik import DEFAULT_LIMIT_MARGIN_RAD, anchor_configuration, solve_gravity_direction_ik
from ._loads import thesis_load_configurations
from ._robot import RobotModel, sensor_pose_in_base

__all__ = [
    "icosphere",
    "gravity_directions_in_sensor",
    "pitch_yaw_from_gravity_in_sensor",
    "gravity_in_sensor_from_pitch_yaw",
    "sensor_rotation_from_pitch_yaw",
    "CalibrationPlan",
    "CandidatePoses",
    "plan_calibration_poses",
    "reachable_candidates",
    "select_poses",
    "select_load_configurations",
    "d_criterion",
    "linear_design_rows",
    "PLAN_STRATEGIES",
    "LINEAR_MODEL_PARAMETERS",
    "THESIS_SUBDIVISIONS",
    "THESIS_EXCLUDED_CAP_DEG",
]

#: Icosphere subdivision level of the thesis' spheres (162 vertices).
THESIS_SUBDIVISIONS: int = 2
#: Half-angle of the cap of directions around "tool face up" left out [deg] (162 -> 155).
THESIS_EXCLUDED_CAP_DEG: float = 20.0
#: Pose-selection strategies of :func:`plan_calibration_poses`.
PLAN_STRATEGIES: tuple[str, ...] = ("geodesic", "random", "d-optimal")
#: Icosphere level of the candidate directions of the random and D-optimal plans (642 vertices).
DEFAULT_CANDIDATE_SUBDIVISIONS: int = 3
#: Parameters of the linear calibration model per output: six wrench regressors and an offset.
LINEAR_MODEL_PARAMETERS: int = 7


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
    K = pin.skew(v)
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
    return np.arccos(np.clip(-g[:, 2], -1.0, 1.0)), np.arctan2(-g[:, 1], g[:, 0])


def gravity_in_sensor_from_pitch_yaw(pitch: ArrayLike, yaw: ArrayLike) -> NDArray[np.float64]:
    """Unit gravity directions in the sensor frame, shape (n, 3), from pitch and yaw [rad]."""
    p, y = np.broadcast_arrays(np.asarray(pitch, dtype=float), np.asarray(yaw, dtype=float))
    return np.stack([np.sin(p) * np.cos(y), -np.sin(p) * np.sin(y), -np.cos(p)], axis=-1).reshape(-1, 3)


def sensor_rotation_from_pitch_yaw(pitch: float, yaw: float, heading: float = 0.0) -> NDArray[np.float64]:
    """Sensor rotation in the base frame ``Rz(heading) Ry(pitch) Rz(yaw)`` (3, 3), angles [rad]."""
    return Rotation.from_euler("ZYZ", [heading, pitch, yaw]).as_matrix()


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


@dataclass
class CandidatePoses:
    """Reachable candidate directions of a dense sphere, with an IK solution each.

    Attributes
    ----------
    gravity_in_sensor : ndarray of shape (m, 3)
        Reachable unit gravity directions in the sensor frame.
    q : ndarray of shape (m, n_joints)
        A joint configuration reaching each [rad] (IK residual and limits checked).
    unreachable : ndarray of shape (k, 3)
        Candidate directions no IK seed reached.
    anchor_position_in_base : ndarray of shape (3,)
        [m].
    n_candidates : int
        Directions after the cap rule, before IK.
    settings : dict
        The sphere and IK settings (to check a plan uses matching candidates).
    """

    gravity_in_sensor: NDArray[np.float64]
    q: NDArray[np.float64]
    unreachable: NDArray[np.float64]
    anchor_position_in_base: NDArray[np.float64]
    n_candidates: int
    settings: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.gravity_in_sensor.shape[0])


def _solve_directions(robot: RobotModel, dirs: NDArray[np.float64], anchor_position_in_base, gravity_in_base,
                      orientation_tol, limit_margin, max_iterations, n_random_seeds,
                      fallback_q: NDArray[np.float64] | None = None) -> tuple[dict, list, list[int], list[int]]:
    """IK of ``dirs`` along a nearest-neighbour tour from the home posture's gravity direction, each from the
    previous solution (``fallback_q`` rows are known solutions): the IK settings, the joint configurations and
    the indices of the directions reached and dropped."""
    ik = dict(anchor_position_in_base=anchor_configuration(robot, anchor_position_in_base),
              gravity_in_base=np.asarray(gravity_in_base, dtype=float), orientation_tol=orientation_tol,
              limit_margin=limit_margin, max_iterations=max_iterations, n_random_seeds=n_random_seeds)
    R_home = sensor_pose_in_base(robot, robot.home_configuration)[:3, :3]
    start = R_home.T @ (ik["gravity_in_base"] / np.linalg.norm(ik["gravity_in_base"]))
    qs, reached, dropped = [], [], []
    prev = robot.home_configuration
    for i in _travel_order(dirs, start):
        res = solve_gravity_direction_ik(robot, dirs[i], q_seed=prev, **ik)
        if not res.success and fallback_q is None:
            dropped.append(i)
            continue
        prev = res.q if res.success else fallback_q[i]
        qs.append(prev)
        reached.append(i)
    return ik, qs, reached, dropped


def reachable_candidates(
    robot: RobotModel,
    *,
    subdivisions: int = DEFAULT_CANDIDATE_SUBDIVISIONS,
    excluded_direction: ArrayLike = (0.0, 0.0, -1.0),
    excluded_cap_deg: float = THESIS_EXCLUDED_CAP_DEG,
    gravity_in_base: ArrayLike = (0.0, 0.0, -1.0),
    anchor_position_in_base: ArrayLike | None = None,
    orientation_tol: float = 1e-6,
    limit_margin: float = DEFAULT_LIMIT_MARGIN_RAD,
    max_iterations: int = 200,
    n_random_seeds: int = 6,
) -> CandidatePoses:
    """The directions of a dense sphere that the robot reaches, with their joint configurations.

    The candidate set of the random and D-optimal plans and of :func:`ftcal.experiment.propose_next_poses`;
    compute it once and pass it as ``candidates=`` to plan several times (IK for the 610
    candidates of level 3 takes a while). Parameters as for :func:`plan_calibration_poses`.

    Examples
    --------
    >>> from ftcal.robot import load_robot
    >>> cands = reachable_candidates(load_robot(), subdivisions=1, excluded_cap_deg=0)
    >>> len(cands), cands.q.shape[1]
    (42, 7)
    """
    dirs = gravity_directions_in_sensor(subdivisions, excluded_direction=excluded_direction,
                                        excluded_cap_deg=excluded_cap_deg)
    ik, qs, reached, dropped = _solve_directions(robot, dirs, anchor_position_in_base, gravity_in_base,
                                                 orientation_tol, limit_margin, max_iterations, n_random_seeds)
    keep = np.sort(np.array(reached, dtype=int))  # candidate order: the sphere's, not the tour's
    q_by_index = dict(zip(reached, qs))
    return CandidatePoses(
        gravity_in_sensor=dirs[keep].reshape(-1, 3),
        q=np.array([q_by_index[i] for i in keep]).reshape(-1, robot.n_joints),
        unreachable=dirs[sorted(dropped)].reshape(-1, 3), anchor_position_in_base=ik["anchor_position_in_base"],
        n_candidates=len(dirs),
        settings={"subdivisions": int(subdivisions), "excluded_cap_deg": float(excluded_cap_deg),
                  "excluded_direction": np.asarray(excluded_direction, dtype=float).tolist(),
                  "gravity_in_base": ik["gravity_in_base"].tolist(), "limit_margin_rad": float(limit_margin),
                  "robot": robot.name, "sensor_frame": robot.sensor_frame},
    )


def _load_positions(load_positions_in_sensor: ArrayLike | None) -> NDArray[np.float64]:
    if load_positions_in_sensor is None:
        return np.array([c.position_in_sensor for c in thesis_load_configurations()])
    r = np.asarray(load_positions_in_sensor, dtype=float)
    if r.ndim != 2 or r.shape[1] != 3 or len(r) == 0 or not np.isfinite(r).all():
        raise PlanningError(f"load_positions_in_sensor must be a finite array of shape (n_configurations, 3) [m]; "
                            f"got shape {r.shape}.")
    return r


def linear_design_rows(gravity_in_sensor: ArrayLike, load_positions_in_sensor: ArrayLike | None = None
                       ) -> NDArray[np.float64]:
    """Regressors of the linear calibration model, ``[1, u, r_c x u / l]``, shape (m, n_configurations, 7).

    ``u`` is the unit gravity direction in the sensor frame (m, 3), ``r_c`` the
    load positions in the sensor frame [m] (default the thesis' seven) and ``l``
    their mean distance from the sensor [m]. Up to an invertible linear map
    (the load's weight, the sensor's raw response) these are the regressors
    the LTM sees for each pose and load configuration.

    Examples
    --------
    >>> rows = linear_design_rows([[0, 0, 1.0]], [[0.1, 0, 0]])
    >>> rows.round(3) + 0.0
    array([[[ 1.,  0.,  0.,  1.,  0., -1.,  0.]]])
    """
    u = np.asarray(gravity_in_sensor, dtype=float).reshape(-1, 3)
    r = _load_positions(load_positions_in_sensor)
    lever = float(np.mean(np.linalg.norm(r, axis=1))) or 1.0
    torque = np.cross(r[None, :, :], u[:, None, :]) / lever
    ones = np.ones((len(u), len(r), 1))
    return np.concatenate([ones, np.broadcast_to(u[:, None, :], torque.shape), torque], axis=2)


def d_criterion(gravity_in_sensor: ArrayLike, load_positions_in_sensor: ArrayLike | None = None) -> float:
    """``log det`` of the linear model's information matrix for a plan (``-inf`` if it is singular).

    Larger is better: the volume of the LTM coefficients' confidence ellipsoid
    scales as ``exp(-d_criterion / 2)``.

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal.robot import gravity_directions_in_sensor
    >>> d_criterion(gravity_directions_in_sensor(1)) > d_criterion(gravity_directions_in_sensor(0))
    True
    """
    rows = linear_design_rows(gravity_in_sensor, load_positions_in_sensor).reshape(-1, LINEAR_MODEL_PARAMETERS)
    sign, logdet = np.linalg.slogdet(rows.T @ rows)
    s = np.linalg.svd(rows, compute_uv=False)
    if sign <= 0 or s[-1] <= 1e-10 * s[0]:
        return float("-inf")
    return float(logdet)


#: Highest polynomial degree of the space-filling term (81 harmonics, a kernel about 20 degrees wide):
#: plans of more than 81 poses keep it, which bounds the cost of an exchange pass.
_MAX_SPACE_FILLING_DEGREE = 8


def _sphere_polynomial_features(u: NDArray[np.float64], degree: int) -> NDArray[np.float64]:
    """Polynomials of degree <= ``degree`` in ``u`` (m, 3), orthonormal in the mean over the rows of ``u``."""
    powers = [(a, b, c) for a in range(degree + 1) for b in range(degree + 1 - a) for c in range(degree + 1 - a - b)]
    mono = np.stack([u[:, 0] ** a * u[:, 1] ** b * u[:, 2] ** c for a, b, c in powers], axis=1)
    left, sing, _ = np.linalg.svd(mono, full_matrices=False)
    rank = int(np.sum(sing > 1e-8 * sing[0]))
    return left[:, :rank] * np.sqrt(len(u))


class _GreedyDesign:
    """The criterion ``J`` of the module docstring over a fixed candidate set, with vectorised gains."""

    def __init__(self, rows: NDArray[np.float64], features: NDArray[np.float64], space_filling: float):
        self.rows, self.features, self.weight = rows, features, float(space_filling)
        per_pose = np.einsum("mcp,mcq->pq", rows, rows) / len(rows)
        self.ridge = 1e-9 * float(np.trace(per_pose)) / rows.shape[2]

    def gains(self, chosen: list[int]) -> NDArray[np.float64]:
        """``J(chosen + k) - J(chosen)`` for every candidate ``k`` (``-inf`` for the chosen ones)."""
        p = self.rows.shape[2]
        sel = self.rows[chosen].reshape(-1, p)
        L = np.linalg.cholesky(sel.T @ sel + self.ridge * np.eye(p))
        z = np.linalg.solve(L, self.rows.reshape(-1, p).T).T.reshape(self.rows.shape)
        inner = np.eye(self.rows.shape[1]) + np.einsum("mcp,mdp->mcd", z, z)
        gain = np.linalg.slogdet(inner)[1] / p
        if self.weight > 0:
            q = self.features.shape[1]
            f = self.features[chosen]
            Lf = np.linalg.cholesky(np.eye(q) + f.T @ f)
            y = np.linalg.solve(Lf, self.features.T)
            gain = gain + self.weight * np.log1p(np.sum(y * y, axis=0)) / q
        gain[chosen] = -np.inf
        return gain


def select_load_configurations(gravity_in_sensor: ArrayLike, n_load_configurations: int,
                               load_positions_in_sensor: ArrayLike | None = None) -> NDArray[np.int64]:
    """Indices of the ``n_load_configurations`` load positions most informative over the candidate directions.

    Maximises :func:`d_criterion` of all candidate directions (m, 3) run with the chosen configurations
    (every subset when there are at most 5000, else greedy forward selection).

    Raises
    ------
    PlanningError
        ``n_load_configurations`` outside ``1 .. n_configurations`` or too few to identify the LTM.

    Examples
    --------
    >>> from ftcal.robot import gravity_directions_in_sensor
    >>> select_load_configurations(gravity_directions_in_sensor(2), 3).tolist()  # of the thesis' seven
    [1, 2, 4]
    """
    from itertools import combinations
    from math import comb

    u = np.asarray(gravity_in_sensor, dtype=float).reshape(-1, 3)
    r = _load_positions(load_positions_in_sensor)
    k = n_load_configurations
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 1 <= k <= len(r):
        raise PlanningError(f"n_load_configurations must be an integer in 1..{len(r)} (the load configurations "
                            f"given); got {k!r}.")
    if comb(len(r), k) <= 5000:
        subsets = [list(c) for c in combinations(range(len(r)), k)]
        scores = [d_criterion(u, r[c]) for c in subsets]
        best = subsets[int(np.argmax(scores))]
        score = max(scores)
    else:
        best = []
        for _ in range(k):
            left = [i for i in range(len(r)) if i not in best]
            trial = [d_criterion(u, r[best + [i]]) if len(best) >= 2 else
                     float(np.linalg.norm(r[i] - (r[best].mean(axis=0) if best else 0))) for i in left]
            best.append(left[int(np.argmax(trial))])
        score = d_criterion(u, r[best])
    if not np.isfinite(score):
        raise PlanningError(f"{k} load configuration(s) can not identify the linear calibration model (its torque "
                            "part needs positions whose differences span 3-D: at least 3 configurations); "
                            "ask for more.")
    return np.array(sorted(best), dtype=np.int64)


def select_poses(
    gravity_in_sensor: ArrayLike,
    n_poses: int,
    *,
    strategy: str = "d-optimal",
    load_positions_in_sensor: ArrayLike | None = None,
    space_filling: float = 0.25,
    max_exchange_passes: int = 20,
    random_state: int | np.random.Generator | None = None,
) -> NDArray[np.int64]:
    """Indices of ``n_poses`` of the candidate directions (m, 3), chosen by ``strategy``.

    Parameters
    ----------
    gravity_in_sensor : array-like of shape (m, 3)
        Candidate unit gravity directions in the sensor frame (the reachable ones).
    n_poses : int
        How many to choose, ``LINEAR_MODEL_PARAMETERS <= n_poses <= m``.
    strategy : {"d-optimal", "random"}
        ``"d-optimal"``: greedy additions then Fedorov exchanges on the criterion of the
        module docstring (deterministic); ``"random"``: uniform without replacement.
    load_positions_in_sensor : array-like of shape (n_configurations, 3), optional
        The load configurations run at every pose [m]; default the thesis' seven.
    space_filling : float, default=0.25
        Weight of the space-filling term (0: pure D-optimality of the linear model).
    max_exchange_passes : int, default=20
        Passes of exchanges over the chosen poses (they stop earlier when none improves).
    random_state : int, Generator or None
        Seed of the random strategy.

    Returns
    -------
    ndarray of shape (n_poses,)
        Candidate indices; for ``"d-optimal"`` in the order the greedy pass added them
        (then exchanged in place), so ``result[:k]`` after the greedy pass is a greedy plan of ``k``.

    Raises
    ------
    PlanningError
        ``n_poses`` outside ``[LINEAR_MODEL_PARAMETERS, m]`` or an unknown strategy.

    Examples
    --------
    >>> from ftcal.robot import gravity_directions_in_sensor
    >>> cands = gravity_directions_in_sensor(2)
    >>> idx = select_poses(cands, 12)
    >>> len(set(idx.tolist())), d_criterion(cands[idx]) > d_criterion(cands[:12])
    (12, True)
    """
    u = np.asarray(gravity_in_sensor, dtype=float).reshape(-1, 3)
    m = len(u)
    if isinstance(n_poses, bool) or not isinstance(n_poses, (int, np.integer)):
        raise PlanningError(f"n_poses must be an integer; got {n_poses!r}.")
    if n_poses > m:
        raise PlanningError(f"{{n_poses}} {n_poses} is more than the {m} reachable candidate directions.",
                            parameter="n_poses", value=n_poses,
                            fix=f"ask for at most {m} poses, or plan on a denser sphere (a larger "
                            "{candidate_subdivisions})", settings={"candidate_subdivisions": NO_SETTING})
    if n_poses < LINEAR_MODEL_PARAMETERS:
        raise PlanningError(f"{{n_poses}} {n_poses} is fewer than the {LINEAR_MODEL_PARAMETERS} parameters of the "
                            "linear calibration model per output (6 wrench regressors and an offset).",
                            parameter="n_poses", value=n_poses, fix=f"ask for at least {LINEAR_MODEL_PARAMETERS} poses")
    if not np.isfinite(space_filling) or space_filling < 0:
        raise PlanningError(f"space_filling must be a finite weight >= 0; got {space_filling!r}.")
    if strategy == "random":
        rng = np.random.default_rng(random_state)
        return np.sort(rng.choice(m, size=int(n_poses), replace=False))
    if strategy != "d-optimal":
        raise PlanningError(f"strategy must be 'random' or 'd-optimal' to select poses; got {strategy!r}.")
    degree = min(int(np.ceil(np.sqrt(n_poses))) - 1, _MAX_SPACE_FILLING_DEGREE)
    design = _GreedyDesign(linear_design_rows(u, load_positions_in_sensor),
                           _sphere_polynomial_features(u, max(degree, 1)), space_filling)
    chosen: list[int] = []
    for _ in range(int(n_poses)):
        chosen.append(int(np.argmax(design.gains(chosen))))  # argmax: the lowest index among ties
    for _ in range(int(max_exchange_passes)):
        improved = False
        for pos in range(len(chosen)):
            rest = chosen[:pos] + chosen[pos + 1:]
            gain = design.gains(rest)
            best = int(np.argmax(gain))
            if gain[best] > gain[chosen[pos]] + 1e-10 * max(1.0, abs(gain[chosen[pos]])):
                chosen[pos] = best
                improved = True
        if not improved:
            break
    return np.array(chosen, dtype=np.int64)


def _chosen_directions(candidates: CandidatePoses, strategy: str, n_poses: int, load_positions_in_sensor,
                       space_filling: float, n_load_configurations: int | None, random_state
                       ) -> tuple[NDArray[np.int64], dict]:
    """The candidates a random or D-optimal plan chooses (their indices) and the plan's settings."""
    positions = _load_positions(load_positions_in_sensor)
    configs = np.arange(len(positions))
    if n_load_configurations is not None:
        if strategy != "d-optimal":
            raise PlanningError("n_load_configurations (which load configurations) needs strategy 'd-optimal'.")
        configs = select_load_configurations(candidates.gravity_in_sensor, n_load_configurations, positions)
    load_positions_in_sensor = positions[configs]
    picked = select_poses(candidates.gravity_in_sensor, n_poses, strategy=strategy,
                          load_positions_in_sensor=load_positions_in_sensor, space_filling=space_filling,
                          random_state=random_state)
    settings = {"strategy": strategy, "n_poses": int(n_poses), **candidates.settings,
                "candidate_subdivisions": candidates.settings.get("subdivisions"),
                "n_reachable_candidates": len(candidates),
                "space_filling": float(space_filling) if strategy == "d-optimal" else None,
                "random_state": random_state if isinstance(random_state, (int, np.integer)) else None,
                "d_criterion": d_criterion(candidates.gravity_in_sensor[picked], load_positions_in_sensor),
                "load_configurations": configs.tolist(),
                "load_positions_in_sensor_m": load_positions_in_sensor.tolist()}
    settings.pop("subdivisions", None)
    return picked, settings


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
    strategy: str = "geodesic",
    n_poses: int | None = None,
    candidate_subdivisions: int = DEFAULT_CANDIDATE_SUBDIVISIONS,
    candidates: CandidatePoses | None = None,
    load_positions_in_sensor: ArrayLike | None = None,
    space_filling: float = 0.25,
    n_load_configurations: int | None = None,
    random_state: int | np.random.Generator | None = None,
) -> CalibrationPlan:
    """Plan calibration poses: a geodesic sphere, or ``n_poses`` chosen from a dense one.

    ``strategy="geodesic"`` (default, the thesis): every icosphere direction of
    level ``subdivisions`` outside the cap. ``"d-optimal"`` / ``"random"``:
    ``n_poses`` of the reachable directions of level ``candidate_subdivisions``
    (see the module docstring and :func:`select_poses`). Directions are visited
    in a greedy nearest-neighbour order (short robot motions); each IK solve
    starts from the previous pose, falling back to the home posture and further
    seeds (for chosen poses, to the candidate's own solution).

    Parameters
    ----------
    robot : RobotModel
    subdivisions, excluded_direction, excluded_cap_deg
        See :func:`gravity_directions_in_sensor` (``subdivisions``: geodesic only).
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
        IK effort per direction (see :func:`ftcal.robot.solve_gravity_direction_ik`).
    strategy : {"geodesic", "random", "d-optimal"}, default="geodesic"
    n_poses : int, optional
        Poses to choose (random and D-optimal only; required there).
    candidate_subdivisions : int, default=3
        Icosphere level of the candidates (642 directions before the cap rule).
    candidates : CandidatePoses, optional
        Precomputed :func:`reachable_candidates` (then the sphere settings above are theirs).
    load_positions_in_sensor : array-like of shape (n_configurations, 3), optional
        Load configurations run at every pose [m] (D-optimal design); default the thesis' seven.
    space_filling : float, default=0.25
        Weight of the space-filling term of the D-optimal criterion.
    n_load_configurations : int, optional
        Also choose this many of the load configurations (D-optimal only; see the module
        docstring); ``plan.settings["load_configurations"]`` lists their indices. Default: all.
    random_state : int, Generator or None
        Seed of the random strategy (the D-optimal plan is deterministic).

    Returns
    -------
    CalibrationPlan

    Raises
    ------
    PlanningError
        Unknown strategy, ``n_poses`` given to the geodesic plan or missing for the others,
        more poses than reachable candidates, fewer than the linear model's 7 parameters.

    Examples
    --------
    >>> from ftcal.robot import load_robot
    >>> plan = plan_calibration_poses(load_robot(), subdivisions=0, excluded_cap_deg=0)
    >>> plan.n_poses, plan.q.shape
    (12, (12, 7))
    >>> small = plan_calibration_poses(load_robot(), strategy="d-optimal", n_poses=8, candidate_subdivisions=1)
    >>> small.n_poses, small.settings["strategy"]
    (8, 'd-optimal')
    """
    if strategy not in PLAN_STRATEGIES:
        raise PlanningError(f"strategy must be one of {', '.join(PLAN_STRATEGIES)}; got {strategy!r}.")
    if strategy == "geodesic":
        if n_poses is not None:
            raise PlanningError(f"the geodesic plan takes every direction of its sphere (n_poses={n_poses} given); "
                                "choose its size with subdivisions (12, 42, 155 poses for 0, 1, 2), or use strategy "
                                "'d-optimal' or 'random' for a given number of poses.")
        dirs = gravity_directions_in_sensor(subdivisions, excluded_direction=excluded_direction,
                                            excluded_cap_deg=excluded_cap_deg)
        anchor, fallback_q = anchor_position_in_base, None
        settings = {"strategy": "geodesic", "subdivisions": int(subdivisions),
                    "excluded_cap_deg": float(excluded_cap_deg),
                    "excluded_direction": np.asarray(excluded_direction, dtype=float).tolist()}
    else:
        if n_poses is None:
            raise PlanningError(f"strategy {strategy!r} needs n_poses (how many poses to choose).")
        if candidates is None:
            candidates = reachable_candidates(
                robot, subdivisions=candidate_subdivisions, excluded_direction=excluded_direction,
                excluded_cap_deg=excluded_cap_deg, gravity_in_base=gravity_in_base,
                anchor_position_in_base=anchor_position_in_base, orientation_tol=orientation_tol,
                limit_margin=limit_margin, max_iterations=max_iterations, n_random_seeds=n_random_seeds)
        picked, settings = _chosen_directions(candidates, strategy, n_poses, load_positions_in_sensor,
                                              space_filling, n_load_configurations, random_state)
        dirs, anchor, fallback_q = candidates.gravity_in_sensor[picked], candidates.anchor_position_in_base, \
            candidates.q[picked]
    ik, qs, reached, dropped = _solve_directions(robot, dirs, anchor, gravity_in_base, orientation_tol, limit_margin,
                                                 max_iterations, n_random_seeds, fallback_q)
    n_candidates, unreachable = (len(dirs), dirs[dropped]) if strategy == "geodesic" else \
        (candidates.n_candidates, candidates.unreachable)
    g = dirs[reached].reshape(-1, 3)
    pitch, yaw = pitch_yaw_from_gravity_in_sensor(g)
    settings.update({"gravity_in_base": ik["gravity_in_base"].tolist(), "limit_margin_rad": float(limit_margin)})
    return CalibrationPlan(
        q=np.array(qs).reshape(-1, robot.n_joints), gravity_in_sensor=g, pitch=pitch, yaw=yaw,
        unreachable=np.asarray(unreachable).reshape(-1, 3), anchor_position_in_base=ik["anchor_position_in_base"],
        robot_name=robot.name, sensor_frame=robot.sensor_frame, anchor_frame=robot.anchor_frame,
        n_candidates=n_candidates, settings=settings,
    )
