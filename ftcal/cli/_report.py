"""``ftcal report``: the calibration report of a model on its data, one self-contained HTML page."""

from __future__ import annotations

import argparse
import json
import re
import shlex
import sys
from pathlib import Path

import numpy as np

from ..core import CalibrationInputError, TooFewSamplesError
from ._common import CliError, Console, OutputPlan, add_jobs_option, existing_file, finish_command
from ._data_options import add_dataset_options, add_fold_options, load_dataset_for_models
from ._messages import cli_error, cli_message
from ._models import model_label

EXAMPLE = """\
examples:
  ftcal report models/linear.model.npz data/dataset.csv --out report
  ftcal report models/linear.model.npz data.csv --rated Fx=500,Fy=500,Fz=900,Tx=20,Ty=20,Tz=20 --spec 1%FS
  ftcal report models/auto.model.npz data.mat --torque-unit N.mm --sensor "FT-1234" --tool tool/tool.tool.json
  ftcal report m.model.npz data.csv --spec 1%FS,Fz=0.5%FS --operator "A. Tester" --recalibration-interval "12 months"
  ftcal report m.model.npz data.csv --reference-uncertainty 0.05% --spec 1%FS
  chromium --headless --no-sandbox --no-pdf-header-footer --print-to-pdf=report/linear.report.pdf report/linear.report.html

writes DIR/NAME.report.html (open it in any browser; no network needed, pictures inline; it prints to a
multi-page PDF with page numbers), DIR/NAME.report.json (the same facts) and DIR/NAME.report.csv (every
held-out load case, applied against indicated, worst first), as one set. The first page is the summary:
U95 per axis in % of full scale (the rated capacity of --rated, else the largest load of the data) from an
uncertainty budget in the GUM's form (held-out reproducibility, repeatability, resolution, the reference of
--reference-uncertainty; k from the Welch-Satterthwaite degrees of freedom), PASS or FAIL against --spec, the
comparison with the best stock model (paired standard error on the same folds), and warnings. Held-out
accuracy comes from ftcal's one fold plan (whole groups held out when the dataset has a group column), beside
the stock scikit-learn baselines on the same folds (a model that cannot be judged is listed as skipped). Conditions and traceability (reference standard, procedure, operator,
ambient temperature, recalibration interval) come from DATA.conditions.yaml / .json beside the dataset,
--conditions FILE, or the options below.
"""

#: Condition options of the report: option -> field of the conditions file.
CONDITION_OPTIONS = {"--reference-standard": "reference_standard", "--procedure": "procedure",
                     "--operator": "operator", "--calibration-date": "calibration_date",
                     "--ambient-temperature": "ambient_temperature",
                     "--recalibration-interval": "recalibration_interval"}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("report", epilog=EXAMPLE,
                       help="the calibration report (HTML) of a model on its calibration data: held-out accuracy per "
                       "axis", description="Write the calibration report of a model: a first-page summary with U95 "
                       "per axis in % of full scale and PASS/FAIL against a specification, the calibration matrix or "
                       "model identity, the held-out applied-vs-indicated table, model choice beside the stock "
                       "scikit-learn baselines, calibrated range.")
    p.add_argument("model", type=existing_file, help="model file written by 'ftcal fit'")
    p.add_argument("dataset", help="the calibration dataset the model was fitted on (.csv, .npz or .mat)")
    add_report_options(p)
    add_jobs_option(p, "processes that fit the stock baselines' folds at once (default: every core)")
    add_dataset_options(p)
    finish_command(p, run, "ftcal-report")


