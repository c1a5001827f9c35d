"""``ftcal identify-load`` and ``ftcal compensate``: a tool's gravity load from static poses, and its removal."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ._common import (CliError, Console, OutputPlan, add_name_option, add_output_file_options, add_robot_options,
                      existing_file, finish_command, load_robot_from_args, numbers)
from ._data_options import add_unit_options, check_lever_arm, named_inputs
from ._prepare import log_files
from ._messages import cli_error
from ._recordings import (add_bag_options, add_recording_options, bag_files, recording_options, refuse_bag_options,
                          say_notes)
from ._tool_drift import add_drift_options
from ..core import FtcalError
from ..io import refuse_twin_recordings

IDENTIFY_EXAMPLE = """\
examples:
  ftcal plan --subdivisions 0 --out tool_plan        # 11 well-spread poses for the robot program
  # record the sensor at each pose with the tool mounted, nothing touching it -> tool_logs/*.csv (run logs)
  ftcal identify-load tool_logs --model models/linear.model.npz --robot kuka_iiwa14 --out tool
  ftcal identify-load poses.csv --wrench-frame base --out tool     # a factory-calibrated sensor: no --model
  ftcal identify-load recording.csv --settle 2 --out tool          # continuous (a 'time' column): still poses found
  ftcal identify-load my_bag --wrench-topic /ft_sensor/wrench --robot ur5 --out tool   # a ROS bag + joint states
  ftcal identify-load my.bag --tf base_link,ft_sensor --out tool  # a ROS 1 bag, the orientation from /tf
  ftcal identify-load poses.csv --mounting --out tool             # with the sensor's mounting rotation

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
errors, the residual RMS in-sample and held out (leave-poses-out: each pose predicted by the tool identified on
the other poses; K-fold over poses, leave-one-out on at most --cv poses) and each pose's time; DIR/NAME.poses.csv: the poses used (time, orientation,
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
    p = sub.add_parser("identify-load", epilog=IDENTIFY_EXAMPLE,
                       help="identify a tool's mass, centre of mass and the sensor bias from static poses",
                       description="Identify the tool load (mass, centre of mass) and the sensor bias from run logs of "
                       "static poses.")
    _add_inputs(p, "run log files or directories of *.csv logs, pose files (CSV, see below), or ROS bags")
    g = p.add_argument_group("pose files and continuous recordings")
    _add_wrench_options(g)
    g.add_argument("--poses", choices=("auto", "static", "continuous"), default="auto",
                   help="static: every row is a pose; continuous: find the still poses (needs times); auto: "
                   "continuous when the rows carry times and most rows share their neighbour's orientation (a bag "
                   "is always continuous)")
    add_recording_options(g)
    add_bag_options(p)
    p.add_argument("--gravity", default="0,0,-9.81", metavar="GX,GY,GZ", help="gravity in the base frame [m/s²]")
    add_name_option(p, "the tool file", default="tool")
    p.add_argument("--mounting", action="store_true",
                   help="also identify the sensor's small mounting rotation relative to the robot's sensor frame (a "
                   "few degrees) with its standard error; refused, naming the axis, when the poses cannot tell it")
    add_drift_options(p)
    finish_command(p, run_identify, "ftcal-tool", seed=False)

    c = sub.add_parser("compensate", epilog=COMPENSATE_EXAMPLE,
                       help="external wrench: remove the tool's weight and the bias from run logs, pose files or ROS "
                       "bags", description="Subtract the identified tool load (and the bias, with its drift) at each "
                       "row's pose and time.")
    _add_inputs(c, "run log files or directories of *.csv logs, pose files (CSV) or ROS bags, as identify-load reads "
                "them")
    _add_wrench_options(c.add_argument_group("pose files and ROS bags"))
    add_bag_options(c)
    c.add_argument("--tool", type=existing_file, required=True, help="tool file (ftcal identify-load)")
    add_output_file_options(c)
    add_drift_options(c, identify=False)
    finish_command(c, run_compensate, seed=False)


def _add_inputs(p: argparse.ArgumentParser, what: str) -> None:
    """The inputs (``what`` they may be), the ``--model`` that turns raw channels into a wrench, and the robot."""
    p.add_argument("inputs", nargs="+", metavar="INPUT", type=existing_input, help=what)
    p.add_argument("--model", type=existing_file,
                   help="calibration model file (ftcal fit); needed for raw channels, not for a wrench")
    add_robot_options(p)


