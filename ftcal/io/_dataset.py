"""The calibration dataset: raw readings paired with reference wrenches, and its file formats.

File formats
------------
CSV (``.csv``)
    One header line, then one row per sample. Columns ``s0 ... s{N-1}`` hold
    the raw channels (any unit the sensor gives: counts, mV, ...), then the
    wrench axes the sensor measures, any of ``Fx, Fy, Fz`` in [N] and
    ``Tx, Ty, Tz`` in [N·m] (a 3-axis load cell has ``Fx, Fy, Fz``); an optional
    ``group`` column holds a label per row (a pose, a session: integers or
    text), an optional ``temperature`` column the sensor temperature [deg C].
    Every other column is ignored, whatever its name (an index, ``time [s]``,
    an empty name). Blank lines and lines starting with ``#`` are skipped
    anywhere; one comment ``# meta: {...}`` carries JSON metadata. Errors name
    the file's 1-based line and the column.
NumPy archive (``.npz``)
    Arrays ``raw`` (n, N), ``wrench`` (n, k), optional ``axes`` (k,) naming the
    wrench axes (default Fx..Tz), ``group`` (n,), ``temperature`` (n,) and
    ``meta_json`` (a JSON string). Read with ``allow_pickle=False``; only the
    arrays used are read.
MATLAB (``.mat``, v4-v7, read only)
    Variables ``raw`` (n, N) and ``wrench`` (n, k) (or one row per component),
    optional ``group`` and ``temperature``; or any variables or column slices
    (``data[:,0:8]``) named by a :class:`~ftcal.io.ColumnMap`. Only the
    variables used are read. v7.3 (HDF5) is refused with the fix.
A folder
    Every ``.csv`` / ``.npz`` / ``.mat`` file in it (one per pose or session),
    read alike and joined; each file is a group unless ``groups`` names a
    column. Files of different columns are refused, naming the file.

Other layouts and units are read through a :class:`~ftcal.io.ColumnMap`
(``CalibrationDataset.load(path, columns=ColumnMap(...))``, the CLI's
``--channels``, ``--wrench``, ``--axes``, ``--groups``, ``--force-unit``,
``--torque-unit``).
"""

from __future__ import annotations

import csv
import json
import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..core._columns import check_plain_fields, csv_rows, is_number
from ..core._exceptions import NO_SETTING, CalibrationInputError, DatasetFileError, Placeholder
from ..core._files import atomic_output, content_twins
from ..core._temperature import check_temperature
from ..core._wrench import MIN_CHANNELS, WRENCH_LABELS, default_axes
from ._readers import (GROUPS, ArrayFile, ColumnMap, canonical_wrench_name, check_real_array, checked_temperature,
                       named_axes, parse_column_slice, read_utf8_text, check_separator, _INTEGER, _slice_columns)

__all__ = ["CalibrationDataset", "RowSources", "DATASET_SUFFIXES", "read_channels"]

_CSV_LAYOUT = "s0,...,s{N-1},Fx,Fy,Fz,Tx,Ty,Tz[,group][,temperature] (any subset of the wrench axes)"
#: The suffixes of dataset files (any letter case), and of the files a dataset folder is made of.
DATASET_SUFFIXES = (".csv", ".npz", ".mat")


def _refuse_twin_files(files: Sequence[Path], parts: Sequence["CalibrationDataset"], labelled: bool) -> None:
    """Refuse two files of a folder that hold the same readings and wrenches (a recording copied in twice, under
    another name, in another format, re-saved with fewer digits or with its rows in another order): its rows would
    count twice and its twins fall in different folds, so a model would be judged on its own training rows. The
    files are compared by what was read from them, as sets of rows, each number within 1e-7 of itself
    (:func:`ftcal.core.content_twins`; a truncated copy is not a twin); with group labels read from a column
    (``labelled``), rows labelled as other poses or sessions are told apart by their labels."""
    by_path = dict(zip(files, parts))

    def values(path: Path) -> list:
        part = by_path[path]
        labels = (part.group, repr(part.meta.get("group_names"))) if labelled and part.group is not None else ()
        return [part.raw, part.wrench, part.temperature, *labels]

    twins = content_twins([f for f, part in by_path.items() if part.n_samples], values,
                          key=lambda path: by_path[path].n_samples)
    if twins:
        first, second = twins[0]
        raise DatasetFileError(
            f"{second} holds the same readings and wrenches as {first} ({by_path[second].n_samples} rows): one "
            "recording given twice would count its rows twice and judge a model on its own rows. Fix: move one of "
            "them out of the folder (give each recording once).")


def dataset_files(folder: Path) -> list[Path]:
    """The files of a folder dataset that :meth:`CalibrationDataset.load` reads, in name order: its ``.csv``,
    ``.npz`` and ``.mat`` files, not hidden ones nor sub-folders (the identity of a folder dataset is theirs)."""
    return sorted(p for p in Path(folder).iterdir() if p.suffix.lower() in DATASET_SUFFIXES
                  and not p.name.startswith(".") and p.is_file())
#: Most files of a dataset folder.
MAX_FOLDER_FILES = 100_000


def _parse_meta(text: str, where: str, what: str = "the meta comment") -> dict:
    """The JSON object of a ``# meta:`` comment or an ``.npz``'s ``meta_json`` (an object, not a list or a
    number)."""
    try:
        meta = json.loads(text)
    except (json.JSONDecodeError, RecursionError) as exc:
        raise DatasetFileError(f"{where}: bad JSON in {what} ({str(exc)[:80]}).") from None
    if not isinstance(meta, dict):
        raise DatasetFileError(
            f"{where}: {what} holds a JSON {type(meta).__name__}; it must be a JSON object "
            "such as {\"alpha\": 50}."
        )
    return meta


def _integer_labels(group, n_rows: int) -> NDArray[np.int64]:
    """``group`` as int64, refusing fractional, non-finite or non-numeric labels (no silent truncation)."""
    g = np.asarray(group)
    if g.shape != (n_rows,):
        raise DatasetFileError(f"group must have shape ({n_rows},), one label per row; got shape {g.shape}.")
    if g.dtype.kind in "iu":
        if g.dtype.kind == "u" and g.size and g.max() > np.iinfo(np.int64).max:  # would wrap to negative labels
            i = int(np.argmax(g > np.iinfo(np.int64).max))
            raise DatasetFileError(f"group row {i} (rows counted from 0) holds {int(g[i])}, beyond the 64-bit integer labels ftcal stores. "
                                   "Fix: number the groups 0, 1, 2, ...")
        return g.astype(np.int64)
    if g.dtype.kind == "b" or g.dtype.kind not in "f":
        raise DatasetFileError(
            f"group must hold integer labels (a load configuration or pose number); got dtype {g.dtype}."
        )
    bad = ~np.isfinite(g) | (g != np.round(g))
    if bad.any():
        i = int(np.argmax(bad))
        raise DatasetFileError(
            f"group must hold integer labels; row {i} (rows counted from 0) holds {float(g[i])!r}. Fix: number the groups 0, 1, 2, ..."
        )
    return g.astype(np.int64)