def add_report_options(p: argparse.ArgumentParser) -> None:
    """The options ``ftcal report`` shares with ``ftcal fit --report``."""
    g = p.add_argument_group("calibration report")
    add_fold_options(g, cv_default=5, folds=False)
    g.add_argument("--no-baselines", action="store_true",
                   help="leave the stock scikit-learn baselines out of the report's model-choice table")
    g.add_argument("--sensor", help="sensor name / serial number shown in the report (default: dataset meta 'sensor')")
    g.add_argument("--tool", type=existing_file, help="tool file of 'ftcal identify-load' to show in the report")
    g.add_argument("--rated", metavar="Fx=500,...|FILE",
                   help="rated capacity per axis in N and N.m (e.g. Fx=500,Fy=500,Fz=900,Tx=20,Ty=20,Tz=20), or a "
                   "sensor file (YAML/JSON) with a 'rated' mapping: every %%FS figure is against it (default: the "
                   "largest load of the data)")
    g.add_argument("--spec", metavar="1%FS|Fx=1%FS,...",
                   help="largest U95 allowed, in %% of full scale, for every axis (1%%FS) or per axis "
                   "(1%%FS,Fz=0.5%%FS): each axis PASSES or FAILS against it on the first page")
    g.add_argument("--reference-uncertainty", metavar="0.05%|Fx=0.1,...",
                   help="expanded uncertainty (k = 2) of the reference loads, as its certificate states it: relative "
                   "to the load (0.05%%) or absolute per axis in N and N.m (Fx=0.1,Fy=0.1,...); a component of the "
                   "report's uncertainty budget (also 'reference_uncertainty' in the conditions file)")
    g.add_argument("--conditions", type=existing_file, metavar="FILE",
                   help="YAML/JSON file of the calibration's conditions and traceability (reference_standard, "
                   "procedure, operator, calibration_date, ambient_temperature, recalibration_interval, "
                   "recalibration_due, location, notes; also sensor, rated, spec, reference_uncertainty); default DATA.conditions.yaml or "
                   ".json beside the dataset when present")
    for option, field in CONDITION_OPTIONS.items():
        g.add_argument(option, metavar="TEXT", help=f"{field.replace('_', ' ')} (overrides the conditions file)")


def report_file_names(label: str) -> list[str]:
    return [f"{label}.report.html", f"{label}.report.json", f"{label}.report.csv"]