def existing_input(text: str) -> str:
    """argparse type: a readable file, or a readable folder (of run logs, or a rosbag2 bag)."""
    import os

    if not Path(text).is_dir():
        existing_file(text)  # a file: refused as every input file is, by what it is
    elif not os.access(text, os.R_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"{text}: permission denied (the folder is not readable by this user)")
    return text


def _add_wrench_options(g: argparse._ArgumentGroup) -> None:
    """The frame and the units of an input's wrench: ``--wrench-frame``, ``--force-unit``, ``--torque-unit``."""
    g.add_argument("--wrench-frame", choices=("sensor", "base"), default="sensor",
                   help="the frame the input's wrench is written in (base: the robot's base frame, torques about "
                   "the sensor origin)")
    add_unit_options(g)


def _inputs_kind(args) -> str:
    """The one kind of the command's inputs (run log, pose file, ROS bag); a mix is refused."""
    from ftcal.experiment import recording_kind

    kinds = {item: recording_kind(item) for item in args.inputs}
    if len(set(kinds.values())) > 1:
        shown = ", ".join(f"{k} ({v})" for k, v in list(kinds.items())[:4])
        raise CliError(f"the inputs mix kinds: {shown}; give run logs, pose files or ROS bags, one kind")
    return next(iter(kinds.values()))


def _read_inputs(args, console: Console, reader):
    """``reader`` (the library's :func:`static_poses` or :func:`recording_rows`) on the command's inputs: the
    paths, model and robot they need, the options mapped, the lever-arm check; its notes on stderr and its errors
    as one line."""
    import ftcal

    kind = _inputs_kind(args)
    if kind == "ROS bag":
        paths = bag_files(args.inputs)
    else:
        refuse_bag_options(args, f"{kind}s")
        if kind == "pose file":
            refuse_twin_recordings(args.inputs, "pose file", CliError)
        paths = log_files(args.inputs) if kind == "run log" else [Path(p) for p in args.inputs]
    if kind == "run log" and args.model is None:
        raise CliError("run logs hold raw channels: give the calibration model that turns them into a wrench, "
                       "--model MODEL.model.npz (ftcal fit); a factory-calibrated sensor's wrench goes in a pose "
                       "file (see 'ftcal identify-load --help')")
    robot = load_robot_from_args(args) if kind == "run log" or (kind == "ROS bag" and args.tf is None) else None
    model = None if args.model is None else ftcal.load_model(args.model)

    def check_wrench(wrench, where: str) -> None:
        check_lever_arm(args, wrench, where, force_unit=args.force_unit or "N", torque_unit=args.torque_unit or "N.m")

    options = recording_options(args, poses=getattr(args, "poses", "static"))  # compensate: every row a pose
    try:
        result = reader(paths, model=model, robot=robot, options=options, check_wrench=check_wrench)
    except FtcalError as exc:
        raise cli_error(exc, args) from None
    say_notes(console, result.notes, args)
    return result


def run_identify(args: argparse.Namespace) -> int:
    from ftcal.experiment import static_poses
    from ._tool_drift import identify, report_names, write_report

    console = Console(args.quiet)
    gravity = numbers(args.gravity, 3)
    if gravity is None:
        raise CliError(f"--gravity {args.gravity!r}: give three comma-separated numbers in m/s², e.g. 0,0,-9.81")
    name, poses_name = f"{args.name}.tool.json", f"{args.name}.poses.csv"
    plan = OutputPlan(args.out, [name, poses_name, *report_names(args.name)], args.force)
    given = list(args.inputs)
    args.inputs = named_inputs(args, args.inputs)  # --columns: headerless files named, joined side by side
    poses = _read_inputs(args, console, static_poses)  # the static poses of the inputs
    sources = poses.sources if args.inputs == given else [str(p) for p in given]  # the user's files, not the join
    _check_frame(args, poses, gravity)  # before the identification, which a wrong frame can make fail
    tool, report = identify(args, poses.rotations, poses.wrenches, gravity, poses.time, poses.temperature,
                            sources, poses.groups)
    info = {"inputs": sources, "n_poses": len(poses.rotations), "model": None if args.model is None else
            str(args.model), "wrench_frame_in_input": args.wrench_frame}
    if poses.kind == "run log":
        info.update(logs=poses.sources, robot=args.robot)
    if poses.time is not None:
        info["pose_time_s"] = poses.time.tolist()
    if poses.still:
        info["still_poses"] = poses.still_summary()
    with plan.as_one_set():  # the tool file and the report describing it: all or none, never another run's report
        plan.write_text(poses_name, poses.to_csv())
        if report is not None:
            write_report(plan, args.name, report)
        else:
            plan.leaving_out(*report_names(args.name))
        plan.write_json(name, {**tool.to_dict(), **info})
    console.info(f"{tool_line(tool, len(poses.rotations))} -> {plan.path(name)}")
    _say_drift(args, poses, gravity)
    return 0


