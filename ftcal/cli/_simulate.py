"""``ftcal simulate``: artificial datasets (``dataset``) and virtual-experiment logs (``experiment``)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ._common import (CliError, Console, OutputPlan, add_robot_options, existing_file, finish_command, finite_float,
                      int_in_range, load_robot_from_args, positive_float)

DATASET_EXAMPLE = """\
examples:
  ftcal simulate dataset --out data                      # thesis preset: train.csv (5000), test.csv (1250)
  ftcal simulate dataset --preset asymmetric --n-datasets 5 --seed 7 --out data5
  ftcal simulate dataset --preset reconstructed --out rec   # 20 % sign-dependent gains, ball test loads
  ftcal simulate dataset --sensor my_sensor.cal --zero-offset 0.05 --format npz --out mine

writes DIR/train.<fmt>, DIR/test.<fmt> (dataset_<k>/... for --n-datasets > 1), info.json
(the sampled error parameters and the noise floor) and coverage.png.
"""

EXPERIMENT_EXAMPLE = """\
examples:
  ftcal simulate experiment --out logs                   # KUKA iiwa 14, default sphere, 7 load configurations
  ftcal simulate experiment --robot panda --mass 2.5 --subdivisions 1 --out logs_panda
  ftcal simulate experiment --subdivisions 0 --bag mcap --out logs   # + logs/bags/config*_load, ..._no-load

writes the load / no-load run logs in the format 'ftcal prepare' reads (the same as a real
recording), so the whole real-world pipeline can be tried without hardware.
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("simulate", help="artificial datasets or virtual-experiment logs, to files",
                       description="Simulate calibration data: 'dataset' (thesis IV-A) or 'experiment' logs (thesis "
                       "IV-B).", epilog="examples:\n  ftcal simulate dataset --out data\n  ftcal simulate experiment --out logs")
    kinds = p.add_subparsers(dest="kind", metavar="KIND", parser_class=type(p))
    kinds.required = True
    _register_dataset(kinds)
    _register_experiment(kinds)


def _register_dataset(kinds: argparse._SubParsersAction) -> None:
    from ..simulation import ERROR_PRESETS, MAX_DATASETS, MAX_POINTS, TEST_DISTRIBUTIONS

    d = kinds.add_parser("dataset", epilog=DATASET_EXAMPLE,
                         help="artificial train/test datasets of the thesis (four spheres, continuous test set)",
                         description="Artificial calibration datasets: 4 training spheres in the torque-scaled wrench "
                         "space, a continuous test set, errors from a preset (creep, noise, crosstalk, nonlinearity, "
                         "...).")
    d.add_argument("--preset", default="thesis", choices=sorted(ERROR_PRESETS), help="error preset")
    d.add_argument("--n-datasets", type=int_in_range(1, MAX_DATASETS, "datasets"), default=1,
                   help="independent datasets (each its own errors)")
    d.add_argument("--n-per-sphere", type=int_in_range(1, MAX_POINTS, "points per sphere"), default=1250,
                   help="training points per sphere (4 spheres)")
    d.add_argument("--n-test", type=int_in_range(1, MAX_POINTS, "test points"), default=1250, help="test points")
    d.add_argument("--test-distribution", default=None, choices=TEST_DISTRIBUTIONS,
                   help="how test wrenches fill the operating range (default: the preset's own, 'ball' for "
                   "reconstructed, else 'radial')")
    d.add_argument("--sensor", type=existing_file, metavar="CAL", help="vendor calibration file (ATI .cal)")
    d.add_argument("--temperature-range", metavar="LOW,HIGH",
                   help="simulate thermal drift: each sample at a random temperature in LOW..HIGH deg C, the sensor's "
                   "zero and span drifting by data-sheet magnitudes (ftcal.core.ThermalDrift.typical); adds a "
                   "temperature column")
    d.add_argument("--zero-offset", type=finite_float, default=0.0, metavar="RAW",
                   help="raw zero-load offset added to every channel (a sensor that is not tared); at most 10^6 times "
                   "the sensor's raw full scale in magnitude")
    d.add_argument("--format", default="csv", choices=("csv", "npz"), help="dataset file format")
    finish_command(d, run_dataset, "ftcal-data")


def _dataset_files(n_datasets: int, fmt: str) -> list[str]:
    stems = ("train", "test")
    return [f"{s}.{fmt}" for s in stems] if n_datasets == 1 else [
        f"dataset_{k:02d}/{s}.{fmt}" for k in range(n_datasets) for s in stems]


