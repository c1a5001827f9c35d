"""The calibration dataset: raw readings paired with reference wrenches, and its file formats.

File formats
------------
CSV (``.csv``)
    One header line, then one row per sample. Columns ``s0 ... s{N-1}`` hold
    the raw channels (any unit the sensor gives: counts, mV, ...), then
    ``Fx, Fy, Fz`` in [N] and ``Tx, Ty, Tz`` in [N·m]; an optional ``group``
    column holds an integer label per row (a load configuration, a sphere,
    ...), an optional ``temperature`` column the sensor temperature [deg C]. Blank lines and lines starting with ``#`` are skipped
    anywhere; one comment ``# meta: {...}`` carries JSON metadata. Errors name
    the file's 1-based line and the column.
NumPy archive (``.npz``)
    Arrays ``raw`` (n, N), ``wrench`` (n, 6), optional ``group`` (n,), and
    ``meta_json`` (a JSON string). Read with ``allow_pickle=False``.
MATLAB (``.mat``, v4-v7, read only)
    Variables ``raw`` (n, N) and ``wrench`` (n, 6) (or one row per component),
    optional ``group`` and ``temperature``; or any variables named by a
    :class:`~ftcal.io.ColumnMap`.

Other layouts and units are read through a :class:`~ftcal.io.ColumnMap`
(``CalibrationDataset.load(path, columns=ColumnMap(...))``, the CLI's
``--channels``, ``--wrench``, ``--force-unit``, ``--torque-unit``); torque
columns may be named ``Mx, My, Mz`` as well as ``Tx, Ty, Tz``.
"""

from __future__ import annotations

import json
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..core._columns import check_plain_fields, csv_rows, is_number, read_header
from ..core._exceptions import CalibrationInputError, DatasetFileError
from ..core._files import atomic_output, describe_file_start
from ..core._temperature import TemperatureValueError, check_temperature
from ..core._wrench import MIN_CHANNELS, WRENCH_LABELS
from ._readers import (ColumnMap, canonical_wrench_name, check_real_array, read_mat_arrays,
                       select_arrays, temperature_message)

__all__ = ["CalibrationDataset"]

_CSV_LAYOUT = "s0,...,s{N-1},Fx,Fy,Fz,Tx,Ty,Tz[,group][,temperature]"