def _group_column(texts: list[str], line_nos: list[int], path, column: str) -> tuple[NDArray, list[str] | None]:
    """A CSV group column as int64 labels: integers exactly (float64 would merge labels above 2^53), or text labels
    (``pose_a``) numbered in order of appearance (returned too, to name the groups)."""
    if not all(is_number(t) for t in texts):  # text labels
        names: dict[str, int] = {}
        for no, text in zip(line_nos, texts):
            if not text:
                raise DatasetFileError(f"{path}: line {no}, column {column}: empty group label; every row needs one.")
            names.setdefault(text, len(names))
        return np.array([names[t] for t in texts], dtype=np.int64), list(names)
    labels: list[int] = []
    for no, text in zip(line_nos, texts):
        if _INTEGER.fullmatch(text):
            value = int(text)
        else:
            number = float(text)
            if not (np.isfinite(number) and number == round(number)):
                raise DatasetFileError(f"{path}: line {no}, column {column}: {text} is not an integer label. Fix: "
                                       "number the groups 0, 1, 2, ... (or name them with text labels)")
            value = int(number)
        if not -(2**63) <= value < 2**63:
            raise DatasetFileError(f"{path}: line {no}: {column} {text} is beyond the 64-bit integer labels ftcal "
                                   "stores. Fix: number the groups 0, 1, 2, ...")
        labels.append(value)
    return np.array(labels, dtype=np.int64), None


def _csv_fields(line: str) -> list[str]:
    """A CSV line's fields (quoted names such as ``"time [s]"`` unquoted), spaces around each dropped."""
    if '"' not in line:
        return [f.strip() for f in line.split(",")]
    return [f.strip() for f in next(csv.reader([line], skipinitialspace=True))]


@dataclass(frozen=True)
class _CsvColumns:
    """Where a CSV's used columns are: the channels, the wrench (and its axes), the group and the temperature."""

    channels: list[int]
    wrench: list[int]
    axes: tuple[str, ...]
    group: int | None
    temperature: int | None


def _find(names: list[str], name: str, option: str, where: str, positions: dict[str, list[int]]) -> int:
    """The position of the column ``name`` (mapped by the argument ``option``, e.g. ``"channels"``) in the header
    ``names`` (``positions``: each name's positions in it, made once for many look-ups: linear time)."""
    if parse_column_slice(name) is not None:
        raise DatasetFileError(f"{where}: {{{option}}} {name}: a column slice selects columns of one array of a .mat "
                               "or .npz file; in a CSV name the columns, or a range such as s0..s7.", parameter=option,
                               value=name)
    hits = positions.get(name, [])
    if not hits:
        shown = ", ".join(n or "''" for n in names)
        raise DatasetFileError(f"{where}: {{{option}}} names column {name!r}, which the header lacks; the header has "
                               f"{shown}.", parameter=option, value=name)
    if len(hits) > 1:
        raise DatasetFileError(f"{where}: column {name!r} appears {len(hits)} times (columns "
                               f"{', '.join(str(i + 1) for i in hits)}); rename one, so ftcal knows which to use.")
    return hits[0]


def _channel_positions(names: list[str], where: str) -> list[int]:
    """The default raw channels: the columns ``s0, s1, ...`` in number order (from 0, no gaps, no leading zeros)."""
    found: dict[int, int] = {}
    for i, name in enumerate(names):
        m = re.fullmatch(r"s([0-9]+)", name)
        if m is None:
            continue
        if len(m.group(1)) > 1 and m.group(1).startswith("0"):
            raise DatasetFileError(f"{where}: column {name!r}: write raw channel numbers without leading zeros "
                                   f"(s{int(m.group(1))}), or name the channels with {{channels}}.",
                                   parameter="channels", value=name)
        k = int(m.group(1))
        if k in found:
            raise DatasetFileError(f"{where}: column {name!r} appears 2 times; each column must be named once.")
        found[k] = i
    if not found:
        raise DatasetFileError(f"{where}: the header names no raw channel columns s0, s1, ... Expected header: "
                               f"{_CSV_LAYOUT}.", parameter="channels", fix="name the channel columns with "
                               "{channels} (e.g. {channels} g1..g6)", settings={"channels": NO_SETTING})
    missing = sorted(set(range(max(found) + 1)) - set(found))
    if missing:
        raise DatasetFileError(f"{where}: raw channel column s{missing[0]} is missing (the header has "
                               f"s{min(found)}..s{max(found)}); raw channel columns must run from s0 without gaps, "
                               "or be named with {channels}.", parameter="channels")
    return [found[k] for k in sorted(found)]


def _refuse_lookalikes(names: list[str], where: str) -> None:
    """A column named with a look-alike of a name ftcal reads (a full-width ``ｓ0``, an Arabic-Indic digit in ``s٢``)
    would be ignored silently, and a channel or axis lost: refused, naming it."""
    import unicodedata

    for pos, name in enumerate(names):
        if name.isascii():
            continue
        folded = "".join(str(unicodedata.digit(c)) if c.isdigit() else c for c in unicodedata.normalize("NFKC", name))
        if folded.isascii() and (re.fullmatch(r"s[0-9]+", folded) or canonical_wrench_name(folded)
                                 or folded in ("group", "temperature")):
            shown = name.encode("ascii", "backslashreplace").decode()
            raise DatasetFileError(
                f"{where}: column {pos + 1} is named {shown!r}; column names must be ASCII letters, digits, '_' or "
                f"'-' (a look-alike character would silently drop a column). Fix: rename it {folded!r}.")