def run_dataset(args: argparse.Namespace) -> int:
    import numpy as np

    import ftcal
    from ..reporting import plot_wrench_coverage

    console = Console(args.quiet)
    files = _dataset_files(args.n_datasets, args.format)
    plan = OutputPlan(args.out, files + ["info.json", "coverage.png"], args.force)
    profile = ftcal.simulation.SensorProfile.default() if args.sensor is None else \
        ftcal.simulation.read_ati_calibration(args.sensor)
    offset = None if args.zero_offset == 0 else np.full(profile.n_channels, _zero_offset(args.zero_offset, profile))
    rng = np.random.default_rng(args.seed)
    thermal = temperature_range(args.temperature_range)
    infos, first_train = [], None  # the coverage plot shows the first dataset's training wrenches
    with plan.as_one_set(), console.progress(total=args.n_datasets, desc="simulating", unit="dataset") as bar:
        for k in range(args.n_datasets):
            train, test, info = ftcal.make_artificial_dataset(
                args.preset, random_state=rng, profile=profile, n_per_sphere=args.n_per_sphere, n_test=args.n_test,
                test_distribution=args.test_distribution, zero_offset=offset)
            if thermal is not None:
                train, test, info["thermal_drift"] = _with_thermal_drift(train, test, thermal, rng)
            for ds, name in zip((train, test), files[2 * k: 2 * k + 2]):
                ds.meta.update(seed=args.seed, dataset_index=k)
                with plan.writing(name) as tmp:
                    ds.save(tmp, overwrite=True)
            infos.append(info)
            first_train = first_train or train
            bar.update(1)
        plan.write_json("info.json", {"seed": args.seed, "sensor": profile.to_dict(), "datasets": infos})
        with plan.writing("coverage.png") as tmp:
            plot_wrench_coverage(first_train.wrench, tmp, alpha=profile.alpha,
                                 title=f"Training wrenches ({args.preset} preset)")
    floors = [i["noise_floor"] for i in infos]
    console.info(f"wrote {args.n_datasets} dataset(s) to {args.out}/ ({first_train.n_samples} train, {args.n_test} "
                 f"test samples each, {profile.n_channels} channels); noise floor {np.mean(floors):.3g} N")
    return 0


def _zero_offset(value: float, profile) -> float:
    """``--zero-offset`` if the virtual sensor accepts it, else a one-line error saying the accepted range."""
    from ..simulation import ZERO_OFFSET_LIMIT, zero_offset_bound

    bound, full_scale = zero_offset_bound(profile)
    if abs(value) > bound:
        raise CliError(f"--zero-offset {value:g}: the accepted range is -{bound:.3g} to {bound:.3g} "
                       f"{profile.raw_unit} ({ZERO_OFFSET_LIMIT:g} x the sensor's raw full scale, {full_scale:.3g} "
                       f"{profile.raw_unit}); beyond it the readings keep too few digits of the load")
    return value


def temperature_range(text: str | None):
    if text is None:
        return None
    try:
        low, high = (float(v) for v in text.split(","))
    except ValueError:
        raise CliError(f"--temperature-range {text!r}: give LOW,HIGH in deg C, e.g. 15,35") from None
    if not (-60 <= low < high <= 200):
        raise CliError(f"--temperature-range {text!r}: need -60 <= LOW < HIGH <= 200 (deg C)")
    return low, high


def _with_thermal_drift(train, test, bounds, rng):
    """The datasets as read at random temperatures by a sensor with typical thermal drift (and the drift)."""
    import numpy as np

    import ftcal

    drift = ftcal.core.ThermalDrift.typical(np.abs(train.raw).max(axis=0), random_state=rng)
    out = []
    for ds in (train, test):
        temperature = rng.uniform(*bounds, size=ds.n_samples)
        meta = {**ds.meta, "temperature_range_deg_c": list(bounds)}
        out.append(ftcal.CalibrationDataset(raw=drift.apply(ds.raw, temperature), wrench=ds.wrench, group=ds.group,
                                            meta=meta, temperature=temperature))
    info = {"offset_per_deg": drift.offset_per_deg.tolist(), "gain_per_deg": drift.gain_per_deg.tolist(),
            "reference_temperature": drift.reference_temperature, "range_deg_c": list(bounds)}
    return out[0], out[1], info


