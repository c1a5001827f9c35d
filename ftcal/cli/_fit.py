"""``ftcal fit``: train a calibrator from the registry on a dataset and save the model file."""

from __future__ import annotations

import argparse
import contextlib
import logging
import threading
import time

import numpy as np

from ._common import CliError, Console, OutputPlan, add_jobs_option, add_name_option, finish_command
from ._data_options import add_alpha_option, add_dataset_options, fit_data_facts, load_dataset_from_args
from ._models import calibrator_params, model_file_name, parse_param
from ._messages import cli_error
from ._report import (_fold_too_small, add_report_options, prepare_report, report_file_names, report_options,
                      write_report)
from ._training import fit_with_progress, ticking

EXAMPLE = """\
examples:
  ftcal fit data/train.csv --model directional --out models
  ftcal fit data/train.csv --model comparative --schedule short --seed 3 --out models
  ftcal fit real.csv --model linear --param ridge=1e-6 --tare 0.12,-0.3,0.05,0.2,0.01,-0.07 --out models
  ftcal fit data/train.csv --model directional --param phase1_epochs=300 --param hidden_layer_sizes=[64,64]
  ftcal fit recording.mat --torque-unit N.mm --model linear --report --out models
  ftcal fit log.csv --channels g1,g2,g3,g4,g5,g6 --wrench Fx,Fy,Fz,Mx,My,Mz --model linear --out models

writes DIR/NAME.model.npz (the model) and DIR/NAME.fit.json (what was trained, on what, how long);
with --report also DIR/NAME.report.html / .json, the calibration report (see 'ftcal report --help').
"""


def register(sub: argparse._SubParsersAction) -> None:
    from ..compose import CALIBRATOR_NAMES

    p = sub.add_parser("fit", help="train a calibrator on a dataset and save the model file", epilog=EXAMPLE,
                       description="Train a calibrator on a calibration dataset (.csv, .npz, .mat, or a folder of "
                       "them) and save it as a model file.")
    p.add_argument("dataset", help="training dataset (.csv, .npz, .mat, or a folder of them: one file per pose or "
                   "session), e.g. as written by 'ftcal simulate' / 'prepare'")
    p.add_argument("-m", "--model", default="directional", choices=tuple(CALIBRATOR_NAMES), help="calibrator")
    p.add_argument("--schedule", choices=("thesis", "short"),
                   help="training schedule of the networks: the thesis' (1700+ epochs; the default for a network "
                   "model) or a short one (minutes; the default for --model auto, whose networks are candidates "
                   "trained once per fold)")
    p.add_argument("--param", action="append", type=parse_param, default=[], metavar="KEY=VALUE",
                   help="a calibrator parameter, value read as JSON (repeatable), e.g. phase1_epochs=200")
    add_alpha_option(p)
    p.add_argument("--tare", metavar="V0,V1,...",
                   help="known zero-load raw reading, one value per channel (default: estimated from the data)")
    p.add_argument("--temperature", action="store_true",
                   help="compensate thermal drift: learn per-channel offset and gain coefficients from the dataset's "
                   "temperature column [deg C] in front of the calibrator")
    p.add_argument("--history", action="store_true",
                   help="add a load-history term (soft or viscoelastic sensors that creep or show hysteresis): the "
                   "rows must be in time order, at the sampling rate of use (the time constant is counted in rows); "
                   "it is chosen by cross-validation, or no term when it does not pay (see HistoryCalibrator); "
                   "'ftcal predict' then reads its input as one stream in time order")
    add_jobs_option(p, "processes that score --model auto's candidates at once (default: every core; the choice is "
                    "the same for any value)")
    add_name_option(p, "the model (default: the --model name)")
    p.add_argument("--report", action="store_true",
                   help="also write the calibration report (NAME.report.html): held-out accuracy per axis by grouped "
                   "cross-validation beside the stock baselines (refits the model --cv times)")
    add_report_options(p)
    add_dataset_options(p)
    finish_command(p, run, "ftcal-models")


def _parse_tare(text: str | None) -> np.ndarray | None:
    if text is None:
        return None
    try:
        values = np.array([float(v) for v in text.replace(" ", "").split(",") if v], dtype=float)
    except ValueError:
        raise CliError(f"--tare {text!r}: give comma-separated numbers, one per raw channel") from None
    if values.size == 0 or not np.all(np.isfinite(values)):
        raise CliError(f"--tare {text!r}: give finite comma-separated numbers, one per raw channel")
    return values


def _rmse_text(rmse: float, axes, alpha: float) -> str:
    """The training RMSE with its unit and scaling: torque-scaled [N] only when the wrench has forces and torques.

    Examples
    --------
    >>> _rmse_text(0.5, ("Fx", "Fy", "Fz"), 1.0)
    '0.5 N (forces only: no torque scaling)'
    >>> _rmse_text(0.5, ("Fx", "Fy", "Fz", "Tx", "Ty", "Tz"), 50.0)
    '0.5 N (torque-scaled, alpha=50)'
    """
    from ..core import force_columns, torque_columns

    if torque_columns(axes) and (force_columns(axes) or alpha != 1.0):
        return f"{rmse:.4g} N (torque-scaled, alpha={alpha:.4g})"
    if torque_columns(axes):
        return f"{rmse:.4g} N·m (torques only: no torque scaling)"
    return f"{rmse:.4g} N (forces only: no torque scaling)"


