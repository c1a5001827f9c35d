"""The bias drift on the command line: ``identify-load``'s drift options and report, ``compensate``'s times,
and ``ftcal retare`` of a tool file (the bias reset at the re-tare's time, the drift's rate kept)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ._common import CliError, Console, OutputPlan, finite_float, int_in_range, numbers
from ._data_options import add_fold_options, add_unit_options, check_lever_arm
from ._messages import cli_message

#: The choices of ``--drift`` (the library's ``DRIFT_CHOICES``; repeated here so that ``--help`` imports nothing).
DRIFT_CHOICES = ("auto", "none", "linear", "spline", "temperature")
#: Most no-load readings a tool re-tare reads (a few hundred are plenty).
MAX_RETARE_READINGS = 1_000_000
TOOL_SUFFIX = ".tool.json"


def add_drift_options(p: argparse.ArgumentParser, *, identify: bool = True) -> None:
    """``--time-from-order`` (both commands), ``--drift`` and ``--cv`` (identify-load: the leave-poses-out folds
    that choose the drift)."""
    g = p.add_argument_group("bias drift")
    if identify:
        g.add_argument("--drift", choices=DRIFT_CHOICES, default="auto",
                       help="auto: add a bias drift (linear or a spline in time, or in temperature when the inputs "
                       "carry one) when it lowers the held-out error (leave-poses-out CV, one-SE rule); none: a "
                       "constant bias; linear, spline, temperature: force that drift")
        add_fold_options(g, cv_default=20, folds=False)  # the poses are the groups the folds keep whole
    g.add_argument("--time-from-order", action="store_true",
                   help="the inputs carry no usable time: take each pose's position in the recording (row order) "
                   "as its time (the drift is then per pose, not per second)")


def identify(args: argparse.Namespace, rotations, wrenches, gravity, times, temperatures, sources: list[str],
             groups=None):
    """``identify_tool_load`` with the drift options, and the report of the identification (None without a time
    or temperature). Library errors name the inputs."""
    import numpy as np

    import ftcal
    from ftcal.core import CalibrationInputError
    from ftcal.experiment import identification_summary

    # the drift's time of each pose and its unit: the row order with --time-from-order, else the inputs' times [s]
    times, unit = (np.arange(len(rotations), dtype=float), "pose") if args.time_from_order else (times, "s")
    if args.drift in ("linear", "spline") and times is None:
        raise CliError(f"--drift {args.drift} needs the time of each pose: the inputs carry none; pass "
                       "--time-from-order to use the recording order")
    settings = dict(drift=args.drift, cv=args.cv, random_state=0, groups=groups)
    try:
        tool = ftcal.experiment.identify_tool_load(rotations, wrenches, gravity=gravity, times=times,
                                                   temperatures=temperatures, time_unit=unit,
                                                   mounting=getattr(args, "mounting", False),
                                                   declared_frame=getattr(args, "wrench_frame", "sensor"), **settings)
        report = None if times is None and temperatures is None else identification_summary(
            rotations, wrenches, tool, times=times, temperatures=temperatures, **settings)
    except CalibrationInputError as exc:
        raise CliError(f"{', '.join(sources[:3])}: {cli_message(exc, args)}") from None
    return tool, report


def report_names(stem: str) -> list[str]:
    """The files of the identification's report: JSON and its figure."""
    return [f"{stem}.identification.json", f"{stem}.identification.png"]


def write_report(plan: OutputPlan, stem: str, report: dict) -> None:
    from ftcal.reporting import plot_drift_residuals

    json_name, png_name = report_names(stem)
    plan.write_json(json_name, report)
    with plan.writing(png_name) as tmp:
        plot_drift_residuals(report, tmp)


def drift_summary(tool) -> str:
    """One line on the drift for the console ('' without a drift)."""
    d = tool.drift
    if d is None:
        return ""
    rate = d.rate_per_hour()
    f, se = (rate[0][:3], rate[1][:3]) if rate is not None else (d.mean_rate[:3], d.mean_rate_std_error[:3])
    per = "N/h" if rate is not None else "N/pose" if d.unit == "pose" else "N/deg C"
    return (f"; bias drift {d.description}, mean force rate [{', '.join(f'{v:.3g}±{s:.2g}' for v, s in zip(f, se))}] "
            f"{per}")