def _csv_columns(names: list[str], columns: ColumnMap, where: str) -> _CsvColumns:
    """The used columns of a CSV header; every other column is ignored, whatever its name."""
    _refuse_lookalikes(names, where)
    positions: dict[str, list[int]] = {}
    for i, n in enumerate(names):
        positions.setdefault(n, []).append(i)
    channels = _channel_positions(names, where) if columns.channels is None else \
        [_find(names, n, "channels", where, positions) for n in columns.channels]
    if columns.wrench is not None:
        wrench = [_find(names, n, "wrench", where, positions) for n in columns.wrench]
        axes = columns.resolve_axes(list(columns.wrench), len(wrench), where)
    else:
        named = [names[i] for i in channels if canonical_wrench_name(names[i])]
        if columns.channels is not None and named:  # the wrench found by its names would lose these axes
            raise DatasetFileError(
                f"{where}: {{channels}} takes column {named[0]!r}, which is named as a wrench axis; the reference "
                "wrench cannot be an input.", parameter="channels", value=named[0],
                fix="name only the sensor's raw channels in {channels}; if that column really is a raw channel, "
                "name the wrench columns with {wrench}", settings={"channels": NO_SETTING, "wrench": NO_SETTING})
        taken = set(channels)
        seen = named_axes([None if i in taken else n for i, n in enumerate(names)], lambda first, name, axis:
                          DatasetFileError(f"{where}: columns {first!r} and {name!r} both read as the wrench axis "
                                           f"{axis}; keep one, or name the wrench columns with {{wrench}} (e.g. "
                                           "{wrench} Fx,Fy,Fz,Mx,My,Mz).", parameter="wrench"))
        if not seen:
            raise DatasetFileError(f"{where}: the header names no wrench columns (Fx, Fy, Fz, Tx, Ty, Tz, or Mx, "
                                   f"force_x, ...). Expected header: {_CSV_LAYOUT}.", parameter="wrench",
                                   fix="name them with {wrench} (and {axes} if their names do not say the axes)",
                                   settings={"wrench": NO_SETTING, "axes": NO_SETTING})
        wrench = list(seen.values())
        axes = columns.resolve_axes([names[i] for i in wrench], len(wrench), where) if columns.axes is not None \
            else tuple(seen)
    both = sorted(set(channels) & set(wrench))
    if both:
        raise DatasetFileError(f"{where}: column {names[both[0]]!r} is mapped both as a channel and as a wrench "
                               "component; map it once.")
    used = channels + wrench
    group = None
    if columns.groups not in (None, "file"):
        group = _find(names, columns.groups, GROUPS, where, positions)
        if group in used:
            raise DatasetFileError(f"{where}: {{{GROUPS}}} {columns.groups!r} is also mapped as a channel or wrench "
                                   "column.", parameter=GROUPS, value=columns.groups)
    elif len(positions.get("group", ())) == 1 and positions["group"][0] not in used:
        group = positions["group"][0]
    temperature = positions["temperature"][0] if len(positions.get("temperature", ())) == 1 else None
    temperature = None if temperature in used else temperature
    order = np.argsort([WRENCH_LABELS.index(a) for a in axes], kind="stable")  # the wrench in Fx..Tz order
    return _CsvColumns(channels=channels, wrench=[wrench[k] for k in order], axes=tuple(axes[k] for k in order),
                       group=group, temperature=temperature)


@dataclass(frozen=True)
class RowSources:
    """Where each row of a dataset came from: the file (by name) and the 1-based line of a CSV, or the 1-based row
    of an ``.npz`` / ``.mat`` array.

    Examples
    --------
    >>> src = RowSources(files=("a.csv",), counted=("line",), file_index=np.zeros(2, int), number=np.array([3, 4]))
    >>> src.where(1)
    ('a.csv', 4)
    >>> src.describe(1)
    'a.csv:4'
    """

    files: tuple[str, ...]
    counted: tuple[str, ...]
    file_index: NDArray[np.int64]
    number: NDArray[np.int64]

    @classmethod
    def of_file(cls, name: str, numbers, counted: str = "line") -> "RowSources":
        """The rows of one file, numbered ``numbers`` (1-based lines of a text file, rows of an array file)."""
        numbers = np.asarray(numbers, dtype=np.int64)
        return cls(files=(str(name),), counted=(counted,), file_index=np.zeros(numbers.size, dtype=np.int64),
                   number=numbers)

    @classmethod
    def joined(cls, parts: list["RowSources"]) -> "RowSources":
        """The sources of datasets stacked in the order given."""
        first = np.cumsum([0] + [len(p.files) for p in parts[:-1]])  # each part's first file in the joined list
        return cls(files=tuple(f for p in parts for f in p.files), counted=tuple(c for p in parts for c in p.counted),
                   file_index=np.concatenate([p.file_index + k for p, k in zip(parts, first)]),
                   number=np.concatenate([p.number for p in parts]))

    def subset(self, index) -> "RowSources":
        """The sources of the rows ``index`` (a mask or integer indices)."""
        return RowSources(self.files, self.counted, self.file_index[index], self.number[index])

    def where(self, row: int) -> tuple[str, int]:
        """``(file name, 1-based line or row)`` of ``row`` (counted from 0 in the dataset)."""
        return self.files[int(self.file_index[row])], int(self.number[row])

    def describe(self, row: int) -> str:
        """``"file:line"`` of ``row`` (``"file:row N"`` for an array file)."""
        name, n = self.where(row)
        return f"{name}:{n}" if self.counted[int(self.file_index[row])] == "line" else f"{name}:row {n}"