def _register_experiment(kinds: argparse._SubParsersAction) -> None:
    from ..simulation import ERROR_PRESETS

    e = kinds.add_parser("experiment", epilog=EXPERIMENT_EXAMPLE,
                         help="virtual robot experiment: load / no-load run logs as a real recording would give",
                         description="Simulate the robot-held calibration experiment (thesis IV-B) and write its run "
                         "logs.")
    add_robot_options(e)
    e.add_argument("--mass", type=positive_float, default=None, help="load mass [kg] (default: the thesis' load)")
    e.add_argument("--fixture", default="thesis", metavar="FILE|thesis",
                   help="load configurations (id, mass, centre of mass [m], optional inertia) from a .json/.csv file; "
                   "'thesis' is the thesis' seven")
    e.add_argument("--subdivisions", type=int_in_range(0, 6, "icosphere subdivisions"), default=None,
                   help="icosphere subdivisions of the pose sphere (default: 2, the thesis' 155 poses)")
    e.add_argument("--preset", default="thesis", choices=sorted(ERROR_PRESETS), help="error preset of the virtual sensor")
    e.add_argument("--temperature-range", metavar="LOW,HIGH",
                   help="simulate thermal drift: each run's temperature ramps within LOW..HIGH deg C and the sensor's "
                   "zero and span drift by data-sheet magnitudes; the logs get a temperature column")
    e.add_argument("--bag", choices=("sqlite3", "mcap", "ros1"),
                   help="also write each run as the robot's continuous recording, a ROS bag in DIR/bags/ (raw gauges "
                   "on /ft_sensor/raw, joints on /joint_states; moves, settling, noise): input for 'ftcal prepare "
                   "DIR/bags --raw-topic /ft_sensor/raw' (needs: pip install \"ftcal[ros]\")")
    finish_command(e, run_experiment, "ftcal-logs")


def run_experiment(args: argparse.Namespace) -> int:
    """Plan the poses, simulate the load / no-load runs, write the logs and a coverage plot."""
    import ftcal
    from ..robot import load_fixture
    from ._plan import write_plan_coverage

    console = Console(args.quiet)
    fixture, configs = load_fixture(getattr(args, "fixture", None))
    names = [f"config{c.config_id}_{kind}.csv" for c in configs for kind in ("no-load", "load")]
    plan_files = OutputPlan(args.out, names + ["virtual_experiment.json", "coverage.png"], args.force)
    bag_storage = getattr(args, "bag", None)
    if bag_storage is not None:
        bag_names = [n[:-4] + (".bag" if bag_storage == "ros1" else "") for n in names]
        taken = [Path(args.out) / "bags" / n for n in bag_names if (Path(args.out) / "bags" / n).exists()]
        if taken:  # a bag is never replaced, --force or not
            raise CliError(f"{taken[0]} exists; a bag is never overwritten: remove it or choose another --out")
        from ..io import check_rosbags

        check_rosbags()
    robot = load_robot_from_args(args)
    kwargs = {} if args.subdivisions is None else {"subdivisions": args.subdivisions}
    console.info(f"planning the pose sphere of {robot.name} ...")
    plan = ftcal.robot.plan_calibration_poses(robot, **kwargs)
    if plan.n_poses == 0:
        raise ftcal.core.KinematicsError(f"no calibration pose of {robot.name} is reachable; try another --robot")
    mass = {} if args.mass is None else {"load_mass": args.mass}
    thermal = temperature_range(args.temperature_range)
    if thermal is not None:
        mass.update(thermal_drift="typical", temperature_range_deg=thermal)
    console.info(f"fixture: {fixture}")  # never silent: the simulated loads rest on it
    console.info(f"simulating {len(configs)} load configurations x {plan.n_poses} poses (load and no-load runs) ...")
    # the logs, the truths and the figure as one set: simulated into a private folder, put in place together
    with plan_files.as_one_set():
        with plan_files.staging() as stage:
            staged = ftcal.experiment.simulate_experiment(stage, robot=robot, plan=plan, errors=args.preset,
                                                          random_state=args.seed, overwrite=True,
                                                          load_configurations=configs, **mass)
        write_plan_coverage(plan_files, plan, f"Virtual experiment on {robot.name}: gravity in the sensor frame")
    paths = [plan_files.path(file.name) for file in staged]
    console.info(f"wrote {len(paths)} run logs to {args.out}/ (next: ftcal prepare {args.out} --out DIR)")
    if bag_storage is not None:
        from ..experiment import write_run_bags

        bags = write_run_bags(paths, Path(args.out) / "bags", bag_storage, joint_names=robot.joint_names,
                              random_state=args.seed)
        console.info(f"wrote {len(bags)} ROS bags ({bag_storage}) of the same runs to {Path(args.out) / 'bags'}/ "
                     f"(next: ftcal prepare {Path(args.out) / 'bags'} --raw-topic /ft_sensor/raw --out DIR)")
    return 0
