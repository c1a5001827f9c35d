"""``ftcal identify-load`` and ``ftcal compensate``: a tool's gravity load from static poses, and its removal."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ._common import (
    load_robot_from_args,
    CliError,
    Console,
    OutputPlan,
    add_output_options,
    add_robot_options,
    add_run_options,
    existing_file,
    path_problem,
    write_json,
)
from ._data_options import add_unit_options, check_lever_arm
from ._prepare import log_files
from ._recordings import (add_bag_options, add_recording_options, bag_files, bag_joints, read_bag_from_args,
                          refuse_bag_options, still_poses)
from ._tool_drift import add_drift_options

IDENTIFY_EXAMPLE = """\
examples:
  ftcal plan --subdivisions 0 --out tool_plan        # 11 well-spread poses for the robot program
  # record the sensor at each pose with the tool mounted, nothing touching it -> tool_logs/*.csv (run logs)
  ftcal identify-load tool_logs --model models/linear.model.npz --robot kuka_iiwa14 --out tool
  ftcal identify-load poses.csv --wrench-frame base --out tool     # a factory-calibrated sensor: no --model
  ftcal identify-load recording.csv --settle 2 --out tool          # continuous (a 'time' column): still poses found
  ftcal identify-load my_bag --wrench-topic /ft_sensor/wrench --robot ur5 --out tool   # a ROS bag + joint states
  ftcal identify-load my.bag --tf base_link,ft_sensor --out tool  # a ROS 1 bag, the orientation from /tf

inputs: run logs (joints and raw channels; need --model), or pose files (CSV): the sensor's orientation in
the base frame as qx,qy,qz,qw (scalar last, as ROS writes it), R00..R22 (Rij = row i, column j) or
roll,pitch,yaw [rad] (fixed axes x, y, z: R = Rz(yaw) Ry(pitch) Rx(roll), the URDF rpy convention), and
the wrench Fx,Fy,Fz,Tx,Ty,Tz (or Mx,My,Mz) [N, N·m] in the frame --wrench-frame names (or raw channels
s0..s{N-1} with --model). A pose file with a 'time' column [s] that holds a continuous recording (most rows
share their neighbour's orientation) has its still poses found: segments that stay within --still-tolerance
for --min-still seconds, minus the first --settle seconds (default from the data: until the drift has
decayed into the noise), averaged; how many were found, kept and rejected (and why) is reported.
ROS bags (rosbag2 sqlite3 / MCAP folders, ROS 1 .bag files; pip install "ftcal[ros]") are continuous
recordings: the sensor's topic (a wrench, or raw gauges with --raw-topic and --model) with the joint states
(interpolated at the sensor's stamps; --robot gives the kinematics) or /tf (--tf); see 'From a ROS bag' in
the README.

writes DIR/NAME.tool.json: mass [kg], centre of mass [m] (sensor frame), bias [N, N·m], their standard
errors, the residual RMS and each pose's time; DIR/NAME.poses.csv: the poses used (time, orientation,
the wrench in the sensor frame and its spread). Every row of run logs is one static pose (the 'run' column
is ignored). 'ftcal export NAME.tool.json --format ros' writes the ROS gravity-compensation YAML.
With the poses' times (run logs' timestamps, a pose file's 'time' column or bag stamps [s], or the row
order with --time-from-order) or temperatures (a 'temperature' column), a bias drift is added when it
lowers the held-out error (--drift); the tool file records it and the span it covers, and
DIR/NAME.identification.json/.png report each pose's residual against time with and without the drift
and the drift rate [N/h, N·m/h] with its standard error.
"""

COMPENSATE_EXAMPLE = """\
examples:
  ftcal compensate run.csv --model models/linear.model.npz --tool tool/tool.tool.json --robot kuka_iiwa14
  ftcal compensate logs/ --model m.model.npz --tool t.tool.json --output external.csv
  ftcal compensate poses.csv --wrench-frame base --tool tool/tool.tool.json     # a factory-calibrated sensor
  ftcal compensate my_bag --tf base_link,ft_sensor --tool tool/tool.tool.json --output external.csv

