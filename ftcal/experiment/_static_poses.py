"""A robot's recordings -> the static poses of a tool identification: run logs, pose files, ROS bags.

What ``ftcal identify-load`` reads, as a library call (:func:`static_poses`), and what ``ftcal compensate`` reads
(:func:`recording_rows`: every row, no still-pose search); :func:`bag_run_log` turns the bag of one run of the
experiment into the run log ``prepare`` pairs.

* **Run logs** (joints and raw channels): the model turns the channels into a wrench, the robot's forward
  kinematics gives the sensor's orientation; every row is a static pose, the rows of one pose of one log are its
  samples (``groups``).
* **Pose files** (CSV: orientation and wrench or raw channels, optional ``time`` and ``temperature``): every row is
  a pose, unless the file is a continuous recording (``poses="continuous"``, or ``"auto"``: the rows carry times
  and most rows share their neighbour's orientation), whose still poses are found
  (:func:`ftcal.experiment.find_still_poses`).
* **ROS bags**: always continuous; the wrench (or raw gauges through the model) with the joint states (through
  the robot) or ``/tf``.

A wrench written in the base frame (``wrench_frame="base"``) is turned into the sensor frame.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..core._exceptions import NO_SETTING, CalibrationInputError, Placeholder
from ._still_poses import DEFAULT_MIN_STILL_S, DEFAULT_STILL_TOLERANCE_DEG, StillPoses, find_still_poses

__all__ = ["StaticPoses", "static_poses", "RecordingRows", "recording_rows", "recording_kind", "bag_run_log",
           "RecordingOptions"]


@dataclass(frozen=True)
class RecordingOptions:
    """How recordings are read (every field has the command line's default).

    ``wrench_frame`` ("sensor" | "base"), ``force_unit`` / ``torque_unit`` (of a wrench read from a file),
    ``poses`` ("auto" | "static" | "continuous"), the still-pose thresholds ``tolerance_deg``,
    ``min_duration_s``, ``settle_s`` (:func:`ftcal.experiment.find_still_poses`), and a bag's ``wrench_topic``,
    ``raw_topic``, ``raw_field``, ``joint_topic``, ``tf`` (base, sensor frame), ``stamps``, ``max_samples``
    (:func:`ftcal.io.read_bag`)."""

    wrench_frame: str = "sensor"
    force_unit: str = "N"
    torque_unit: str = "N.m"
    poses: str = "auto"
    tolerance_deg: float = DEFAULT_STILL_TOLERANCE_DEG
    min_duration_s: float = DEFAULT_MIN_STILL_S
    settle_s: float | None = None
    wrench_topic: str | None = None
    raw_topic: str | None = None
    raw_field: str = "data"
    joint_topic: str | None = None
    tf: tuple[str, str] | None = None
    stamps: str = "header"
    max_samples: int | None = None

    def __post_init__(self) -> None:
        for name, allowed in (("wrench_frame", ("sensor", "base")), ("poses", ("auto", "static", "continuous"))):
            if getattr(self, name) not in allowed:
                raise CalibrationInputError(f"{name} must be one of {', '.join(allowed)}; got {getattr(self, name)!r}.",
                                            parameter=name, value=getattr(self, name))


@dataclass
class StaticPoses:
    """The static poses of an identification and where they came from.

    Attributes
    ----------
    sources : list of str
        The files read.
    kind : {"run log", "pose file", "ROS bag"}
    rotations : ndarray of shape (n, 3, 3)
        Sensor to base frame at each pose.
    wrenches : ndarray of shape (n, 6)
        The wrench in the sensor frame [N, N·m].
    time : ndarray of shape (n,) or None
        Each pose's time [s] (run logs' timestamps, a pose file's ``time`` column, the bag stamps).
    temperature : ndarray of shape (n,) or None
        [deg C].
    groups : ndarray of shape (n,) or None
        The pose of each row when several rows are samples of one pose (run logs).
    still : list of StillPoses
        The still poses found in each continuous recording (empty for static inputs).
    notes : list of (str, str or FtcalError)
        What a user should know, per source (still poses found, a bag's clock offsets, a model not used).
    """

    sources: list[str]
    kind: str
    rotations: NDArray[np.float64]
    wrenches: NDArray[np.float64]
    time: NDArray[np.float64] | None = None
    temperature: NDArray[np.float64] | None = None
    groups: NDArray | None = None
    still: list[StillPoses] = field(default_factory=list)
    notes: list = field(default_factory=list)

    @property
    def n_poses(self) -> int:
        return int(len(self.rotations))

    def still_summary(self) -> list[dict]:
        """JSON-able: per continuous recording, the still poses found, kept and rejected (with reasons)."""
        return [{"found": s.n_found, "kept": s.n_kept, "rejected": [{"start_time_s": t, "reason": why}
                                                                   for t, why in s.rejected],
                 "settle_s": s.settle_s, "settle_from_data": s.settle_from_data} for s in self.still]

    def to_csv(self) -> str:
        """The poses as CSV text: time (when known), orientation sensor -> base (qx, qy, qz, qw), wrench in the
        sensor frame, and for one continuous recording each pose's sample count and spread."""
        from scipy.spatial.transform import Rotation

        from ..core._columns import csv_rows
        from ..core._wrench import WRENCH_LABELS

        names = ["qx", "qy", "qz", "qw", *WRENCH_LABELS]
        blocks = [Rotation.from_matrix(self.rotations).as_quat(), self.wrenches]
        if self.time is not None:
            names.insert(0, "time")
            blocks.insert(0, self.time[:, None])
        if len(self.still) == 1:
            names += ["n_samples"] + [f"{c}_std" for c in WRENCH_LABELS]
            blocks += [self.still[0].n_samples[:, None].astype(object), self.still[0].spread]
        head = ("# the static poses ftcal identify-load used: orientation sensor -> base (x, y, z, w), wrench in the "
                "sensor frame [N, N·m]\n")
        return head + ",".join(names) + "\n" + "".join(csv_rows(*[np.asarray(b) for b in blocks]))


def recording_kind(path: str | Path) -> str:
    """``"ROS bag"``, ``"pose file"`` (a CSV whose header names an orientation) or ``"run log"``."""
    from ..io._bags import is_bag
    from ..io._poses import is_pose_file

    path = Path(path)
    if is_bag(path) or (path.is_dir() and any(is_bag(c) for c in path.iterdir())):
        return "ROS bag"
    if path.is_file() and path.suffix.lower() == ".csv" and is_pose_file(path):
        return "pose file"
    return "run log"


def _one_kind(recording) -> tuple[list[Path], str]:
    """The recording's paths and their one kind (:func:`recording_kind`); a mix of kinds is refused."""
    paths = [Path(recording)] if isinstance(recording, (str, Path)) else [Path(p) for p in recording]
    kinds = {str(p): recording_kind(p) for p in paths}
    if not kinds:
        raise CalibrationInputError("no recordings given; pass run logs, pose files or ROS bags.")
    if len(set(kinds.values())) > 1:
        shown = ", ".join(f"{k} ({v})" for k, v in list(kinds.items())[:4])
        raise CalibrationInputError(f"the inputs mix kinds: {shown}; give run logs, pose files or ROS bags, one kind.")
    return paths, next(iter(kinds.values()))


def _need_model(model, what: str):
    if model is None:
        raise CalibrationInputError(f"{what} holds raw channels: give the calibration model that turns them into a "
                                    "wrench.", parameter="model", fix="pass {model} (a fitted calibrator, ftcal fit)",
                                    settings={"model": NO_SETTING})
    return model


def _through_model(model, raw: NDArray, where: str) -> NDArray:
    model = _need_model(model, where)
    if raw.shape[1] != model.n_features_in_:
        raise CalibrationInputError(f"{where}: {raw.shape[1]} raw channels but the model takes "
                                    f"{model.n_features_in_}.", parameter="model", value=raw.shape[1])
    return model.predict(raw)


def _to_sensor_frame(R: NDArray, wrench: NDArray, options: RecordingOptions) -> NDArray:
    from ._tool_load import wrench_in_sensor_frame

    return wrench_in_sensor_frame(R, wrench) if options.wrench_frame == "base" else wrench


def _pose_file_rows(path: Path, model, options: RecordingOptions, check_wrench, notes: list):
    """A pose file's record and its wrench as written (units converted; raw channels through the model)."""
    from ..io._poses import read_pose_file

    rec = read_pose_file(path, force_unit=options.force_unit, torque_unit=options.torque_unit)
    if rec.wrench is not None:
        if model is not None:
            notes.append((str(path), "the file holds a wrench; the model is not used for it"))
        if check_wrench is not None:
            check_wrench(rec.wrench, str(path))
        return rec, rec.wrench
    return rec, _through_model(model, rec.raw, str(path))


def _is_continuous(options: RecordingOptions, time, rotations) -> bool:
    """Whether rows are a continuous recording (most rows share a neighbour's orientation) or static poses."""
    if options.poses != "auto":
        return options.poses == "continuous"
    if time is None or len(rotations) < 3:
        return False
    cos = (np.einsum("nij,nij->n", rotations[1:], rotations[:-1]) - 1.0) / 2.0
    still = np.arccos(np.clip(cos, -1.0, 1.0)) <= np.radians(options.tolerance_deg)
    return bool(np.mean(still) > 0.5)


def _still(options: RecordingOptions, source: str, time, reading, **pose) -> StillPoses:
    try:
        return find_still_poses(time, reading, tolerance_deg=options.tolerance_deg, settle_s=options.settle_s,
                                min_duration_s=options.min_duration_s, **pose)
    except CalibrationInputError as exc:
        raise exc.located(f"{source}: ") from None


def _joined(parts: list) -> NDArray | None:
    return None if not parts or any(p is None for p in parts) else np.concatenate(parts)


def _read_bag(path: Path, options: RecordingOptions, notes: list, *, wrench: bool = True):
    from ..io._bags import DEFAULT_MAX_SAMPLES, read_bag

    rec = read_bag(path, wrench_topic=options.wrench_topic if wrench else None, raw_topic=options.raw_topic,
                   raw_field=options.raw_field, joint_topic=options.joint_topic, tf=options.tf, stamps=options.stamps,
                   max_samples=options.max_samples or DEFAULT_MAX_SAMPLES)
    notes += [(str(path), note) for note in rec.notes]
    return rec


def _bag_rows(path: Path, model, options: RecordingOptions, check_wrench, notes: list):
    """A bag's record and its wrench [N, N·m] as the sensor wrote it (raw gauges through the model)."""
    from ..io._readers import unit_scale

    rec = _read_bag(path, options, notes)
    where = f"{path} (topic {rec.sensor_topic})"
    if rec.kind == "raw":
        return rec, _through_model(model, rec.reading, where)
    reading = rec.reading.copy()  # N and N·m in ROS, unless the driver says otherwise (the options)
    reading[:, :3] *= unit_scale(options.force_unit, "force")
    reading[:, 3:] *= unit_scale(options.torque_unit, "torque")
    if check_wrench is not None:
        check_wrench(reading, where)
    return rec, reading


def bag_joints(rec, robot) -> NDArray[np.float64]:
    """The bag's joint positions in the robot's joint order, matched by name (a bag whose joint names are not the
    robot's is refused even when the counts agree: its columns in order would give wrong kinematics)."""
    names, wanted = list(rec.joint_names), list(robot.joint_names)
    if set(wanted) <= set(names):
        return rec.joints[:, [names.index(n) for n in wanted]]
    raise CalibrationInputError(
        f"{rec.path}: the joint states of {rec.pose_topic} name {', '.join(names)} but the robot {robot.name} has "
        f"{', '.join(wanted)}.", parameter="robot", value=robot.name,
        fix="give the robot the bag was recorded with, or the sensor's orientation from {tf}",
        settings={"tf": Placeholder("(<base frame>, <sensor frame>)")})


def _bag_still(options: RecordingOptions, path: Path, rec, reading: NDArray, robot) -> StillPoses:
    """The still poses of a bag's reading, by its /tf orientations or its joint states (through the robot)."""
    if rec.rotation is not None:
        return _still(options, str(path), rec.time, reading, rotations=rec.rotation)
    return _still(options, str(path), rec.time, reading, joints=bag_joints(rec, _need_robot(robot)))


def _file_poses(paths, kind: str, model, robot, options, check_wrench) -> StaticPoses:
    """The static poses of pose files or bags: a static pose file's rows, or the still poses of each recording."""
    from ..robot import sensor_pose_in_base

    parts, still_list, notes = [], [], []
    for path in paths:
        if kind == "ROS bag":
            rec, reading = _bag_rows(path, model, options, check_wrench, notes)
            still = _bag_still(options, path, rec, reading, robot)
            R = still.rotation if still.rotation is not None else sensor_pose_in_base(robot, still.joints)[:, :3, :3]
            parts.append((R, _to_sensor_frame(R, still.reading, options), still.time, None))
        else:
            rec, wrench = _pose_file_rows(path, model, options, check_wrench, notes)
            wrench = _to_sensor_frame(rec.rotation, wrench, options)
            if options.poses == "continuous" and rec.time is None:
                raise CalibrationInputError(f"{path}: continuous poses need a 'time' column [s] to find the still "
                                            "poses in.", parameter="poses", value="continuous")
            if not _is_continuous(options, rec.time, rec.rotation):
                parts.append((rec.rotation, wrench, rec.time, rec.temperature))
                continue
            still = _still(options, str(path), rec.time, wrench, rotations=rec.rotation)
            parts.append((still.rotation, still.reading, still.time,
                          None if rec.temperature is None else np.interp(still.time, rec.time, rec.temperature)))
        notes.append((str(path), still.summary()))
        still_list.append(still)
    rotations, wrenches, times, temperatures = zip(*parts)
    return StaticPoses([str(p) for p in paths], kind, np.concatenate(rotations), np.concatenate(wrenches),
                       _joined(times), _joined(temperatures), None, still_list, notes)


def _need_robot(robot):
    if robot is None:
        raise CalibrationInputError("the joints need the robot's kinematics: give the robot model.", parameter="robot",
                                    fix="pass {robot} (ftcal.robot.load_robot), or the orientation from {tf}",
                                    settings={"robot": NO_SETTING, "tf": NO_SETTING})
    return robot


def _run_logs(paths, model, robot):
    """The run logs read, and their rows' orientations, wrenches (through the model), times and temperatures."""
    from ..io._logs import read_run_log
    from ..robot import sensor_pose_in_base

    model, robot = _need_model(model, "run logs"), _need_robot(robot)
    logs = [read_run_log(p, n_channels=int(model.n_features_in_), n_joints=robot.n_joints) for p in paths]
    rotations = sensor_pose_in_base(robot, np.vstack([lg.q for lg in logs]))[:, :3, :3]
    return (logs, rotations, model.predict(np.vstack([lg.raw for lg in logs])),
            np.concatenate([lg.timestamp for lg in logs]), _joined([lg.temperature for lg in logs]))


def _log_poses(paths, model, robot) -> StaticPoses:
    logs, rotations, wrenches, time, temperature = _run_logs(paths, model, robot)
    # the rows of one pose of one log are samples of one static pose: held out together
    groups = np.concatenate([[f"{i}:{p}" for p in lg.pose] for i, lg in enumerate(logs)])
    return StaticPoses([str(lg.path) for lg in logs], "run log", rotations, wrenches, time, temperature,
                       groups if np.unique(groups).size > 1 else None)


def static_poses(recording, *, model=None, robot=None, options: RecordingOptions | None = None,
                 check_wrench: Callable[[NDArray, str], None] | None = None) -> StaticPoses:
    """The static poses of a robot's recordings, as ``ftcal identify-load`` reads them (module docstring).

    Parameters
    ----------
    recording : path or sequence of paths
        Run log files, pose files (CSV) or ROS bags (one kind).
    model : fitted calibrator, optional
        Turns raw channels into a wrench (run logs, pose files or bags of raw gauges).
    robot : RobotModel, optional
        The kinematics of run logs and of bags with joint states (:func:`ftcal.robot.load_robot`).
    options : RecordingOptions, optional
        Frame, units, still-pose thresholds and bag topics (defaults: the command line's).
    check_wrench : callable, optional
        Called as ``check_wrench(wrench, source)`` on each wrench read from a file (e.g. a plausibility check).

    Returns
    -------
    StaticPoses

    Examples
    --------
    >>> import numpy as np, pathlib, tempfile
    >>> from scipy.spatial.transform import Rotation
    >>> from ftcal.experiment import ToolLoad, continuous_recording, identify_tool_load
    >>> R = Rotation.random(12, random_state=0).as_matrix()
    >>> W = ToolLoad(mass=1.0, center_of_mass=np.array([0, 0, 0.05]), bias=np.zeros(6)).gravity_wrench(R)
    >>> rec = continuous_recording(W, rotations=R, still_s=3, move_s=1, sensor_rate_hz=20, pose_rate_hz=20,
    ...                            noise=0.01, random_state=0)                   # 12 poses, 10 mN of noise
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "recording.csv"
    >>> rows = np.hstack([rec.sensor_time[:, None], Rotation.from_matrix(rec.rotations).as_quat(), rec.reading])
    >>> np.savetxt(path, rows, delimiter=",", header="time,qx,qy,qz,qw,Fx,Fy,Fz,Tx,Ty,Tz", comments="")
    >>> poses = static_poses(path)
    >>> poses.kind, poses.n_poses, round(identify_tool_load(poses.rotations, poses.wrenches).mass, 2)
    ('pose file', 12, 1.0)
    >>> poses.notes[0][1].startswith("found 12 still poses, kept 12")
    True
    """
    options = options or RecordingOptions()
    paths, kind = _one_kind(recording)
    if kind == "run log":
        return _log_poses(paths, model, robot)
    return _file_poses(paths, kind, model, robot, options, check_wrench)


@dataclass
class RecordingRows:
    """Every row of recordings (no still-pose search), as ``ftcal compensate`` reads them.

    ``lead_names`` and ``lead`` (one string per row) are the leading columns of the output: ``timestamp,pose``
    for run logs, ``time`` (or ``row``, the row number, without times) otherwise."""

    lead_names: str
    lead: list[str]
    rotations: NDArray[np.float64]
    wrenches: NDArray[np.float64]
    time: NDArray[np.float64] | None
    temperature: NDArray[np.float64] | None
    notes: list = field(default_factory=list)


def recording_rows(recording, *, model=None, robot=None, options: RecordingOptions | None = None,
                   check_wrench: Callable[[NDArray, str], None] | None = None) -> RecordingRows:
    """Every row of the recordings with its orientation, wrench (sensor frame), time and temperature (parameters as
    :func:`static_poses`)."""
    from ..robot import sensor_pose_in_base

    options = options or RecordingOptions()
    paths, kind = _one_kind(recording)
    if kind == "run log":
        logs, *rows = _run_logs(paths, model, robot)
        return RecordingRows("timestamp,pose", [f"{t:.9g},{p}" for lg in logs for t, p in zip(lg.timestamp, lg.pose)],
                             *rows)
    parts, notes = [], []
    for path in paths:
        if kind == "pose file":
            rec, wrench = _pose_file_rows(path, model, options, check_wrench, notes)
            R, temperature = rec.rotation, rec.temperature
        else:
            rec, wrench = _bag_rows(path, model, options, check_wrench, notes)
            R = rec.rotation if rec.rotation is not None else \
                sensor_pose_in_base(_need_robot(robot), bag_joints(rec, robot))[:, :3, :3]
            temperature = None
        parts.append((R, _to_sensor_frame(R, wrench, options), rec.time, temperature))
    rotations, wrenches, times, temperatures = zip(*parts)
    time = _joined(times)
    n = sum(len(w) for w in wrenches)
    lead = [repr(float(t)) for t in time] if time is not None else [str(i) for i in range(1, n + 1)]
    return RecordingRows("time" if time is not None else "row", lead, np.concatenate(rotations),
                         np.concatenate(wrenches), time, _joined(temperatures), notes)


_RUN_NAME = re.compile(r"config(-?\d+)_(load|no-load)")


def bag_run_log(path, robot=None, *, options: RecordingOptions | None = None):
    """The bag of one run of the experiment (raw gauges and joints, or /tf) as a run log of its still poses: one
    row per pose, in order; its :class:`StillPoses` (whose ``summary()`` says what was found); and the notes of
    reading the bag (source, note).

    The bag is named after its run, ``config<C>_load`` or ``config<C>_no-load`` (as ``ftcal simulate experiment
    --bag`` writes them), so that the still poses of a load run and its no-load run pair in order."""
    from ..io._logs import RunLog

    options = options or RecordingOptions()
    path = Path(path)
    match = _RUN_NAME.search(path.name)
    if match is None:
        raise CalibrationInputError(
            f"{path}: name each bag after its run, config<C>_load or config<C>_no-load (C the load configuration id, "
            "-1 for a no-load run shared by all), as ftcal's virtual experiment writes them; the still poses "
            "of a load run and its no-load run pair in order.")
    if options.raw_topic is None:
        raise CalibrationInputError(f"{path}: a calibration run's bag holds raw gauges: name their topic.",
                                    parameter="raw_topic", fix="pass {raw_topic} (and {raw_field})",
                                    settings={"raw_topic": NO_SETTING, "raw_field": NO_SETTING})
    notes: list = []
    rec = _read_bag(path, options, notes, wrench=False)
    still = _bag_still(options, path, rec, rec.reading, robot)
    if rec.rotation is not None:  # tf: the orientation recorded, no joints and no robot model needed
        q, rotation, frame, name = np.empty((still.n_kept, 0)), still.rotation, None, getattr(robot, "name", None)
    else:
        q, rotation, frame, name = still.joints, None, robot.sensor_frame, robot.name
    k = still.n_kept
    log = RunLog(path=path, timestamp=still.time, run_kind=np.array([match.group(2)] * k),
                 config=np.full(k, int(match.group(1)), dtype=np.int64), pose=np.arange(k, dtype=np.int64),
                 q=q, raw=still.reading, line=np.arange(1, k + 1, dtype=np.int64), raw_unit="raw", robot=name,
                 sensor_frame=frame, rotation=rotation, meta={"bag": str(path), "topic": rec.sensor_topic})
    return log, still, notes
