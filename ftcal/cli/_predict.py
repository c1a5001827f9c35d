"""``ftcal predict``: a saved model applied to raw readings, wrenches out; made for pipelines."""

from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np

from ._common import (CliError, Console, OutputPlan, add_output_file_options, existing_file, finish_command,
                      int_in_range, path_problem)
from ._data_options import (add_channel_option, channel_names, joined_origin, model_reading, print_reading_findings,
                            readings_input)
from ._readings import (iter_reading_chunks, located_error, read_readings_npz, takes_temperature, utf8_lines,
                        write_wrench_rows)
from ..core import default_axes
from ..io import RangeExcess, range_excess

EXAMPLE = """\
input: one raw reading per line (comma or space separated; an optional header
naming the channels s0..s{N-1}, or the columns the model was fitted with (--channels at fit),
or the columns --channels names; '#' comments), or a .npz / .mat file. output: CSV of the
model's axes, e.g. Fx,Fy,Fz [N],Tx,Ty,Tz [N·m] (Fx,Fy,Fz for a 3-axis load cell).

examples:
  ftcal predict models/directional.model.npz readings.csv --output wrench.csv
  my_sensor_reader | ftcal predict models/directional.model.npz --line-buffered | my_controller
  ftcal predict models/linear.model.npz data/test.csv --no-header | head -3
  ftcal predict models/linear.model.npz live.csv --range models/linear.report.json   # + out_of_range column
  ftcal predict models/linear.model.npz log.csv --channels g1..g6     # channels named g1..g6 in log.csv

--range FILE (a calibration report .json, or the calibration dataset) adds a column out_of_range:
1 when a reading lies beyond the calibrated range (a channel below its smallest or above its
largest calibration reading), else 0; a count of such readings goes to stderr at the end.
Bad readings of a file (out of the ADC range, spikes, stuck, repeated) are pointed out on stderr by
file:line:channel and still predicted: the output keeps one wrench per input line (no --drop-bad-readings).
  ftcal predict models/gaussian_process.model.npz readings.csv --std     # + std_Fx..std_Tz columns
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("predict", epilog=EXAMPLE,
                       help="apply a saved model to raw readings (file or stdin) -> wrenches (file or stdout)",
                       description="Apply a saved calibration model to raw readings. Nothing but the wrenches goes to "
                       "stdout.")
    p.add_argument("model", type=existing_file, help="model file written by 'ftcal fit'")
    p.add_argument("input", nargs="?", default="-",
                   help="raw readings: a CSV / whitespace text file, a .npz or .mat with array 'raw' (or the "
                   "--channels arrays), or '-' for stdin")
    add_channel_option(p)
    add_output_file_options(p)
    p.add_argument("--no-header", action="store_true", help="do not write the Fx,...,Tz header line")
    p.add_argument("--chunk-size", type=int_in_range(1, 1_000_000, "rows per chunk"), default=4096,
                   help="readings predicted together (memory vs. latency)")
    p.add_argument("--line-buffered", action="store_true",
                   help="answer each input line at once and flush (live streams; same as --chunk-size 1)")
    p.add_argument("--range", metavar="FILE", dest="range_file",
                   help="the calibrated range: a calibration report .json ('ftcal report') or the calibration "
                   "dataset; adds an out_of_range column (1 = a reading beyond it); without it, readings beyond the "
                   "model's own training readings are counted in a warning")
    p.add_argument("--std", action="store_true",
                   help="also write each component's predictive standard deviation (std_Fx..std_Tz; "
                   "Gaussian-process models, also when auto chose one)")
    # one wrench per input line, in order: predict points bad readings out but drops none (refused with the reason)
    p.add_argument("--drop-bad-readings", metavar="KIND", help=argparse.SUPPRESS)
    finish_command(p, run, seed=False)


def calibrated_raw_range(path: str, n_channels: int, temperature: bool = False,
                         columns=None) -> tuple[np.ndarray, np.ndarray]:
    """Per-channel (min, max) of the calibration readings, from a report ``.json`` or a dataset file.

    The bounds are those recorded at calibration; a re-tared model moves them by its re-tare shift
    (:func:`retare_shift`), as it does its own range. Without ``--range`` the model's own range is used. A
    dataset is read as the model's training data were (``columns``: the mapping the model file keeps, e.g. a
    ``.mat`` sliced as ``data[:,0:6]``), so that its readings are the channels the model takes.
    """
    import json

    from ..core import DatasetFileError
    from ..io import CalibrationDataset
    from ._messages import cli_message, fix_names

    file = Path(path)
    problem = path_problem(file)  # a pipe (<(...)), a directory, a broken link: said as what it is
    if problem is not None:
        raise CliError(f"--range {problem} (give the report .json of 'ftcal report' or the dataset)")
    takes = "--range takes the calibration report .json of 'ftcal report' or the calibration dataset"
    if file.suffix.lower() == ".json":
        try:
            facts = json.loads(file.read_text(encoding="utf-8"))
            found = facts["calibrated_range"]
            lo, hi = _range_bound(found, "raw_min", path), _range_bound(found, "raw_max", path)
        except (ValueError, KeyError, TypeError, UnicodeDecodeError):
            raise CliError(f"--range {path}: not a calibration report .json (written by 'ftcal report')") from None
        if lo.shape != hi.shape:
            raise _damaged(path, f"calibrated_range.raw_min has {lo.size} entries but raw_max has {hi.size}")
        swapped = np.flatnonzero(lo > hi)
        if swapped.size:
            k = int(swapped[0])
            raise _damaged(path, f"calibrated_range.raw_min[{k}] = {lo[k]:g} is above raw_max[{k}] = {hi[k]:g}")
    else:
        from ..persistence import is_model_file  # here: the module loads scikit-learn (`ftcal --help` stays light)

        if is_model_file(file):
            raise CliError(f"--range {path} is a model file; {takes} (e.g. 'ftcal report MODEL DATASET' writes "
                           "the report)")
        try:
            data = CalibrationDataset.load(file, columns=columns)
        except DatasetFileError as exc:  # a fix naming the column options does not apply: --range reads ftcal's layout
            text = cli_message(exc, fix="" if fix_names(exc, ("channels", "wrench")) else None)
            raise CliError(f"--range {text.rstrip('. ')}. {takes} in ftcal's layout") from None
        lo, hi = data.raw.min(axis=0), data.raw.max(axis=0)
    n = n_channels
    allowed = (n, n - 1) if temperature else (n,)
    if lo.shape != hi.shape or lo.size not in allowed:
        raise CliError(f"--range {path} covers {lo.size} raw channels but the model takes {n - 1 if temperature else n}"
                       f"{' and the temperature' if temperature else ''}; give the report or dataset of this model")
    if lo.size == n - 1:  # a temperature-compensated model: the temperature column is not range-checked
        lo, hi = np.append(lo, -np.inf), np.append(hi, np.inf)
    return lo, hi


def range_of_another_fit(range_file: str, model_path: str, model, limits) -> str | None:
    """Why the calibration report ``range_file`` describes another fit than ``model_path``, or None: it certifies
    a model file of another SHA-256 *and* its range is not the model's own training range (a re-tared model has
    another SHA-256 but the same range; a report of this model on other data the same SHA-256)."""
    import json

    from ..reporting import file_sha256

    if Path(range_file).suffix.lower() != ".json" or getattr(model, "calibrated_range_", None) is None:
        return None
    certified = (json.loads(Path(range_file).read_text(encoding="utf-8")).get("model") or {}).get("sha256")
    own = np.asarray(model.calibrated_range_, dtype=float)
    lo, hi = (np.asarray(b, dtype=float)[: own.shape[1]] for b in limits)
    if not certified or certified == file_sha256(model_path) or (own.shape == (2, lo.size)
                                                                  and np.allclose(own, [lo, hi])):
        return None
    return (f"--range {range_file} certifies another model file (SHA-256 {certified[:12]}...) calibrated on other "
            f"readings than {model_path}: its range is not this model's; run 'ftcal report' for this model, or "
            "drop --range to check against the model's own training readings")


def _damaged(path: str, what: str) -> CliError:
    return CliError(f"--range {path}: {what}; the report is damaged. Write it again with 'ftcal report'")


def _range_bound(found, key: str, path: str) -> np.ndarray:
    """``calibrated_range[key]`` of a report: a list of finite numbers (KeyError/TypeError: not a report)."""
    values = found[key]
    try:
        array = np.array(values, dtype=float) if isinstance(values, list) and values else None
    except (TypeError, ValueError):
        array = None
    if array is None or array.ndim != 1 or any(isinstance(v, bool) for v in values):
        raise _damaged(path, f"calibrated_range.{key} is not a list of numbers (one per raw channel)")
    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        raise _damaged(path, f"calibrated_range.{key}[{int(bad[0])}] is {values[int(bad[0])]}, not a finite number")
    return array


def run(args: argparse.Namespace) -> int:
    from functools import partial

    import ftcal
    from ..compose import history_reach, provides_std, reads_history, spread_flags

    if args.drop_bad_readings is not None:
        raise CliError(f"--drop-bad-readings {args.drop_bad_readings}: predict writes one wrench per input line, in "
                       "order, so it drops no reading (dropping would misalign the output with the input); it points "
                       "the bad readings out on stderr by file:line:channel. Drop --drop-bad-readings, and remove "
                       "those lines from the input if they must not be predicted")
    console = Console(args.quiet)
    plan = OutputPlan.single_file(args.output, args.force)
    shown = args.input
    args.input = readings_input(args, args.input, "the raw readings to predict")  # --columns: a headerless file
    model = ftcal.load_model(args.model)
    n_channels = int(model.n_features_in_)
    temperature = takes_temperature(model)
    chunk = 1 if args.line_buffered else args.chunk_size
    stored, axes, _ = model_reading(args.model)  # the channel mapping and wrench axes the model was fitted with
    channels = args.channels if args.channels is not None else (stored.channels if stored is not None else None)
    axes = axes or default_axes(int(getattr(model, "n_outputs_", 6)))
    if args.std and not provides_std(model):
        chosen = getattr(model, "best_name_", type(model).__name__)
        if reads_history(model):  # a load-history wrapper: its history term has no standard deviation
            raise CliError(f"--std: {args.model} has a load-history term (fitted with --history), which gives no "
                           "standard deviation, whatever model it wraps. Drop --std, or fit without --history")
        if takes_temperature(model):  # a temperature wrapper (its tags): it passes no standard deviation through
            raise CliError(f"--std: {args.model} is temperature-compensated (fitted with --temperature), and the "
                           "compensation passes no standard deviation through, whatever model it wraps. Drop --std, "
                           "or fit without --temperature")
        raise CliError(f"--std: {args.model} holds {chosen}, which gives no standard deviation; only Gaussian-process "
                       "models do (ftcal fit --model gaussian_process). Drop --std")
    # the column needs --range; without it the model's own calibrated range still gives the warning at the end
    limits = None if args.range_file is None else calibrated_raw_range(args.range_file, n_channels, temperature,
                                                                      columns=stored)
    if limits is not None:  # the range was recorded before any re-tare: it moves with the zero, as the model's own
        stale = range_of_another_fit(args.range_file, args.model, model, limits)
        if stale:
            print(f"ftcal: warning: {stale}", file=sys.stderr, flush=True)
        from ..calibrators import retare_shift

        limits = tuple(bound + retare_shift(model, n_channels) for bound in limits)
    # the model's own range (its training readings, re-tare shift applied); files of older versions have none
    own_range = model.out_of_range if getattr(model, "calibrated_range_", None) is not None else None
    range_source = args.range_file if limits is not None else f"{args.model} (its training readings)"
    beyond = [0]
    # a load-history model reads its input as one stream in time order: the history carries across chunks, and so
    # does a reading beyond the range, into the flags of the rows whose history holds it
    predict = model.stream() if reads_history(model) else model.predict
    reach = history_reach(model.tau_rows_) if reads_history(model) and model.tau_rows_ is not None else None
    if reach is not None and own_range is not None:
        own_range = partial(model.out_of_range, spread=False)  # spread below, across the chunks
    since = [None]
    # the readings of a file are checked as they go by (a live stream, one line at a time, is not)
    checking = args.input != "-" and chunk > 1
    findings: list = []
    excess: list = []  # per chunk, the readings beyond --range

    def emit(out) -> int:
        total = 0
        chunks = raw_chunks(args.input, n_channels, chunk, temperature=temperature, channels=channels)
        # a regular file's first chunk is read (its columns checked) before anything is written: a wrong file leaves
        # no header behind; from stdin or a pipe the header goes at once (a driver waiting for it must not wait for
        # a reading)
        first = list(itertools.islice(chunks, 1)) if args.input != "-" and Path(args.input).is_file() else []
        if not args.no_header:
            labels = [*axes, *([f"std_{a}" for a in axes] if args.std else [])]
            out.write(",".join(labels) + (",out_of_range" if limits is not None else "") + "\n")
            out.flush()
        for raw, lines in itertools.chain(first, chunks):
            try:
                if args.std:
                    wrench, std = model.predict(raw, return_std=True)
                    values = np.hstack([np.asarray(wrench, dtype=float), np.asarray(std, dtype=float)])
                else:
                    values = np.asarray(predict(raw), dtype=float)
            except ValueError as exc:  # name the input's line, not the row inside a chunk
                raise located_error(exc, "stdin" if args.input == "-" else args.input, lines, args) from None
            if limits is not None:
                # no tolerance from the readings: a chunk's (a line's) own noise would make the flags depend on the
                # chunk size; they are the model's own out_of_range (exact edges)
                names = _range_names(channels, temperature, raw.shape[1])
                excess.append(range_excess(raw, limits[0], limits[1], names, tolerance=0.0))
                flags = excess[-1].mask
            else:
                flags = None if own_range is None else np.asarray(own_range(raw), dtype=bool)
            if flags is not None and reach is not None:
                flags, since[0] = spread_flags(flags, reach, since[0])
            if flags is not None:
                beyond[0] += int(flags.sum())
            if checking:
                findings.extend(_chunk_findings(raw, lines, args.input, channels, temperature, total))
            write_wrench_rows(out, values, None if limits is None else flags)
            total += len(values)
            if chunk == 1 or out is sys.stdout:
                out.flush()
        return total

    if plan is None:
        total = emit(sys.stdout)  # flushed line by line
    else:
        with plan.writing(Path(args.output).name) as tmp, open(tmp, "w", encoding="utf-8") as fh:
            total = emit(fh)
        console.info(f"wrote {total} wrenches to {args.output}")
    if findings:
        from ..io import ReadingChecks

        print_reading_findings(ReadingChecks(findings=tuple(findings), n_rows=total), shown, fix=False)
    if beyond[0]:
        column = " (out_of_range = 1)" if limits is not None else ""
        what = ("readings lie beyond the calibrated range, or follow one closely enough that their load history holds "
                "it," if reach is not None else "readings lie beyond the calibrated range")
        per_channel = f" ({RangeExcess.combined(excess).words()})" if excess else ""
        print(f"ftcal: warning: {beyond[0]} of {total} {what} of {range_source}{column}{per_channel}; their wrenches "
              "are extrapolations", file=sys.stderr)
    return 0


def _range_names(channels, temperature: bool, width: int) -> list[str]:
    """The names of an input's ``width`` columns (its channels, then the temperature of a compensated model)."""
    if temperature:
        return channel_names(channels, width - 1) + ["temperature"]
    return channel_names(channels, width)


