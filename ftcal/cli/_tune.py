"""``ftcal tune``: hyperparameter search of a calibrator on a dataset (cross-validated, eq. 18 RMSE)."""

from __future__ import annotations

import argparse
import time

from ..core import CalibrationInputError
from ._common import (CliError, Console, OutputPlan, add_jobs_option, add_name_option, add_scheduler_option,
                      finish_command, int_in_range)
from ._data_options import (add_alpha_option, add_dataset_options, add_fold_options, fit_data_facts, fold_groups,
                            load_dataset_from_args, training_targets)
from ._models import calibrator_params, check_fold_count, model_file_name, parse_param

EXAMPLE = """\
examples:
  ftcal tune data/train.csv --model polynomial --out tuned                  # the default search space
  ftcal tune data/train.csv --model axis_nonlinear --grid 'powers=[[1.5], [1, 2]]' --grid 'ridge=[1e-6, 1e-3]'
  ftcal tune data/train.csv --model directional --grid 'hidden_layer_sizes=[[64, 64], [128, 128, 128]]' \\
      --grid 'lr=loguniform(1e-4, 1e-2)' --n-iter 8 --cv 3 --out tuned
  ftcal tune real.csv --model directional_ensemble --grid 'estimator__lr=[3e-4, 1e-3]' --folds group

searches the values (a JSON list per parameter: grid search over every combination; with --n-iter,
a randomized search that also takes loguniform(a, b), uniform(a, b), randint(a, b)) by k-fold
cross-validation of the torque-scaled RMSE (eq. 18), refits the best on the whole dataset and writes
DIR/NAME.tune.json (every candidate, ranked) and DIR/NAME.model.npz (the best model).
"""


def register(sub: argparse._SubParsersAction) -> None:
    from ..compose import CALIBRATOR_NAMES

    p = sub.add_parser("tune", help="search a calibrator's hyperparameters by cross-validation", epilog=EXAMPLE,
                       description="Hyperparameter search (scikit-learn GridSearchCV / RandomizedSearchCV) of a "
                       "calibrator, scored by the cross-validated torque-scaled RMSE.")
    p.add_argument("dataset", help="training dataset (.csv, .npz, .mat, or a folder of them)")
    p.add_argument("-m", "--model", default="axis_nonlinear", choices=tuple(CALIBRATOR_NAMES), help="calibrator")
    p.add_argument("--grid", action="append", default=[], metavar="KEY=VALUES",
                   help="values of one parameter: a JSON list, or a distribution with --n-iter (repeatable; "
                   "default: the model's documented search space, ftcal.compose._search.DEFAULT_SEARCH_SPACES)")
    p.add_argument("--n-iter", type=int_in_range(1, 10_000, "candidates"),
                   help="randomized search with this many candidates")
    add_fold_options(p.add_argument_group("cross-validation"), cv_default=3)
    p.add_argument("--schedule", default="short", choices=("thesis", "short"), help="starting training schedule")
    p.add_argument("--param", action="append", type=parse_param, default=[], metavar="KEY=VALUE",
                   help="a fixed calibrator parameter, value read as JSON (repeatable)")
    add_alpha_option(p)
    add_jobs_option(p, "parallel joblib workers of the search", default=1)
    add_scheduler_option(p)
    add_name_option(p, "the outputs (default: the --model name)")
    add_dataset_options(p)
    finish_command(p, run, "ftcal-tuned")


def parse_grid(entries: list[str], randomized: bool) -> dict | None:
    """The search space of the ``--grid KEY=VALUES`` options (None: the model's default), each entry checked before
    any work: a distribution's bounds (scipy would only fail when sampling, with "Domain error in arguments") and a
    distribution without a randomized search.

    Examples
    --------
    >>> parse_grid(["ridge=[1e-6, 1e-3]"], randomized=False)
    {'ridge': [1e-06, 0.001]}
    >>> parse_grid(["ridge=loguniform(1, 0)"], randomized=True)
    Traceback (most recent call last):
    ...
    ftcal.cli._messages.CliError: --grid 'ridge=loguniform(1, 0)': loguniform(a, b) needs 0 < a < b; got a = 1, b = 0
    """
    from ..compose import parse_search_space

    space: dict = {}
    for entry in entries:
        where = f"--grid {entry!r}"
        try:
            parsed = parse_search_space([entry])
        except CalibrationInputError as exc:
            raise CliError(str(exc).replace(f"search entry {entry!r}", where, 1)) from None
        if not randomized and any(not isinstance(values, list) for values in parsed.values()):
            raise CliError(f"{where}: a distribution is sampled by a randomized search; pass --n-iter N (the number "
                           f"of candidates), or give a JSON list of values")
        space.update(parsed)
    return space or None


def run(args: argparse.Namespace) -> int:
    import ftcal
    from ..compose import search_calibrator, search_summary
    from ._scale_out import dask_backend

    console = Console(args.quiet)
    name = args.name or args.model
    plan = OutputPlan(args.out, [model_file_name(name), f"{name}.tune.json"], args.force)
    space = parse_grid(args.grid, randomized=args.n_iter is not None)
    data = load_dataset_from_args(args, args.dataset, "training dataset")
    check_fold_count(data, args.cv, args.dataset)
    groups = fold_groups(args, data, args.dataset)
    params = calibrator_params(args, data)
    start = time.perf_counter()
    with dask_backend(args.scheduler):  # a scheduler that cannot be used fails here, before any status line
        console.info(f"searching {args.model} on {data.n_samples} samples x {data.n_channels} channels, {args.cv}-fold")
        search = search_calibrator(args.model, data.raw, training_targets(data), space=space, n_iter=args.n_iter,
                                   cv=args.cv, groups=groups, schedule=args.schedule, random_state=args.seed,
                                   n_jobs=-1 if args.scheduler else args.jobs, **params)
    seconds = time.perf_counter() - start
    summary = {"model": args.model, "dataset": str(args.dataset), "schedule": args.schedule, "seed": args.seed,
               "search_seconds": round(seconds, 3), **search_summary(search)}
    with plan.as_one_set():  # the model and its search summary: all or none, never another run's file replaced
        with plan.writing(model_file_name(name)) as tmp:
            ftcal.save_model(search.best_estimator_, tmp, overwrite=True, data=fit_data_facts(args, data))
        plan.write_json(f"{name}.tune.json", summary)
    console.info(f"done in {seconds:.1f} s: best {summary['best_params']} with cross-validated RMSE "
                 f"{summary['best_rmse']:.4g} N; model -> {plan.path(model_file_name(name))}")
    return 0
