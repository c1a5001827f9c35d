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
  seed is ``--seed`` everywhere.

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

from ._common import CliError, int_in_range, path_problem, positive_float
from ._messages import cli_error, cli_spelling

__all__ = ["add_dataset_options", "add_channel_option", "add_columns_option", "named_inputs", "readings_input", "joined_origin",
           "bad_readings_handled", "print_reading_findings", "channel_names", "add_unit_options", "add_fold_options",
           "fold_groups", "DATASET_OPTIONS", "add_alpha_option", "training_targets", "check_lever_arm",
           "dataset_columns", "load_dataset_from_args", "fit_data_facts", "model_wrench_range", "model_reading",
           "load_dataset_for_models"]

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


#: What ``--drop-bad-readings auto`` drops: single readings no sensor gave and rows written twice (a stuck channel
#: spoils a whole group: dropped only when named, or with ``all``).
AUTO_DROPPED = ("out_of_range", "spike", "repeated")
_CHECKED_KINDS = ("out_of_range", "spike", "stuck", "repeated")


def _bad_readings(text: str) -> tuple[str, ...]:
    """``--drop-bad-readings``: none, auto, all, or a comma-separated list of kinds."""
    word = text.strip()
    named = {"none": (), "auto": AUTO_DROPPED, "all": _CHECKED_KINDS}
    if word in named:
        return named[word]
    kinds = tuple(k.strip() for k in word.split(","))
    unknown = [k for k in kinds if k not in _CHECKED_KINDS]
    if unknown or not kinds:
        raise argparse.ArgumentTypeError(f"{text!r}: give none, auto ({','.join(AUTO_DROPPED)}), all, or kinds "
                                         f"among {','.join(_CHECKED_KINDS)}")
    return kinds


def _saturation(text: str):
    if text.strip() == "auto":
        return "auto"
    try:
        low, high = (float(v) for v in text.split(","))
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
    """``--channels`` alone (``predict``, ``retare``: raw readings in, no wrench), and ``--columns``."""
    _add_channels(p)
    add_columns_option(p)


#: The one help text of ``--columns``.
COLUMNS_HELP = ("the names of the columns of input files without a header line, in order (a range s0..s5 counts); "
                "several such inputs of one row per sample are joined side by side in the order given, e.g. "
                "pose.txt wrench.txt --columns x,y,z,qx,qy,qz,qw,Fx,Fy,Fz,Tx,Ty,Tz")


def add_columns_option(g) -> None:
    """``--columns NAMES`` (once per command, whichever option group asks first)."""
    if "--columns" in getattr(g, "_option_string_actions", {}):
        return
    g.add_argument("--columns", type=_names, metavar="NAME,...", help=COLUMNS_HELP)


#: The joined file behind each input path :func:`named_inputs` made -> its table (where its rows came from).
_JOINED: dict[str, object] = {}


def named_inputs(args: argparse.Namespace, items: list[str], *, header_needed: bool = True) -> list[str]:
    """The inputs as the commands read them: with ``--columns``, the headerless text files ``items`` joined side by
    side into one file with a header (:func:`ftcal.io.join_headerless`, written to a temporary folder removed at
    exit); without it, ``items`` themselves, a headerless text file refused in one line naming ``--columns`` when
    ``header_needed`` (a raw-readings input reads without a header)."""
    import atexit
    import shutil
    import tempfile
    from pathlib import Path

    from ..core import DatasetFileError
    from ..io import has_header, join_headerless

    columns = getattr(args, "columns", None)
    texts = [i for i in items if i != "-" and Path(i).is_file()
             and Path(i).suffix.lower() not in (".npz", ".mat", ".bag", ".mcap", ".db3", ".json")]
    try:
        if columns is None:
            if header_needed:
                for item in texts:
                    if not has_header(item):
                        raise CliError(f"{item}: the file has no header line (its first line holds numbers). Fix: "
                                       "name its columns with --columns NAME,... (e.g. --columns x,y,z,qx,qy,qz,qw,"
                                       "Fx,Fy,Fz,Tx,Ty,Tz; several such files are joined side by side), or add a "
                                       "header line")
            return items
        if len(texts) != len(items):
            other = next(i for i in items if i not in texts)
            raise CliError(f"--columns names the columns of text files without a header; {other} is not one (give "
                           "text files only, or drop --columns)")
        table = join_headerless(texts, columns)
    except DatasetFileError as exc:
        raise cli_error(exc, args) from None
    folder = Path(tempfile.mkdtemp(prefix="ftcal-columns-"))
    atexit.register(shutil.rmtree, folder, True)
    joined = folder / f"{table.name}.csv"
    table.write(joined)
    _JOINED[str(joined)] = table
    return [str(joined)]


