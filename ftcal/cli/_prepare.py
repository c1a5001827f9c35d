"""``ftcal prepare``: recorded load / no-load run logs -> calibration dataset (the real-world pipeline)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ._common import (CliError, Console, OutputPlan, add_robot_options, finish_command, int_in_range,
                      load_robot_from_args, path_problem, positive_float)
from ..io import refuse_twin_recordings, run_log_files
from ._data_options import add_columns_option, named_inputs
from ._messages import cli_spelling
from ._recordings import add_bag_options, add_recording_options, bag_files, bag_run_log, refuse_bag_options

EXAMPLE = """\
examples:
  ftcal prepare logs/ --out data                          # every *.csv log in logs/
  ftcal prepare runs/config*_load.csv runs/config*_no-load.csv --mass 2.0 --out data
  ftcal prepare logs/ --fixture my_fixture.csv --out data     # your own load configurations

--fixture FILE: your load configurations, CSV with a header id,name,mass_kg,com_x_m,com_y_m,com_z_m
(optional ixx,iyy,izz,ixy,ixz,iyz [kg·m²]) or JSON [{"id": 0, "mass_kg": 2.0, "center_of_mass_m":
[x, y, z]}, ...]; centres of mass in the sensor frame [m], ids as in the logs' config column. The
default, 'thesis', is the thesis' seven configurations (centre and Table I); the fixture used is
always named on stderr and in prepare.json.
  ftcal prepare logs/ --robot my_arm.urdf --sensor-frame ft_frame --format npz --out data

  ftcal prepare bags/ --raw-topic /ft_sensor/raw --mass 2.0 --out data    # ROS bags of the runs

ROS bags (rosbag2 sqlite3 / MCAP folders, ROS 1 .bag files), one per run, named config<C>_load and
config<C>_no-load: the raw gauges (--raw-topic, --raw-field) and the joint states (--joint-topic), or the
sensor's orientation from /tf (--tf BASE,SENSOR: no joints, no robot model), are aligned (interpolated at
the gauges' stamps), the still poses found in each run (the settling after
each move dropped) and averaged; the k-th still pose of a load run pairs with the k-th of its no-load run.

pairs every load run with its no-load run (same configuration, same pose index), aligns
them with R_delta = P_no-load^T P_load (thesis eq. 17), subtracts the no-load reading and
computes the reference wrench of the load from the forward kinematics (eq. 15-16).
writes DIR/dataset.<fmt> (group = load configuration id), prepare.json and coverage.png.
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("prepare", help="recorded load / no-load logs -> calibration dataset", epilog=EXAMPLE,
                       description="Turn the run logs of a robot-held calibration experiment into a calibration "
                       "dataset.")
    p.add_argument("logs", nargs="+", metavar="LOG",
                   help="run log files, or directories holding *.csv logs; or ROS bags of the runs (or their folder)")
    add_robot_options(p)
    p.add_argument("--mass", type=positive_float, help="load mass [kg] (default: the fixture's masses, else the logs' "
                   "load_mass_kg)")
    p.add_argument("--fixture", default="thesis", metavar="FILE|thesis",
                   help="your load configurations (id, mass, centre of mass in the sensor frame, optional inertia) "
                   "from a .json or .csv file; 'thesis' is the thesis' seven (see 'ftcal prepare --help')")
    p.add_argument("--n-channels", type=int_in_range(3, 1024, "channels"), metavar="N",
                   help="expected raw channel count (checked in every log)")
    p.add_argument("--format", default="csv", choices=("csv", "npz"), help="dataset file format")
    add_columns_option(p)
    add_bag_options(p, wrench=False)
    add_recording_options(p.add_argument_group("still poses in ROS bags"))
    finish_command(p, run, "ftcal-data", seed=False)


def log_files(items: list[str]) -> list[Path]:
    files: list[Path] = []
    for item in items:
        path = Path(item)
        if path.is_dir():
            found = run_log_files(path)
            if not found:
                raise CliError(f"{path}: directory holds no *.csv run logs")
            files += found
        elif path_problem(path) is None:
            files.append(path)
        else:
            raise CliError(f"{path_problem(path)} (a run log, or a directory of *.csv run logs)")
    files = list(dict.fromkeys(files))
    refuse_twin_recordings(files, "run log", CliError)
    return files


def run(args: argparse.Namespace) -> int:
    import ftcal
    from ..reporting import plot_wrench_coverage
    from ..robot import load_fixture

    console = Console(args.quiet)
    args.logs = named_inputs(args, args.logs)  # --columns: headerless logs named, joined side by side
    name = f"dataset.{args.format}"
    plan = OutputPlan(args.out, [name, "prepare.json", "coverage.png"], args.force)
    bags = bag_files(args.logs)
    if bags is None:
        refuse_bag_options(args, "run logs")
    logs = bags if bags is not None else log_files(args.logs)
    robot = load_robot_from_args(args)
    what = "ROS bags" if bags is not None else "run logs"
    pose = f"the sensor's orientation from /tf ({', '.join(args.tf)})" if bags is not None and args.tf else \
        f"{robot.name} (sensor frame {robot.sensor_frame})"
    console.info(f"preparing {len(logs)} {what} with {pose} ...")
    inputs = logs if bags is None else [bag_run_log(args, path, robot, console) for path in bags]
    if bags is not None and args.n_channels is not None and inputs[0].n_channels != args.n_channels:
        raise CliError(f"{bags[0]}: {inputs[0].n_channels} raw channels but --n-channels {args.n_channels}")
    fixture, configurations = load_fixture(args.fixture)
    console.info(f"fixture: {fixture}")  # never silent (and kept in prepare.json): the reference wrenches rest on it
    try:
        dataset = ftcal.experiment.prepare_dataset(inputs, robot, args.mass, n_channels=args.n_channels,
                                                   load_configurations=configurations)
    except ftcal.core.LogFormatError as exc:
        if exc.parameter != "load_configurations":
            raise
        raise CliError(exc.render(cli_spelling(args), fix=f"the fixture used was {fixture}: describe yours in a file "
                                  "and pass --fixture FILE (see 'ftcal prepare --help')")) from None
    dataset.meta["fixture"] = fixture
    groups = {} if dataset.group is None else {str(g): int((dataset.group == g).sum())
                                               for g in sorted(set(dataset.group.tolist()))}
    alpha = ftcal.core.alpha_from_wrenches(dataset.wrench)
    with plan.as_one_set():  # the dataset, its summary and its figure: all or none
        with plan.writing(name) as tmp:
            dataset.save(tmp, overwrite=True)
        plan.write_json("prepare.json", {
            "logs": [str(p) for p in logs], "robot": robot.name, "sensor_frame": robot.sensor_frame,
            "n_samples": dataset.n_samples, "n_channels": dataset.n_channels, "samples_per_configuration": groups,
            "fixture": fixture, "meta": dataset.meta})
        with plan.writing("coverage.png") as tmp:
            plot_wrench_coverage(dataset.wrench, tmp, alpha=alpha, title="Reference wrenches of the prepared dataset")
    console.info(f"{dataset.n_samples} samples x {dataset.n_channels} channels from {len(groups)} load configurations "
                 f"-> {plan.path(name)} (next: ftcal fit {plan.path(name)} --out DIR)")
    return 0