@dataclass
class CalibrationDataset:
    """Raw readings and the reference wrenches they were recorded under.

    Parameters
    ----------
    raw : ndarray of shape (n_samples, n_channels)
        Raw sensor readings, one row per sample.
    wrench : ndarray of shape (n_samples, n_axes)
        Reference wrench, the axes ``axes`` (default ``[Fx, Fy, Fz, Tx, Ty, Tz]``) in [N] and [N·m].
    group : ndarray of shape (n_samples,), optional
        Integer label per sample (load configuration, pose, session, file of a folder ...), for
        grouped splits such as ``GroupKFold``.
    meta : dict
        JSON-serialisable facts about where the data came from.
    temperature : ndarray of shape (n_samples,), optional
        Sensor temperature [deg C] per sample (for
        :class:`~ftcal.TemperatureCompensatedCalibrator`: ``features(temperature=True)``).
    axes : tuple of str, optional
        The wrench axes, a subset of ``Fx, Fy, Fz, Tx, Ty, Tz`` in that order: a 3-axis load cell has
        ``("Fx", "Fy", "Fz")``, a 1-axis cell ``("Fz",)``. Default: Fx..Tz for six columns, else the first
        columns of Fx..Tz.
    sources : RowSources, optional
        Where each row came from (file and line), set by :meth:`load`; kept by :meth:`subset`. Not saved.

    Examples
    --------
    >>> import numpy as np
    >>> ds = CalibrationDataset(raw=np.ones((4, 6)), wrench=np.zeros((4, 6)))
    >>> ds.n_samples, ds.n_channels, ds.axes
    (4, 6, ('Fx', 'Fy', 'Fz', 'Tx', 'Ty', 'Tz'))
    >>> CalibrationDataset(raw=np.ones((4, 2)), wrench=np.zeros((4, 1)), axes=("Fz",)).n_axes
    1
    """

    raw: NDArray[np.float64]
    wrench: NDArray[np.float64]
    group: NDArray[np.int64] | None = None
    meta: dict = field(default_factory=dict)
    temperature: NDArray[np.float64] | None = None
    axes: tuple[str, ...] | None = None
    sources: RowSources | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        for name in ("raw", "wrench"):
            value = np.asarray(getattr(self, name))
            if np.iscomplexobj(value):
                raise DatasetFileError(f"{name} holds complex numbers (shape {value.shape}); readings and wrenches "
                                       "are real. Fix: pass the real part explicitly if that is what you mean.")
            setattr(self, name, np.asarray(value, dtype=float))
        if self.raw.ndim != 2:
            raise DatasetFileError(f"raw must be 2-D (n_samples, n_channels); got shape {self.raw.shape}.")
        if self.wrench.ndim != 2 or not 1 <= self.wrench.shape[1] <= len(WRENCH_LABELS):
            raise DatasetFileError(f"wrench must have shape (n_samples, n_axes), 1 to 6 axes of Fx, Fy, Fz, Tx, Ty, "
                                   f"Tz; got shape {self.wrench.shape}.")
        axes = default_axes(self.wrench.shape[1]) if self.axes is None else tuple(str(a) for a in self.axes)
        if len(axes) != self.wrench.shape[1] or any(a not in WRENCH_LABELS for a in axes) \
                or list(axes) != sorted(set(axes), key=WRENCH_LABELS.index):
            raise DatasetFileError(f"axes {axes!r} must name the wrench's {self.wrench.shape[1]} columns, each one of "
                                   "Fx, Fy, Fz, Tx, Ty, Tz once, in that order.")
        self.axes = axes
        needed = min(MIN_CHANNELS, len(axes))
        if self.raw.shape[1] < needed:
            raise DatasetFileError(
                f"raw has {self.raw.shape[1]} channel(s) (shape {self.raw.shape}); a {len(axes)}-axis calibration "
                f"needs at least {needed} raw channels. Fix: one column per strain-gauge channel."
            )
        if self.raw.shape[0] != self.wrench.shape[0]:
            raise DatasetFileError(
                f"raw has {self.raw.shape[0]} rows but wrench has {self.wrench.shape[0]}; they must match."
            )
        if self.group is not None:
            self.group = _integer_labels(self.group, self.raw.shape[0])
        if self.temperature is not None:
            try:
                self.temperature = check_temperature(self.temperature, self.raw.shape[0])
            except CalibrationInputError as exc:
                counted = " (rows counted from 0)" if getattr(exc, "row", None) is not None else ""
                raise DatasetFileError(f"{exc}{counted}") from None
        if not isinstance(self.meta, dict):
            raise DatasetFileError(f"meta must be a dict (JSON object); got {type(self.meta).__name__}.")
        if self.sources is not None and self.sources.number.shape != (self.raw.shape[0],):
            raise DatasetFileError(f"sources name {self.sources.number.size} rows but the dataset has "
                                   f"{self.raw.shape[0]}.")

    def row_sources(self) -> RowSources:
        """Where each row came from: :attr:`sources`, else the rows of the dataset numbered from 1 (named by the
        meta's ``source_file`` when known)."""
        if self.sources is not None:
            return self.sources
        name = self.meta.get("source_file") if isinstance(self.meta.get("source_file"), str) else "dataset"
        return RowSources.of_file(name, np.arange(1, self.n_samples + 1), "row")

    @property
    def n_samples(self) -> int:
        """Number of rows."""
        return int(self.raw.shape[0])

    @property
    def n_channels(self) -> int:
        """Number of raw channels."""
        return int(self.raw.shape[1])

    @property
    def n_axes(self) -> int:
        """Number of wrench axes (6 for a 6-axis sensor, 3 for a 3-axis load cell)."""
        return int(self.wrench.shape[1])

    def subset(self, index: NDArray) -> "CalibrationDataset":
        """The rows selected by ``index`` (a boolean mask or integer indices), as a new dataset."""
        rows = {name: None if getattr(self, name) is None else getattr(self, name)[index]
                for name in ("raw", "wrench", "group", "temperature")}
        return CalibrationDataset(**rows, meta=dict(self.meta), axes=self.axes,
                                  sources=None if self.sources is None else self.sources.subset(index))

    def features(self, temperature: bool = False) -> NDArray[np.float64]:
        """The calibrators' ``X``: the raw channels, with the temperature [deg C] as a last column if asked."""
        if not temperature:
            return self.raw
        if self.temperature is None:
            raise DatasetFileError("this dataset has no temperature column; record the sensor temperature "
                                   "(a 'temperature' column in deg C) to compensate thermal drift.")
        return np.column_stack([self.raw, self.temperature])

    def pinned_rows(self, min_rows: int = 3) -> tuple[NDArray[np.bool_], list[str]]:
        """Rows where a channel sits at its extreme value (the smallest or largest it reads) under at least
        ``min_rows`` different loads and 1 % of the rows: an ADC pinned at its limit (a saturated channel) reads one
        value exactly whatever the load, while a live reading varies with it. Rows that repeat one load case (the
        same wrench recorded again) count as one load: a repeated load reads the same value without any
        saturation. Returns the mask and one phrase per pinned channel extreme.

        Examples
        --------
        >>> raw = np.column_stack([np.r_[np.linspace(0, 1, 97), 4095, 4095, 4095], np.linspace(0, 1, 100)])
        >>> loads = np.linspace(0, 50, 100)[:, None]
        >>> mask, said = CalibrationDataset(raw=raw, wrench=loads, axes=("Fz",)).pinned_rows()
        >>> int(mask.sum()), said
        (3, ['s0 at 4095 in 3 rows'])
        >>> cases = np.column_stack([np.r_[np.linspace(0, 1, 9), 4095], np.linspace(0, 1, 10)])  # the top load: 4095
        >>> repeated = CalibrationDataset(raw=np.repeat(cases, 10, axis=0), axes=("Fz",),  # 10 rows a load case
        ...                               wrench=np.repeat(np.linspace(0, 50, 10)[:, None], 10, axis=0))
        >>> repeated.pinned_rows()[1]
        []
        """
        mask = np.zeros(self.n_samples, dtype=bool)
        said = []
        need = max(int(min_rows), int(np.ceil(0.01 * self.n_samples)))
        for k in range(self.n_channels):
            column = self.raw[:, k]
            if np.ptp(column) == 0:
                continue
            for value in (column.min(), column.max()):
                at = column == value
                if len(np.unique(self.wrench[at], axis=0)) >= need:  # different loads, not repeats
                    mask |= at
                    said.append(f"s{k} at {value:.10g} in {int(at.sum())} rows")
        return mask, said

    # ------------------------------------------------------------------ files
    def _checked_for_saving(self, path: Path) -> str:
        """The meta as strict JSON, after checking that the file would read back: finite values (the readers
        refuse NaN and inf) and a meta of plain JSON values."""
        for name in ("raw", "wrench", "temperature"):
            values = getattr(self, name)
            if values is not None and not np.isfinite(values).all():
                where = np.argwhere(~np.isfinite(values))[0]
                raise DatasetFileError(
                    f"cannot save {path}: {name} holds {values[tuple(where)]} at row {int(where[0])} (rows counted from "
                    f"0){f', column {int(where[1])}' if where.size > 1 else ''}; a dataset file holds finite values "
                    "(ftcal's readers refuse NaN and inf). Fix: drop or repair those rows first.")
        try:
            return json.dumps(self.meta, allow_nan=False)
        except (TypeError, ValueError) as exc:
            raise DatasetFileError(
                f"cannot save {path}: meta must hold plain JSON values (text, finite numbers, lists, dicts); "
                f"{exc}.") from None

    def save(self, path: str | Path, *, overwrite: bool = False) -> Path:
        """Write the dataset to ``path`` (``.csv`` or ``.npz``, chosen by suffix) and return it.

        The file is written to a unique temporary file beside ``path`` and
        renamed into place, so an interrupted save never leaves half a file.
        An existing ``path`` raises :class:`~ftcal.core.DatasetFileError` unless
        ``overwrite=True``.
        """
        path = Path(path)
        if path.suffix not in (".csv", ".npz"):
            raise DatasetFileError(f"{path}: unknown dataset suffix {path.suffix!r}; use .csv or .npz.")
        if path.exists() and not overwrite:
            raise DatasetFileError(f"{path} already exists; pass overwrite=True to replace it, or choose another path.")
        meta_json = self._checked_for_saving(path)
        with atomic_output(path, overwrite=overwrite, error=DatasetFileError) as tmp:
            if path.suffix == ".npz":
                arrays = {"raw": self.raw, "wrench": self.wrench, "meta_json": np.array(meta_json),
                          "axes": None if self.axes == WRENCH_LABELS else np.array(self.axes), "group": self.group,
                          "temperature": self.temperature}
                arrays = {name: values for name, values in arrays.items() if values is not None}
                with open(tmp, "wb") as fh:
                    np.savez(fh, **arrays)
            else:
                extra = {"group": self.group, "temperature": self.temperature}
                extra = {name: values[:, None] for name, values in extra.items() if values is not None}
                if "group" in extra:  # exact integer labels (Python ints, never through float64)
                    extra["group"] = extra["group"].astype(object)
                cols = [f"s{i}" for i in range(self.n_channels)] + list(self.axes) + list(extra)
                with open(tmp, "w", encoding="utf-8", newline="\n") as fh:
                    fh.write(f"# meta: {meta_json}\n" + ",".join(cols) + "\n")
                    fh.writelines(csv_rows(self.raw, self.wrench, *extra.values()))
        return path

    @classmethod
    def load(cls, path: str | Path, *, columns: ColumnMap | None = None) -> "CalibrationDataset":
        """Read a dataset: ``.csv`` / ``.npz`` as written by :meth:`save` (or by hand), a MATLAB ``.mat``, or a
        folder of such files (one per pose or session, each a group).

        Parameters
        ----------
        path : path
            The file (its suffix, in any letter case, chooses the reader) or a folder of files.
        columns : ColumnMap, optional
            Which columns / variables hold the raw channels and the wrench, the group column, and the
            units of the file's forces and torques (converted to [N] and [N·m]).
        """
        path = Path(path)
        columns = ColumnMap() if columns is None else columns
        if path.is_dir():
            return cls._load_folder(path, columns)
        if not path.is_file():
            raise DatasetFileError(f"{path}: no such dataset file.")
        if columns.groups == "file":
            raise DatasetFileError(f"{path}: {{{GROUPS}}} file makes each file of a folder a group; give the folder "
                                   "of files, or name the group column.", parameter=GROUPS, value="file")
        ds, _ = cls._load_file(path, columns)
        if columns.groups is not None:
            _check_groups(ds, f"{path}: {{{GROUPS}}} {columns.groups}", columns.groups)
        return ds

    @classmethod
    def _load_file(cls, path: Path, columns: ColumnMap) -> tuple["CalibrationDataset", tuple[str, ...]]:
        """The dataset of one file in ftcal's units, and the names of the file's columns (or arrays)."""
        readers = {".npz": cls._load_arrays, ".csv": cls._load_csv, ".mat": cls._load_arrays}
        reader = readers.get(path.suffix.lower())
        if reader is None:
            raise DatasetFileError(f"{path}: unknown dataset suffix {path.suffix!r}; use .csv, .npz or .mat.")
        ds, names = reader(path, columns)
        if not columns.is_default:
            ds.wrench = columns.to_si(ds.wrench, ds.axes)
            ds.meta = {**ds.meta, **columns.units_meta()}
        return ds, names

    @classmethod
    def _load_folder(cls, folder: Path, columns: ColumnMap) -> "CalibrationDataset":
        """Every dataset file of ``folder``, read alike and joined; each file a group unless a column is named."""
        try:
            files = dataset_files(folder)
        except OSError as exc:
            raise DatasetFileError(f"{folder}: the folder cannot be read ({exc.strerror or exc}).") from None
        if not files:
            raise DatasetFileError(f"{folder}: the folder holds no dataset files ({', '.join(DATASET_SUFFIXES)}); "
                                   "put one file per pose or session in it.")
        if len(files) > MAX_FOLDER_FILES:
            raise DatasetFileError(f"{folder}: {len(files)} files, more than ftcal reads as one dataset "
                                   f"({MAX_FOLDER_FILES}); join them first.")
        parts, first_names = [], None
        by_file = columns.groups in (None, "file")
        for path in files:
            ds, names = cls._load_file(path, columns)
            if first_names is None:
                first_names = names
            elif _canonical(names) != _canonical(first_names):  # read by name: order and aliases mean nothing
                extra = sorted(set(_canonical(names)) - set(_canonical(first_names))) or \
                    sorted(set(_canonical(first_names)) - set(_canonical(names)))
                raise DatasetFileError(
                    f"{path}: its columns ({', '.join(names)}) differ from those of {files[0]} "
                    f"({', '.join(first_names)}{'; ' + extra[0] + ' differs' if extra else ''}); every file of a "
                    "dataset folder needs the same columns. Fix: move that file out of the folder, or give it the "
                    "same columns.")
            if by_file:
                ds.group = np.full(ds.n_samples, len(parts), dtype=np.int64)
            parts.append(ds)
        if len({p.axes for p in parts}) > 1 or len({p.n_channels for p in parts}) > 1:
            raise DatasetFileError(f"{folder}: the files hold different channels or wrench axes; every file needs "
                                   "the same columns.")
        _refuse_twin_files(files, parts, labelled=not by_file)
        temperature = np.concatenate([p.temperature for p in parts]) if all(p.temperature is not None for p in parts) \
            else None
        groups = None if any(p.group is None for p in parts) else np.concatenate([p.group for p in parts])
        meta = {k: v for k, v in parts[0].meta.items() if k not in ("group_names", "group_labels")}
        meta["source_files"] = [p.name for p in files]
        if not by_file and groups is not None and all(isinstance(p.meta.get("group_names"), list) for p in parts):
            names: dict[str, int] = {}  # text labels, numbered per file: one numbering for the folder
            groups = np.concatenate([np.array([names.setdefault(p.meta["group_names"][g], len(names))
                                               for g in p.group], dtype=np.int64) for p in parts])
            meta["group_labels"] = meta["group_names"] = list(names)
        if by_file:
            meta["group_labels"] = meta["group_names"] = [p.name for p in files]
        sources = RowSources.joined([p.row_sources() for p in parts])
        ds = cls(raw=np.vstack([p.raw for p in parts]), wrench=np.vstack([p.wrench for p in parts]), group=groups,
                 meta=meta, temperature=temperature, axes=parts[0].axes, sources=sources)
        _check_groups(ds, f"{folder}: {f'{{{GROUPS}}} ' + columns.groups if columns.groups else 'its files'}",
                      columns.groups or "file")  # a named column, or the files: each a group
        return ds

    @classmethod
    def _load_arrays(cls, path: Path, columns: ColumnMap) -> tuple["CalibrationDataset", tuple[str, ...]]:
        """A dataset from the named arrays of an ``.npz`` / ``.mat``, reading only the arrays it uses."""
        with ArrayFile(path) as source:
            meta: dict = {"source_file": path.name} if not source.is_npz else {}
            if source.is_npz and "meta_json" in source.entries:
                meta = _npz_meta(source.read("meta_json"), path)
            names = tuple(n for n in source.names() if n != "meta_json")
            ds = _dataset_from_arrays(cls, source, columns, meta)
        ds.sources = RowSources.of_file(path.name, np.arange(1, ds.n_samples + 1), "row")
        return ds, names

    @classmethod
    def _load_csv(cls, path: Path, columns: ColumnMap) -> tuple["CalibrationDataset", tuple[str, ...]]:
        # a byte-order mark (spreadsheet exports) is not part of the first column's name
        lines = read_utf8_text(path, "a dataset CSV is a text file").splitlines()
        meta, header_no, line_nos = _csv_layout(lines, path)
        if header_no is None and not lines:
            raise DatasetFileError(f"{path}: the file is empty (no text); expected a header line {_CSV_LAYOUT} and "
                                   "data rows. Fix: give the file that holds the recording (the copy or export may "
                                   "have failed).")
        if header_no is None:
            raise DatasetFileError(f"{path}: no header line; expected {_CSV_LAYOUT}.")
        where = f"{path}: line {header_no}"
        names = _csv_fields(lines[header_no - 1].lstrip("\ufeff"))
        check_separator(names, where, next_row=lines[line_nos[0] - 1] if line_nos else "")
        if all(f and is_number(f) for f in names):
            raise DatasetFileError(
                f"{where}: the file has no header: its first line holds numbers, not column names.",
                parameter="channels", fix=f"add a header line naming the columns ({_CSV_LAYOUT}), or name them with "
                "{channels}/{wrench} after adding one", settings={"channels": NO_SETTING, "wrench": NO_SETTING})
        used = _csv_columns(names, columns, where)
        if not line_nos:
            raise DatasetFileError(f"{path}: no data rows after the header.")
        width = len(names)
        numeric = used.channels + used.wrench + ([used.temperature] if used.temperature is not None else [])
        shown = [n or f"{i + 1} (unnamed)" for i, n in enumerate(names)]
        rows, group_texts = [], []
        for no in line_nos:  # numpy's own message counts data rows, not the file's lines
            fields = _csv_fields(lines[no - 1])
            if len(fields) != width:
                raise DatasetFileError(f"{path}: line {no}: {len(fields)} values but the header names "
                                       f"{width} columns; repair or remove that line.")
            values = [fields[i] for i in numeric]
            # `1_000`, `nan`: float() and numpy take forms no logger writes; only the used columns are looked at
            check_plain_fields(",".join(values), f"{path}: line {no}", [shown[i] for i in numeric], DatasetFileError,
                               quick=True)
            rows.append(values)
            if used.group is not None:
                group_texts.append(fields[used.group])
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                data = np.array(rows, dtype=float).reshape(len(rows), len(numeric))
        except ValueError:  # an empty cell or '1.0.0' passed the quick look: name its line and column
            for no, values in zip(line_nos, rows):
                check_plain_fields(",".join(values), f"{path}: line {no}", [shown[i] for i in numeric],
                                   DatasetFileError)
            raise
        n_ch, n_w = len(used.channels), len(used.wrench)
        if [names[i] for i in used.channels] != [f"s{i}" for i in range(len(used.channels))]:  # the user's names
            meta = {**meta, "channel_names": [str(names[i]) for i in used.channels]}  # (the report prints them)
        bad = np.argwhere(~np.isfinite(data[:, :n_ch + n_w]))
        if bad.size:
            row, k = (int(v) for v in bad[0])
            raise DatasetFileError(f"{path}: line {line_nos[row]}, column {shown[numeric[k]]}: "
                                   f"{rows[row][k]!r} is NaN or inf (or beyond float64); "
                                   "remove or repair that line.")
        group = None
        if used.group is not None:
            group, labels = _group_column(group_texts, line_nos, path, names[used.group])
            if labels is not None:
                meta = {**meta, "group_labels": labels, "group_names": labels}
        temperature = None
        if used.temperature is not None:
            temperature = checked_temperature(data[:, -1], path, line_nos, DatasetFileError)
        try:
            ds = cls(raw=data[:, :n_ch], wrench=data[:, n_ch:n_ch + n_w], group=group, meta=meta,
                     temperature=temperature, axes=used.axes, sources=RowSources.of_file(path.name, line_nos))
        except DatasetFileError as exc:
            raise exc.located(f"{path}: ") from None
        return ds, tuple(names)


