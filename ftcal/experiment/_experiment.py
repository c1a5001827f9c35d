"""From recorded load / no-load runs to a calibration dataset (thesis IV-B-d/e).

Each sphere of poses is run twice: without the external load (*no-load*: the
sensor carries only the mounting device) and with it (*load*). The dataset must
hold the external load's effect only, so the no-load reading of each pose is
subtracted from the load reading of the same pose.

The two runs never reach exactly the same joint angles (tenths of a degree).
Eq. 17 gives the rotation between the two sensor poses of a pair from forward
kinematics, ``R_delta = R_no-load^T R_load``. Rotating the *raw* readings by it
would only be right if the raw channels were a wrench; instead we use what
makes the correction exact for any raw channel layout:

1. The mounting device is a rigid mass, so the no-load reading is affine in
   the gravity direction seen by the sensor, ``u = R^T g_hat``:
   ``raw_no-load ~= B u + z``. ``B`` (N, 3) and ``z`` (N,) are fitted by least
   squares over the no-load poses of each no-load run (>= 4 directions that
   span 3-D; a sphere gives ~155).
2. The no-load reading *at the load pose* is the measured one moved by the
   small rotation: ``aligned = raw_no-load + B (R_delta^T - I) u_no-load``
   (``R_delta^T u_no-load`` is the gravity direction at the load pose). Using
   the measured reading keeps its pose-specific part (anything ``B`` misses);
   the fit only carries the tiny difference.
3. Input ``X = raw_load - aligned`` (zero offset cancelled), target ``y`` =
   the reference wrench of the external load at the load pose (eq. 15-16).

The dataset's ``group`` is the load configuration id, for grouped splits.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
from sklearn.linear_model import LinearRegression
from numpy.typing import ArrayLike, NDArray

from ..io._dataset import CalibrationDataset
from ..core._exceptions import KinematicsError, LogFormatError, Placeholder
from ..robot._loads import GRAVITY_IN_BASE, LoadConfiguration, reference_wrench, thesis_load_configurations
from ..io._logs import SHARED_NO_LOAD_CONFIG, RunLog, read_run_log, run_log_files
from ..robot._robot import RobotModel, load_robot, sensor_pose_in_base

__all__ = ["rotation_delta", "NoLoadModel", "fit_no_load_model", "PairedRuns", "pair_runs", "prepare_dataset"]


def rotation_delta(pose_no_load: ArrayLike, pose_load: ArrayLike) -> NDArray[np.float64]:
    """``R_delta = R_no-load^T R_load`` (eq. 17) for stacks of poses.

    Parameters
    ----------
    pose_no_load, pose_load : array-like of shape (n, 4, 4) or (n, 3, 3)
        Sensor poses (or rotations) in the base frame of paired poses.

    Returns
    -------
    ndarray of shape (n, 3, 3)
        The load pose's rotation expressed in the no-load sensor frame.

    Examples
    --------
    >>> import numpy as np
    >>> c, s = np.cos(0.01), np.sin(0.01)
    >>> Rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    >>> np.allclose(rotation_delta(np.eye(3)[None], Rz[None])[0], Rz)
    True
    """
    a, b = np.asarray(pose_no_load, dtype=float), np.asarray(pose_load, dtype=float)
    if a.ndim == 2:
        a, b = a[None], b[None]
    if a.shape != b.shape or a.ndim != 3 or a.shape[1:] not in ((3, 3), (4, 4)):
        raise KinematicsError(f"poses must be two stacks of the same shape (n, 4, 4) or (n, 3, 3); "
                              f"got {a.shape} and {b.shape}.")
    return np.einsum("nji,njk->nik", a[:, :3, :3], b[:, :3, :3])


@dataclass(frozen=True)
class NoLoadModel:
    """Affine model of the no-load (mounting device only) reading: ``raw = u @ matrix.T + offset``.

    Attributes
    ----------
    matrix : ndarray of shape (n_channels, 3)
        Raw response to the unit gravity direction ``u`` in the sensor frame.
    offset : ndarray of shape (n_channels,)
        Raw reading at zero load (the sensor's tare).
    residual_rms : ndarray of shape (n_channels,)
        RMS of the fit residual per channel, in raw units.
    n_poses : int
    """

    matrix: NDArray[np.float64]
    offset: NDArray[np.float64]
    residual_rms: NDArray[np.float64]
    n_poses: int

    def predict(self, gravity_in_sensor: ArrayLike) -> NDArray[np.float64]:
        """Modelled no-load readings (n, n_channels) for unit gravity directions (n, 3) in the sensor frame."""
        return np.asarray(gravity_in_sensor, dtype=float) @ self.matrix.T + self.offset


def fit_no_load_model(gravity_in_sensor: ArrayLike, raw: ArrayLike) -> NoLoadModel:
    """Least-squares fit of :class:`NoLoadModel` to no-load poses.

    Parameters
    ----------
    gravity_in_sensor : array-like of shape (n, 3)
        Unit gravity direction in the sensor frame of each no-load pose.
    raw : array-like of shape (n, n_channels)
        Their raw readings.

    Raises
    ------
    LogFormatError
        Fewer than 4 poses, or directions that do not span 3-D.

    Examples
    --------
    >>> import numpy as np
    >>> u = np.vstack([np.eye(3), -np.eye(3)])
    >>> B = np.arange(18.0).reshape(6, 3)
    >>> m = fit_no_load_model(u, u @ B.T + 5.0)
    >>> np.allclose(m.matrix, B), np.allclose(m.offset, 5.0)
    (True, True)
    """
    u, r = np.asarray(gravity_in_sensor, dtype=float), np.asarray(raw, dtype=float)
    A = np.hstack([u, np.ones((u.shape[0], 1))])
    if u.shape[0] < 4 or np.linalg.matrix_rank(A, tol=1e-3) < 4:
        raise LogFormatError(
            f"the no-load run has {u.shape[0]} poses whose gravity directions do not span 3-D; "
            "record at least 4 poses in different directions (a calibration sphere) without the load."
        )
    fit = LinearRegression().fit(u, r)  # the affine model r = B u + offset
    resid = r - fit.predict(u).reshape(r.shape)
    return NoLoadModel(matrix=fit.coef_.reshape(r.shape[1], 3).copy(), offset=np.reshape(fit.intercept_, -1).copy(),
                       residual_rms=np.sqrt(np.mean(resid**2, axis=0)), n_poses=int(u.shape[0]))


@dataclass
class PairedRuns:
    """Load poses with their no-load partner, and every no-load pose, averaged per pose.

    Attributes
    ----------
    config, pose : ndarray of shape (m,)
        Load configuration id and pose index of each pair.
    q_load, q_no_load : ndarray of shape (m, n_joints)
        Joint angles [rad] of the two poses of a pair.
    raw_load, raw_no_load : ndarray of shape (m, n_channels)
    no_load_run : ndarray of shape (m,)
        ``config`` value of the no-load run each pair used (its own id or -1).
    source : list of str
        ``"file:line"`` of each pair's first load row.
    temperature_load : ndarray of shape (m,) or None
        Sensor temperature [deg C] of each load pose, when every load row has one.
    no_load : dict
        No-load run id -> (q (k, n_joints), raw (k, n_channels)) of all its poses.
    rotation_load, rotation_no_load : ndarray of shape (m, 3, 3) or None
        The sensor's orientation (sensor to base) of each pose of a pair, when the runs recorded it (tf) instead
        of joint angles.
    no_load_rotations : dict
        No-load run id -> the orientations (k, 3, 3) of all its poses, when recorded.
    """

    config: NDArray[np.int64]
    pose: NDArray[np.int64]
    q_load: NDArray[np.float64]
    q_no_load: NDArray[np.float64]
    raw_load: NDArray[np.float64]
    raw_no_load: NDArray[np.float64]
    no_load_run: NDArray[np.int64]
    source: list[str]
    no_load: dict[int, tuple[NDArray[np.float64], NDArray[np.float64]]]
    temperature_load: NDArray[np.float64] | None = None
    rotation_load: NDArray[np.float64] | None = None
    rotation_no_load: NDArray[np.float64] | None = None
    no_load_rotations: dict[int, NDArray[np.float64]] = field(default_factory=dict)


def _average_samples(logs: Sequence[RunLog], same_pose_tol: float):
    """(kind, config, pose) -> (mean q, mean raw, first 'file:line', mean temperature or None, mean rotation or
    None); the rows of one pose must agree within ``same_pose_tol`` [rad] (each joint, or the orientation)."""
    from scipy.spatial.transform import Rotation

    groups: dict[tuple[str, int, int], list[tuple[RunLog, int]]] = defaultdict(list)
    for log in logs:
        for i in range(log.n_rows):
            groups[(str(log.run_kind[i]), int(log.config[i]), int(log.pose[i]))].append((log, i))
    out = {}
    for key, members in groups.items():
        q = np.array([lg.q[i] for lg, i in members])
        raw = np.array([lg.raw[i] for lg, i in members])
        spread = float(np.max(np.ptp(q, axis=0), initial=0.0))  # no joints when the orientation was recorded
        at = [f"{lg.path}:line {lg.line[i]}" for lg, i in members]
        first = at[0]
        if spread > same_pose_tol:
            j = int(np.argmax(np.ptp(q, axis=0)))
            k = int(np.argmax(np.abs(q[:, j] - q[0, j])))
            raise LogFormatError(
                f"{first} and {at[k]}: {key[0]} rows of config {key[1]}, pose {key[2]} differ by {spread:.4f} rad "
                f"in q{j + 1}; one pose index was used for two different poses. Give each pose its own index."
            )
        temps = [lg.temperature[i] for lg, i in members if lg.temperature is not None]
        temperature = float(np.mean(temps)) if len(temps) == len(members) else None
        rotation = None
        if members[0][0].rotation is not None:  # the orientation recorded itself (tf), not joints
            turns = Rotation.from_matrix(np.array([lg.rotation[i] for lg, i in members]))
            apart = (turns * turns[0].inv()).magnitude()
            if apart.max() > same_pose_tol:
                k = int(np.argmax(apart))
                raise LogFormatError(
                    f"{first} and {at[k]}: {key[0]} rows of config {key[1]}, pose {key[2]} are {apart[k]:.4f} rad "
                    "apart in orientation; one pose index was used for two different poses. Give each pose its own "
                    "index.")
            rotation = turns.mean().as_matrix()
        out[key] = (q.mean(axis=0), raw.mean(axis=0), first, temperature, rotation)
    return out


def pair_runs(logs: Sequence[RunLog], *, same_pose_tol: float = 0.01) -> PairedRuns:
    """Pair each load pose with the no-load pose of the same configuration (or the shared run) and index.

    Parameters
    ----------
    logs : sequence of RunLog
        All files of an experiment, read with :func:`ftcal.io.read_run_log`.
    same_pose_tol : float, default=0.01
        Largest joint spread [rad] among repeated rows of one pose.

    Raises
    ------
    LogFormatError
        Channel or joint counts that differ between files, a load pose without
        a no-load partner, a no-load pose of a configuration without a load
        partner, or no load rows at all. Messages name file and line.
    """
    if not logs:
        raise LogFormatError("no log files given; pass the paths of the load and no-load run logs.")
    ref = logs[0]
    for lg in logs[1:]:
        for what, a, b in (("raw channels", lg.n_channels, ref.n_channels), ("joints", lg.n_joints, ref.n_joints)):
            if a != b:
                raise LogFormatError(f"{lg.path}: {a} {what} but {ref.path} has {b}; all logs of one "
                                     "experiment must come from the same sensor and robot.")
        if (lg.rotation is None) != (ref.rotation is None):
            raise LogFormatError(f"{lg.path} and {ref.path}: one records the sensor's orientation (tf), the other joint "
                                 "angles; give the runs of one experiment recorded alike.")
    samples = _average_samples(logs, same_pose_tol)
    load_keys = sorted(k for k in samples if k[0] == "load")
    if not load_keys:
        raise LogFormatError(f"no 'load' rows in {', '.join(str(lg.path) for lg in logs)}; "
                             "the dataset needs load runs besides the no-load runs.")
    partners = []
    for _, c, p in load_keys:
        partner = ("no-load", c, p) if ("no-load", c, p) in samples else ("no-load", SHARED_NO_LOAD_CONFIG, p)
        if partner not in samples:
            raise LogFormatError(f"{samples[('load', c, p)][2]}: load pose {p} of config {c} has no no-load partner "
                                 f"(no 'no-load' row with config {c} or {SHARED_NO_LOAD_CONFIG} and pose {p}); "
                                 "record that pose without the load, or remove it.")
        partners.append(partner)
    loads = [samples[k] for k in load_keys]
    with_temperature = [s[3] is not None for s in loads]
    if any(with_temperature) and not all(with_temperature):  # never drop the temperature of the others silently
        has, lacks = loads[with_temperature.index(True)][2], loads[with_temperature.index(False)][2]
        raise LogFormatError(
            f"{lacks}: this load row has no temperature but {has} has a temperature column; the dataset's "
            "temperature [deg C] needs it for every load row. Record it in every log, or remove the temperature "
            "column from all of them.")
    no_loads = [samples[k] for k in partners]
    load_set = {(c, p) for _, c, p in load_keys}
    runs: dict[int, list] = defaultdict(list)  # no-load run id -> the samples of its poses, in pose order
    for (kind, c, p), sample in sorted(samples.items()):
        if kind != "no-load":
            continue
        if c != SHARED_NO_LOAD_CONFIG and (c, p) not in load_set:
            raise LogFormatError(f"{sample[2]}: no-load pose {p} of config {c} has no load partner (no 'load' row "
                                 f"with config {c} and pose {p}); was the load run cut short?")
        runs[c].append(sample)
    recorded = ref.rotation is not None
    return PairedRuns(
        config=np.array([k[1] for k in load_keys], dtype=np.int64),
        pose=np.array([k[2] for k in load_keys], dtype=np.int64),
        q_load=np.array([s[0] for s in loads]), q_no_load=np.array([s[0] for s in no_loads]),
        raw_load=np.array([s[1] for s in loads]), raw_no_load=np.array([s[1] for s in no_loads]),
        no_load_run=np.array([k[1] for k in partners], dtype=np.int64), source=[s[2] for s in loads],
        no_load={c: (np.array([s[0] for s in v]), np.array([s[1] for s in v])) for c, v in runs.items()},
        temperature_load=np.array([s[3] for s in loads]) if all(with_temperature) else None,
        rotation_load=np.array([s[4] for s in loads]) if recorded else None,
        rotation_no_load=np.array([s[4] for s in no_loads]) if recorded else None,
        no_load_rotations={c: np.array([s[4] for s in v]) for c, v in runs.items()} if recorded else {},
    )


def _config_positions(load_configurations: Sequence[LoadConfiguration] | Mapping[int, ArrayLike] | None):
    if load_configurations is None:
        load_configurations = thesis_load_configurations()
    if isinstance(load_configurations, Mapping):
        return {int(k): np.asarray(v, dtype=float) for k, v in load_configurations.items()}
    return {c.config_id: np.asarray(c.position_in_sensor, dtype=float) for c in load_configurations}


def _check_limits(robot: RobotModel, q: NDArray[np.float64], sources: list[str], tol: float) -> None:
    lo, hi = robot.lower_limits - tol, robot.upper_limits + tol
    bad = np.argwhere((q < lo) | (q > hi))
    if bad.size:
        r, j = bad[0]
        raise LogFormatError(f"{sources[r]}: q{j + 1} = {q[r, j]:.4f} rad lies outside the limits "
                             f"[{robot.lower_limits[j]:.4f}, {robot.upper_limits[j]:.4f}] of {robot.name!r}; "
                             "wrong robot, wrong joint order or wrong unit?")


def _load_masses(logs: list[RunLog], load_mass: float | None, load_configurations) -> tuple[float, dict[int, float]]:
    """The load mass [kg] (given, else the one the logs declare, else the fixture's median) and each
    configuration's mass the fixture states (every one, else none used); refuses masses that disagree."""
    masses = {lg.load_mass for lg in logs if lg.load_mass is not None}
    fixture_mass = {c.config_id: c.mass_kg for c in (load_configurations or ())
                    if isinstance(c, LoadConfiguration) and c.mass_kg is not None}
    if fixture_mass and load_mass is None and len(fixture_mass) == len(load_configurations):
        # the fixture states every configuration's mass (the logs' per-file masses then need not agree with each
        # other, but each must agree with the configurations it records)
        for lg in logs:
            if lg.load_mass is None:
                continue
            for cid in sorted(set(int(c) for c in lg.config)):
                stated = fixture_mass.get(cid)
                if stated is not None and abs(stated - lg.load_mass) > 1e-6 * max(stated, 1.0):
                    raise LogFormatError(
                        f"{lg.path}: the log declares load_mass_kg {lg.load_mass:g} but the fixture gives "
                        f"configuration {cid} a mass of {stated:g} kg; which one is right? Fix the fixture file "
                        "or the '# load_mass_kg' comment.")
        load_mass = float(np.median(list(fixture_mass.values())))
        masses = set()
    if load_mass is None:
        if len(masses) != 1:
            raise LogFormatError(f"{{load_mass}} not given and the logs declare {sorted(masses) or 'none'}.",
                                 parameter="load_mass", fix="pass {load_mass} or write '# load_mass_kg: <kg>' in "
                                 "the logs", settings={"load_mass": Placeholder("<kg>")})
        load_mass = masses.pop()
    elif masses and any(abs(m - load_mass) > 1e-9 for m in masses):
        raise LogFormatError(f"{{load_mass}} {load_mass:g} kg but the logs declare {sorted(masses)} kg; which one "
                             "is right?", parameter="load_mass", value=load_mass,
                             fix="correct {load_mass} or the '# load_mass_kg' comments")
    if not np.isfinite(load_mass) or load_mass <= 0:
        raise LogFormatError(f"load_mass must be a positive mass in kg; got {load_mass!r}.")
    return load_mass, fixture_mass


def prepare_dataset(log_paths: Sequence[str | Path] | str | Path, robot: RobotModel | str | Path = "kuka_iiwa14",
                    load_mass: float | None = None, *,
                    load_configurations: Sequence[LoadConfiguration] | Mapping[int, ArrayLike] | None = None,
                    gravity_in_base: ArrayLike = GRAVITY_IN_BASE, n_channels: int | None = None,
                    max_pair_rotation_deg: float = 3.0, limit_tolerance_rad: float = 0.01) -> CalibrationDataset:
    """Turn load / no-load run logs into a :class:`ftcal.CalibrationDataset` (method in the module docstring).

    Parameters
    ----------
    log_paths : sequence of paths or RunLog, or one path
        Every log file of the experiment (any split of runs into files), or the
        run logs already read (:class:`ftcal.io.RunLog`); a single path is one log
        file, or a folder whose ``*.csv`` are the logs.
    robot : RobotModel, built-in name or URDF path, default="kuka_iiwa14"
        The arm the joint angles belong to (its sensor frame gives the poses).
    load_mass : float, optional
        Mass of the external load [kg]; default the logs' ``load_mass_kg``.
    load_configurations : sequence of LoadConfiguration or mapping, optional
        Load positions in the sensor frame [m] by config id; default the
        thesis' seven (:func:`ftcal.robot.thesis_load_configurations`).
    gravity_in_base : array-like of shape (3,), default=(0, 0, -9.80665)
        Gravity in the base frame [m/s²].
    n_channels : int, optional
        Expected raw channel count.
    max_pair_rotation_deg : float, default=3
        Largest rotation between the two poses of a pair [deg]; larger means
        the pose indices of the two runs do not match.
    limit_tolerance_rad : float, default=0.01
        Allowed excess of logged joint angles over the robot's limits [rad].

    Returns
    -------
    CalibrationDataset
        ``raw`` = load minus aligned no-load reading, ``wrench`` = reference
        wrench of the external load [N, N·m], ``group`` = load configuration id;
        ``meta`` records robot, mass, configurations, files and fit residuals.

    Examples
    --------
    See :func:`ftcal.experiment.simulate_experiment` for logs to feed it.
    """
    if isinstance(robot, (str, Path)):
        robot = load_robot(robot)
    if isinstance(log_paths, (str, Path)):  # one file or a folder of logs, not a string of characters
        one = Path(log_paths)
        paths = run_log_files(one) if one.is_dir() else [one]
        if not paths:
            raise LogFormatError(f"{one}: the folder holds no .csv run logs.")
    else:
        paths = [p if isinstance(p, RunLog) else Path(p) for p in log_paths]
    if not paths:
        raise LogFormatError("no run logs given; pass the load and no-load log files (or their folder).")
    # a RunLog already read (e.g. the still poses of a ROS bag) is used as it is
    logs = [p if isinstance(p, RunLog) else read_run_log(p, n_channels=n_channels, n_joints=robot.n_joints)
            for p in paths]
    paths = [lg.path for lg in logs]
    for lg in logs:  # the frame the wrenches are computed in must be the one the log was recorded with
        if lg.sensor_frame is not None and lg.sensor_frame != robot.sensor_frame:
            raise LogFormatError(
                f"{lg.path}: the log was recorded with sensor frame {lg.sensor_frame!r} but the robot model's is "
                f"{robot.sensor_frame!r}; give the same sensor frame (or the same sensor mounting) as the recording.")
    load_mass, fixture_mass = _load_masses(logs, load_mass, load_configurations)
    positions = _config_positions(load_configurations)
    pairs = pair_runs(logs)
    unknown = sorted(set(pairs.config.tolist()) - set(positions))
    if unknown:
        first = pairs.source[int(np.flatnonzero(pairs.config == unknown[0])[0])]
        raise LogFormatError(f"{first}: load configuration {unknown[0]} is not among the known ones "
                             f"{sorted(positions)}.", parameter="load_configurations", value=int(unknown[0]),
                             fix="pass {load_configurations} with its position")
    g = np.asarray(gravity_in_base, dtype=float)
    g_hat = g / np.linalg.norm(g)
    recorded = pairs.rotation_load is not None  # the orientation recorded (tf), else the robot's joints through FK
    if recorded:
        R_load, R_no_load = pairs.rotation_load, pairs.rotation_no_load
    else:
        for q in (pairs.q_load, pairs.q_no_load):
            _check_limits(robot, q, pairs.source, limit_tolerance_rad)
        R_load = sensor_pose_in_base(robot, pairs.q_load)[:, :3, :3]
        R_no_load = sensor_pose_in_base(robot, pairs.q_no_load)[:, :3, :3]
    R_delta = rotation_delta(R_no_load, R_load)
    angle = np.degrees(np.arccos(np.clip((np.trace(R_delta, axis1=1, axis2=2) - 1) / 2, -1, 1)))
    if np.any(angle > max_pair_rotation_deg):
        i = int(np.argmax(angle))
        raise LogFormatError(f"{pairs.source[i]}: load and no-load poses {pairs.pose[i]} of config {pairs.config[i]} "
                             f"differ by {angle[i]:.2f} deg (> {max_pair_rotation_deg}); the pose indices of the two "
                             "runs do not refer to the same commanded pose.")
    u_no_load = np.einsum("nji,j->ni", R_no_load, g_hat)
    du = np.einsum("nji,nj->ni", R_delta, u_no_load) - u_no_load  # (R_delta^T - I) u_no-load
    aligned, fits = pairs.raw_no_load.copy(), {}
    for run, (q_nl, raw_nl) in pairs.no_load.items():
        R_run = pairs.no_load_rotations[run] if recorded else sensor_pose_in_base(robot, q_nl)[:, :3, :3]
        fits[run] = fit_no_load_model(np.einsum("nji,j->ni", R_run, g_hat), raw_nl)
        sel = pairs.no_load_run == run
        aligned[sel] += du[sel] @ fits[run].matrix.T
    raw = pairs.raw_load - aligned
    r = np.array([positions[c] for c in pairs.config])
    row_mass = np.array([fixture_mass.get(int(c), load_mass) for c in pairs.config])
    wrench = reference_wrench(R_load, 1.0, r, g) * row_mass[:, None]  # eq. 15-16 are linear in the mass
    meta = {
        "source": "ftcal.experiment.prepare_dataset",
        "robot": robot.name, "urdf": str(robot.urdf_path), "sensor_frame": robot.sensor_frame,
        "load_mass_kg": float(load_mass), "gravity_in_base_m_s2": g.tolist(),
        "load_mass_kg_by_config": {str(k): float(v) for k, v in sorted(fixture_mass.items())},
        "load_positions_in_sensor_m": {str(k): v.tolist() for k, v in sorted(positions.items())},
        "log_files": [str(p) for p in paths], "n_pairs": int(raw.shape[0]),
        "pair_rotation_deg_max": float(angle.max()), "pair_rotation_deg_mean": float(angle.mean()),
        "no_load_fit_residual_rms": {str(k): f.residual_rms.tolist() for k, f in fits.items()},
        "method": "raw = load - (no-load + B (R_delta^T - I) u_no-load); wrench = eq. 15-16 at the load pose",
        "raw_unit": logs[0].raw_unit,
        "orientation_source": "recorded (tf)" if recorded else "forward kinematics of the joints",
    }
    return CalibrationDataset(raw=raw, wrench=wrench, group=pairs.config, meta=meta,
                              temperature=pairs.temperature_load)
