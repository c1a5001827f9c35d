"""``ftcal plan``: calibration poses (joint configurations) for a robot and a pose sphere, to CSV."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from ._common import (CliError, Console, OutputPlan, add_robot_options, existing_file, finish_command, finite_float,
                      int_in_range, load_robot_from_args, positive_float, positive_int)
from ._data_options import DATASET_OPTIONS, add_dataset_options, load_dataset_for_models

EXAMPLE = """\
examples:
  ftcal plan --out plan                                   # KUKA iiwa 14, 155 poses (thesis sphere)
  ftcal plan --robot panda --subdivisions 1 --degrees --out plan_panda
  ftcal plan --robot my_arm.urdf --sensor-frame ft_frame --excluded-cap-deg 0 --out plan_mine
  ftcal plan --poses 52 --strategy d-optimal --out plan52   # a third of the poses, chosen to teach the most
  ftcal plan --next 10 --dataset data.csv --model m.model.npz --out next10   # where to measure next

writes DIR/poses.csv: one row per pose in execution order (greedy shortest tour):
  pose, <joint names>_rad (or _deg with --degrees), g_x, g_y, g_z (unit gravity direction
  in the sensor frame), pitch_<unit>, yaw_<unit>
plus plan.json (robot, frames, settings, unreachable directions; with --next the predicted
uncertainty and expected gain of each proposal) and coverage.png.

--strategy d-optimal chooses --poses N of the reachable directions of a dense sphere
(--candidate-subdivisions, 3: 642 before the cap rule) maximising the information of the
linear calibration model plus a space-filling term; random draws N of them (--seed).
--next K ranks the candidates by the predicted wrench uncertainty given the dataset measured
so far (the linear model's, plus a Gaussian-process model's own); rows are the proposals,
most informative first.
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("plan", epilog=EXAMPLE,
                       help="calibration poses (joint configurations) for a robot, to a CSV a robot program can read",
                       description="Plan the calibration poses of one sphere (thesis IV-B-c): icosphere gravity "
                       "directions in the sensor frame -> pitch/yaw -> joint configurations by inverse kinematics, "
                       "within joint limits.")
    add_robot_options(p)
    p.add_argument("--subdivisions", type=int_in_range(0, 6, "icosphere subdivisions"), default=2,
                   help="icosphere subdivisions (2: 162 vertices)")
    p.add_argument("--excluded-cap-deg", type=finite_float, default=20.0,
                   help="leave out directions within this angle of 'tool face up' [deg] (20: 162 -> 155 poses)")
    p.add_argument("--strategy", choices=("geodesic", "random", "d-optimal"), default="geodesic",
                   help="geodesic: every direction of the --subdivisions sphere (the thesis); random / d-optimal: "
                   "--poses of the reachable directions of a dense sphere")
    p.add_argument("--poses", type=positive_int, default=None, metavar="N",
                   help="number of poses of a random or d-optimal plan (at least 7, the linear model's parameters)")
    p.add_argument("--candidate-subdivisions", type=int_in_range(0, 5, "candidate icosphere subdivisions"),
                   default=3, help="icosphere level of the candidates of random, d-optimal and --next (3: 642)")
    p.add_argument("--space-filling", type=finite_float, default=0.25,
                   help="weight of the space-filling term of the d-optimal criterion (0: pure D-optimality)")
    p.add_argument("--load-configurations", type=positive_int, default=None, metavar="K",
                   help="with --strategy d-optimal: also choose which K of the thesis' 7 load configurations to run "
                   "(at least 3; listed in plan.json settings.load_configurations); default all")
    p.add_argument("--next", type=positive_int, default=None, metavar="K", dest="next_poses",
                   help="propose the K poses where the model's predicted wrench is most uncertain "
                   "(needs --dataset and --model)")
    p.add_argument("--dataset", type=existing_file, default=None, help="with --next: the dataset measured so far")
    p.add_argument("--model", type=existing_file, default=None, help="with --next: a model file fitted on it")
    p.add_argument("--load-mass", type=positive_float, default=None,
                   help="with --next: load mass [kg] if the dataset's metadata lacks it")
    p.add_argument("--degrees", action="store_true", help="write joint angles, pitch and yaw in degrees")
    add_dataset_options(p)  # how --next reads --dataset (default: as the model was fitted)
    finish_command(p, run, "ftcal-plan")


def _check_arguments(args: argparse.Namespace) -> None:
    if args.next_poses is not None:
        missing = [flag for flag, value in (("--dataset", args.dataset), ("--model", args.model)) if value is None]
        if missing:
            raise CliError(f"--next needs {' and '.join(missing)} (the dataset measured so far and a model fitted on it)")
        if args.poses is not None or args.strategy != "geodesic":
            raise CliError("--next proposes poses from a dataset and a model; do not combine it with --poses/--strategy")
        return
    if args.dataset is not None or args.model is not None:
        raise CliError("--dataset and --model are for --next K (which poses to measure next)")
    given = [f"--{k.replace('_', '-')}" for k in DATASET_OPTIONS if getattr(args, k, None) is not None]
    if given:
        raise CliError(f"{', '.join(given)} say how --next reads its --dataset; give them with --next K")
    if args.strategy == "geodesic" and args.poses is not None:
        raise CliError(f"--poses {args.poses} needs --strategy d-optimal or random (the geodesic plan takes every "
                       "direction of its sphere; choose its size with --subdivisions)")
    if args.strategy != "geodesic" and args.poses is None:
        raise CliError(f"--strategy {args.strategy} needs --poses N (how many poses to choose)")
    if args.load_configurations is not None and args.strategy != "d-optimal":
        raise CliError("--load-configurations needs --strategy d-optimal")
    if not (0 <= args.space_filling <= 1e6):  # beyond, the criterion's terms overflow (the default is 0.25)
        raise CliError(f"--space-filling must be a weight from 0 to 1e6; got {args.space_filling}")


