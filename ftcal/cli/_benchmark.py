"""``ftcal benchmark``: the artificial (thesis Tables II-III) and real-world (Tables IV-V) benchmarks."""

from __future__ import annotations

import argparse
from pathlib import Path

from ._common import (CliError, Console, OutputPlan, add_jobs_option, add_scheduler_option, finish_command,
                      int_in_range, positive_float)

ARTIFICIAL_EXAMPLE = """\
examples:
  ftcal benchmark artificial --quick --out bench              # smoke run, under 2 minutes
  ftcal benchmark artificial --schedule short --n-datasets 10 --jobs 2 --out bench
  ftcal benchmark artificial --preset thesis --preset asymmetric --preset stress --out bench_full
  ftcal benchmark artificial --preset reconstructed --model linear --model directional --baselines --out rec
  ftcal benchmark artificial --n-datasets 30 --preset thesis --scheduler tcp://head-node:8786 --out bench_full

N datasets per preset, every calibrator and (unless --model is given) the stock scikit-learn
baselines on the same data; writes artificial_results.json / .md (RMSE and
relative errors mean ± std beside the thesis' Tables II-III, Wilcoxon p-values, noise floor)
and artificial_rmse_<preset>.png. Finished fits are cached in DIR/cache: re-running the same
command resumes where it stopped.
"""

REAL_WORLD_EXAMPLE = """\
examples:
  ftcal benchmark real-world --quick --out bench_rw          # 11 poses per configuration, short schedule
  ftcal benchmark real-world --schedule short --split random20 --out bench_rw

the virtual robot experiment (7 load configurations x ~155 poses) through the real pipeline,
split by held-out load configurations and by a random 20 %; RMSE and relative errors
(thesis Tables IV-V) and the per-sample RMSE plot (Fig. 6). The leave-one-config-out split
(7 fits per model) always uses the short schedule. writes real_world_results.json / .md,
real_world_rmse.png and the run logs in DIR/logs/.
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("benchmark", help="the artificial and the real-world benchmarks",
                       description="Compare calibrators the way the thesis does: on 30 artificial datasets, or on the "
                       "virtual robot experiment.", epilog="examples:\n  ftcal benchmark artificial --quick --out bench\n"
                       "  ftcal benchmark real-world --quick --out bench_rw")
    kinds = p.add_subparsers(dest="kind", metavar="KIND", parser_class=type(p))
    kinds.required = True
    _register_artificial(kinds)
    _register_real_world(kinds)
    _register_dataset(kinds)


def _add_common(p: argparse.ArgumentParser, handler, default_out: str, jobs: bool = True,
                default_models: tuple[str, ...] = ("linear", "comparative", "directional")) -> None:
    import ftcal

    p.add_argument("--model", dest="models", action="append", choices=tuple(ftcal.compose.CALIBRATOR_NAMES),
                   metavar="NAME", help=f"calibrator to include (repeatable; default: {', '.join(default_models)}; "
                   f"known: {', '.join(ftcal.compose.CALIBRATOR_NAMES)})")
    p.add_argument("--schedule", default="thesis", choices=("thesis", "short"), help="training schedule")
    p.add_argument("--quick", action="store_true", help="smoke mode: small data, few epochs")
    if jobs:
        add_jobs_option(p, "parallel joblib workers", default=1)
    finish_command(p, handler, default_out)


def _register_artificial(kinds: argparse._SubParsersAction) -> None:
    from ..simulation import ERROR_PRESETS, MAX_DATASETS, TEST_DISTRIBUTIONS

    a = kinds.add_parser("artificial", help="N artificial datasets, every calibrator (thesis Tables II-III, Fig. 5)",
                         description="The artificial-data benchmark (thesis IV-A / V-A).", epilog=ARTIFICIAL_EXAMPLE)
    a.add_argument("--preset", dest="presets", action="append", choices=sorted(ERROR_PRESETS),
                   help="error preset (repeatable; default: thesis)")
    a.add_argument("--n-datasets", type=int_in_range(1, MAX_DATASETS, "datasets"), default=30,
                   help="datasets per preset")
    a.add_argument("--test-distribution", choices=TEST_DISTRIBUTIONS, default=None,
                   help="test-load sampling (default: the preset's own, 'ball' for reconstructed, else 'radial')")
    a.add_argument("--baselines", action=argparse.BooleanOptionalAction, default=None,
                   help="also fit the stock scikit-learn baselines (sk_linear ... sk_gp) on the same data "
                   "(default: yes unless --model is given)")
    a.add_argument("--stack", type=int_in_range(1, 1000, "stack"), default=1,
                   help="train up to this many network fits (one preset and model, several datasets) together as "
                   "one stacked module: same results up to float32 rounding, ~10x less CPU with 30 (default 1)")
    add_scheduler_option(a)
    _add_common(a, run_artificial, "ftcal-benchmark")


def _register_real_world(kinds: argparse._SubParsersAction) -> None:
    from ..simulation import ERROR_PRESETS

    r = kinds.add_parser("real-world", epilog=REAL_WORLD_EXAMPLE,
                         help="the virtual robot experiment through the real pipeline (thesis Tables IV-V, Fig. 6)",
                         description="The real-world benchmark (thesis IV-B / V-B) on a virtual experiment with the "
                         "KUKA iiwa 14.")
    r.add_argument("--mass", type=positive_float, help="load mass [kg] (default: the thesis' load)")
    r.add_argument("--subdivisions", type=int_in_range(0, 6, "icosphere subdivisions"), default=2,
                   help="icosphere level (2: 155 poses)")
    r.add_argument("--preset", default="thesis", choices=sorted(ERROR_PRESETS), help="error preset of the virtual sensor")
    r.add_argument("--split", dest="splits", action="append", choices=("random20", "leave-one-config-out"),
                   help="train/test split (repeatable; default: both)")
    _add_common(r, run_real_world, "ftcal-benchmark-real-world", jobs=False)


DATASET_EXAMPLE = """\
examples:
  ftcal benchmark dataset my_sensor.csv --out bench_mine                 # closed-form models and the GP
  ftcal benchmark dataset my_sensor.csv --model linear --model directional --schedule short --out b
  ftcal benchmark dataset robot.csv --folds kfold --cv 10 --out b