def _read_mapping(path: Path, what: str) -> dict:
    """A small YAML or JSON file holding one mapping."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise CliError(f"{what} {path}: cannot be read ({getattr(exc, 'strerror', None) or exc})") from None
    if len(text) > 1_000_000:
        raise CliError(f"{what} {path}: {len(text)} characters; a conditions or sensor file is a few lines")
    if path.suffix.lower() == ".json":
        try:
            value = json.loads(text)
        except (json.JSONDecodeError, RecursionError) as exc:
            raise CliError(f"{what} {path}: not valid JSON ({exc})") from None
    else:
        try:
            import yaml
        except ImportError:
            raise CliError(f"{what} {path}: reading YAML needs PyYAML (pip install pyyaml); or write the file as "
                           ".json") from None
        try:
            value = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            where = f" line {mark.line + 1}" if mark is not None else ""
            raise CliError(f"{what} {path}{where}: not valid YAML ({getattr(exc, 'problem', None) or exc})") from None
        except RecursionError:
            raise CliError(f"{what} {path}: nested too deeply") from None
    if not isinstance(value, dict):
        raise CliError(f"{what} {path}: must hold a mapping of fields (field: value); got {type(value).__name__}")
    return value


def _axis_values(text_or_map, axes: list[str], option: str, percent: bool, zero_ok: bool = False) -> np.ndarray:
    """Per-axis values from ``Fx=500,Fy=...`` (or a mapping); with ``percent``, ``1%FS`` and a bare default."""
    from ..io import canonical_wrench_name

    def number(raw, where: str) -> float:
        t = str(raw).strip()
        if percent:
            t = re.sub(r"\s*%\s*(FS)?$", "", t, flags=re.IGNORECASE)
        try:
            value = float(t)
        except ValueError:
            value = float("nan")
        if not np.isfinite(value) or value < 0 or (value == 0 and not zero_ok):
            raise CliError(f"{option} {where}: {raw!r} is not a positive number"
                           + (" (write it as 1%FS or 1)" if percent else " (in N or N.m)"))
        return value

    if isinstance(text_or_map, dict):
        pairs, default = list(text_or_map.items()), None
    else:
        pairs, default = [], None
        for part in [p for p in str(text_or_map).split(",") if p.strip()]:
            if "=" in part:
                key, _, val = part.partition("=")
                pairs.append((key.strip(), val))
            elif percent and default is None:
                default = number(part, part.strip())
            else:
                raise CliError(f"{option} {text_or_map!r}: {part.strip()!r} names no axis; write AXIS=VALUE, e.g. "
                               + ("Fx=1%FS (or one value first for every axis: 1%FS,Fz=0.5%FS)" if percent
                                  else "Fx=500,Fy=500,Fz=900,Tx=20,Ty=20,Tz=20"))
    lookup = {a.lower(): a for a in axes}
    values: dict[str, float] = {}
    for key, val in pairs:
        name = lookup.get(str(key).strip().lower()) or lookup.get((canonical_wrench_name(str(key)) or "").lower())
        if name is None:
            raise CliError(f"{option}: axis {key!r} is not an output of this dataset; its axes are {', '.join(axes)}")
        if name in values:
            raise CliError(f"{option}: axis {name} is given twice")
        values[name] = number(val, f"{name}")
    missing = [a for a in axes if a not in values and default is None]
    if missing:
        raise CliError(f"{option}: no value for {', '.join(missing)}; give every axis of the dataset ("
                       + ", ".join(axes) + ")" + (", or one value first for all (1%FS)" if percent else ""))
    return np.array([values.get(a, default) for a in axes], dtype=float)


def prepare_report(args: argparse.Namespace, data, dataset_path) -> dict:
    """Every check of the report's options and files, before any work: the keyword arguments of
    :func:`~ftcal.reporting._calibration_report.calibration_certificate` (tool, rated, spec, conditions...)."""
    from ..reporting import CONDITION_FIELDS, check_conditions, dataset_axis_names

    axes = dataset_axis_names(data, data.wrench.shape[1])
    conditions_file = args.conditions
    if conditions_file is None and dataset_path is not None:  # DATA.conditions.yaml / .yml / .json beside it
        base = Path(dataset_path)
        conditions_file = next((c for c in (base.with_name(base.stem + suffix) for suffix in (
            ".conditions.yaml", ".conditions.yml", ".conditions.json")) if c.is_file()), None)
    fields = {} if conditions_file is None else _read_mapping(Path(conditions_file), "--conditions")
    sensor = args.sensor or fields.pop("sensor", None)
    rated_field, spec_field = fields.pop("rated", None), fields.pop("spec", None)
    reference_field = fields.pop("reference_uncertainty", None)
    unknown = sorted(set(fields) - set(CONDITION_FIELDS))
    if unknown:
        raise CliError(f"--conditions {conditions_file}: field {unknown[0]!r} is not known; the fields are "
                       f"{', '.join(CONDITION_FIELDS)}, sensor, rated, spec, reference_uncertainty")
    fields.update({field: getattr(args, field) for field in CONDITION_OPTIONS.values()
                   if getattr(args, field) is not None})
    try:
        conditions = check_conditions(fields)
    except CalibrationInputError as exc:
        raise cli_error(exc, args, f"--conditions {conditions_file}" if conditions_file else "") from None
    rated = None
    if args.rated is not None:
        if "=" not in args.rated and Path(args.rated).is_file():
            sensor_file = _read_mapping(Path(args.rated), "--rated")
            if "rated" not in sensor_file:
                raise CliError(f"--rated {args.rated}: the sensor file holds no 'rated' mapping (rated: {{Fx: 500, "
                               "...}})")
            rated = _axis_values(sensor_file["rated"], axes, f"--rated {args.rated}", percent=False)
            sensor = sensor or sensor_file.get("sensor")
        else:
            rated = _axis_values(args.rated, axes, "--rated", percent=False)
    elif rated_field is not None:
        rated = _axis_values(rated_field, axes, f"--conditions {conditions_file}: rated", percent=False)
    spec = _axis_values(args.spec, axes, "--spec", percent=True) if args.spec is not None else None \
        if spec_field is None else _axis_values(spec_field if isinstance(spec_field, dict) else str(spec_field), axes,
                                                f"--conditions {conditions_file}: spec", percent=True)
    tool = None
    if args.tool is not None:
        from ..experiment import ToolLoad

        try:
            tool = ToolLoad.load(args.tool)
        except CalibrationInputError as exc:
            raise CliError(f"--tool {cli_message(exc, args)}") from None
    reference = _reference(args.reference_uncertainty, "--reference-uncertainty", axes) \
        if args.reference_uncertainty is not None else None if reference_field is None else \
        _reference(reference_field, f"--conditions {conditions_file}: reference_uncertainty", axes)
    return {"tool": tool, "rated": rated, "spec": spec, "conditions": conditions,
            "sensor": None if sensor is None else str(sensor), **(reference or {})}


def _reference(value, option: str, axes: list[str]) -> dict:
    """``0.05%`` (relative) or ``Fx=0.1,...`` / a mapping (absolute per axis) -> the certificate's keyword."""
    text = str(value).strip() if not isinstance(value, dict) else None
    if text is not None and "=" not in text:
        if not text.endswith("%"):
            raise CliError(f"{option} {text!r}: give it relative to the load (0.05%) or per axis (Fx=0.1,...)")
        try:
            relative = float(text[:-1]) / 100
        except ValueError:
            relative = float("nan")
        if not (np.isfinite(relative) and 0 <= relative < 1):  # 0%: an ideal reference
            raise CliError(f"{option} {text!r}: not a percentage from 0 up to below 100 (e.g. 0.05%)")
        return {"reference_relative": relative}
    return {"reference_uncertainty": _axis_values(value, axes, option, percent=False, zero_ok=True)}