def run(args: argparse.Namespace) -> int:
    import ftcal

    _check_arguments(args)
    console = Console(args.quiet)
    plan_files = OutputPlan(args.out, ["poses.csv", "plan.json", "coverage.png"], args.force)
    robot = load_robot_from_args(args)
    extra: dict = {}
    if args.next_poses is not None:
        # read as the model was fitted (its stored columns and units), each option given overriding
        dataset = load_dataset_for_models(args, args.dataset, "dataset", [args.model])
        model = ftcal.load_model(args.model)
        console.info(f"ranking the reachable poses of {robot.name} by the predicted uncertainty of {args.model} ...")
        candidates = ftcal.robot.reachable_candidates(robot, subdivisions=args.candidate_subdivisions,
                                                      excluded_cap_deg=args.excluded_cap_deg)
        plan = ftcal.experiment.propose_next_poses(robot, dataset, model, args.next_poses, candidates=candidates,
                                                   load_mass=args.load_mass)
        extra = {"uncertainty": plan.uncertainty, "predicted_std_N": plan.predicted_std,
                 "expected_gain": plan.expected_gain, "total_variance_before_N2": plan.total_variance_before,
                 "total_variance_after_N2": plan.total_variance_after, "dataset": str(args.dataset),
                 "model": str(args.model)}
    else:
        console.info(f"planning poses for {robot.name} (sensor frame {robot.sensor_frame}) ...")
        plan = ftcal.robot.plan_calibration_poses(
            robot, subdivisions=args.subdivisions, excluded_cap_deg=args.excluded_cap_deg, strategy=args.strategy,
            n_poses=args.poses, candidate_subdivisions=args.candidate_subdivisions, space_filling=args.space_filling,
            n_load_configurations=args.load_configurations, random_state=args.seed)
    unit = "deg" if args.degrees else "rad"
    to_unit = np.degrees if args.degrees else (lambda a: np.asarray(a, dtype=float))
    columns = ["pose", *(f"{j}_{unit}" for j in robot.joint_names), "g_x", "g_y", "g_z", f"pitch_{unit}", f"yaw_{unit}"]
    table = np.column_stack([np.arange(plan.n_poses), to_unit(plan.q), plan.gravity_in_sensor, to_unit(plan.pitch),
                             to_unit(plan.yaw)])
    table = np.round(table, 8) + 0.0  # no "-0.00000000" cells
    with plan_files.as_one_set():  # poses, summary and figure: all or none
        with plan_files.writing("poses.csv") as tmp:
            np.savetxt(tmp, table, delimiter=",", header=",".join(columns), comments="",
                       fmt=["%d"] + ["%.8f"] * (table.shape[1] - 1))
        plan_files.write_json("plan.json", {
            "robot": robot.name, "urdf": str(robot.urdf_path), "sensor_frame": plan.sensor_frame,
            "anchor_frame": plan.anchor_frame, "anchor_position_in_base_m": plan.anchor_position_in_base,
            "joint_names": list(robot.joint_names), "angle_unit": unit, "n_candidates": plan.n_candidates,
            "n_poses": plan.n_poses, "unreachable_gravity_in_sensor": plan.unreachable, "settings": plan.settings,
            **extra})
        write_plan_coverage(plan_files, plan, f"Calibration poses of {robot.name}: gravity directions in the sensor frame")
    said = (f"{plan.n_poses} poses proposed ({plan.uncertainty} uncertainty); they remove "
            f"{100 * plan.expected_gain.sum():.1f} % of the predicted variance" if args.next_poses is not None
            else f"{plan.n_poses} poses ({args.strategy}) of {plan.n_candidates} directions")
    console.info(f"{said}; poses -> {plan_files.path('poses.csv')}")
    from ..robot import LINEAR_MODEL_PARAMETERS

    if args.next_poses is None and plan.n_poses < LINEAR_MODEL_PARAMETERS:
        print(f"ftcal: warning: {plan.n_poses} poses cannot calibrate even the linear model (it needs "
              f"{LINEAR_MODEL_PARAMETERS} per load configuration); widen the sphere (a smaller --excluded-cap-deg, "
              "more --subdivisions)", file=sys.stderr)
    return 0


def write_plan_coverage(files: OutputPlan, plan, title: str) -> None:
    """``coverage.png``: the plan's reachable and unreachable gravity directions on the sphere."""
    from ..reporting import plot_sphere_coverage

    directions = np.vstack([plan.gravity_in_sensor, plan.unreachable])
    reached = np.r_[np.ones(plan.n_poses, bool), np.zeros(len(plan.unreachable), bool)]
    with files.writing("coverage.png") as tmp:
        plot_sphere_coverage(directions, tmp, reached=reached, title=title)