#: Longest silence [s] of a long fit before a heartbeat line says it is still working.
HEARTBEAT_SECONDS = 10.0


def _json_comparison(comparison):
    """A comparison as JSON columns (:meth:`~ftcal.model_selection.Comparison.to_dict`), a dict as it is."""
    return comparison.to_dict() if hasattr(comparison, "to_dict") else comparison


class _ProgressLines(logging.Handler):
    """Prints each finished row of a comparison (the ``compare:`` records of the ``ftcal`` logger) as one line."""

    def __init__(self, console: Console, said) -> None:
        super().__init__(logging.INFO)
        self.console, self.said = console, said

    def emit(self, record: logging.LogRecord) -> None:
        message = record.getMessage()
        if message.startswith("compare: "):
            self.console.info("  " + message[len("compare: "):])
            self.said()


@contextlib.contextmanager
def comparison_progress(console: Console, label: str, every: float = HEARTBEAT_SECONDS):
    """While a model chooses among candidates: each candidate's line as it finishes (name, held-out RMSE ± SE,
    seconds; through :mod:`logging`), and a heartbeat line whenever nothing was said for ``every`` seconds. Silent
    with ``--quiet``."""
    if console.quiet:
        yield
        return
    start = time.perf_counter()
    last = [start]
    lock = threading.Lock()

    def said() -> None:
        with lock:
            last[0] = time.perf_counter()

    logger = logging.getLogger("ftcal")
    handler, level = _ProgressLines(console, said), logger.level
    logger.addHandler(handler)
    if logger.getEffectiveLevel() > logging.INFO:
        logger.setLevel(logging.INFO)

    def beat() -> None:
        now = time.perf_counter()
        with lock:
            quiet_for = now - last[0]
        if quiet_for >= every:
            console.info(f"  ... {label} still fitting ({now - start:.0f} s so far)")
            said()

    try:
        with ticking(beat, "ftcal-heartbeat"):
            yield
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)