def tool_line(tool, n_poses: int) -> str:
    """The console's line on an identified tool: mass, centre of mass, the residual in-sample and held out, the
    mounting rotation and the drift, each with its standard error where it has one."""
    import numpy as np

    from ._tool_drift import drift_summary

    c = tool.center_of_mass * 1000
    held = tool.held_out_residual_rms
    held_text = "" if held is None else f"; held out (leave-poses-out) {held[0]:.3g} N, {held[1]:.3g} N·m"
    mount = ""
    if np.any(tool.mounting_rotation):
        r, se = np.degrees(tool.mounting_rotation), np.degrees(tool.mounting_rotation_std_error)
        mount = (f"; mounting rotation [{', '.join(f'{v:.2f}±{s:.2g}' for v, s in zip(r, se))}] deg (rotation "
                 "vector, sensor frame)")
    return (f"tool: {tool.mass:.4f} ± {tool.mass_std_error:.2g} kg at [{c[0]:.1f}, {c[1]:.1f}, {c[2]:.1f}] mm "
            f"(sensor frame), from {n_poses} poses; residual RMS {tool.residual_rms[0]:.3g} N, "
            f"{tool.residual_rms[1]:.3g} N·m in-sample{held_text}{mount}{drift_summary(tool)}")


def _check_frame(args, poses, gravity) -> None:
    """A warning line on stderr when gravity fits the wrench far better in the other frame than the declared one."""
    from ftcal.core import CalibrationInputError
    from ftcal.experiment import check_wrench_frame

    try:
        frame = check_wrench_frame(poses.rotations, poses.wrenches, args.wrench_frame, gravity=gravity)
    except CalibrationInputError:  # inputs the identification refuses with its own words
        return
    if frame.other_fits_better:
        print(f"ftcal: warning: {', '.join(poses.sources[:3])}: {frame.words('--wrench-frame')}", file=sys.stderr)


def _say_drift(args, poses, gravity) -> None:
    """For poses without times (in recording order), one line on stderr when a drift over the row order cuts the
    held-out residual by more than its paired SE: the figures, the mass and centre of mass change, the option."""
    from ftcal.experiment import drift_in_recording_order

    if poses.time is None and not args.time_from_order and args.drift == "auto" and poses.temperature is None:
        try:
            found = drift_in_recording_order(poses.rotations, poses.wrenches, gravity, groups=poses.groups,
                                             cv=args.cv, random_state=0)
        except ValueError:  # too few poses for a drift: nothing to say
            return
        if found is not None:
            print(f"ftcal: note: {', '.join(poses.sources[:3])}: {found.words('--time-from-order')}", file=sys.stderr)


def run_compensate(args: argparse.Namespace) -> int:
    import ftcal
    from ftcal.core import WRENCH_LABELS
    from ._tool_drift import compensate_rows, compensation_values

    console = Console(args.quiet)
    plan = OutputPlan.single_file(args.output, args.force)
    given = ", ".join(args.inputs)  # the user's files (named in messages, not ftcal's join of them)
    args.inputs = named_inputs(args, args.inputs)  # --columns: headerless files named, joined side by side
    tool = ftcal.experiment.ToolLoad.load(args.tool)
    from ftcal.experiment import recording_rows

    rows = _read_inputs(args, console, recording_rows)
    head, lead, rotations, wrenches = rows.lead_names, rows.lead, rows.rotations, rows.wrenches
    values = compensation_values(args, tool, len(wrenches), rows.time, rows.temperature, given)
    external = compensate_rows(args, tool, rotations, wrenches, values)
    frame = ftcal.experiment.check_wrench_frame(rotations, wrenches, args.wrench_frame, tool=tool, **values)
    if frame.other_fits_better:
        print(f"ftcal: warning: {given}: {frame.words('--wrench-frame')}", file=sys.stderr)
    lines = [f"{head}," + ",".join(WRENCH_LABELS)]
    lines += [f"{first}," + ",".join(f"{v:.9g}" for v in row) for first, row in zip(lead, external)]
    text = "\n".join(lines) + "\n"
    if plan is None:
        sys.stdout.write(text)
        return 0
    plan.write_text(Path(args.output).name, text)
    console.info(f"wrote {len(external)} compensated wrenches to {args.output}")
    return 0