reads the inputs as identify-load does (run logs with --model, pose files or continuous CSV recordings, ROS
bags with the same topic, --tf and --stamps options; --wrench-frame and the units for a wrench), and
subtracts the tool's weight at each row's pose and the bias at each row's time (a drifting tool file: the
rows' timestamps, a pose file's 'time' column, the bag stamps; or --time-from-order). Every row is
compensated (no still-pose search). Output CSV: timestamp,pose,Fx..Tz for run logs; time,Fx..Tz (or
row,Fx..Tz, the row number, for a pose file without times) otherwise: the external wrench in the sensor
frame [N, N·m].
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "identify-load",
        help="identify a tool's mass, centre of mass and the sensor bias from static poses",
        description="Identify the tool load (mass, centre of mass) and the sensor bias from run logs of static poses.",
        epilog=IDENTIFY_EXAMPLE,
    )
    p.add_argument("inputs", nargs="+", metavar="INPUT", type=existing_input,
                   help="run log files or directories of *.csv logs, pose files (CSV, see below), or ROS bags")
    p.add_argument("--model", type=existing_file,
                   help="calibration model file (ftcal fit); needed for raw channels, not for a wrench")
    add_robot_options(p)
    _add_recording_options(p)
    p.add_argument("--gravity", default="0,0,-9.81", metavar="GX,GY,GZ", help="gravity in the base frame [m/s²]")
    p.add_argument("--name", default="tool", help="file name stem of the tool file")
    add_drift_options(p)
    add_output_options(p, "ftcal-tool")
    add_run_options(p, seed=False)
    p.set_defaults(handler=run_identify)

    c = sub.add_parser(
        "compensate",
        help="external wrench: remove the tool's weight and the bias from run logs, pose files or ROS bags",
        description="Subtract the identified tool load (and the bias, with its drift) at each row's pose and time.",
        epilog=COMPENSATE_EXAMPLE,
    )
    c.add_argument("inputs", nargs="+", metavar="INPUT", type=existing_input,
                   help="run log files or directories of *.csv logs, pose files (CSV) or ROS bags, as identify-load "
                   "reads them")
    c.add_argument("--model", type=existing_file,
                   help="calibration model file (ftcal fit); needed for raw channels, not for a wrench")
    add_robot_options(c)
    g = c.add_argument_group("pose files and ROS bags")
    _add_wrench_options(g)
    add_bag_options(c)
    c.add_argument("--tool", type=existing_file, required=True, help="tool file (ftcal identify-load)")
    c.add_argument("--output", default="-", metavar="FILE", help="where the wrenches go; '-' is stdout")
    c.add_argument("-f", "--force", action="store_true", help="overwrite --output FILE if it exists")
    add_drift_options(c, identify=False)
    add_run_options(c, seed=False)
    c.set_defaults(handler=run_compensate)


def existing_input(text: str) -> str:
    """argparse type: a readable file, or a readable folder (of run logs, or a rosbag2 bag)."""
    import os

    path = Path(text)
    if path.is_dir():
        if not os.access(path, os.R_OK | os.X_OK):
            raise argparse.ArgumentTypeError(f"{text}: permission denied (the folder is not readable by this user)")
        return text
    problem = path_problem(text)
    if problem is not None:
        raise argparse.ArgumentTypeError(problem)
    return text


def _add_recording_options(p: argparse.ArgumentParser) -> None:
    """How a pose file or a recording is read: the wrench's frame and units, the bag's topics, the still poses."""
    g = p.add_argument_group("pose files and continuous recordings")
    _add_wrench_options(g)
    g.add_argument("--poses", choices=("auto", "static", "continuous"), default="auto",
                   help="static: every row is a pose; continuous: find the still poses (needs times); auto: "
                   "continuous when the rows carry times and most rows share their neighbour's orientation (a bag "
                   "is always continuous)")
    add_recording_options(g)
    add_bag_options(p)


