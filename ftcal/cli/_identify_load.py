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
    write_json,
)
from ._prepare import log_files

IDENTIFY_EXAMPLE = """\
examples:
  ftcal plan --subdivisions 0 --out tool_plan        # 11 well-spread poses for the robot program
  # record the sensor at each pose with the tool mounted, nothing touching it -> tool_logs/*.csv (run logs)
  ftcal identify-load tool_logs --model models/linear.model.npz --robot kuka_iiwa14 --out tool

writes DIR/NAME.tool.json: mass [kg], centre of mass [m] (sensor frame), bias [N, N·m], their standard
errors, and the residual RMS. Every row of the logs is one static pose (the 'run' column is ignored).
"""

COMPENSATE_EXAMPLE = """\
examples:
  ftcal compensate run.csv --model models/linear.model.npz --tool tool/tool.tool.json --robot kuka_iiwa14
  ftcal compensate logs/ --model m.model.npz --tool t.tool.json --output external.csv

reads run logs (joints and raw channels per row), calibrates the raw channels with the model, and
subtracts the tool's weight at each row's pose (forward kinematics) and the bias. Output CSV:
timestamp,pose,Fx,Fy,Fz,Tx,Ty,Tz: the external wrench in the sensor frame [N, N·m].
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "identify-load",
        help="identify a tool's mass, centre of mass and the sensor bias from static poses",
        description="Identify the tool load (mass, centre of mass) and the sensor bias from run logs of static poses.",
        epilog=IDENTIFY_EXAMPLE,
    )
    _add_log_inputs(p)
    p.add_argument("--gravity", default="0,0,-9.81", metavar="GX,GY,GZ", help="gravity in the base frame [m/s²]")
    p.add_argument("--name", default="tool", help="file name stem of the tool file")
    add_output_options(p, "ftcal-tool")
    add_run_options(p, seed=False)
    p.set_defaults(handler=run_identify)

    c = sub.add_parser(
        "compensate",
        help="external wrench from run logs: calibrate, then remove the tool's weight and the bias",
        description="Calibrate run logs with a model and subtract the identified tool load at each pose.",
        epilog=COMPENSATE_EXAMPLE,
    )
    _add_log_inputs(c)
    c.add_argument("--tool", type=existing_file, required=True, help="tool file (ftcal identify-load)")
    c.add_argument("--output", default="-", metavar="FILE", help="where the wrenches go; '-' is stdout")
    c.add_argument("-f", "--force", action="store_true", help="overwrite --output FILE if it exists")
    add_run_options(c, seed=False)
    c.set_defaults(handler=run_compensate)


def _add_log_inputs(p: argparse.ArgumentParser) -> None:
    """The run logs, the model that calibrates them and the robot whose kinematics give their poses."""
    p.add_argument("logs", nargs="+", metavar="LOG", help="run log files or directories of *.csv logs")
    p.add_argument("--model", type=existing_file, required=True, help="calibration model file (ftcal fit)")
    add_robot_options(p)


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
    logs = [ftcal.read_run_log(p, n_channels=int(model.n_features_in_), n_joints=robot.n_joints)
            for p in log_files(args.logs)]
    q = np.vstack([lg.q for lg in logs])
    raw = np.vstack([lg.raw for lg in logs])
    rotations = ftcal.sensor_pose_in_base(robot, q)[:, :3, :3]
    return logs, rotations, model.predict(raw)


def run_identify(args: argparse.Namespace) -> int:
    import ftcal

    console = Console(args.quiet)
    gravity = _gravity(args.gravity)
    name = f"{args.name}.tool.json"
    plan = OutputPlan(args.out, [name], args.force)
    logs, rotations, wrenches = _poses_and_wrenches(args)
    tool = ftcal.identify_tool_load(rotations, wrenches, gravity=gravity)
    with plan.writing(name) as tmp:
        write_json(tmp, {**tool.to_dict(), "logs": [str(lg.path) for lg in logs], "n_poses": len(rotations),
                         "model": str(args.model), "robot": args.robot})
    c = tool.center_of_mass * 1000
    console.info(
        f"tool: {tool.mass:.4f} ± {tool.mass_std_error:.2g} kg at [{c[0]:.1f}, {c[1]:.1f}, {c[2]:.1f}] mm "
        f"(sensor frame), from {len(rotations)} poses; residual RMS {tool.residual_rms[0]:.3g} N, "
        f"{tool.residual_rms[1]:.3g} N·m -> {plan.path(name)}"
    )
    return 0


def run_compensate(args: argparse.Namespace) -> int:
    import numpy as np

    import ftcal
    from ..core._wrench import WRENCH_LABELS

    console = Console(args.quiet)
    plan = OutputPlan.single_file(args.output, args.force)
    tool = ftcal.ToolLoad.load(args.tool)
    logs, rotations, wrenches = _poses_and_wrenches(args)
    external = tool.compensate(rotations, wrenches)
    timestamp = np.concatenate([lg.timestamp for lg in logs])
    pose = np.concatenate([lg.pose for lg in logs])
    lines = ["timestamp,pose," + ",".join(WRENCH_LABELS)]
    lines += [f"{t:.9g},{p}," + ",".join(f"{v:.9g}" for v in row) for t, p, row in zip(timestamp, pose, external)]
    text = "\n".join(lines) + "\n"
    if plan is None:
        sys.stdout.write(text)
        return 0
    with plan.writing(Path(args.output).name) as tmp:
        tmp.write_text(text, encoding="utf-8")
    console.info(f"wrote {len(external)} compensated wrenches to {args.output}")
    return 0