def _check_groups(ds: CalibrationDataset, where: str, column: str) -> None:
    """A group column given on purpose (``column``, or ``"file"``) must tell at least two groups apart (grouped
    folds hold out whole groups); ``where`` may name the argument as ``{columns.groups}``."""
    if ds.group is None:
        return
    values = np.unique(ds.group)
    if values.size < 2:
        labels = ds.meta.get("group_labels")
        shown = labels[0] if isinstance(labels, list) and labels else int(values[0]) if values.size else "none"
        raise DatasetFileError(f"{where}: every one of the {ds.n_samples} rows is in one group ({shown}); grouped "
                               "cross-validation holds out whole groups and needs at least two.", parameter=GROUPS,
                               value=column, fix="name the column that tells the poses or sessions apart, give a "
                               f"folder of several files, or drop {{{GROUPS}}}", settings={GROUPS: NO_SETTING})


def _npz_meta(value: np.ndarray, path: Path) -> dict:
    """The JSON object of an ``.npz``'s ``meta_json``."""
    if value.dtype.kind not in "US" or value.size != 1:
        raise DatasetFileError(f"{path}: meta_json is not a JSON text (dtype {value.dtype}); save it as "
                               "numpy.array(json.dumps(meta)).")
    return _parse_meta(str(value.reshape(())), str(path), "meta_json")


