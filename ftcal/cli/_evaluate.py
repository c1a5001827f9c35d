"""``ftcal evaluate``: metrics (RMSE, relative errors, per axis) and plots of model(s) on a dataset."""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path

import numpy as np

from ._common import CliError, Console, OutputPlan, existing_file, finish_command, write_json
from ._data_options import add_alpha_option, add_dataset_options, load_dataset_for_models
from ._models import evaluation_alpha, model_label
from ..reporting import EVALUATION_PLOTS, axis_table, comparison_table, predicted_plot_name, write_evaluation_plots

EXAMPLE = """\
examples:
  ftcal evaluate data/test.csv models/directional.model.npz --out eval
  ftcal evaluate data/test.csv models/*.model.npz --alpha 50 --out eval --force

prints the comparison table (markdown) on stdout and writes to DIR: metrics.json,
metrics.md, rmse_distribution.png, axis_rmse.png and errors_<model>.png per model.
RMSE is over the torque-scaled wrench [F, alpha*T] in N (thesis eq. 18); relative
errors are ||F - F_hat|| / ||F|| and the same for torque (eq. 19).

evaluate on data the model was NOT fitted on (a held-out recording). Given the training file
of a model (recognised by the hash 'ftcal fit' keeps in NAME.fit.json beside the model), it warns
that the figures are training errors; 'ftcal report MODEL DATASET' gives held-out figures by
grouped cross-validation instead.
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("evaluate", help="metrics and plots of one or more models on a dataset", epilog=EXAMPLE,
                       description="Evaluate fitted models on a calibration dataset: RMSE, relative errors, per-axis "
                       "RMSE, plots.")
    p.add_argument("dataset", help="evaluation dataset (.csv, .npz, .mat, or a folder of them)")
    p.add_argument("models", nargs="+", metavar="MODEL", type=existing_file, help="model files written by 'ftcal fit'")
    add_alpha_option(p)
    p.add_argument("--no-plots", action="store_true", help="write the metrics only")
    add_dataset_options(p)
    finish_command(p, run, "ftcal-eval", seed=False)


def run(args: argparse.Namespace) -> int:
    import ftcal
    from ..reporting import model_inputs  # scikit-learn behind it: not at `ftcal --help`

    console = Console(args.quiet)
    labels = [model_label(m) for m in args.models]
    if len(set(labels)) != len(labels):
        raise CliError(f"two model files share a name ({', '.join(labels)}); give each model file its own name")
    names = ["metrics.json", "metrics.md"]
    if not args.no_plots:
        names += list(EVALUATION_PLOTS) + [predicted_plot_name(label) for label in labels]
    plan = OutputPlan(args.out, names, args.force)
    data = load_dataset_for_models(args, args.dataset, "evaluation dataset", args.models)  # as they were fitted
    trained_on = training_data_of(args.dataset, args.models)
    for label in trained_on:
        print(f"ftcal: warning: {args.dataset} is the training data of {label}: its figures below are training "
              "errors, not the accuracy on new data. Evaluate on a held-out recording, or run 'ftcal report MODEL "
              "DATASET' for held-out figures by grouped cross-validation.", file=sys.stderr)
    alpha = evaluation_alpha(data, args.alpha)
    noise_floor = data.meta.get("noise_floor")
    predictions, reports, beyond = {}, {}, {}
    with console.progress(total=len(labels), desc="evaluating", unit="model") as bar:
        for label, path in zip(labels, args.models):
            model = ftcal.load_model(path)
            predictions[label] = np.asarray(model.predict(model_inputs(model, data)), dtype=float)
            if predictions[label].shape != data.wrench.shape:
                raise CliError(f"{path} predicts {predictions[label].shape[1]} wrench axes but {args.dataset} has "
                               f"{data.n_axes} ({', '.join(data.axes)}); give the dataset of that sensor")
            reports[label] = ftcal.core.calibration_metrics(data.wrench, predictions[label], alpha=alpha, axes=data.axes)
            beyond[label] = extrapolation(model, path, data)
            bar.update(1)
    for label, found in beyond.items():
        for what, excess in found.items():
            if excess.any:
                print(f"ftcal: warning: {args.dataset}: {int(excess.mask.sum())} of {data.n_samples} rows go beyond "
                      f"the {what} {label} was calibrated on ({excess.words(AXIS_UNITS)}); its figures there are "
                      "extrapolations", file=sys.stderr)
    table = comparison_table(reports, noise_floor)
    axes = axis_table(reports)
    # metrics and plots are one set: all are put in place, or none (a failing plot leaves no metrics behind)
    with plan.as_one_set(), contextlib.ExitStack() as stack:
        tmps = {name: stack.enter_context(plan.writing(name)) for name in plan.names}
        write_json(tmps["metrics.json"], {
            "dataset": str(args.dataset), "alpha": alpha, "noise_floor": noise_floor,
            "models": {label: {"file": str(path), "training_data": label in trained_on, **reports[label].to_dict(),
                               "extrapolation": {what.split()[0]: e.to_dict() for what, e in beyond[label].items()}}
                       for label, path in zip(labels, args.models)}})
        note = (f"\n**Training data of {', '.join(trained_on)}**: these are training errors, not held-out ones.\n"
                if trained_on else "")
        outside = "".join(f"\n**Beyond the {what} {label} was calibrated on**: {e.words(AXIS_UNITS)}.\n"
                          for label, found in beyond.items() for what, e in found.items() if e.any)
        tmps["metrics.md"].write_text(f"# Evaluation on {args.dataset} (alpha = {alpha:.4g} 1/m)\n{note}{outside}\n"
                                      f"{table}\n\nRMSE per axis:\n\n{axes}\n")
        if not args.no_plots:
            console.info("plotting ...")
            paths = {"distribution": tmps[EVALUATION_PLOTS[0]], "axis": tmps[EVALUATION_PLOTS[1]]}
            paths.update({label: tmps[predicted_plot_name(label)] for label in labels})
            write_evaluation_plots(paths, data.wrench, predictions, alpha, noise_floor, dataset_name=str(args.dataset),
                                   axes=data.axes)
    print(f"{table}\n\n{axes}")
    console.info(f"results in {args.out}/")
    return 0


#: The unit of each wrench axis, for the extrapolation's words.
AXIS_UNITS = {"Fx": "N", "Fy": "N", "Fz": "N", "Tx": "N·m", "Ty": "N·m", "Tz": "N·m"}


def extrapolation(model, model_path, data) -> dict:
    """How far the dataset goes beyond what the model was calibrated on (:func:`ftcal.io.range_excess`): its loads
    beyond the calibration's wrench range per axis (``"loads"``, when the model file keeps that range), and its
    readings beyond the calibration's readings per channel (``"readings"``, as ``predict --range`` counts them)."""
    from ..calibrators import retare_shift
    from ..io import range_excess
    from ..reporting import model_inputs
    from ._data_options import channel_names, model_wrench_range

    found = {}
    loads = model_wrench_range(model_path, data.axes)
    if loads is not None:
        found["loads"] = range_excess(data.wrench, *loads, names=data.axes)
    own = getattr(model, "calibrated_range_", None)
    X = np.asarray(model_inputs(model, data), dtype=float)
    if own is not None and np.shape(own) == (2, X.shape[1]):
        shift = retare_shift(model, X.shape[1])
        names = channel_names(None, data.n_channels) + ["temperature"] * (X.shape[1] - data.n_channels)
        found["readings"] = range_excess(X, own[0] + shift, own[1] + shift, names=names)
    return found


def training_data_of(dataset, model_paths) -> list[str]:
    """Labels of the models whose ``NAME.fit.json`` (beside the model file) says they were fitted on ``dataset``."""
    from ..benchmark import read_json_record
    from ..core import same_file
    from ..reporting import file_sha256

    found, digest = [], None
    for path in model_paths:
        label = model_label(path)
        facts = read_json_record(Path(path).with_name(f"{label}.fit.json"))  # None: no fit.json to read
        if facts is None:
            continue
        if facts.get("dataset_sha256"):
            digest = digest or file_sha256(dataset)
            if facts["dataset_sha256"] == digest:
                found.append(label)
        elif isinstance(facts.get("dataset"), str) and same_file(facts["dataset"], dataset):
            found.append(label)
    return found
