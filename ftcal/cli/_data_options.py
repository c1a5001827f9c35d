"""The options that say how to read a user's calibration data, defined once for every command that reads data.

Every command that reads data takes the same options, defined here once (one name, one meaning, one help text;
``tests/test_cli_shared_options.py`` walks every subcommand's parser to hold that):

* a calibration dataset (``fit``, ``evaluate``, ``report``, ``tune``, ``benchmark dataset``, ``plan --next``):
  :func:`add_dataset_options` -- ``--channels``, ``--wrench``, ``--axes``, ``--groups``, ``--force-unit``,
  ``--torque-unit`` and ``--exclude-saturated``;
* raw readings for a model (``predict``, ``retare``): ``--channels`` (:func:`add_channel_option`);
* wrenches (``identify-load``, ``compensate``, a tool's ``retare``): ``--force-unit``, ``--torque-unit``
  (:func:`add_unit_options`);
* cross-validation (``fit --report``, ``report``, ``tune``, ``benchmark dataset``, ``identify-load``'s drift):
  :func:`add_fold_options` -- ``--cv K`` and, where the split can be chosen, ``--folds auto|group|kfold``; the
  seed is ``--seed`` everywhere. Old spellings (``tune --group-folds``/``--random-folds``, ``identify-load
  --drift-cv``, ``prepare --channels N``) still work, hidden from ``--help``.

A model file keeps the mapping and units it was fitted with, and the commands that read data for a model
(``evaluate``, ``report``, ``predict``, ``retare``, ``plan --next``) apply them unless the options say otherwise.

The lever-arm check runs on every dataset whatever options are given: an implausibly long arm (torques in N·mm read
as N·m, or forces in kN read as N) is refused with the likely unit of the forces or of the torques, unless both units
are declared (``--force-unit N --torque-unit N.m`` confirms an unusual arm); an implausibly short one is pointed
out (a 3-axis cell's torque columns may hold noise alone).
"""

from __future__ import annotations

import argparse
import sys

from ._common import CliError, int_in_range
from ._messages import cli_error, cli_spelling

__all__ = ["add_dataset_options", "add_channel_option", "add_unit_options", "add_fold_options", "fold_groups", "DATASET_OPTIONS",
           "add_alpha_option", "training_targets",
           "check_lever_arm", "dataset_columns", "load_dataset_from_args", "stored_columns", "fit_data_facts", "model_reading", "load_dataset_for_models"]

_SPEC_HELP = ("a list of names (g1,g2,g3), a range (s0..s7) or a column slice of one array of a .mat/.npz "
              "(data[:,0:8])")


def _names(text: str) -> tuple[str, ...]:
    if "[" in text:  # a column slice holds a comma: data[:,0:8]
        return (text.strip(),)
    names = tuple(n.strip() for n in text.split(","))
    if not all(names):
        raise argparse.ArgumentTypeError(f"{text!r}: give comma-separated column names, e.g. s1,s2,s3, or a range "
                                         "s0..s7")
    return names