def _parse_meta(text: str, where: str) -> dict:
    """The JSON object of a ``# meta:`` comment (an object, not a list or a number)."""
    try:
        meta = json.loads(text)
    except (json.JSONDecodeError, RecursionError) as exc:
        raise DatasetFileError(f"{where}: bad JSON in the meta comment ({str(exc)[:80]}).") from None
    if not isinstance(meta, dict):
        raise DatasetFileError(
            f"{where}: the meta comment holds a JSON {type(meta).__name__}; it must be a JSON object "
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


def _exact_group_column(body_lines: list[str], column: int, line_nos: list[int], path) -> NDArray:
    """The ``group`` column of CSV data lines as exact int64 labels (float64 merges labels above 2^53 and turns
    those above 2^63 into -2^63); a label that is no integer is refused with its line."""
    labels = []
    for no, line in zip(line_nos, body_lines):
        text = line.split(",")[column].strip()
        if _INTEGER.fullmatch(text):
            value = int(text)
        else:
            number = float(text)
            if not (np.isfinite(number) and number == round(number)):
                raise DatasetFileError(f"{path}: line {no}, column group: {text} is not an integer label. Fix: "
                                       "number the groups 0, 1, 2, ...")
            value = int(number)
        if not -(2**63) <= value < 2**63:
            raise DatasetFileError(f"{path}: line {no}: group {text} is beyond the 64-bit integer labels ftcal "
                                   "stores. Fix: number the groups 0, 1, 2, ...")
        labels.append(value)
    return np.array(labels, dtype=np.int64)


_INTEGER = re.compile(r"[+-]?[0-9]+")


def _mapped_names(fields: list[str], columns: ColumnMap, where: str) -> list[str]:
    """Header names with the mapped columns renamed to ftcal's (``s0..``, ``Fx..Tz``) and aliases resolved.

    Unmapped columns that would clash with a mapped name are renamed out of the way (they are ignored).
    """
    names = list(fields)
    renamed: dict[int, str] = {}
    for mapping, targets, what in ((columns.channels, None, "--channels"), (columns.wrench, WRENCH_LABELS, "--wrench")):
        if mapping is None:
            continue
        if len(mapping) == 1 and targets is not None:
            raise DatasetFileError(f"{where}: --wrench names one column; a CSV needs the six Fx,Fy,Fz,Tx,Ty,Tz columns.")
        for k, name in enumerate(mapping):
            if name not in names:
                raise DatasetFileError(f"{where}: {what} names column {name!r}, which the header lacks; the header "
                                       f"has {', '.join(names)}.")
            renamed[names.index(name)] = f"s{k}" if targets is None else targets[k]
    out = []
    for i, name in enumerate(names):
        if i in renamed:
            out.append(renamed[i])
        elif columns.wrench is None and canonical_wrench_name(name) is not None:
            out.append(canonical_wrench_name(name))  # Mx -> Tx, fx -> Fx
        elif renamed and (name in renamed.values() or (name[:1] == "s" and name[1:].isdigit())):
            out.append(f"_unmapped_{i}")  # an unmapped column that would clash with a mapped one: ignored
        else:
            out.append(name)
    return out


@dataclass
class CalibrationDataset:
    """Raw readings and the reference wrenches they were recorded under.

    Parameters
    ----------
    raw : ndarray of shape (n_samples, n_channels)
        Raw sensor readings, one row per sample.
    wrench : ndarray of shape (n_samples, 6)
        Reference wrench ``[Fx, Fy, Fz, Tx, Ty, Tz]`` in [N] and [N·m].
    group : ndarray of shape (n_samples,), optional
        Integer label per sample (load configuration, sphere index, ...), for
        grouped splits such as ``GroupKFold``.
    meta : dict
        JSON-serialisable facts about where the data came from.
    temperature : ndarray of shape (n_samples,), optional
        Sensor temperature [deg C] per sample (for
        :class:`~ftcal.TemperatureCompensatedCalibrator`: ``features(temperature=True)``).

    Examples
    --------
    >>> import numpy as np
    >>> ds = CalibrationDataset(raw=np.ones((4, 6)), wrench=np.zeros((4, 6)))
    >>> ds.n_samples, ds.n_channels
    (4, 6)
    """

    raw: NDArray[np.float64]
    wrench: NDArray[np.float64]
    group: NDArray[np.int64] | None = None
    meta: dict = field(default_factory=dict)
    temperature: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        for name in ("raw", "wrench"):
            value = np.asarray(getattr(self, name))
            if np.iscomplexobj(value):
                raise DatasetFileError(f"{name} holds complex numbers (shape {value.shape}); readings and wrenches "
                                       "are real. Fix: pass the real part explicitly if that is what you mean.")
            setattr(self, name, np.asarray(value, dtype=float))
        if self.raw.ndim != 2:
            raise DatasetFileError(f"raw must be 2-D (n_samples, n_channels); got shape {self.raw.shape}.")
        if self.raw.shape[1] < MIN_CHANNELS:
            raise DatasetFileError(
                f"raw has {self.raw.shape[1]} channel(s) (shape {self.raw.shape}); a 6-axis calibration needs at "
                f"least {MIN_CHANNELS} raw channels. Fix: one column per strain-gauge channel."
            )
        if self.wrench.ndim != 2 or self.wrench.shape[1] != 6:
            raise DatasetFileError(f"wrench must have shape (n_samples, 6); got shape {self.wrench.shape}.")
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

    @property
    def n_samples(self) -> int:
        """Number of rows."""
        return int(self.raw.shape[0])

    @property
    def n_channels(self) -> int:
        """Number of raw channels."""
        return int(self.raw.shape[1])

    def subset(self, index: NDArray) -> "CalibrationDataset":
        """The rows selected by ``index`` (a boolean mask or integer indices), as a new dataset."""
        return CalibrationDataset(
            raw=self.raw[index],
            wrench=self.wrench[index],
            group=None if self.group is None else self.group[index],
            meta=dict(self.meta),
            temperature=None if self.temperature is None else self.temperature[index],
        )

    def features(self, temperature: bool = False) -> NDArray[np.float64]:
        """The calibrators' ``X``: the raw channels, with the temperature [deg C] as a last column if asked."""
        if not temperature:
            return self.raw
        if self.temperature is None:
            raise DatasetFileError("this dataset has no temperature column; record the sensor temperature "
                                   "(a 'temperature' column in deg C) to compensate thermal drift.")
        return np.column_stack([self.raw, self.temperature])

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
        An existing ``path`` raises :class:`~ftcal.DatasetFileError` unless
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
                arrays = {"raw": self.raw, "wrench": self.wrench, "meta_json": np.array(meta_json)}
                if self.group is not None:
                    arrays["group"] = self.group
                if self.temperature is not None:
                    arrays["temperature"] = self.temperature
                with open(tmp, "wb") as fh:
                    np.savez(fh, **arrays)
            else:
                cols = [f"s{i}" for i in range(self.n_channels)] + list(WRENCH_LABELS)
                columns = [self.raw, self.wrench]
                if self.group is not None:  # exact integer labels (Python ints, never through float64)
                    cols.append("group")
                    columns.append(self.group[:, None].astype(object))
                if self.temperature is not None:
                    cols.append("temperature")
                    columns.append(self.temperature[:, None])
                with open(tmp, "w", encoding="utf-8", newline="\n") as fh:
                    fh.write(f"# meta: {meta_json}\n" + ",".join(cols) + "\n")
                    fh.writelines(csv_rows(*columns))
        return path

    @classmethod
    def load(cls, path: str | Path, *, columns: ColumnMap | None = None) -> "CalibrationDataset":
        """Read a dataset: ``.csv`` / ``.npz`` as written by :meth:`save` (or by hand), or a MATLAB ``.mat``.

        Parameters
        ----------
        path : path
            The file; its suffix chooses the reader.
        columns : ColumnMap, optional
            Which columns / variables hold the raw channels and the wrench, and the
            units of the file's forces and torques (converted to [N] and [N·m]).
        """
        path = Path(path)
        columns = ColumnMap() if columns is None else columns
        if not path.is_file():
            raise DatasetFileError(f"{path}: no such dataset file.")
        readers = {".npz": cls._load_npz, ".csv": cls._load_csv, ".mat": cls._load_mat}
        reader = readers.get(path.suffix.lower())
        if reader is None:
            raise DatasetFileError(f"{path}: unknown dataset suffix {path.suffix!r}; use .csv, .npz or .mat.")
        ds = reader(path, columns)
        if not columns.is_default:
            ds.wrench = columns.to_si(ds.wrench)
            ds.meta = {**ds.meta, **columns.units_meta()}
        return ds

    @classmethod
    def _from_arrays(cls, path: Path, arrays: dict, columns: ColumnMap, meta: dict,
                     kind: str = "variable") -> "CalibrationDataset":
        """A dataset from named arrays (``.npz``, ``.mat``), selected by ``columns``."""
        where = str(path)
        vector_wrench = []
        for label in WRENCH_LABELS:
            found = [n for n in arrays if canonical_wrench_name(n) == label]
            vector_wrench.append(found[0] if len(found) == 1 else label)
        channel_vectors = sorted((n for n in arrays if n[:1] == "s" and n[1:].isdigit()), key=lambda n: int(n[1:]))
        wrench = select_arrays(arrays, columns.wrench, "wrench", vector_wrench, "wrench", where, 6, kind)
        raw = select_arrays(arrays, columns.channels, "raw", channel_vectors, "raw channels", where, None, kind)
        if raw.shape[0] != wrench.shape[0] and raw.shape[1] == wrench.shape[0]:
            raw = raw.T
        extra = {}
        for name in ("group", "temperature"):
            if name in arrays:
                value = check_real_array(arrays[name], name, where, kind)
                extra[name] = value.ravel() if value.ndim == 2 and 1 in value.shape else value
        try:
            ds = cls(raw=raw, wrench=wrench, meta=meta, **extra)
        except DatasetFileError as exc:
            raise DatasetFileError(f"{path}: {exc}") from None
        ds._check_finite(path)
        return ds

    @classmethod
    def _load_mat(cls, path: Path, columns: ColumnMap) -> "CalibrationDataset":
        return cls._from_arrays(path, read_mat_arrays(path), columns, {"source_file": path.name})

    @classmethod
    def _load_npz(cls, path: Path, columns: ColumnMap) -> "CalibrationDataset":
        import zipfile

        if not zipfile.is_zipfile(path):  # np.load would try it as a pickle and advise allow_pickle=True
            raise DatasetFileError(f"{path}: not an .npz (zip) archive: {describe_file_start(path)}. A dataset .npz holds "
                                   "the arrays raw and wrench (numpy.savez); a .csv dataset must keep its .csv suffix.")
        try:
            with np.load(path, allow_pickle=False) as z:
                arrays = {}
                for name in z.files:
                    try:
                        arrays[name] = z[name]
                    except ValueError as exc:
                        if "pickle" not in str(exc):
                            raise
                        raise DatasetFileError(f"{path}: array {name!r} holds Python objects (a pickle), which ftcal "
                                               "never loads; save numeric arrays (numpy.savez(path, raw=..., "
                                               "wrench=...)).") from None
        except DatasetFileError:
            raise
        except Exception as exc:  # zipfile/numpy errors on truncated or foreign files
            raise DatasetFileError(f"{path}: not a readable .npz dataset ({exc}).") from exc
        meta_json = arrays.pop("meta_json", None)
        try:
            meta = json.loads(str(meta_json)) if meta_json is not None else {}
        except (json.JSONDecodeError, RecursionError) as exc:
            raise DatasetFileError(f"{path}: bad JSON in meta_json ({str(exc)[:80]}).") from None
        if not isinstance(meta, dict):
            raise DatasetFileError(f"{path}: meta_json holds a JSON {type(meta).__name__}; it must be an object.")
        return cls._from_arrays(path, arrays, columns, meta, kind="array")

    @classmethod
    def _load_csv(cls, path: Path, columns: ColumnMap) -> "CalibrationDataset":
        try:
            # utf-8-sig: a byte-order mark (spreadsheet exports) is not part of the first column's name
            lines = path.read_text(encoding="utf-8-sig").splitlines()
        except UnicodeDecodeError as exc:
            raise DatasetFileError(f"{path}: not a UTF-8 text file ({exc}).") from None
        meta, header_no, line_nos = _csv_layout(lines, path)
        if header_no is None:
            raise DatasetFileError(f"{path}: no header line; expected {_CSV_LAYOUT}.")
        where = f"{path}: line {header_no}"
        fields = [f.strip() for f in lines[header_no - 1].split(",")]
        if all(f and is_number(f) for f in fields):
            raise DatasetFileError(
                f"{where}: the file has no header: its first line holds numbers, not column names. Fix: add a "
                f"header line naming the columns ({_CSV_LAYOUT}), or name them with --channels/--wrench after adding "
                "one."
            )
        mapped = _mapped_names(fields, columns, where)
        header = read_header(
            mapped, where=where, error=DatasetFileError,
            required=WRENCH_LABELS, optional=("group", "temperature"), expected=_CSV_LAYOUT,
            allow_other=not columns.is_default and (columns.channels is not None or columns.wrench is not None),
        )
        names = [f.lstrip("\ufeff").strip() for f in fields]
        body_lines = [lines[no - 1] for no in line_nos]
        width = len(header.names)
        for no, line in zip(line_nos, body_lines):  # numpy's own message counts data rows, not the file's lines
            if line.count(",") + 1 != width:
                raise DatasetFileError(f"{path}: line {no}: {line.count(',') + 1} values but the header names "
                                       f"{width} columns; repair or remove that line.")
            # `1_000`, `nan`: float() and numpy take forms no logger writes
            check_plain_fields(line, f"{path}: line {no}", names, DatasetFileError, quick=True)
        if not body_lines:
            raise DatasetFileError(f"{path}: no data rows after the header.")
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                data = np.loadtxt(body_lines, delimiter=",", ndmin=2, comments=None)
        except ValueError as exc:
            for no, line in zip(line_nos, body_lines):  # name the file's line and the column, not numpy's row
                check_plain_fields(line, f"{path}: line {no}", names, DatasetFileError)
            raise DatasetFileError(f"{path}: unreadable number ({' '.join(str(exc).split())[:100]}).") from None
        used = header.numbered("s") + [header.index[c] for c in WRENCH_LABELS]
        bad = np.argwhere(~np.isfinite(data[:, used]))
        if bad.size:
            row, col = int(bad[0, 0]), used[int(bad[0, 1])]
            raise DatasetFileError(f"{path}: line {line_nos[row]}, column {names[col]}: "
                                   f"{body_lines[row].split(',')[col].strip()!r} is NaN or inf (or beyond float64); "
                                   "remove or repair that line.")
        raw = data[:, header.numbered("s")]
        wrench = data[:, [header.index[c] for c in WRENCH_LABELS]]
        group = _exact_group_column(body_lines, header.index["group"], line_nos, path) if "group" in header \
            else None
        temperature = None
        if "temperature" in header:
            try:
                temperature = check_temperature(data[:, header.index["temperature"]], len(line_nos))
            except TemperatureValueError as exc:
                if exc.row is None:
                    raise DatasetFileError(f"{path}: {exc}") from None
                raise DatasetFileError(temperature_message(exc, path, line_nos[exc.row])) from None
        try:
            ds = cls(raw=raw, wrench=wrench, group=group, meta=meta, temperature=temperature)
        except DatasetFileError as exc:
            raise DatasetFileError(f"{path}: {exc}") from None
        return ds

    def _check_finite(self, path: Path) -> None:
        """NaN or inf in the arrays of a ``.npz`` / ``.mat`` file, named by array and row (counted from 0)."""
        for name, arr in (("raw", self.raw), ("wrench", self.wrench)):
            bad = np.argwhere(~np.isfinite(arr))
            if bad.size:
                row = int(bad[0, 0])
                raise DatasetFileError(f"{path}: array {name!r}, row {row} (rows counted from 0): NaN or inf; "
                                       "remove or repair that row.")



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


