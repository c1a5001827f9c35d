"""``ftcal simulate experiment``: the virtual robot experiment, written as run logs."""

from __future__ import annotations

import argparse
from pathlib import Path

from ._common import CliError, Console, OutputPlan, load_robot_from_args
from ._plan import write_plan_coverage


def simulate_logs(args: argparse.Namespace) -> int:
    """Plan the poses, simulate the load / no-load runs, write the logs and a coverage plot."""
    import ftcal

    from ._simulate import temperature_range

    console = Console(args.quiet)
    from ..robot._loads import load_fixture

    fixture, configs = load_fixture(getattr(args, "fixture", None))
    names = [f"config{c.config_id}_{kind}.csv" for c in configs for kind in ("no-load", "load")]
    plan_files = OutputPlan(args.out, names + ["virtual_experiment.json", "coverage.png"], args.force)
    bag_storage = getattr(args, "bag", None)
    if bag_storage is not None:
        bag_names = [n[:-4] + (".bag" if bag_storage == "ros1" else "") for n in names]
        taken = [Path(args.out) / "bags" / n for n in bag_names if (Path(args.out) / "bags" / n).exists()]
        if taken:  # a bag is never replaced, --force or not
            raise CliError(f"{taken[0]} exists; a bag is never overwritten: remove it or choose another --out")
        from ..io._bags import check_rosbags

        check_rosbags()
    robot = load_robot_from_args(args)
    kwargs = {} if args.subdivisions is None else {"subdivisions": args.subdivisions}
    console.info(f"planning the pose sphere of {robot.name} ...")
    plan = ftcal.plan_calibration_poses(robot, **kwargs)
    if plan.n_poses == 0:
        raise ftcal.KinematicsError(f"no calibration pose of {robot.name} is reachable; try another --robot")
    mass = {} if args.mass is None else {"load_mass": args.mass}
    thermal = temperature_range(args.temperature_range)
    if thermal is not None:
        mass.update(thermal_drift="typical", temperature_range_deg=thermal)
    console.info(f"fixture: {fixture}")  # never silent: the simulated loads rest on it
    console.info(f"simulating {len(configs)} load configurations x {plan.n_poses} poses (load and no-load runs) ...")
    paths = ftcal.simulate_experiment(
        args.out, robot=robot, plan=plan, errors=args.preset, random_state=args.seed, overwrite=args.force,
        load_configurations=configs, **mass,
    )
    write_plan_coverage(plan_files, plan, f"Virtual experiment on {robot.name}: gravity in the sensor frame")
    console.info(f"wrote {len(paths)} run logs to {args.out}/ (next: ftcal prepare {args.out} --out DIR)")
    if bag_storage is not None:
        from ..experiment._virtual_recording import write_run_bags

        bags = write_run_bags(paths, Path(args.out) / "bags", bag_storage, joint_names=robot.joint_names,
                              random_state=args.seed)
        console.info(f"wrote {len(bags)} ROS bags ({bag_storage}) of the same runs to {Path(args.out) / 'bags'}/ "
                     f"(next: ftcal prepare {Path(args.out) / 'bags'} --raw-topic /ft_sensor/raw --out DIR)")
    return 0