def compensate_rows(args: argparse.Namespace, tool, rotations, wrenches, values: dict):
    """The external wrenches of the inputs' rows (:meth:`ToolLoad.compensate` with each row's time [s] or
    temperature [deg C] of :func:`compensation_values`); a drift evaluated beyond the span it covers is one
    ``ftcal: warning:`` line naming the tool file."""
    import sys
    import warnings

    from ftcal.experiment import DriftExtrapolationWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", DriftExtrapolationWarning)
        external = tool.compensate(rotations, wrenches, **values)
    for w in caught:
        if issubclass(w.category, DriftExtrapolationWarning):
            print(f"ftcal: warning: {args.tool}: {w.message}", file=sys.stderr)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return external


def compensation_values(args: argparse.Namespace, tool, n: int, times, temperatures, source: str) -> dict:
    """``times`` / ``temperatures`` for :meth:`ToolLoad.compensate` from the inputs' rows (their times [s] or the
    row order, their temperatures)."""
    import numpy as np

    d = tool.drift
    if d is None:
        return {}
    if d.variable == "temperature":
        if temperatures is None:
            raise CliError(f"{source}: the tool's bias drifts with temperature ({d.description}) but the input has "
                           "no 'temperature' column")
        return {"temperatures": np.asarray(temperatures, dtype=float)}
    if d.unit == "pose":
        if not args.time_from_order:
            raise CliError(f"{args.tool}: the tool's bias drift was identified against the pose order "
                           "(--time-from-order); pass --time-from-order here too, or re-tare the tool at a known time")
        return {"times": np.arange(n, dtype=float)}
    if args.time_from_order:
        raise CliError(f"{args.tool}: the tool's bias drift is in seconds; --time-from-order does not apply (the "
                       "inputs' times are used)")
    if times is None:
        raise CliError(f"{source}: the tool's bias drifts with time ({d.description}) but the input has no times: "
                       "give a pose file with a 'time' column [s] (or run logs, or a bag)")
    return {"times": np.asarray(times, dtype=float)}


# ------------------------------------------------------------------------------------------- retare of a tool
RETARE_EXAMPLE = """\

re-taring a tool file:
  ftcal retare tool/tool.tool.json no_load.csv --orientation 0,0,0,1 --time 1764100000
  ftcal retare tool/tool.tool.json no_load_tool_off.csv --tool-off --time 1764100000

A tool file (of 'ftcal identify-load'): READINGS is a CSV of calibrated no-load wrenches, header
Fx,Fy,Fz,Tx,Ty,Tz (or Mx,My,Mz) in N, N·m or the --force-unit/--torque-unit given (sensor frame), optional
columns time [s] (or the pose order of a --time-from-order tool), temperature [deg C] and the sensor's
orientation in the base frame as in a pose file (qx,qy,qz,qw scalar last, or R00..R22, or roll,pitch,yaw). With the tool mounted (nothing touching it) the orientation is needed (columns or
--orientation) to remove its weight; with --tool-off the readings are the bias itself. The new tool file's
bias is their mean at the readings' time (--time, else the mean of the time column); a drift keeps its rate
from there on.
"""


def add_retare_tool_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("re-taring a tool file (MODEL is NAME.tool.json)")
    g.add_argument("--time", type=finite_float, metavar="T",
                   help="when the readings were taken (the drift's time unit), for a drifting tool")
    g.add_argument("--temperature", type=finite_float, metavar="DEG_C",
                   help="the sensor's temperature during the readings, for a tool whose bias drifts with temperature")
    g.add_argument("--orientation", metavar="QX,QY,QZ,QW",
                   help="the sensor's orientation (sensor to base, scalar last) while the readings were taken")
    g.add_argument("--tool-off", action="store_true", help="the tool was taken off: the readings are the bias")
    add_unit_options(g)