def run(args: argparse.Namespace) -> int:
    import ftcal
    from ftcal.calibrators import calibration_tags

    from ..core import TooFewSamplesError
    from ..model_selection import DegenerateCalibrationError
    from ..reporting import file_sha256
    from ..workflow import calibrate

    console = Console(args.quiet)
    name = args.name or args.model

    # the report files are planned without --report too: a forced refit removes an earlier fit's report with the
    # set (it would certify the replaced model, and 'predict --range' would read its range), never keeps it beside
    names = [model_file_name(name), f"{name}.fit.json"] + report_file_names(name)
    plan = OutputPlan(args.out, names, args.force)
    tare = _parse_tare(args.tare)
    report_given = [o for o, given in (("--tool", args.tool), ("--rated", args.rated), ("--spec", args.spec),
                                       ("--conditions", args.conditions), ("--no-baselines", args.no_baselines))
                    if given]
    if report_given and not args.report:
        raise CliError(f"{report_given[0]} is an option of the report; add --report (or drop {report_given[0]})")
    data = load_dataset_from_args(args, args.dataset, "training dataset")
    dataset_sha256 = file_sha256(args.dataset)  # the identity of the data, taken once (fit.json and report agree)
    settings = prepare_report(args, data, args.dataset) if args.report else None  # every check before any work
    if tare is not None and tare.size != data.n_channels:
        raise CliError(f"--tare has {tare.size} values but {args.dataset} has {data.n_channels} raw channels")
    params = calibrator_params(args, data)
    if tare is not None:
        params["zero_reading"] = tare
    known = ftcal.compose.calibrator_parameters(args.model)
    if args.jobs is not None and "n_jobs" not in known and not args.report:
        raise CliError(f"--jobs: {args.model} scores no candidates in parallel (only --model auto does, and the "
                       "report's stock baselines with --report); drop --jobs")
    # auto scores its candidates on every core unless --jobs says, on the folds its report shows
    params.update({k: v for k, v in (("n_jobs", args.jobs or -1), ("cv", args.cv)) if k in known and k not in params})
    unknown = sorted(set(params) - set(known))
    if unknown:
        raise CliError(f"--param {unknown[0]}: {args.model} has no such parameter; known: {', '.join(sorted(known))}")
    if params.get("group_offsets") and data.group is None:
        raise CliError(f"--param group_offsets=true needs one group (pose, session) per row, and {args.dataset} has "
                       "no group column; add one, or drop the parameter")
    if args.schedule is None:
        args.schedule = "short" if args.model == "auto" else "thesis"
    estimator = ftcal.make_calibrator(args.model, schedule=args.schedule, random_state=args.seed, **params)
    X = data.raw
    if args.history and args.temperature:
        raise CliError("--history and --temperature cannot be combined (the history term would see the temperature "
                       "column as a channel); drop one of them")
    if args.temperature:
        if data.temperature is None:
            raise CliError(f"--temperature: {args.dataset} has no temperature column; record the sensor "
                           "temperature (deg C) with the data, or drop the option")
        X = data.features(temperature=True)
    # a wrapper hands its own alpha / tare / seed to the inner calibrator: give them to the wrapper
    wrapped = dict(alpha=params.get("alpha"), zero_reading=params.get("zero_reading"), random_state=args.seed)
    for given, wrapper in ((args.temperature, ftcal.TemperatureCompensatedCalibrator),
                           (args.history, ftcal.HistoryCalibrator)):
        estimator = wrapper(estimator, **wrapped) if given else estimator
    schedule = f" ({args.schedule} schedule)" if ftcal.compose.training_schedule(args.schedule, args.model) else ""
    console.info(f"fitting {args.model}{schedule} on {data.n_samples} samples x {data.n_channels} channels")
    start = time.perf_counter()
    chooses = calibration_tags(estimator).chooses_model  # auto, or a wrapper (history) around it
    # the library's workflow fits and gates (never ship a calibration no better than the mean wrench): every model
    # judged on its held-out predictions of the one fold plan, with or without --report, before any file is written
    with comparison_progress(console, args.model) if chooses else contextlib.nullcontext():
        try:
            # with --report the certificate is made here and the gate judges its held-out predictions (one refit
            # per fold); its model file and hash are filled in when the model is written
            result = calibrate(data, estimator, cv=args.cv, random_state=args.seed,
                               certify=bool(args.report), certificate_options=report_options(
                                   args, settings, dataset_path=args.dataset, dataset_sha256=dataset_sha256,
                                   console=console) if args.report else None,
                               fit=None if chooses else lambda est, X_, y_, **kw: fit_with_progress(
                                   est, X_, y_, console, label=args.model, **kw))
        except DegenerateCalibrationError as exc:
            raise cli_error(exc, args, str(args.dataset)) from None
        except TooFewSamplesError as exc:
            raise _fold_too_small(exc, data.n_samples, args.cv, args.dataset) or exc
    seconds = time.perf_counter() - start
    report = ftcal.core.calibration_metrics(data.wrench, estimator.predict(X), alpha=estimator.alpha_, axes=data.axes)
    summary = {"model": args.model, "schedule": args.schedule, "temperature_compensation": bool(args.temperature),
               "history": bool(args.history), "seed": args.seed,
               "params": {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in params.items()},
               "dataset": str(args.dataset),
               "dataset_sha256": dataset_sha256,  # lets 'ftcal evaluate' tell training data from held-out data
               "n_samples": data.n_samples, "n_channels": data.n_channels, "alpha": estimator.alpha_,
               "fit_seconds": round(seconds, 3), "training_rmse": report.rmse, "training_report": report.to_dict()}
    if args.history:
        taus = [float(t) for t in np.ravel(estimator.taus)]
        summary["history_tau_rows"] = estimator.tau_rows_
        summary["history_cv_rmse"] = {"none": estimator.cv_rmse_[0],  # held-out RMSE (eq. 18) of each candidate
                                      **{f"tau={t:g}": v for t, v in zip(taus, estimator.cv_rmse_[1:])}}
        if estimator.static_choice_ is not None:
            summary["chosen"], summary["cv_results"] = estimator.static_choice_, _json_comparison(
                estimator.static_cv_results_)
            console.info(f"auto chose {estimator.static_choice_} (the static model, before the history term)")
        kept = "no history term" if estimator.tau_rows_ is None else f"a history term, tau = {estimator.tau_rows_:g} rows"
        console.info(f"history: {kept} (cross-validated RMSE (eq. 18) without: {estimator.cv_rmse_[0]:.4g} N, with the "
                     f"best time constant: {estimator.cv_rmse_[1:].min():.4g} N, the best of {len(taus)} tried, so "
                     "slightly optimistic; --report gives a held-out figure)")
    if getattr(estimator, "comparison_", None) is not None:  # auto itself (not a wrapper): its whole comparison
        summary["chosen"] = estimator.best_name_
        summary["cv_results"] = _json_comparison(estimator.comparison_)
        summary["fold_plan"] = estimator.comparison_.facts
        console.info(f"auto chose {estimator.best_name_}:\n{estimator.summary()}")
    # every output of this run is written to its own temporary file and put in place as one set at the end: a
    # failing report (or a full disk) leaves nothing behind, and the hashes are of the bytes this run wrote
    with plan.as_one_set() as files:
        with plan.writing(model_file_name(name)) as tmp:
            ftcal.save_model(estimator, tmp, overwrite=True, data=fit_data_facts(args, data))
        summary["model_sha256"] = files.sha256(plan.path(model_file_name(name)))
        plan.write_json(f"{name}.fit.json", summary)
        if args.report:
            write_report(plan, name, result.certificate, model_path=plan.out_dir / model_file_name(name),
                         model_sha256=summary["model_sha256"], console=console)
        else:
            plan.leaving_out(*report_file_names(name))
    console.info(f"done in {seconds:.1f} s: training RMSE {_rmse_text(report.rmse, data.axes, estimator.alpha_)}; "
                 f"model -> {plan.path(model_file_name(name))}")
    return 0