which calibration should I use for my sensor? every chosen calibrator, cross-validated on the
same folds, beside the stock scikit-learn baselines (sk_linear, sk_poly2, sk_poly3,
sk_kernel_ridge, sk_gp: never chosen, the margin over what is free); whole groups held out
when the dataset has a 'group' column (a pose or load
configuration per row: the score of a calibration on poses it has not seen), else shuffled
k-fold. writes dataset_results.json / .md (held-out RMSE, eq. 18 over all 6n torque-scaled
values, ± standard error, per-axis RMSE, fit
time, the one-standard-error choice) and dataset_rmse.png.
"""

#: Default models of ``ftcal benchmark dataset``: the ones that fit in seconds to a minute on 2 cores.
DATASET_DEFAULT_MODELS = ("linear", "polynomial", "axis_nonlinear", "gaussian_process")
#: The models ``--history`` also scores with a load-history term: closed forms, since the term's own
#: cross-validation fits the model 32 times in every fold (a network or a GP would take hours).
HISTORY_MODELS = ("linear", "polynomial", "axis_nonlinear")


def _register_dataset(kinds: argparse._SubParsersAction) -> None:
    from ._data_options import add_alpha_option, add_dataset_options, add_fold_options

    d = kinds.add_parser("dataset", epilog=DATASET_EXAMPLE,
                         help="every calibrator on YOUR dataset, cross-validated: which one to use for your sensor",
                         description="Cross-validate calibrators on your own calibration dataset (.csv, .npz, .mat or "
                         "a folder of them).")
    d.add_argument("dataset", help="calibration dataset (.csv, .npz, .mat, or a folder of them: one file per pose or "
                   "session), e.g. as written by 'ftcal prepare'")
    add_fold_options(d.add_argument_group("cross-validation"), cv_default=5)
    add_alpha_option(d)
    d.add_argument("--history", action="store_true",
                   help="also score each closed-form model (" + ", ".join(HISTORY_MODELS) + ") with a load-history "
                   "term (soft or viscoelastic sensors, as 'ftcal fit --history'): needs whole groups held out "
                   "(--folds group), each group one recording in time order")
    # the names are checked when the command runs: importing the calibrators here would load scikit-learn for
    # every `ftcal --help`
    d.add_argument("--stock-baseline", action="append", metavar="NAME",
                   help="the stock baseline(s) --model stock scores as a model that may be chosen (repeatable; "
                   "default: every one; an unknown name is answered with the list)")
    # the dataset options after --out/--quiet/--seed, as --help has always listed them
    _add_common(d, run_dataset, "ftcal-benchmark-dataset", jobs=False, default_models=DATASET_DEFAULT_MODELS)
    add_dataset_options(d)


def run_dataset(args: argparse.Namespace) -> int:
    import numpy as np

    import ftcal
    from ..calibrators import STOCK_BASELINE_NAMES, StockCalibrator
    from ..compose import score_candidates
    from ..core import WRENCH_LABELS
    from ..reporting import plot_axis_errors
    from ._data_options import fold_groups, load_dataset_from_args
    from ._models import check_fold_count, evaluation_alpha

    console = Console(args.quiet)
    names = tuple(dict.fromkeys(args.models or DATASET_DEFAULT_MODELS))
    if "auto" in names:
        raise CliError("--model auto: 'auto' is itself this comparison; list the calibrators to compare instead")
    plan = OutputPlan(args.out, ["dataset_results.json", "dataset_results.md", "dataset_rmse.png"], args.force)
    data = load_dataset_from_args(args, args.dataset, "dataset")
    groups = fold_groups(args, data, args.dataset)
    check_fold_count(data, args.cv, args.dataset)
    if args.folds == "group" and groups is not None and np.unique(groups).size < 2:
        raise CliError(f"--folds group holds whole groups out, but {args.dataset}'s group column holds one group; "
                       "give at least 2 groups, or remove that column (or use --folds kfold) to hold out rows")
    if args.history and groups is None:
        raise CliError(f"--history: a load history runs along consecutive rows, so whole recordings must be held out; "
                       f"{args.dataset} needs a group column (one recording per group, rows in time order) and "
                       "--folds group or auto")
    if args.history and not set(names) & set(HISTORY_MODELS):
        raise CliError(f"--history scores the closed-form models with a history term ({', '.join(HISTORY_MODELS)}); "
                       "list at least one of them with --model")
    alpha = evaluation_alpha(data, args.alpha)
    schedule = "short" if args.quick else args.schedule
    if args.stock_baseline and "stock" not in names:
        raise CliError("--stock-baseline says which baselines --model stock scores; add --model stock")
    unknown = [b for b in args.stock_baseline or () if b not in STOCK_BASELINE_NAMES]
    if unknown:
        raise CliError(f"--stock-baseline {unknown[0]!r} is no stock baseline; choose from "
                       f"{', '.join(STOCK_BASELINE_NAMES)}")
    candidates = [(f"stock({b})", StockCalibrator(baseline=b, random_state=args.seed or 0))
                  for b in dict.fromkeys(args.stock_baseline or STOCK_BASELINE_NAMES) if "stock" in names]
    for name in (n for n in names if n != "stock"):
        extra = {"phase1_epochs": 5, "plateau_epochs": 2, "max_recover_epochs": 2} if args.quick and \
            ftcal.compose.training_schedule(schedule, name) else {}
        candidates.append((name, ftcal.make_calibrator(name, schedule=schedule, random_state=args.seed, **extra)))
    if args.history:  # after the static models: a history term is the more complex model
        candidates += [(f"history({name})", ftcal.HistoryCalibrator(ftcal.make_calibrator(name), random_state=args.seed))
                       for name in names if name in HISTORY_MODELS]
    split = f"{len(np.unique(groups))} groups" if groups is not None else "shuffled rows"
    console.info(f"cross-validating {len(candidates)} calibrators on {data.n_samples} samples, {args.cv} folds "
                 f"over {split}")
    comparison = score_candidates(
        candidates, data.raw, data.wrench, groups=groups, cv=args.cv, alpha=alpha, random_state=args.seed,
        # the stock baselines as calibrators: their tags say which are light work (scored in this process)
        baselines={name: StockCalibrator(baseline=name, random_state=args.seed or 0) for name in STOCK_BASELINE_NAMES},
        axes=tuple(data.axes) if len(data.axes) == data.wrench.shape[1] and set(data.axes) <= set(WRENCH_LABELS)
        else None,  # eq. 18 scales the torques of the axes the data have (a plate's Tx, Ty)
        race=False)  # a benchmark scores every model on every fold
    comparison.choose()  # the one-SE rule; each row against the choice in symmetric words (paired SE)
    results = comparison.to_dict()
    results.update(dataset=str(args.dataset), alpha=alpha, cv=args.cv, n_samples=data.n_samples,
                   n_channels=data.n_channels, axes=list(data.axes))
    table = _dataset_table(comparison, data.axes)
    axis = {n: a for n, a in zip(results["name"], results["axis_rmse"]) if a is not None}
    with plan.as_one_set():  # the results, their table and their figure: all or none
        plan.write_json("dataset_results.json", results)
        plan.write_text("dataset_results.md", f"# Calibrators on {args.dataset}\n\n{table}\n")
        with plan.writing("dataset_rmse.png") as tmp:
            plot_axis_errors(axis, tmp, title=f"Held-out RMSE per axis ({comparison.facts['kind']} folds)")
    print(table)
    console.info(f"choose {results['chosen']} (the simplest within one standard error of the best, or within 0.5 % "
                 f"of its RMSE); files in {args.out}")
    return 0


def _dataset_table(comparison, axes) -> str:
    from ..core import axis_unit

    head = "| model | " + " | ".join(f"{a} [{axis_unit(a)}]" for a in axes) + " |"
    lines = [head, "|" + "---|" * (1 + len(axes))]
    for row in comparison.rows:
        if row.axis_rmse is not None:
            lines.append(f"| {row.name} | " + " | ".join(f"{v:.3g}" for v in row.axis_rmse) + " |")
    return comparison.table() + "\n\nHeld-out RMSE per axis:\n\n" + "\n".join(lines)


def _models(args: argparse.Namespace) -> tuple[str, ...]:
    return tuple(dict.fromkeys(args.models or ("linear", "comparative", "directional")))


def _artificial_models(args: argparse.Namespace) -> tuple[str, ...]:
    """``benchmark artificial``'s models: the named ones, and the stock baselines unless only named models are
    asked for (``--baselines`` / ``--no-baselines`` decide when given)."""
    from ..calibrators import STOCK_BASELINE_NAMES

    wanted = not args.models if args.baselines is None else args.baselines
    return _models(args) + (STOCK_BASELINE_NAMES if wanted else ())


def run_artificial(args: argparse.Namespace) -> int:
    import ftcal
    from ._scale_out import dask_backend

    console = Console(args.quiet)
    presets = tuple(dict.fromkeys(args.presets or ("thesis",)))
    n_jobs = -1 if args.scheduler else args.jobs  # on a cluster: as many tasks at once as it has workers
    with dask_backend(args.scheduler), console.progress(total=None, desc="fits", unit="fit") as bar:

        def progress(done: int, total: int, record: dict) -> None:
            bar.total = total
            bar.set_postfix_str(f"{record['preset']} #{record['dataset']} {record['model']}", refresh=False)
            bar.update(done - bar.n)

        result = ftcal.benchmark.run_artificial_benchmark(
            n_datasets=args.n_datasets, presets=presets, models=_artificial_models(args), schedule=args.schedule,
            test_distribution=args.test_distribution, seed=args.seed, n_jobs=n_jobs, out_dir=args.out,
            quick=args.quick, progress=progress, force=args.force, stack=args.stack)
    md = result.get("files", {}).get("markdown")  # the benchmark's markdown tables (its .md file) on stdout
    if md and Path(md).is_file():
        print(Path(md).read_text(encoding="utf-8").rstrip())
    console.info(f"results in {args.out}/: " + ", ".join(Path(p).name for p in result.get("files", {}).values()))
    return 0


def run_real_world(args: argparse.Namespace) -> int:
    import ftcal

    console = Console(args.quiet)
    files = ["real_world_results.json", "real_world_results.md", "real_world_rmse.png"]
    plan = OutputPlan(args.out, files, args.force)
    log_dir = plan.out_dir / "logs"
    if log_dir.exists() and any(log_dir.iterdir()) and not args.force:
        raise CliError(f"{log_dir} holds files already; pass --force to overwrite or choose another --out")
    mass = {} if args.mass is None else {"load_mass": args.mass}
    console.info("simulating the robot experiment, preparing the dataset, fitting every model on every split ...")
    result = ftcal.benchmark.run_real_world_benchmark(
        models=_models(args), splits=tuple(dict.fromkeys(args.splits or ("random20", "leave-one-config-out"))),
        schedule="short" if args.quick else args.schedule, grouped_schedule="short",
        subdivisions=0 if args.quick else args.subdivisions, errors=args.preset, random_state=args.seed,
        log_dir=log_dir, plot_path=plan.path("real_world_rmse.png"), **mass)
    markdown = ftcal.benchmark.real_world_markdown(result)
    with plan.as_one_set():
        plan.write_text("real_world_results.md", markdown + "\n")
        plan.write_json("real_world_results.json", result)
    print(markdown)
    console.info(f"results in {args.out}/: " + ", ".join(files) + " and the run logs in logs/")
    return 0