def _add_wrench_options(g: argparse._ArgumentGroup) -> None:
    """The frame and the units of an input's wrench: ``--wrench-frame``, ``--force-unit``, ``--torque-unit``."""
    g.add_argument("--wrench-frame", choices=("sensor", "base"), default="sensor",
                   help="the frame the input's wrench is written in (base: the robot's base frame, torques about "
                   "the sensor origin)")
    add_unit_options(g)


def _gravity(text: str):
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3:
        raise CliError(f"--gravity {text!r}: give three comma-separated numbers in m/s², e.g. 0,0,-9.81")
    return values


def _poses_and_wrenches(args):
    import numpy as np

    import ftcal

    robot = load_robot_from_args(args)
    model = ftcal.load_model(args.model)
    logs = [ftcal.io.read_run_log(p, n_channels=int(model.n_features_in_), n_joints=robot.n_joints)
            for p in log_files(args.inputs)]
    q = np.vstack([lg.q for lg in logs])
    raw = np.vstack([lg.raw for lg in logs])
    rotations = ftcal.robot.sensor_pose_in_base(robot, q)[:, :3, :3]
    return logs, rotations, model.predict(raw)


class _Poses:
    """The static poses an identification uses: where they came from, orientation, wrench, time, still-pose info."""

    def __init__(self, sources, rotations, wrenches, time=None, still=None, model=None, temperature=None, groups=None):
        self.sources, self.rotations, self.wrenches, self.time = sources, rotations, wrenches, time
        self.still, self.model, self.temperature, self.groups = still, model, temperature, groups


def _input_kind(item: str) -> str:
    from ..io import is_bag
    from ..io import is_pose_file

    path = Path(item)
    if is_bag(path) or (path.is_dir() and bag_files([item]) is not None):
        return "ROS bag"
    if path.is_file() and path.suffix.lower() == ".csv" and is_pose_file(path):
        return "pose file"
    return "run log"


def _load_model(args, what: str):
    import ftcal

    if args.model is None:
        raise CliError(f"{what} holds raw channels: give the calibration model that turns them into a wrench, "
                       "--model MODEL.model.npz (ftcal fit)")
    return ftcal.load_model(args.model)


def _is_continuous(args, time, rotations) -> bool:
    """Whether the rows are a continuous recording (most rows share a neighbour's orientation) or static poses."""
    import numpy as np

    if args.poses != "auto":
        return args.poses == "continuous"
    if time is None or len(rotations) < 3:
        return False
    cos = (np.einsum("nij,nij->n", rotations[1:], rotations[:-1]) - 1.0) / 2.0
    still = np.arccos(np.clip(cos, -1.0, 1.0)) <= np.radians(args.still_tolerance)
    return bool(np.mean(still) > 0.5)


def _pose_file_rows(args, console: Console, path: Path, model):
    """A pose file's rows: the record, its wrench in the sensor frame [N, N·m] (units checked, raw channels through
    the model) and the model (loaded on first need)."""
    from ..experiment import wrench_in_sensor_frame
    from ..io import read_pose_file

    rec = read_pose_file(path, force_unit=args.force_unit or "N", torque_unit=args.torque_unit or "N.m")
    if rec.wrench is not None:
        if args.model is not None:
            console.info(f"{path}: the file holds a wrench; --model is not used for it")
        wrench = rec.wrench
        check_lever_arm(args, wrench, path, force_unit=args.force_unit or "N", torque_unit=args.torque_unit or "N.m")
    else:
        model = model or _load_model(args, str(path))
        if rec.raw.shape[1] != model.n_features_in_:
            raise CliError(f"{path}: {rec.raw.shape[1]} raw channels but the model {args.model} takes "
                           f"{model.n_features_in_}")
        wrench = model.predict(rec.raw)
    if args.wrench_frame == "base":
        wrench = wrench_in_sensor_frame(rec.rotation, wrench)
    return rec, wrench, model


