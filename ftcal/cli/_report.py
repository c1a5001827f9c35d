"""``ftcal report``: the calibration report of a model on its data, one self-contained HTML page."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from ..core._exceptions import CalibrationInputError
from ._common import CliError, Console, OutputPlan, add_output_options, add_run_options, existing_file, int_in_range
from ._data_options import add_dataset_options, load_dataset_from_args

EXAMPLE = """\
examples:
  ftcal report models/linear.model.npz data/dataset.csv --out report
  ftcal report models/auto.model.npz data.mat --torque-unit N.mm --sensor "FT-1234" --tool tool/tool.tool.json
  chromium --headless --no-sandbox --print-to-pdf=report/linear.report.pdf report/linear.report.html

writes DIR/NAME.report.html (open it in any browser; no network needed, pictures inline) and
DIR/NAME.report.json (the same facts). Held-out accuracy per axis comes from grouped
cross-validation of the model's settings (whole groups held out when the dataset has a group
column), beside the stock scikit-learn baselines on the same folds: this refits the model K times.
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "report",
        help="the calibration report (HTML) of a model on its calibration data: held-out accuracy per axis",
        description="Write the calibration report of a model: held-out accuracy per axis in units and % of full "
        "scale, 95 % expanded uncertainty, model choice beside the stock scikit-learn baselines, calibrated range.",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=existing_file, help="model file written by 'ftcal fit'")
    p.add_argument("dataset", help="the calibration dataset the model was fitted on (.csv, .npz or .mat)")
    add_report_options(p)
    add_dataset_options(p)
    add_output_options(p, "ftcal-report")
    add_run_options(p)
    p.set_defaults(handler=run)


def add_report_options(p: argparse.ArgumentParser) -> None:
    """The options ``ftcal report`` shares with ``ftcal fit --report``."""
    g = p.add_argument_group("calibration report")
    g.add_argument("--cv", type=int_in_range(2, 50, "folds"), default=5, help="cross-validation folds of the report")
    g.add_argument("--no-baselines", action="store_true",
                   help="leave the stock scikit-learn baselines out of the report's model-choice table")
    g.add_argument("--sensor", help="sensor name / serial number shown in the report (default: dataset meta 'sensor')")
    g.add_argument("--tool", type=existing_file, help="tool file of 'ftcal identify-load' to show in the report")


def report_file_names(label: str) -> list[str]:
    return [f"{label}.report.html", f"{label}.report.json"]


def write_report(plan: OutputPlan, label: str, model, data, args: argparse.Namespace, model_path, dataset_path,
                 console: Console) -> None:
    """Compute the report of ``model`` on ``data`` and write its two planned files."""
    from ..evaluation._calibration_report import calibration_certificate, render_report_html, report_json

    tool = None
    if args.tool is not None:
        from ..experiment._tool_load import ToolLoad

        tool = ToolLoad.load(args.tool)
    console.info(f"report: cross-validating {type(model).__name__}"
                 f"{'' if args.no_baselines else ' and the stock baselines'} ({args.cv} folds) ...")
    try:
        report = calibration_certificate(model, data, model_path=model_path, dataset_path=dataset_path,
                                         sensor=args.sensor, cv=args.cv, baselines=not args.no_baselines, tool=tool,
                                         random_state=getattr(args, "seed", 0))
    except CalibrationInputError as exc:
        raise _fold_too_small(exc, data.n_samples, args.cv, dataset_path) or exc

    html_name, json_name = report_file_names(label)
    with plan.writing(html_name) as tmp:
        tmp.write_text(render_report_html(report), encoding="utf-8")
    with plan.writing(json_name) as tmp:
        tmp.write_text(report_json(report), encoding="utf-8")
    console.info(f"report -> {plan.path(html_name)}")


def _fold_too_small(exc: Exception, n_rows: int, cv: int, dataset_path) -> CliError | None:
    """The library's "X has 5 sample(s), but LinearCalibrator needs at least 7" said of a cross-validation fold:
    which file, how many folds, and how many rows the report needs (None for any other error)."""
    import math
    import re

    found = re.match(r"X has (\d+) sample\(s\), but (\w+) needs at least (\d+)", str(exc))
    if found is None or int(found.group(1)) >= n_rows:
        return None
    got, name, need = int(found.group(1)), found.group(2), int(found.group(3))

    def train_rows(n: int, k: int) -> int:  # the smallest training part of k folds of n rows (equal folds)
        return n - math.ceil(n / k)

    rows = next(n for n in range(need + 1, 100 * need + 100) if train_rows(n, cv) >= need)
    # more folds leave more rows to train on (each holds out n / k); at most n_rows folds (leave one out)
    more = next((k for k in range(cv + 1, min(n_rows, 50) + 1) if train_rows(n_rows, k) >= need), None)  # --cv <= 50
    fix = f"pass --cv {more} (more folds hold out fewer rows each), or record more rows" if more is not None \
        else "record more rows"
    return CliError(f"{dataset_path}: the report's {cv}-fold cross-validation of its {n_rows} rows trains {name} on "
                    f"only {got} rows (one fold held out), but {name} needs at least {need}; {cv} folds need a dataset of at least "
                    f"{rows} rows (more when whole groups are held out). Fix: {fix}")


def run(args: argparse.Namespace) -> int:
    from ._models import load_model_file, model_inputs, model_label

    console = Console(args.quiet)
    label = model_label(args.model)
    plan = OutputPlan(args.out, report_file_names(label), args.force)
    model = load_model_file(args.model)
    data = load_dataset_from_args(args, args.dataset, "calibration dataset")
    inputs = model_inputs(model, data)  # a dataset of another sensor is refused before the cross-validation starts
    fitted_range = getattr(model, "calibrated_range_", None)
    if fitted_range is not None and inputs.shape[1] == fitted_range.shape[1] and not np.allclose(
            [inputs.min(axis=0), inputs.max(axis=0)], fitted_range, rtol=1e-9, atol=0.0):
        print(f"ftcal: warning: {args.dataset} is not the data {args.model} was fitted on (its readings span "
              "another range); the report's held-out figures are of the model refitted on this dataset by "
              "cross-validation, and its calibrated range is this dataset's", file=sys.stderr)
    write_report(plan, label, model, data, args, args.model, args.dataset, console)
    return 0
