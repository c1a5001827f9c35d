"""A robot's continuous recording, simulated: still poses joined by moves, a settling transient, noise.

What a robot's own recording (a ROS bag, a CSV with a ``time`` column) looks like, made from a list of
poses and the sensor's reading at each:

* the arm **stands still** at each pose for ``still_s`` seconds (from the start of the recording), then
  **moves** to the next in ``move_s`` seconds (joints interpolated with a smooth step, orientations by
  spherical interpolation);
* at each arrival the reading carries a **settling transient**: ``A exp(-t / settle_tau_s)`` per
  component, of amplitude ``settle_amplitude`` and a random sign (the sensor's creep and the arm's ringing
  after a move; about 1 N over the first seconds on a real Axia80);
* Gaussian **noise** of ``noise`` per component on every sample;
* the pose stream (joint states, or orientations as tf would give them) and the sensor stream run at
  **different rates** (``pose_rate_hz``, ``sensor_rate_hz``), with their own stamps.

:func:`ftcal.experiment.find_still_poses` must find the poses, drop the settling and recover the pose readings.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import CalibrationInputError

__all__ = ["ContinuousRecording", "continuous_recording", "write_run_bags"]


@dataclass
class ContinuousRecording:
    """Two streams of a simulated recording.

    Attributes
    ----------
    sensor_time : ndarray of shape (n,)
        [s].
    reading : ndarray of shape (n, m)
        The sensor's reading at ``sensor_time``.
    pose_time : ndarray of shape (k,)
        [s].
    joints : ndarray of shape (k, n_joints) or None
        Joint angles [rad] at ``pose_time`` (when the poses were given as joints).
    rotations : ndarray of shape (k, 3, 3) or None
        Orientations (sensor to base) at ``pose_time`` (when the poses were given as rotations).
    still_from, still_to : ndarray of shape (n_poses,)
        When the arm stands still at each pose [s].
    """

    sensor_time: NDArray[np.float64]
    reading: NDArray[np.float64]
    pose_time: NDArray[np.float64]
    joints: NDArray[np.float64] | None
    rotations: NDArray[np.float64] | None
    still_from: NDArray[np.float64]
    still_to: NDArray[np.float64]


def continuous_recording(
    pose_readings: ArrayLike,
    *,
    joints: ArrayLike | None = None,
    rotations: ArrayLike | None = None,
    still_s: float = 4.0,
    move_s: float = 2.0,
    sensor_rate_hz: float = 100.0,
    pose_rate_hz: float = 50.0,
    settle_amplitude: ArrayLike = 0.0,
    settle_tau_s: float = 0.5,
    noise: ArrayLike = 0.0,
    start_time_s: float = 0.0,
    random_state: int | np.random.Generator | None = None,
) -> ContinuousRecording:
    """Simulate a continuous recording of the given poses (see the module docstring).

    Parameters
    ----------
    pose_readings : array-like of shape (n_poses, m)
        The sensor's settled, noise-free reading at each pose.
    joints : array-like of shape (n_poses, n_joints), optional
        The poses as joint angles [rad] (give ``joints`` or ``rotations``).
    rotations : array-like of shape (n_poses, 3, 3), optional
        The poses as orientations, sensor to base frame.
    still_s, move_s : float
        Seconds still at each pose, and moving between two poses.
    sensor_rate_hz, pose_rate_hz : float
        Rates of the sensor stream and of the pose stream.
    settle_amplitude : float or array-like of shape (m,)
        Amplitude of the settling transient per component.
    settle_tau_s : float
        Its time constant [s].
    noise : float or array-like of shape (m,)
        Standard deviation of the reading's noise per component.
    start_time_s : float
        Time of the first sample [s] (a ROS clock reads ~1.7e9 s).
    random_state : int or Generator, optional

    Returns
    -------
    ContinuousRecording

    Examples
    --------
    >>> import numpy as np
    >>> rec = continuous_recording(np.eye(3), joints=np.diag([0.0, 0.5, 1.0]), still_s=2, move_s=1)
    >>> rec.sensor_time.size, rec.reading.shape[1], rec.joints.shape[1]
    (800, 3, 3)
    """
    from scipy.spatial.transform import Rotation, Slerp

    values = np.atleast_2d(np.asarray(pose_readings, dtype=float))
    if (joints is None) == (rotations is None):
        raise CalibrationInputError("give the poses as joints (n_poses, n_joints) or rotations (n_poses, 3, 3).")
    poses = np.asarray(joints if joints is not None else rotations, dtype=float)
    n_poses = len(values)
    if len(poses) != n_poses:
        raise CalibrationInputError(f"{len(poses)} poses but {n_poses} pose readings; give one reading per pose.")
    for name, v in (("still_s", still_s), ("move_s", move_s), ("sensor_rate_hz", sensor_rate_hz),
                    ("pose_rate_hz", pose_rate_hz), ("settle_tau_s", settle_tau_s)):
        if not (np.isfinite(v) and v > 0):
            raise CalibrationInputError(f"{name} must be a positive number; got {v!r}.")
    rng = np.random.default_rng(random_state)
    period = still_s + move_s
    # pose i: still from i * period to i * period + still_s, then the move to pose i + 1
    arrive = np.arange(n_poses) * period
    leave = arrive + still_s
    end = float(leave[-1])

    def pose_phase(t: NDArray[np.float64]) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
        """The pose held or being left, the next pose, and the smooth-step fraction of the move between them."""
        i = np.clip(np.floor(t / period).astype(np.int64), 0, n_poses - 1)
        frac = np.clip((t - i * period - still_s) / move_s, 0.0, 1.0)
        return i, np.minimum(i + 1, n_poses - 1), frac * frac * (3.0 - 2.0 * frac)

    sensor_t = np.arange(0.0, end, 1.0 / sensor_rate_hz)
    cur, nxt, frac = pose_phase(sensor_t)
    reading = values[cur] + (values[nxt] - values[cur]) * frac[:, None]
    amplitude = np.broadcast_to(np.asarray(settle_amplitude, dtype=float), (values.shape[1],))
    signs = rng.choice([-1.0, 1.0], size=(n_poses, values.shape[1]))
    since = sensor_t - arrive[cur]
    settling = np.where(since[:, None] >= 0, np.exp(-np.maximum(since, 0.0) / settle_tau_s)[:, None], 0.0)
    reading = reading + signs[cur] * amplitude * settling
    sigma = np.broadcast_to(np.asarray(noise, dtype=float), (values.shape[1],))
    reading = reading + rng.normal(size=reading.shape) * sigma
    pose_t = np.arange(0.0, end, 1.0 / pose_rate_hz)
    cur, nxt, frac = pose_phase(pose_t)
    q = R = None
    if joints is not None:
        q = poses[cur] + (poses[nxt] - poses[cur]) * frac[:, None]
    else:
        R = np.empty((len(pose_t), 3, 3))
        for i in range(n_poses):
            sel = cur == i
            R[sel] = Slerp([0.0, 1.0], Rotation.from_matrix(poses[[i, min(i + 1, n_poses - 1)]]))(frac[sel]).as_matrix()
    return ContinuousRecording(sensor_time=sensor_t + start_time_s, reading=reading, pose_time=pose_t + start_time_s,
                               joints=q, rotations=R, still_from=arrive + start_time_s, still_to=leave + start_time_s)


def write_run_bags(
    log_paths: Sequence[str | Path],
    out_dir: str | Path,
    storage: str = "mcap",
    *,
    still_s: float = 3.0,
    move_s: float = 1.5,
    sensor_rate_hz: float = 50.0,
    joint_rate_hz: float = 25.0,
    settle_tau_s: float = 0.4,
    joint_names: Sequence[str] | None = None,
    random_state: int | None = None,
) -> list[Path]:
    """Write each run log (one row per pose) as the robot's continuous recording of that run: a ROS bag.

    The arm stands still at each pose of the log for ``still_s`` seconds and moves to the next in ``move_s``;
    the raw gauges (``/ft_sensor/raw``, ``std_msgs/Float64MultiArray``) at ``sensor_rate_hz`` carry the log's
    reading of each pose plus a settling transient after each move (10 noise levels, time constant
    ``settle_tau_s``) and noise (1e-4 of each channel's span over the run); the joint states
    (``/joint_states``) run at ``joint_rate_hz``. The bag of ``config0_load.csv`` is ``config0_load`` (a rosbag2
    folder) or ``config0_load.bag`` (ROS 1), so that ``ftcal prepare`` pairs the runs as it pairs the logs.

    Parameters
    ----------
    log_paths : sequence of paths
        Run logs (e.g. of :func:`ftcal.experiment.simulate_experiment`).
    out_dir : str or path
        Folder for the bags (created); an existing bag is an error.
    storage : {"sqlite3", "mcap", "ros1"}
    still_s, move_s, sensor_rate_hz, joint_rate_hz, settle_tau_s : float
    joint_names : sequence of str, optional
        The joints' names in the joint states (the robot's); default ``joint1, joint2, ...``.
    random_state : int, optional

    Returns
    -------
    list of pathlib.Path
    """
    from ..io._bags import write_bag
    from ..io._logs import read_run_log

    out = Path(out_dir)
    rng = np.random.default_rng(random_state)
    logs = [read_run_log(p) for p in log_paths]
    targets = [out / (Path(lg.path).stem + (".bag" if storage == "ros1" else "")) for lg in logs]
    existing = [str(t) for t in targets if t.exists()]
    if existing:
        raise CalibrationInputError(f"{existing[0]} exists; a bag is never overwritten. Choose an empty folder.")
    out.mkdir(parents=True, exist_ok=True)
    for lg, target in zip(logs, targets):
        order = np.argsort(lg.pose, kind="stable")
        raw, q = lg.raw[order], lg.q[order]
        noise = 1e-4 * np.ptp(raw, axis=0) + 1e-12
        rec = continuous_recording(raw, joints=q, still_s=still_s, move_s=move_s, sensor_rate_hz=sensor_rate_hz,
                                   pose_rate_hz=joint_rate_hz, settle_amplitude=10 * noise, settle_tau_s=settle_tau_s,
                                   noise=noise, start_time_s=float(lg.timestamp[0]) + 1.7e9, random_state=rng)
        write_bag(target, storage, sensor_time=rec.sensor_time, reading=rec.reading, pose_time=rec.pose_time,
                  joints=rec.joints, joint_names=list(joint_names or [f"joint{j + 1}" for j in range(q.shape[1])]), raw=True)
    return targets