def _pose_file_poses(args, console: Console, paths: list[Path]) -> _Poses:
    import numpy as np

    rotations, wrenches, times, still_list, model, temperatures = [], [], [], [], None, []
    for path in paths:
        rec, wrench, model = _pose_file_rows(args, console, path, model)
        if args.poses == "continuous" and rec.time is None:
            raise CliError(f"{path}: --poses continuous needs a 'time' column [s] to find the still poses in")
        if _is_continuous(args, rec.time, rec.rotation):
            still = still_poses(args, str(path), rec.time, wrench, rotations=rec.rotation)
            console.info(f"{path}: {still.summary()}")
            still_list.append(still)
            rotations.append(still.rotation)
            wrenches.append(still.reading)
            times.append(still.time)
            temperatures.append(None if rec.temperature is None else np.interp(still.time, rec.time, rec.temperature))
        else:
            rotations.append(rec.rotation)
            wrenches.append(wrench)
            times.append(rec.time)
            temperatures.append(rec.temperature)
    time = None if any(t is None for t in times) else np.concatenate(times)
    temperature = None if any(t is None for t in temperatures) else np.concatenate(temperatures)
    return _Poses([str(p) for p in paths], np.concatenate(rotations), np.concatenate(wrenches), time, still_list, model,
                  temperature)


def _wrench_in_si(args, wrench):
    """A wrench read in the options' units (``--force-unit``, ``--torque-unit``) in N and N·m."""
    from ..io import unit_scale

    wrench = wrench.copy()
    wrench[:, :3] *= unit_scale(args.force_unit or "N", "force")
    wrench[:, 3:] *= unit_scale(args.torque_unit or "N.m", "torque")
    return wrench


def _bag_rows(args, console: Console, path: Path, model):
    """A bag's sensor samples: the record, the wrench [N, N·m] as the sensor wrote it (units checked, raw gauges
    through the model) and the model (loaded on first need)."""
    rec = read_bag_from_args(args, path, console)
    reading = rec.reading
    if rec.kind == "raw":
        model = model or _load_model(args, f"{path} (topic {rec.sensor_topic})")
        if reading.shape[1] != model.n_features_in_:
            raise CliError(f"{path}: topic {rec.sensor_topic} holds {reading.shape[1]} raw values but the model "
                           f"{args.model} takes {model.n_features_in_} channels")
        reading = model.predict(reading)
    else:  # a wrench message: N and N·m in ROS, unless the driver says otherwise (the options)
        reading = _wrench_in_si(args, reading)
        check_lever_arm(args, reading, f"{path} (topic {rec.sensor_topic})", force_unit=args.force_unit or "N",
                        torque_unit=args.torque_unit or "N.m")
    return rec, reading, model


def _bag_poses(args, console: Console, paths: list[Path]) -> _Poses:
    """The still poses of each bag: the wrench (or the raw gauges through --model) and the pose (tf, or joints
    through the robot's forward kinematics)."""
    import numpy as np

    import ftcal
    from ..experiment import wrench_in_sensor_frame

    robot = None if args.tf is not None else load_robot_from_args(args)
    rotations, wrenches, times, still_list, model = [], [], [], [], None
    for path in paths:
        rec, reading, model = _bag_rows(args, console, path, model)
        if robot is None:
            still = still_poses(args, str(path), rec.time, reading, rotations=rec.rotation)
            R = still.rotation
        else:
            still = still_poses(args, str(path), rec.time, reading, joints=bag_joints(rec, robot))
            R = ftcal.robot.sensor_pose_in_base(robot, still.joints)[:, :3, :3]
        console.info(f"{path}: {still.summary()}")
        wrench = still.reading
        if args.wrench_frame == "base":
            wrench = wrench_in_sensor_frame(R, wrench)
        rotations.append(R)
        wrenches.append(wrench)
        times.append(still.time)
        still_list.append(still)
    return _Poses([str(p) for p in paths], np.concatenate(rotations), np.concatenate(wrenches),
                  np.concatenate(times), still_list, model)