def _chunk_findings(raw, lines, source: str, channels, temperature: bool, offset: int) -> list:
    """The bad readings (:func:`ftcal.io.check_readings`) of one chunk of ``source``, its rows counted from
    ``offset``: named by the input's line (the row of an ``.npz`` / ``.mat``)."""
    from dataclasses import replace

    from ..io import RowSources, check_readings

    if Path(source).suffix.lower() in (".npz", ".mat"):
        name, numbers, counted = Path(source).name, np.asarray(lines) + 1, "row"
    else:
        (name, numbers), counted = joined_origin(source, lines), "line"
    found = check_readings(raw, sources=RowSources.of_file(name, numbers, counted),
                           channel_names=_range_names(channels, temperature, raw.shape[1]))
    return [replace(f, rows=f.rows + offset) for f in found.findings]


def _most_columns(source: str) -> tuple[str, int] | None:
    """The 2-D array of a ``.npz`` / ``.mat`` with the most columns as ftcal reads it (an array wider than tall is
    read transposed: :func:`ftcal.io.read_channels`), as ``(name, columns)`` (None if unreadable)."""
    from ..io import ArrayFile

    try:
        with ArrayFile(source) as archive:
            shapes = {name: np.shape(archive.read(name)) for name in archive.names()}
    except (OSError, ValueError):
        return None
    wide = [(name, int(min(shape))) for name, shape in shapes.items() if len(shape) == 2]  # wide: read transposed
    return max(wide, key=lambda item: item[1]) if wide else None