def _rows_first(a: np.ndarray) -> np.ndarray:
    """A 2-D array with the samples as rows: MATLAB users often store one row per component, so an array wider
    than tall is transposed (a calibration has more samples than channels or axes); a vector is one column."""
    if a.ndim == 1:
        return a[:, None]
    if a.ndim == 2 and a.shape[0] < a.shape[1]:
        return a.T
    return a


def _canonical(names) -> list[str]:
    """A file's column or member names as the reader takes them: a wrench alias as its axis (``Mx`` and ``tx``
    are ``Tx``), in sorted order (a folder's files may list them in any order)."""
    return sorted(canonical_wrench_name(n) or n for n in names)


def _oriented(raw: np.ndarray, wrench: np.ndarray, raw_whole: bool, wrench_whole: bool):
    """The raw and wrench arrays with the samples as rows. MATLAB users often store one row per component: a whole
    wrench variable of more than six columns and at most six rows is transposed (a wrench has 1 to 6 axes), and a
    whole variable is transposed where that makes the two arrays' rows agree."""
    axes = len(WRENCH_LABELS)
    if wrench_whole and wrench.shape[1] > axes >= wrench.shape[0]:
        wrench = wrench.T
    if raw_whole and raw.shape[0] != wrench.shape[0] and raw.shape[1] == wrench.shape[0]:
        raw = raw.T
    if wrench_whole and raw.shape[0] != wrench.shape[0] and wrench.shape[1] == raw.shape[0] and wrench.shape[0] <= axes:
        wrench = wrench.T
    return raw, wrench