def _log_poses(args) -> _Poses:
    _log_poses_model_needed(args)
    logs, rotations, wrenches = _poses_and_wrenches(args)
    import numpy as np

    temperature = None if any(lg.temperature is None for lg in logs) else np.concatenate([lg.temperature for lg in logs])
    # the rows of one pose of one log are samples of one static pose: held out together when choosing the drift
    groups = np.concatenate([[f"{i}:{p}" for p in lg.pose] for i, lg in enumerate(logs)])
    return _Poses([str(lg.path) for lg in logs], rotations, wrenches, np.concatenate([lg.timestamp for lg in logs]),
                  temperature=temperature, groups=groups if np.unique(groups).size > 1 else None)


def _inputs_kind(args) -> str:
    """The one kind of the command's inputs (run log, pose file, ROS bag); a mix is refused."""
    kinds = {item: _input_kind(item) for item in args.inputs}
    if len(set(kinds.values())) > 1:
        shown = ", ".join(f"{k} ({v})" for k, v in list(kinds.items())[:4])
        raise CliError(f"the inputs mix kinds: {shown}; give run logs, pose files or ROS bags, one kind")
    return next(iter(kinds.values()))


def identification_poses(args, console: Console) -> _Poses:
    """The poses of the command's inputs (run logs, pose files), each kind read as it must be."""
    kind = _inputs_kind(args)
    if kind == "ROS bag":
        return _bag_poses(args, console, bag_files(args.inputs))
    refuse_bag_options(args, f"{kind}s")
    if kind == "pose file":
        return _pose_file_poses(args, console, [Path(p) for p in args.inputs])
    return _log_poses(args)


def _poses_csv(poses: _Poses) -> str:
    from scipy.spatial.transform import Rotation

    from ..core import csv_rows
    from ..core import WRENCH_LABELS

    import numpy as np

    quat = Rotation.from_matrix(poses.rotations).as_quat()  # x, y, z, w
    names = ["qx", "qy", "qz", "qw", *WRENCH_LABELS]
    blocks = [quat, poses.wrenches]
    if poses.time is not None:
        names.insert(0, "time")
        blocks.insert(0, poses.time[:, None])
    if poses.still and len(poses.still) == 1:  # the spread of each averaged pose
        names += ["n_samples"] + [f"{c}_std" for c in WRENCH_LABELS]
        blocks += [poses.still[0].n_samples[:, None].astype(object), poses.still[0].spread]
    head = "# the static poses ftcal identify-load used: orientation sensor -> base (x, y, z, w), wrench in the " \
           "sensor frame [N, N·m]\n"
    return head + ",".join(names) + "\n" + "".join(csv_rows(*[np.asarray(b) for b in blocks]))


def run_identify(args: argparse.Namespace) -> int:
    from ._tool_drift import drift_summary, identify, report_names, write_report

    console = Console(args.quiet)
    gravity = _gravity(args.gravity)
    name, poses_name = f"{args.name}.tool.json", f"{args.name}.poses.csv"
    plan = OutputPlan(args.out, [name, poses_name, *report_names(args.name)], args.force)
    poses = identification_poses(args, console)
    tool, report = identify(args, poses.rotations, poses.wrenches, gravity, poses.time, poses.temperature,
                            poses.sources, poses.groups)
    info = {"inputs": poses.sources, "n_poses": len(poses.rotations), "model": None if args.model is None else
            str(args.model), "wrench_frame_in_input": args.wrench_frame}
    if _input_kind(args.inputs[0]) == "run log":
        info.update(logs=poses.sources, robot=args.robot)
    if poses.time is not None:
        info["pose_time_s"] = poses.time.tolist()
    if poses.still:
        info["still_poses"] = [{"found": s.n_found, "kept": s.n_kept, "rejected": [
            {"start_time_s": t, "reason": why} for t, why in s.rejected], "settle_s": s.settle_s,
            "settle_from_data": s.settle_from_data} for s in poses.still]
    with plan.as_one_set():  # the tool file and the report describing it: all or none, never another run's report
        with plan.writing(poses_name) as tmp:
            tmp.write_text(_poses_csv(poses), encoding="utf-8")
        if report is not None:
            write_report(plan, args.name, report)
        else:
            for stale in report_names(args.name):
                plan.leaving_out(stale)
        with plan.writing(name) as tmp:
            write_json(tmp, {**tool.to_dict(), **info})
    c = tool.center_of_mass * 1000
    console.info(
        f"tool: {tool.mass:.4f} ± {tool.mass_std_error:.2g} kg at [{c[0]:.1f}, {c[1]:.1f}, {c[2]:.1f}] mm "
        f"(sensor frame), from {len(poses.rotations)} poses; residual RMS {tool.residual_rms[0]:.3g} N, "
        f"{tool.residual_rms[1]:.3g} N·m{drift_summary(tool)} -> {plan.path(name)}"
    )
    return 0