def readings_input(args: argparse.Namespace, item: str, what: str) -> str:
    """The raw-readings input ``item`` as the commands read it (:func:`named_inputs`, no header needed): a file, a
    stream (``-``, a pipe) or the join of headerless files; one that cannot be read is refused, saying ``what`` it
    holds."""
    read = named_inputs(args, [item], header_needed=False)[0]
    problem = None if read == "-" else path_problem(read, streams=True)
    if problem is not None:
        raise CliError(f"{problem} ({what})")
    return read


def joined_origin(path: str, lines):
    """``(name, lines)``: the user's file(s) and lines of rows read from ``path`` at the 1-based ``lines``, when
    :func:`named_inputs` joined ``path`` (its line 1 the header ``--columns`` gave); else ``(file name, lines)``."""
    import numpy as np
    from pathlib import Path

    table = _JOINED.get(str(path))
    if table is None:
        return Path(path).name, np.asarray(lines)
    return table.name, np.asarray(table.lines)[np.asarray(lines) - 2]


def _sources_of_joined(data, path: str):
    """A dataset read from a file :func:`named_inputs` joined: its rows named by the user's files and lines."""
    from ..io import RowSources

    table = _JOINED.get(str(path))
    if table is not None and data.sources is not None and data.n_samples == len(table.lines):
        data.sources = RowSources.of_file(table.name, table.lines)
    return data


def add_fold_options(g, *, cv_default: int, folds: bool = True) -> None:
    """``--cv K`` (default ``cv_default``) and, with ``folds``, ``--folds auto|group|kfold``: the same options on
    every command that cross-validates."""
    g.add_argument("--cv", type=int_in_range(2, 1000, "folds"), default=cv_default, metavar="K", help=CV_HELP)
    if folds:
        g.add_argument("--folds", choices=("auto", "group", "kfold"), default="auto", help=FOLDS_HELP)


def add_alpha_option(p) -> None:
    """``--alpha``: the torque scale of eq. 18, the same on every command that fits or scores on a dataset."""
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
    add_columns_option(g)


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
DATASET_OPTIONS = ("channels", "wrench", "axes", "groups", "force_unit", "torque_unit", "exclude_saturated",
                   "drop_bad_readings")


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
    # which of the flagged readings (:func:`ftcal.io.check_readings`) are dropped
    g.add_argument("--drop-bad-readings", type=_bad_readings, metavar="none|auto|all|KIND,...",
                   help="the readings are checked before use for values beyond the channel's ADC range, spikes, "
                   "stuck channels and repeated rows, each pointed out by file:line:channel; this option drops them: "
                   f"auto ({','.join(AUTO_DROPPED)}), all (stuck channels' rows too), a list of those kinds, or none "
                   "(default: none, they are pointed out)")


def dataset_columns(args: argparse.Namespace, stored=None):
    """The :class:`~ftcal.io.ColumnMap` of the options, each unset one taken from ``stored`` (a model's)."""
    from ..io import ColumnMap

    def pick(option: str, default=None):
        given = getattr(args, option, None)
        return given if given is not None else getattr(stored, option) if stored is not None else default

    return ColumnMap(**{option: pick(option) for option in ("channels", "wrench", "axes", "groups")},
                     force_unit=pick("force_unit", "N"), torque_unit=pick("torque_unit", "N.m"))