def _saturation(text: str):
    if text.strip() == "auto":
        return "auto"
    parts = text.split(",")
    try:
        low, high = (float(v) for v in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: give LOW,HIGH (the ADC's limits, e.g. 0,4095 or "
                                         "-32768,32767), or auto") from None
    if not (low < high) or low != low or high != high:
        raise argparse.ArgumentTypeError(f"{text!r}: LOW must be below HIGH, e.g. 0,4095")
    return low, high


#: The one help text of ``--channels``, on every command.
CHANNELS_HELP = (f"the raw-channel columns (or .mat/.npz variables) in channel order: {_SPEC_HELP} (default: the "
                 "mapping the model was fitted with, when a model reads the data; else s0,s1,... or the variable 'raw')")
#: The one help text of ``--cv`` and ``--folds``, on every command that cross-validates.
CV_HELP = ("cross-validation folds (at least 2): every row is held out once, whole groups (poses, sessions, files) "
           "together when the data have groups (default: %(default)s)")
FOLDS_HELP = ("how the rows are split into folds: auto: whole groups held out when the data have groups, else "
              "shuffled rows; group: whole groups (the data must have groups); kfold: shuffled rows even with groups "
              "(flatters flexible models: rows of one pose land on both sides of a split)")


def _add_channels(g) -> None:
    g.add_argument("--channels", type=_names, metavar="SPEC", help=CHANNELS_HELP)


def add_channel_option(p: argparse.ArgumentParser) -> None:
    """``--channels`` alone (``predict``, ``retare``: raw readings in, no wrench)."""
    _add_channels(p)


def add_fold_options(g, *, cv_default: int, folds: bool = True) -> None:
    """``--cv K`` (default ``cv_default``) and, with ``folds``, ``--folds auto|group|kfold`` (with the hidden old
    spellings ``--group-folds`` / ``--random-folds``): the same options on every command that cross-validates."""
    g.add_argument("--cv", type=int_in_range(2, 1000, "folds"), default=cv_default, metavar="K", help=CV_HELP)
    if folds:
        g.add_argument("--folds", choices=("auto", "group", "kfold"), default="auto", help=FOLDS_HELP)
        g.add_argument("--group-folds", dest="folds", action="store_const", const="group", help=argparse.SUPPRESS)
        g.add_argument("--random-folds", dest="folds", action="store_const", const="kfold", help=argparse.SUPPRESS)


def add_alpha_option(p) -> None:
    """``--alpha``: the torque scale of eq. 18, the same on every command that fits or scores on a dataset."""
    from ._common import positive_float

    p.add_argument("--alpha", type=positive_float, metavar="1/m",
                   help="torque scale Fmax/Tmax [1/m] that weighs torques against forces (eq. 18) (default: the "
                   "dataset's meta 'alpha', else from its wrenches over the axes that exist)")


def fold_groups(args: argparse.Namespace, data, path):
    """The groups the folds keep whole as ``--folds`` says (None: shuffled rows); ``group`` without groups is
    refused naming the file."""
    if args.folds == "group" and data.group is None:
        raise CliError(f"--folds group: {path} has no group column; name it with --groups COLUMN, or use "
                       "--folds kfold")
    return None if args.folds == "kfold" else data.group


def add_unit_options(g: argparse._ArgumentGroup) -> None:
    """``--force-unit`` and ``--torque-unit`` (unset: N and N·m, checked by the loads' lever arm)."""
    from ..io import FORCE_UNITS, TORQUE_UNITS

    g.add_argument("--force-unit", metavar="UNIT",
                   help=f"unit of the file's forces, converted to N, exact and case-sensitive (MN is not mN): "
                   f"{', '.join(FORCE_UNITS)}, any SI prefix of N or g (masses are read as their weight, g = 9.80665 "
                   "m/s^2) (default N)")
    g.add_argument("--torque-unit", metavar="UNIT",
                   help=f"unit of the file's torques, converted to N·m: {', '.join(TORQUE_UNITS)}, any force unit "
                   "times m, mm, cm, in or ft (default N.m)")


def check_lever_arm(args: argparse.Namespace, wrench, where, axes=None, force_unit: str = "N",
                    torque_unit: str = "N.m", confirmed: bool = False) -> None:
    """Refuse an implausibly long lever arm of ``wrench`` ([N, N·m] after conversion) naming the likely unit, unless
    both units were declared (or ``confirmed``); point out an implausibly short one on stderr."""
    from ..core import WRENCH_LABELS
    from ..io import PLAUSIBLE_LEVER_ARM_M, lever_arm_m, lever_arm_problem

    axes = WRENCH_LABELS if axes is None else axes
    problem = lever_arm_problem(wrench, torque_unit, axes, force_unit)
    if problem is None:
        return
    # too long an arm (torques in N·mm read as N·m, forces in kN read as N) is refused unless both units were
    # declared; too short a one (a 3-axis cell whose torque columns hold only noise) is only pointed out
    too_long = lever_arm_m(wrench, axes) > PLAUSIBLE_LEVER_ARM_M[1]
    declared = confirmed or (getattr(args, "torque_unit", None) is not None
                             and getattr(args, "force_unit", None) is not None)
    spell = cli_spelling(args)
    confirm = (f"if both really are right, confirm them with {spell('force_unit', force_unit)} "
               f"{spell('torque_unit', torque_unit)}")
    text = problem.render(spell, fix=f"{problem.render_fix(spell)}; {confirm}")
    if too_long and not declared:
        raise CliError(f"{where}: {text}")
    print(f"ftcal: warning: {where}: {text}", file=sys.stderr)


#: The destinations of :func:`add_dataset_options` (unset: None).
DATASET_OPTIONS = ("channels", "wrench", "axes", "groups", "force_unit", "torque_unit", "exclude_saturated")


def add_dataset_options(p: argparse.ArgumentParser) -> None:
    """``--channels``, ``--wrench``, ``--axes``, ``--groups``, ``--force-unit``, ``--torque-unit``,
    ``--exclude-saturated``."""
    g = p.add_argument_group("reading the dataset (.csv, .npz, .mat, or a folder of them: one file per pose)")
    _add_channels(g)
    g.add_argument("--wrench", type=_names, metavar="SPEC",
                   help=f"the wrench columns, any number of axes: {_SPEC_HELP}; e.g. Fx,Fy,Fz for a 3-axis load cell, "
                   "data[:,8:14] (default: every column named Fx..Tz, Mx.., force_x.., or the variable 'wrench')")
    g.add_argument("--axes", type=_names, metavar="AXIS,...",
                   help="the output axes of the wrench columns, in their order, when their names do not say: e.g. "
                   "Fz for a 1-axis cell, Fx,Fy,Fz (six unnamed columns are Fx,Fy,Fz,Tx,Ty,Tz)")
    g.add_argument("--groups", metavar="COLUMN",
                   help="the column holding each row's pose or session (integers or text), for grouped "
                   "cross-validation (default: 'group'); 'file' for a folder makes each file a group (the default "
                   "for a folder)")
    add_unit_options(g)
    g.add_argument("--exclude-saturated", type=_saturation, metavar="LOW,HIGH|auto",
                   help="drop the rows where a raw channel reaches LOW or HIGH (the ADC's limits), or, with auto, "
                   "where a channel sits at its extreme value in several rows (pinned: saturated); without it such "
                   "rows are pointed out")


def stored_columns(facts: dict | None, where: str):
    """The :class:`~ftcal.io.ColumnMap` a model file stored (``None`` for a file without one)."""
    from ..core import DatasetFileError
    from ..io import ColumnMap

    if not facts or not isinstance(facts, dict) or "columns" not in facts:
        return None
    try:
        return ColumnMap.from_dict(facts["columns"], where)
    except DatasetFileError as exc:
        raise cli_error(exc) from None


def dataset_columns(args: argparse.Namespace, stored=None):
    """The :class:`~ftcal.io.ColumnMap` of the options, each unset one taken from ``stored`` (a model's)."""
    from ..io import ColumnMap

    def pick(option: str, default):
        value = getattr(args, option, None)
        if value is not None:
            return value
        return getattr(stored, option) if stored is not None else default

    return ColumnMap(channels=pick("channels", None), wrench=pick("wrench", None), axes=pick("axes", None),
                     groups=pick("groups", None), force_unit=pick("force_unit", "N"),
                     torque_unit=pick("torque_unit", "N.m"))


def load_dataset_from_args(args: argparse.Namespace, path, role: str = "dataset", stored=None,
                           confirmed: bool = False):
    """The dataset at ``path`` read as the options (else ``stored``, a model's mapping) say, its units checked by the
    loads' lever arm, its saturated rows dropped or pointed out.

    ``confirmed``: the model's stored units were confirmed at fit time (both declared).
    """
    from ._models import load_dataset

    columns = dataset_columns(args, stored)
    data = load_dataset(path, role, columns=columns)
    check_lever_arm(args, data.wrench, path, data.axes, columns.force_unit, columns.torque_unit, confirmed)
    return _saturated_rows_handled(args, data, path)


def _saturated_rows_handled(args: argparse.Namespace, data, path):
    """The dataset without its saturated rows (``--exclude-saturated``), or with them pointed out in one line."""
    import numpy as np

    option = getattr(args, "exclude_saturated", None)
    quiet = getattr(args, "quiet", False)
    if isinstance(option, tuple):
        low, high = option
        drop = np.any((data.raw <= low) | (data.raw >= high), axis=1)
        said = f"a raw channel at or beyond {low:g} or {high:g}"
    else:
        drop, pinned = data.pinned_rows()
        said = f"a channel pinned at its extreme ({'; '.join(pinned[:3])}{'; ...' if len(pinned) > 3 else ''})"
        if option is None:
            if drop.any():
                print(f"ftcal: warning: {path}: {int(drop.sum())} of {data.n_samples} rows have {said}: saturated "
                      "readings? Fix: drop them with --exclude-saturated auto (or LOW,HIGH, the ADC's limits)",
                      file=sys.stderr)
            return data
    if not drop.any():
        if not quiet:
            print(f"ftcal: {path}: no rows with {said.split(' (')[0]}; none dropped", file=sys.stderr)
        return data
    if drop.all():
        raise CliError(f"{path}: --exclude-saturated would drop every one of the {data.n_samples} rows ({said}); "
                       "check the limits")
    kept = data.subset(~drop)
    if not quiet:
        print(f"ftcal: {path}: dropped {int(drop.sum())} of {data.n_samples} rows with {said}", file=sys.stderr)
    return kept


def training_targets(data):
    """The dataset's wrench as the calibrators take it: a table named by its axes when they are not the default
    ones of its width (a plate's Fz, Tx, Ty: its torques are scaled), else the array."""
    from ..core import default_axes, named_targets

    named = None if tuple(data.axes) == default_axes(len(data.axes)) else tuple(data.axes)
    return named_targets(data.wrench, named)


def fit_data_facts(args: argparse.Namespace, data) -> dict:
    """What a model file keeps of how its training data were read (``ftcal.save_model(..., data=...)``): the column
    mapping and units (so that ``predict``, ``evaluate``, ``report`` and ``retare`` read their data alike), the
    wrench axes, and whether both units were declared (an unusual lever arm confirmed)."""
    columns = dataset_columns(args)
    return {"columns": columns.to_dict(), "axes": list(data.axes), "n_channels": data.n_channels,
            "units_confirmed": getattr(args, "force_unit", None) is not None
            and getattr(args, "torque_unit", None) is not None}


def model_reading(model_path) -> tuple:
    """``(ColumnMap or None, axes or None, units confirmed)`` a model file keeps of its training data."""
    from ..core import ModelFileError
    from ..persistence import model_data

    try:
        facts = model_data(model_path)
    except ModelFileError as exc:
        raise cli_error(exc) from None
    axes = facts.get("axes")
    if axes is not None and not (isinstance(axes, list) and all(isinstance(a, str) for a in axes) and len(axes) <= 6):
        raise CliError(f"{model_path}: the stored wrench axes are damaged; fit the model again")
    return (stored_columns(facts, str(model_path)), None if axes is None else tuple(axes),
            bool(facts.get("units_confirmed", False)))


def load_dataset_for_models(args: argparse.Namespace, path, role: str, model_paths):
    """The dataset at ``path`` read as the models were fitted (their stored mapping and units, each option given
    overriding), refused when the models were fitted on differently read data or on other wrench axes."""
    readings = [model_reading(m) for m in model_paths]
    stored, _, confirmed = readings[0]
    for (other, _, _), m in zip(readings[1:], model_paths[1:]):
        if (other.to_dict() if other else None) != (stored.to_dict() if stored else None):
            raise CliError(f"{m} was fitted on data read with other columns or units than {model_paths[0]}; "
                           "evaluate them one at a time, or give the mapping with --channels/--wrench/--force-unit/"
                           "--torque-unit")
    data = load_dataset_from_args(args, path, role, stored=stored, confirmed=confirmed)
    for (_, axes, _), m in zip(readings, model_paths):
        if axes is not None and tuple(axes) != tuple(data.axes):
            raise CliError(f"{path}: the wrench axes read ({', '.join(data.axes)}) are not those {m} was fitted on "
                           f"({', '.join(axes)}); give the dataset of that sensor, or map its columns with --wrench")
    return data