def raw_chunks(source: str, n_channels: int, chunk: int, *, temperature: bool = False,
               channels: tuple[str, ...] | None = None):
    """Arrays of at most ``chunk`` readings of ``source``, each with its line numbers (the rows of a ``.npz`` /
    ``.mat`` are numbered from 0): ``(array, line numbers)``. ``channels``: the channel columns (or arrays, or a column
    slice) to read, as ``--channels`` or the model's stored mapping name them."""
    from ..io import expand_names, parse_column_slice

    names = None if channels is None or parse_column_slice(channels[0]) is not None else expand_names(channels)
    if source == "-":
        if sys.stdin.isatty():
            print("ftcal predict: reading raw readings from the terminal; end with Ctrl-D", file=sys.stderr)
        stream = utf8_lines(sys.stdin)
        try:
            yield from iter_reading_chunks(stream, "stdin", n_channels, chunk, temperature=temperature, names=names)
        finally:
            if stream is not sys.stdin:
                stream.detach()  # standard input stays open for the caller
    elif Path(source).suffix.lower() in (".npz", ".mat"):
        if channels is None and Path(source).suffix.lower() == ".npz":
            raw = read_readings_npz(source, n_channels)
        else:
            from ..io import read_channels

            raw = read_channels(source, channels)
            if raw.shape[1] != n_channels:  # --channels can help only where the file holds enough columns
                held = _most_columns(source)
                fix = ("name the model's channels with --channels (e.g. a column slice such as "
                       f"{held[0]}[:,0:{n_channels}])" if held is not None and held[1] >= n_channels else
                       f"no array of the file holds {n_channels} columns: give the readings this model was "
                       "calibrated for, or the model of this sensor")
                raise CliError(f"{source}: {raw.shape[1]} raw channels read"
                               f"{' (--channels ' + ','.join(channels) + ')' if channels else ''} but the model takes "
                               f"{n_channels}; {fix}")
        for start in range(0, len(raw), chunk):
            yield raw[start:start + chunk], np.arange(start, min(start + chunk, len(raw)))
    else:
        with open(source, encoding="utf-8", errors="surrogateescape", newline="") as fh:
            yield from iter_reading_chunks(fh, source, n_channels, chunk, temperature=temperature, names=names)