def load_dataset_from_args(args: argparse.Namespace, path, role: str = "dataset", stored=None,
                           confirmed: bool = False):
    """The dataset at ``path`` read as the options (else ``stored``, a model's mapping) say, its units checked by the
    loads' lever arm, its saturated rows dropped or pointed out.

    ``confirmed``: the model's stored units were confirmed at fit time (both declared).
    """
    from ._models import load_dataset

    columns = dataset_columns(args, stored)
    read = named_inputs(args, [str(path)])[0]
    data = _sources_of_joined(load_dataset(read, role, columns=columns), read)
    check_lever_arm(args, data.wrench, path, data.axes, columns.force_unit, columns.torque_unit, confirmed)
    data = _saturated_rows_handled(args, data, path)
    return bad_readings_handled(args, data, path, channel_names(columns.channels, data.n_channels))


def channel_names(channels, n_channels: int) -> list[str]:
    """The raw channels' names: those the mapping gives (not a column slice), else ``s0, s1, ...``."""
    if channels and len(channels) == n_channels and "[" not in channels[0]:  # not a column slice (data[:,0:8])
        return list(channels)
    return [f"s{k}" for k in range(n_channels)]


#: Most entries of one kind kept in a dataset's ``meta["readings_dropped"]`` / ``["readings_flagged"]`` (the rest
#: are counted in one more entry).
MAX_LISTED_READINGS = 100


def _listed(entries: list[dict]) -> list[dict]:
    """``entries`` with at most :data:`MAX_LISTED_READINGS` of each kind, the rest counted in one entry."""
    out, seen = [], {}
    for entry in entries:
        seen[entry["kind"]] = seen.get(entry["kind"], 0) + 1
        if seen[entry["kind"]] <= MAX_LISTED_READINGS:
            out.append(entry)
    for kind, count in seen.items():
        if count > MAX_LISTED_READINGS:
            out.append({"kind": kind, "file": None, "line": None, "channel": None, "value": None,
                        "reason": f"and {count - MAX_LISTED_READINGS} more of this kind"})
    return out


def _record(data, key: str, entries: list[dict]) -> None:
    if entries:
        data.meta[key] = _listed(list(data.meta.get(key, [])) + entries)


def print_reading_findings(found, source, fix: bool = True) -> None:
    """One warning line per kind of bad reading found (:meth:`ftcal.io.ReadingChecks.summary`)."""
    for kind, line in zip(found.kinds(), found.summary()):
        option = "auto" if kind.value in AUTO_DROPPED else kind.value
        hint = f"; drop them with --drop-bad-readings {option}" if fix else ""
        print(f"ftcal: warning: {source}: {line}{hint}", file=sys.stderr)