def _read_wrench_readings(args: argparse.Namespace):
    """The no-load readings of a tool re-tare, read by the pose-file reader (its layout, units and checks, the
    orientation optional): ``wrench`` (n, 6) [N, N·m] and, when the file has them, ``time``, ``temperature`` and
    ``rotation`` (n, 3, 3)."""
    from ftcal.core import LogFormatError
    from ftcal.io import read_pose_file

    force_unit, torque_unit = args.force_unit or "N", args.torque_unit or "N.m"
    try:
        rec = read_pose_file(args.readings, force_unit=force_unit, torque_unit=torque_unit,
                             orientation_required=False, repeated_times=True)
    except LogFormatError as exc:
        raise CliError(cli_message(exc, args)) from None
    if rec.wrench is None:
        raise CliError(f"{args.readings}: a tool re-tare reads calibrated wrenches, header Fx,Fy,Fz,Tx,Ty,Tz (or "
                       "Mx,My,Mz); the file holds raw channels: predict them with the sensor's model first")
    if rec.n_rows > MAX_RETARE_READINGS:
        raise CliError(f"{args.readings}: more than {MAX_RETARE_READINGS} readings; a few hundred quiet readings are "
                       "enough for a re-tare, pass fewer")
    if not args.tool_off:  # the tool's weight and the bias: a lever arm of a tool's size, unless the units are off
        check_lever_arm(args, rec.wrench, args.readings, force_unit=force_unit, torque_unit=torque_unit)
    return {k: v for k, v in (("wrench", rec.wrench), ("time", rec.time), ("temperature", rec.temperature),
                              ("rotation", rec.rotation)) if v is not None}


def run_retare_tool(args: argparse.Namespace, output: Path) -> int:
    """``ftcal retare TOOL.tool.json READINGS``: a new tool file (``output``) whose bias is reset at the readings'
    time."""
    import numpy as np
    from scipy.spatial.transform import Rotation

    import ftcal
    from ftcal.core import CalibrationInputError

    console = Console(args.quiet)
    plan = OutputPlan.single_file(output, args.force)
    if args.readings == "-":
        raise CliError("a tool re-tare reads its readings from a file, not stdin")
    tool = ftcal.experiment.ToolLoad.load(args.model)
    data = _read_wrench_readings(args)
    if args.tool_off and (args.orientation or "rotation" in data):
        raise CliError("--tool-off: the readings were taken without the tool, so no orientation is needed; drop "
                       "--orientation (or the orientation columns) or --tool-off")
    if args.orientation and "rotation" in data:
        raise CliError(f"--orientation: {args.readings} has its own orientation columns, one orientation per row; "
                       "give one or the other (drop --orientation to use the file's, or the file's orientation "
                       "columns to hold the sensor at --orientation)")
    rotations = data.get("rotation")  # none with --orientation (refused above)
    if args.orientation:
        quat = numbers(args.orientation, 4)
        if quat is None:
            raise CliError(f"--orientation {args.orientation!r}: give qx,qy,qz,qw, four comma-separated numbers")
        norm = float(np.linalg.norm(quat))
        if not np.isfinite(quat).all() or abs(norm - 1.0) > 1e-2:
            raise CliError(f"--orientation: quaternion {[float(v) for v in quat]} is not a unit quaternion (norm "
                           f"{norm:.4g}); give qx,qy,qz,qw of the sensor's orientation, scalar last")
        rotations = Rotation.from_quat(quat).as_matrix()
    elif rotations is None and not args.tool_off:
        raise CliError(f"{args.readings}: with the tool mounted its weight must be removed, which needs the sensor's "
                       "orientation: add qx,qy,qz,qw columns (or R00..R22, or roll,pitch,yaw) or --orientation "
                       "QX,QY,QZ,QW; or, if the tool was taken off, pass --tool-off")
    time, temperature = (given if given is not None else float(np.mean(data[key])) if key in data else None
                         for given, key in ((args.time, "time"), (args.temperature, "temperature")))
    try:
        new = tool.retare(data["wrench"], sensor_rotations=rotations, time=time, temperature=temperature,
                          max_spread=args.max_spread)
    except CalibrationInputError as exc:
        raise CliError(f"{args.readings}: {cli_message(exc, args)}") from None
    with plan.writing(output.name) as tmp:
        new.save(tmp, overwrite=True)
    before = tool.bias if tool.drift is None else tool.bias + tool.drift.offset([new.drift.reference], warn=False)[0]
    shift = new.bias - before
    at = "" if new.drift is None else f" at {new.drift.variable} {new.drift.reference:.6g} (drift rate kept)"
    console.info(f"re-tared from {len(data['wrench'])} readings{at}: bias moved by "
                 f"[{', '.join(f'{v:.4g}' for v in shift)}] N, N·m -> {output}")
    return 0
