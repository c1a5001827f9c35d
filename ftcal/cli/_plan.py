"""``ftcal plan``: calibration poses (joint configurations) for a robot and a pose sphere, to CSV."""

from __future__ import annotations

import argparse

import numpy as np

from ._common import (
    int_in_range,
    Console,
    OutputPlan,
    add_output_options,
    add_robot_options,
    add_run_options,
    nonnegative_int,
    write_json,
)

EXAMPLE = """\
examples:
  ftcal plan --out plan                                   # KUKA iiwa 14, 155 poses (thesis sphere)
  ftcal plan --robot panda --subdivisions 1 --degrees --out plan_panda
  ftcal plan --robot my_arm.urdf --sensor-frame ft_frame --excluded-cap-deg 0 --out plan_mine

writes DIR/poses.csv: one row per pose in execution order (greedy shortest tour):
  pose, <joint names>_rad (or _deg with --degrees), g_x, g_y, g_z (unit gravity direction
  in the sensor frame), pitch_<unit>, yaw_<unit>
plus plan.json (robot, frames, settings, unreachable directions) and coverage.png.
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "plan",
        help="calibration poses (joint configurations) for a robot, to a CSV a robot program can read",
        description="Plan the calibration poses of one sphere (thesis IV-B-c): icosphere gravity directions in "
        "the sensor frame -> pitch/yaw -> joint configurations by inverse kinematics, within joint limits.",
        epilog=EXAMPLE,
    )
    add_robot_options(p)
    p.add_argument("--subdivisions", type=int_in_range(0, 6, "icosphere subdivisions"), default=2, help="icosphere subdivisions (2: 162 vertices)")
    p.add_argument(
        "--excluded-cap-deg", type=float, default=20.0,
        help="leave out directions within this angle of 'tool face up' [deg] (20: 162 -> 155 poses)",
    )
    p.add_argument("--degrees", action="store_true", help="write joint angles, pitch and yaw in degrees")
    add_output_options(p, "ftcal-plan")
    add_run_options(p, seed=False)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    import ftcal

    console = Console(args.quiet)
    plan_files = OutputPlan(args.out, ["poses.csv", "plan.json", "coverage.png"], args.force)
    robot = ftcal.load_robot(args.robot, sensor_frame=args.sensor_frame, sensor_mounting=args.sensor_mounting)
    console.info(f"planning poses for {robot.name} (sensor frame {robot.sensor_frame}) ...")
    plan = ftcal.plan_calibration_poses(
        robot, subdivisions=args.subdivisions, excluded_cap_deg=args.excluded_cap_deg
    )
    unit = "deg" if args.degrees else "rad"
    to_unit = np.degrees if args.degrees else (lambda a: np.asarray(a, dtype=float))
    columns = ["pose", *(f"{j}_{unit}" for j in robot.joint_names), "g_x", "g_y", "g_z", f"pitch_{unit}", f"yaw_{unit}"]
    table = np.column_stack([
        np.arange(plan.n_poses), to_unit(plan.q), plan.gravity_in_sensor, to_unit(plan.pitch), to_unit(plan.yaw),
    ])
    table = np.round(table, 8) + 0.0  # no "-0.00000000" cells
    with plan_files.writing("poses.csv") as tmp:
        np.savetxt(tmp, table, delimiter=",", header=",".join(columns), comments="",
                   fmt=["%d"] + ["%.8f"] * (table.shape[1] - 1))
    with plan_files.writing("plan.json") as tmp:
        write_json(tmp, {
            "robot": robot.name,
            "urdf": str(robot.urdf_path),
            "sensor_frame": plan.sensor_frame,
            "anchor_frame": plan.anchor_frame,
            "anchor_position_in_base_m": plan.anchor_position_in_base,
            "joint_names": list(robot.joint_names),
            "angle_unit": unit,
            "n_candidates": plan.n_candidates,
            "n_poses": plan.n_poses,
            "unreachable_gravity_in_sensor": plan.unreachable,
            "settings": plan.settings,
        })
    write_plan_coverage(plan_files, plan, f"Calibration poses of {robot.name}: gravity directions in the sensor frame")
    console.info(
        f"{plan.n_poses} of {plan.n_candidates} directions reachable; poses -> {plan_files.path('poses.csv')}"
    )
    return 0


def write_plan_coverage(files: OutputPlan, plan, title: str) -> None:
    """``coverage.png``: the plan's reachable and unreachable gravity directions on the sphere."""
    from ..evaluation import _plots

    directions = np.vstack([plan.gravity_in_sensor, plan.unreachable])
    reached = np.r_[np.ones(plan.n_poses, bool), np.zeros(len(plan.unreachable), bool)]
    with files.writing("coverage.png") as tmp:
        _plots.plot_sphere_coverage(directions, tmp, reached=reached, title=title)