def _vector(source: ArrayFile, name: str, what: str) -> np.ndarray:
    v = check_real_array(source.read(name), name, source.where, source.kind)
    if v.ndim == 2 and 1 in v.shape:
        v = v.ravel()
    if v.ndim != 1:
        raise DatasetFileError(f"{source.where}: {source.kind} {name!r} has shape {v.shape}; a {what} column must be "
                               "a vector.")
    return v


def _refuse_containers_only(source: ArrayFile, available: list[str]) -> None:
    """A .mat file holding only structs or cells (no numeric array): said as such, with the MATLAB fix; a column
    slice of a struct, the generic advice, would fail the same way."""
    classes = {n: source.entries[n][1] for n in available if n != "meta_json"}
    containers = {n: c for n, c in classes.items() if c in ("struct", "cell", "object")}
    if classes and len(containers) == len(classes):
        name, cls = next(iter(containers.items()))
        raise DatasetFileError(f"{source.where}: the file holds no numeric array, only "
                               f"{', '.join(f'{n} (a {c})' for n, c in containers.items())}; ftcal reads numeric "
                               f"arrays. Fix: in MATLAB, save the fields as variables: save(FILE, '-struct', "
                               f"'{name}', '-v7')" + ("." if cls == "struct" else f" (for a {cls}, its arrays one by one)."))


def _select(source: ArrayFile, names: tuple[str, ...] | None, default: str, vectors: list[str], what: str,
            option: str) -> tuple[np.ndarray, list[str], str | None]:
    """One (n, k) array from a file's arrays: one 2-D variable, a column slice of one, or a list of vectors.
    Returns the array, the names of its columns and the variable a slice came from."""
    where, kind = source.where, source.kind
    available = source.names()
    if names is None:
        if default in available:
            names = (default,)
        elif vectors:
            names = tuple(vectors)
        else:
            _refuse_containers_only(source, available)
            source.refuse_if_cut(f"{kind} {default!r} (or the {what} vectors)")
            raise DatasetFileError(
                f"{where}: no {kind} {default!r} holding the {what}; the file has "
                f"{', '.join(n for n in available if n != 'meta_json') or f'no {kind}s'}.", parameter=option,
                fix=f"name them with {{{option}}} NAME[,NAME...] (or a column slice of one array, e.g. "
                f"{{{option}}} 'data[:,0:8]')", settings={option: NO_SETTING})
    spec = parse_column_slice(names[0]) if len(names) == 1 else None
    base = spec[0] if spec is not None else None
    missing = [n for n in ([base] if spec is not None else names) if n not in available]
    if missing:
        source.refuse_missing(missing[0], option)
    if spec is not None or len(names) == 1:
        name = base if spec is not None else names[0]
        a = check_real_array(source.read(name), name, where, kind)
        if a.ndim > 2 or a.ndim == 0 or a.size == 0:
            what = "no values" if a.ndim and a.size == 0 else f"shape {a.shape}"
            raise DatasetFileError(f"{where}: {kind} {name!r} has {what}; expected (n_samples, k) with at least one "
                                   "sample. Fix: save the whole recording's array.")
        if spec is None:  # a whole variable: oriented beside the other array (_oriented)
            return (a[:, None] if a.ndim == 1 else a).astype(float), [name], None
        a = _rows_first(a).astype(float)
        picked = _slice_columns(spec, a.shape[1], where, option)
        return a[:, picked], [f"{name}[:,{k}]" for k in picked], name
    cols = [_vector(source, n, what) for n in names]
    if len({c.size for c in cols}) != 1:
        raise DatasetFileError(f"{where}: the {what} {kind}s have different lengths "
                               f"({', '.join(f'{n}: {c.size}' for n, c in zip(names, cols))}).")
    return np.column_stack(cols).astype(float), list(names), None


def _channel_vectors(source: ArrayFile) -> list[str]:
    """The vectors ``s0, s1, ...`` of an array file, in number order (the raw channels when no ``raw`` array)."""
    return sorted((n for n in source.names() if re.fullmatch(r"s[0-9]+", n)), key=lambda n: int(n[1:]))