def report_options(args: argparse.Namespace, settings: dict, *, dataset_path, dataset_sha256: str | None,
                   console: Console) -> dict:
    """The keyword arguments of :func:`~ftcal.reporting.calibration_certificate` these options ask for (the
    model's file and hash are filled in by :func:`write_report`); says that the cross-validation starts."""
    console.info(f"report: cross-validating ({args.cv} folds"
                 f"{'' if args.no_baselines else ', with the stock baselines'}) ...")
    return dict(dataset_path=dataset_path, dataset_sha256=dataset_sha256, baselines=not args.no_baselines,
                n_jobs=getattr(args, "jobs", None) or -1, command=" ".join(shlex.quote(a) for a in sys.argv),
                **settings)


def write_report(out: OutputPlan, label: str, cert, *, model_path, model_sha256: str, console: Console) -> None:
    """Write the three planned files of the certificate ``cert`` of the model at ``model_path`` with ``out``
    (within its :meth:`~ftcal.cli._common.OutputPlan.as_one_set`: nothing is in place before the set is)."""
    cert.identity["model"].update(file=Path(model_path).name, path=str(model_path), sha256=model_sha256)
    html_name, json_name, csv_name = report_file_names(label)
    for file_name, text in ((html_name, cert.to_html()), (json_name, cert.to_json()), (csv_name, cert.to_csv())):
        out.write_text(file_name, text)
    verdict = cert.verdict
    console.info(f"report -> {out.path(html_name)}" + (f" ({verdict} against --spec)" if verdict else ""))


def _fold_too_small(exc: TooFewSamplesError, n_rows: int, cv: int, dataset_path) -> CliError | None:
    """The library's "X has 5 sample(s), but LinearCalibrator needs at least 7" (its fields: the rows, the estimator,
    the rows it needs) said of a cross-validation fold: which file, how many folds, and how many rows the report
    needs (None when the whole dataset was too small, not a fold)."""
    import math

    if exc.needed is None or not isinstance(exc.value, int) or exc.value >= n_rows:
        return None
    got, name, need = exc.value, exc.estimator, exc.needed

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
    import ftcal
    from ..reporting import bytes_sha256, calibration_certificate, file_sha256, model_inputs

    console = Console(args.quiet)
    label = model_label(args.model)
    plan = OutputPlan(args.out, report_file_names(label), args.force)
    model_bytes = Path(args.model).read_bytes()  # hashed as read, before it is loaded (not re-read later)
    model = ftcal.load_model(args.model)
    if bytes_sha256(Path(args.model).read_bytes()) != bytes_sha256(model_bytes):
        raise CliError(f"{args.model} changed while it was being read; run the report again")
    dataset_sha256 = file_sha256(args.dataset)
    data = load_dataset_for_models(args, args.dataset, "calibration dataset", [args.model])  # as it was fitted
    inputs = model_inputs(model, data)  # a dataset of another sensor is refused before the cross-validation starts
    settings = prepare_report(args, data, args.dataset)
    fitted_range = getattr(model, "calibrated_range_", None)
    if fitted_range is not None and inputs.shape[1] == fitted_range.shape[1] and not np.allclose(
            [inputs.min(axis=0), inputs.max(axis=0)], fitted_range, rtol=1e-9, atol=0.0):
        print(f"ftcal: warning: {args.dataset} is not the data {args.model} was fitted on (its readings span "
              "another range); the report's held-out figures are of the model refitted on this dataset by "
              "cross-validation, and its calibrated range is this dataset's", file=sys.stderr)
    options = report_options(args, settings, dataset_path=args.dataset, dataset_sha256=dataset_sha256, console=console)
    try:
        cert = calibration_certificate(model, data, cv=args.cv, random_state=getattr(args, "seed", 0), **options)
    except TooFewSamplesError as exc:
        raise _fold_too_small(exc, data.n_samples, args.cv, args.dataset) or exc
    with plan.as_one_set():
        write_report(plan, label, cert, model_path=args.model, model_sha256=bytes_sha256(model_bytes),
                     console=console)
    return 0