def bad_readings_handled(args: argparse.Namespace, data, path, names=None):
    """The dataset checked (:func:`ftcal.io.check_readings`): each kind found said in one warning line; the kinds
    ``--drop-bad-readings`` names dropped. The dropped and the flagged ones are recorded in the dataset's
    ``meta["readings_dropped"]`` / ``meta["readings_flagged"]``."""
    from ..io import check_readings

    found = check_readings(data.raw, wrench=data.wrench, groups=data.group, sources=data.row_sources(),
                           channel_names=names)
    drop_kinds = tuple(getattr(args, "drop_bad_readings", None) or ())
    kept_kinds = [k for k in found.kinds() if k.value not in drop_kinds]
    if found.clean:
        return data
    dropping = [k for k in found.kinds() if k.value in drop_kinds]
    drop = found.mask(dropping)
    if drop.all():
        raise CliError(f"{path}: --drop-bad-readings would drop every one of the {data.n_samples} rows; check the "
                       "data (ftcal names each bad reading without the option)")
    print_reading_findings(type(found)(findings=tuple(f for f in found.findings if f.kind in kept_kinds),
                                       n_rows=found.n_rows), path)
    if drop.any():
        if not getattr(args, "quiet", False):
            print(f"ftcal: {path}: dropped {int(drop.sum())} of {data.n_samples} rows with bad readings ("
                  f"{', '.join(f'{len(found.of_kind(k))} {k.value}' for k in dropping)})", file=sys.stderr)
        data = data.subset(~drop)
    _record(data, "readings_dropped", found.to_json(dropping))
    _record(data, "readings_flagged", found.to_json(kept_kinds))
    return data


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
                _record(data, "readings_flagged", _saturated_entries(data, drop, said))
            return data
    if not drop.any():
        if not quiet:
            print(f"ftcal: {path}: no rows with {said.split(' (')[0]}; none dropped", file=sys.stderr)
        return data
    if drop.all():
        raise CliError(f"{path}: --exclude-saturated would drop every one of the {data.n_samples} rows ({said}); "
                       "check the limits")
    kept = data.subset(~drop)
    _record(kept, "readings_dropped", _saturated_entries(data, drop, said))
    if not quiet:
        print(f"ftcal: {path}: dropped {int(drop.sum())} of {data.n_samples} rows with {said}", file=sys.stderr)
    return kept


def _saturated_entries(data, mask, said: str) -> list[dict]:
    """The rows of ``mask`` as ``saturated`` entries of ``meta["readings_dropped"/"readings_flagged"]``."""
    import numpy as np

    sources = data.row_sources()
    return [{"kind": "saturated", "file": file, "line": line, "channel": None, "value": None, "reason": said}
            for file, line in (sources.where(int(row)) for row in np.flatnonzero(mask))]


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
            and getattr(args, "torque_unit", None) is not None,
            "wrench_range": [data.wrench.min(axis=0).tolist(), data.wrench.max(axis=0).tolist()]}


def _model_facts(model_path) -> dict:
    """What the model file keeps of its training data (:func:`ftcal.persistence.model_data`), its errors in one line."""
    from ..core import ModelFileError
    from ..persistence import model_data

    try:
        return model_data(model_path)
    except ModelFileError as exc:
        raise cli_error(exc) from None


def model_wrench_range(model_path, axes):
    """The calibrated range of each of ``axes`` (the loads the model was fitted on, [N, N·m]) as ``(low, high)``
    arrays, or None for a model file that does not keep it (fitted by an older ftcal, or in Python)."""
    import numpy as np

    facts = _model_facts(model_path)
    found, fitted_axes = facts.get("wrench_range"), facts.get("axes")
    try:
        low, high = (np.asarray(b, dtype=float) for b in found)
    except (TypeError, ValueError):
        return None
    if not isinstance(fitted_axes, list) or low.shape != (len(fitted_axes),) or high.shape != low.shape \
            or list(fitted_axes) != list(axes) or not (np.isfinite(low).all() and np.isfinite(high).all()):
        return None
    return low, high


def model_reading(model_path) -> tuple:
    """``(ColumnMap or None, axes or None, units confirmed)`` a model file keeps of its training data."""
    from ..core import DatasetFileError
    from ..io import ColumnMap

    facts = _model_facts(model_path)
    axes = facts.get("axes")
    if axes is not None and not (isinstance(axes, list) and all(isinstance(a, str) for a in axes) and len(axes) <= 6):
        raise CliError(f"{model_path}: the stored wrench axes are damaged; fit the model again")
    try:  # None for a file without a mapping
        stored = ColumnMap.from_dict(facts["columns"], str(model_path)) if "columns" in facts else None
    except DatasetFileError as exc:
        raise cli_error(exc) from None
    return stored, None if axes is None else tuple(axes), bool(facts.get("units_confirmed", False))


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