def _compensation_rows(args, console: Console):
    """Every row of the inputs: (header, leading columns per row, rotations, wrenches in the sensor frame, times,
    temperatures); run logs keep their timestamp and pose, pose files and bags give each row's time."""
    import numpy as np

    import ftcal

    kind = _inputs_kind(args)
    if kind == "run log":
        _log_poses_model_needed(args)
        logs, rotations, wrenches = _poses_and_wrenches(args)
        temperature = None if any(lg.temperature is None for lg in logs) else \
            np.concatenate([lg.temperature for lg in logs])
        lead = [f"{t:.9g},{p}" for lg in logs for t, p in zip(lg.timestamp, lg.pose)]
        return "timestamp,pose", lead, rotations, wrenches, np.concatenate([lg.timestamp for lg in logs]), temperature
    rotations, wrenches, times, temperatures, model = [], [], [], [], None
    if kind == "pose file":
        for path in map(Path, args.inputs):
            rec, wrench, model = _pose_file_rows(args, console, path, model)
            rotations.append(rec.rotation)
            wrenches.append(wrench)
            times.append(rec.time)
            temperatures.append(rec.temperature)
    else:
        from ..experiment import wrench_in_sensor_frame

        robot = None if args.tf is not None else load_robot_from_args(args)
        for path in bag_files(args.inputs):
            rec, reading, model = _bag_rows(args, console, path, model)
            R = rec.rotation if robot is None else ftcal.robot.sensor_pose_in_base(robot, bag_joints(rec, robot))[:, :3, :3]
            rotations.append(R)
            wrenches.append(wrench_in_sensor_frame(R, reading) if args.wrench_frame == "base" else reading)
            times.append(rec.time)
            temperatures.append(None)
    time = None if any(t is None for t in times) else np.concatenate(times)
    temperature = None if any(t is None for t in temperatures) else np.concatenate(temperatures)
    n = sum(len(w) for w in wrenches)
    lead = [repr(float(t)) for t in time] if time is not None else [str(i) for i in range(1, n + 1)]  # ROS stamps: ns
    return "time" if time is not None else "row", lead, np.concatenate(rotations), np.concatenate(wrenches), time, \
        temperature


def _log_poses_model_needed(args) -> None:
    if args.model is None:
        raise CliError("run logs hold raw channels: give the calibration model that turns them into a wrench, "
                       "--model MODEL.model.npz (ftcal fit); a factory-calibrated sensor's wrench goes in a pose "
                       "file (see 'ftcal identify-load --help')")


def run_compensate(args: argparse.Namespace) -> int:
    import ftcal
    from ..core import WRENCH_LABELS
    from ._tool_drift import compensate_rows

    console = Console(args.quiet)
    plan = OutputPlan.single_file(args.output, args.force)
    tool = ftcal.experiment.ToolLoad.load(args.tool)
    head, lead, rotations, wrenches, times, temperatures = _compensation_rows(args, console)
    external = compensate_rows(args, tool, rotations, wrenches, times, temperatures, ", ".join(args.inputs))
    lines = [f"{head}," + ",".join(WRENCH_LABELS)]
    lines += [f"{first}," + ",".join(f"{v:.9g}" for v in row) for first, row in zip(lead, external)]
    text = "\n".join(lines) + "\n"
    if plan is None:
        sys.stdout.write(text)
        return 0
    with plan.writing(Path(args.output).name) as tmp:
        tmp.write_text(text, encoding="utf-8")
    console.info(f"wrote {len(external)} compensated wrenches to {args.output}")
    return 0