def _refuse_non_finite(where: str, arrays: list[tuple[np.ndarray, list[str]]]) -> None:
    """NaN or inf in the arrays read from a ``.npz`` / ``.mat`` file, named by the array the user named (a whole
    array, a vector, or a column slice such as ``data[:,3]``; ``labels``: one per column, or one for them all) and
    the row (counted from 0)."""
    for values, labels in arrays:
        bad = np.argwhere(~np.isfinite(values))
        if bad.size:
            row, col = int(bad[0, 0]), int(bad[0, 1])
            name = labels[col] if len(labels) == values.shape[1] else labels[0]
            raise DatasetFileError(f"{where}: array {name!r}, row {row} (rows counted from 0): NaN or inf; "
                                   "remove or repair that row.")


def _dataset_from_arrays(cls, source: ArrayFile, columns: ColumnMap, meta: dict) -> CalibrationDataset:
    """The dataset the mapped arrays of ``source`` make (only those arrays are read)."""
    where = source.where
    available = source.names()
    found = named_axes(available, lambda first, n, axis: DatasetFileError(
        f"{where}: {source.kind}s {first!r} and {n!r} both read as the wrench axis {axis}; name the wrench with "
        "{wrench}.", parameter="wrench"))
    vector_wrench = [available[found[a]] for a in WRENCH_LABELS if a in found]
    wrench, wrench_labels, wrench_base = _select(source, columns.wrench, "wrench", vector_wrench, "wrench", "wrench")
    raw, raw_labels, raw_base = _select(source, columns.channels, "raw", _channel_vectors(source), "raw channels",
                                        "channels")
    raw, wrench = _oriented(raw, wrench, len(raw_labels) == 1 and raw_base is None,
                            len(wrench_labels) == 1 and wrench_base is None)
    if len(wrench_labels) == 1 and wrench_base is None and wrench.shape[1] > 1:
        wrench_labels = [f"{wrench_labels[0]}[:,{k}]" for k in range(wrench.shape[1])]
    both = [label for label in raw_labels if label in set(wrench_labels)]
    if raw_base is not None and both:
        raise DatasetFileError(
            f"{where}: {{channels}} {columns.channels[0]} and {{wrench}} {columns.wrench[0]} overlap ({both[0]} would "
            "be both).", parameter="channels", value=columns.channels[0],
            fix=f"give disjoint column slices of {raw_base!r}, e.g. {{channels}} {{wrench}}",
            settings={"channels": Placeholder(f"'{raw_base}[:,0:8]'"), "wrench": Placeholder(f"'{raw_base}[:,8:14]'")})
    if both:  # e.g. channels named by hand that include the wrench columns found by their names
        raise DatasetFileError(f"{where}: column {both[0]!r} is read both as a raw channel and as the wrench; the "
                               "reference wrench cannot be an input.", parameter="channels", value=both[0],
                               fix="name only the sensor's raw channels in {channels} (and the wrench in {wrench})",
                               settings={"channels": NO_SETTING, "wrench": NO_SETTING})
    if columns.wrench is None and columns.axes is None and "axes" in available and "wrench" in available:
        stored = source.read("axes")
        if stored.dtype.kind not in "US" or stored.ndim != 1 or stored.size != wrench.shape[1]:
            raise DatasetFileError(f"{where}: array 'axes' must name the {wrench.shape[1]} wrench axes as text, "
                                   "e.g. numpy.array(['Fx', 'Fy', 'Fz']).")
        axes = tuple(str(a) for a in stored)
    else:
        axes = columns.resolve_axes(wrench_labels, wrench.shape[1], where)
    order = np.argsort([WRENCH_LABELS.index(a) if a in WRENCH_LABELS else 99 for a in axes], kind="stable")
    wrench, axes = wrench[:, order], tuple(axes[k] for k in order)
    if raw.shape[0] != wrench.shape[0]:
        raise DatasetFileError(f"{where}: the raw channels have {raw.shape[0]} rows but the wrench has "
                               f"{wrench.shape[0]}; they must match (one row per sample).")
    _refuse_non_finite(where, [(raw, raw_labels), (wrench, wrench_labels)])
    group_name = columns.groups if columns.groups not in (None, "file") else "group"
    if columns.groups not in (None, "file") and group_name not in available:
        source.refuse_missing(group_name, GROUPS)
    extra = {key: _vector(source, name, key) for key, name in (("group", group_name), ("temperature", "temperature"))
             if name in available}
    try:
        return cls(raw=raw, wrench=wrench, meta=meta, axes=axes, **extra)
    except DatasetFileError as exc:
        raise exc.located(f"{where}: ") from None


def _csv_layout(lines: list[str], path) -> tuple[dict, int | None, list[int]]:
    """The ``# meta:`` object, the header's line number and the data lines' numbers (all 1-based) of a dataset CSV.

    Blank lines and ``#`` comment lines may stand anywhere (as in ``ftcal predict``'s input); one ``# meta:``
    comment at most, since a second would silently override the first.
    """
    meta: dict = {}
    meta_no = header_no = None
    data: list[int] = []
    for no, line in enumerate(lines, 1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            body = stripped[1:].strip()
            if body.startswith("meta:"):
                if meta_no is not None:
                    raise DatasetFileError(f"{path}: line {no}: a second '# meta:' comment (the first is line "
                                           f"{meta_no}); the second would override the first. Merge them into one "
                                           "JSON object on one line.")
                meta, meta_no = _parse_meta(body[len("meta:"):], f"{path}: line {no}"), no
            continue
        if header_no is None:
            header_no = no
        else:
            data.append(no)
    return meta, header_no, data




def read_channels(path: str | Path, channels: tuple[str, ...] | None = None) -> NDArray[np.float64]:
    """The raw channels of an ``.npz`` / ``.mat`` file: the array ``raw``, the vectors ``s0, s1, ...``, or the
    variables / column slice ``channels`` names (``("data[:,0:8]",)``); only those arrays are read, bounded.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> path = os.path.join(tempfile.mkdtemp(), "r.npz")
    >>> np.savez(path, data=np.arange(20.0).reshape(5, 4))  # 5 readings of 4 columns (more rows than columns)
    >>> read_channels(path, ("data[:,1:3]",)).tolist()
    [[1.0, 2.0], [5.0, 6.0], [9.0, 10.0], [13.0, 14.0], [17.0, 18.0]]

    An array wider than tall holds one row per column (MATLAB): it is read transposed.
    """
    if channels is not None:
        channels = ColumnMap(channels=channels).channels
    with ArrayFile(path) as source:
        raw, labels, base = _select(source, channels, "raw", _channel_vectors(source), "raw channels", "channels")
    if len(labels) == 1 and base is None:
        raw = _rows_first(raw)  # one row per channel (MATLAB)
    bad = np.argwhere(~np.isfinite(raw))
    if bad.size:
        raise DatasetFileError(f"{path}: raw row {int(bad[0, 0])} (rows counted from 0) holds NaN or inf; repair or "
                               "remove that row.")
    return raw
