"""Log files of recorded calibration runs: the layout, a writer and a validating reader.

Layout (CSV, UTF-8)
-------------------
Comment lines starting with ``#`` come first, as ``# key: value``:

=================  ========  ==================================================
key                required  meaning
=================  ========  ==================================================
``ftcal-run-log``  no        format version, ``1``
``time_unit``      yes       unit of ``timestamp``: ``s`` or ``ms``
``joint_unit``     yes       unit of ``q1..qJ``: ``rad`` or ``deg``
``raw_unit``       no        unit of the raw channels (free text: counts, mV)
``load_mass_kg``   no        mass of the external load of the load rows [kg]
``robot``          no        robot name or URDF the joint angles belong to
``sensor_frame``   no        the frame the sensor sits at
``meta``           no        JSON object with anything else
=================  ========  ==================================================

Then one header line and one row per sample with these columns (any order)::

    timestamp,run,config,pose,q1,...,qJ,s0,...,s{N-1}

* ``timestamp``: time of the sample, in ``time_unit``.
* ``run``: ``load`` (external load attached) or ``no-load``.
* ``config``: integer load configuration id (thesis Table I: 0-6). A no-load
  row carries the id of the configuration whose load run it belongs to, or
  ``-1`` for a no-load run shared by every configuration.
* ``pose``: integer index of the commanded pose on the sphere; a load row and
  a no-load row with the same ``config`` (or ``-1``) and ``pose`` are a pair.
  Several rows with the same ``run``, ``config`` and ``pose`` are samples of
  one static pose and are averaged.
* ``q1..qJ``: measured joint angles, ``J`` >= 1 contiguous columns.
* ``s0..s{N-1}``: raw sensor channels, ``N`` >= 3 contiguous columns.

Runs may be split over several files in any way (one file per run is usual).
:func:`read_run_log` checks each file; pairing across files happens in
:func:`ftcal.experiment.prepare_dataset`. Every error is a :class:`ftcal.core.LogFormatError`
naming the file and the line.
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._columns import parse_number, read_header
from ..core._exceptions import CalibrationInputError, LogFormatError
from ..core._memory import check_allocation
from ..core._temperature import check_temperature
from ..core._wrench import MAX_LOAD_MASS_KG
from ._readers import _INTEGER, check_separator, checked_temperature, read_utf8_text

__all__ = ["RunLog", "read_run_log", "write_run_log", "run_log_files", "RUN_KINDS", "SHARED_NO_LOAD_CONFIG"]

#: Allowed values of the ``run`` column.
RUN_KINDS: tuple[str, str] = ("load", "no-load")
#: ``config`` value of a no-load run shared by every load configuration.
SHARED_NO_LOAD_CONFIG: int = -1
#: The run-log format version this ftcal writes and reads (``# ftcal-run-log: 1``).
LOG_FORMAT_VERSION = 1

_TIME_UNITS = {"s": 1.0, "ms": 1e-3}
_JOINT_UNITS = {"rad": 1.0, "deg": np.pi / 180.0}
_FIXED_COLUMNS = ("timestamp", "run", "config", "pose")
# Joint values beyond this magnitude in a file that says "rad" are almost surely degrees.
_MAX_PLAUSIBLE_RAD = 2 * np.pi + 1e-6
#: Memory of a log read into Python strings, per byte of the file (the text, its lines, the rows' fields).
_TEXT_MEMORY_FACTOR = 8


@dataclass
class RunLog:
    """The rows of one log file, checked and converted to SI units.

    Attributes
    ----------
    path : pathlib.Path
    timestamp : ndarray of shape (n,)
        [s].
    run_kind : ndarray of shape (n,)
        ``"load"`` or ``"no-load"`` per row.
    config, pose : ndarray of shape (n,), int
    q : ndarray of shape (n, n_joints)
        Joint angles [rad].
    raw : ndarray of shape (n, n_channels)
        Raw channels, in ``raw_unit``.
    line : ndarray of shape (n,), int
        1-based line number of each row in the file (for error messages).
    raw_unit : str
    load_mass : float or None
        [kg], from the ``load_mass_kg`` comment.
    robot, sensor_frame : str or None
    meta : dict
    temperature : ndarray of shape (n,) or None
        [deg C].
    rotation : ndarray of shape (n, 3, 3) or None
        The sensor's orientation (sensor to base) of each row when the recording carries it (a ROS bag read with
        ``/tf``) instead of joint angles for the robot model (``q`` then has no columns).
    """

    path: Path
    timestamp: NDArray[np.float64]
    run_kind: NDArray[np.str_]
    config: NDArray[np.int64]
    pose: NDArray[np.int64]
    q: NDArray[np.float64]
    raw: NDArray[np.float64]
    line: NDArray[np.int64]
    raw_unit: str = "counts"
    load_mass: float | None = None
    robot: str | None = None
    sensor_frame: str | None = None
    meta: dict = field(default_factory=dict)
    temperature: NDArray[np.float64] | None = None
    rotation: NDArray[np.float64] | None = None

    @property
    def n_rows(self) -> int:
        """Number of sample rows."""
        return int(self.q.shape[0])

    @property
    def n_joints(self) -> int:
        """Number of joint columns."""
        return int(self.q.shape[1])

    @property
    def n_channels(self) -> int:
        """Number of raw channels."""
        return int(self.raw.shape[1])


def _parse_comments(path: Path, lines: list[str]) -> tuple[dict[str, str], int, dict[str, int]]:
    """The ``# key: value`` comments before the header, their count, and the (1-based) line of each key."""
    info: dict[str, str] = {}
    where: dict[str, int] = {}
    n = 0
    for text in lines:
        if not text.startswith("#"):
            break
        n += 1
        body = text[1:].strip()
        if ":" in body:
            key, _, value = body.partition(":")
            info[key.strip()] = value.strip()
            where[key.strip()] = n
    return info, n, where


def run_log_files(folder: str | Path) -> list[Path]:
    """The run logs of a folder, in name order: its ``*.csv`` files, not hidden ones (a killed run's temporaries,
    ``.NAME.XXXX.partial.csv``) nor sub-folders (a run that lost a race keeps its files in one).

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> for name in ("config1_load.csv", "config0_load.csv", ".config0_load.x1.partial.csv", "notes.txt"):
    ...     _ = (folder / name).write_text("")
    >>> [p.name for p in run_log_files(folder)]
    ['config0_load.csv', 'config1_load.csv']
    """
    return sorted(p for p in Path(folder).glob("*.csv") if not p.name.startswith(".") and p.is_file())


def read_text_lines(path: Path, what: str, fix: str) -> list[str]:
    """The lines of the CSV text file ``path`` (a ``what``: "run log", "pose file"), its size checked first
    (``fix`` says how to make it smaller); a missing file or one that is not UTF-8 is a :class:`LogFormatError`
    naming the line."""
    if not path.is_file():
        raise LogFormatError(f"{path}: no such {what}.")
    # the text, its lines and each row's fields as Python strings take several times the file's size
    check_allocation(_TEXT_MEMORY_FACTOR * path.stat().st_size, f"reading the {what} {path}", fix)
    return read_utf8_text(path, f"a {what} is a CSV text file", LogFormatError).splitlines()


def text_rows(lines: list[str], first: int) -> list[tuple[int, list[str]]]:
    """The CSV rows of ``lines[first:]`` as ``(1-based line, fields without their spaces)``, blank rows skipped."""
    return [(first + 1 + k, [f.strip() for f in fields]) for k, fields in enumerate(csv.reader(lines[first:]))
            if any(f.strip() for f in fields)]


def read_run_log(path: str | Path, *, n_channels: int | None = None, n_joints: int | None = None) -> RunLog:
    """Read and validate one run log (layout in the module docstring).

    Parameters
    ----------
    path : str or path
        The ``.csv`` file.
    n_channels : int, optional
        Expected number of raw channels; a file with another count is an error.
    n_joints : int, optional
        Expected number of joint columns (the robot's).

    Returns
    -------
    RunLog

    Raises
    ------
    LogFormatError
        Missing file, unit comment or column; unknown unit; a row with the wrong
        number of fields, a non-number, NaN or inf, an unknown run kind, a
        non-integer config or pose, joint angles that look like degrees in a
        ``rad`` file, or an unexpected channel/joint count. The message names the
        file and the line.

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "run.csv"
    >>> _ = write_run_log(p, timestamp=[0.0, 1.0], run_kind=["no-load", "load"], config=[0, 0],
    ...                   pose=[0, 0], q=np.zeros((2, 7)), raw=np.ones((2, 6)), load_mass=2.0)
    >>> log = read_run_log(p, n_channels=6)
    >>> log.n_rows, log.n_joints, log.load_mass, log.run_kind.tolist()
    (2, 7, 2.0, ['no-load', 'load'])
    """
    path = Path(path)
    text_lines = read_text_lines(path, "log file", "split the log into several files (one per run or configuration)")
    info, n_comment, info_line = _parse_comments(path, text_lines)
    units = _log_units(path, info, info_line, text_lines, n_comment)
    head_line = n_comment + 1
    check_separator(text_lines[n_comment].split(","), f"{path}: line {head_line}", error=LogFormatError,
                    next_row=text_lines[n_comment + 1] if n_comment + 1 < len(text_lines) else "")
    header, q_cols, s_cols = _log_columns(path, text_lines[n_comment], head_line, n_channels, n_joints)
    rows = text_rows(text_lines, head_line)
    for lineno, fields in rows:
        if len(fields) != len(header):
            raise LogFormatError(f"{path}: line {lineno}: {len(fields)} fields but the header names {len(header)}.")
    if not rows:
        raise LogFormatError(f"{path}: no data rows after the header (line {head_line}).")
    log = _log_rows(path, rows, {c: i for i, c in enumerate(header)}, q_cols, s_cols, units)
    _check_log_values(log, q_cols, s_cols, radians=units["joint_unit"] == 1.0)
    log.q *= units["joint_unit"]
    log.raw_unit, log.robot, log.sensor_frame = info.get("raw_unit", "counts"), info.get("robot"), \
        info.get("sensor_frame")
    log.load_mass, log.meta = _log_mass_and_meta(path, info, info_line)
    if log.temperature is not None:
        checked_temperature(log.temperature, path, log.line, LogFormatError)
    return log


def _log_units(path: Path, info: dict[str, str], info_line: dict[str, int], text_lines: list[str],
               n_comment: int) -> dict[str, float]:
    """The format version checked, a header line after the comments, and the scale of the time and joint units."""
    version = info.get("ftcal-run-log")
    if version is not None and version != str(LOG_FORMAT_VERSION):
        raise LogFormatError(f"{path}: line {info_line['ftcal-run-log']}: run-log format version {version!r}; this "
                             f"ftcal reads version {LOG_FORMAT_VERSION} (was the log written by a newer ftcal? "
                             "update ftcal).")
    if n_comment >= len(text_lines) or not text_lines[n_comment].strip():
        raise LogFormatError(f"{path}: line {n_comment + 1}: no header line; expected "
                             "timestamp,run,config,pose,q1,...,qJ,s0,...,s{N-1}.")
    units = {}
    for key, table in (("time_unit", _TIME_UNITS), ("joint_unit", _JOINT_UNITS)):
        if key not in info:
            raise LogFormatError(f"{path}: missing comment '# {key}: <unit>' before the header "
                                 f"(allowed units: {', '.join(table)}).")
        if info[key] not in table:
            raise LogFormatError(f"{path}: unknown {key} {info[key]!r}; use one of {', '.join(table)}.")
        units[key] = table[info[key]]
    return units


def _log_columns(path: Path, line: str, head_line: int, n_channels: int | None,
                 n_joints: int | None) -> tuple[list[str], list[str], list[str]]:
    """The header's names, joint columns and raw channel columns, their counts checked."""
    head = read_header(
        line.split(","), where=f"{path}: line {head_line}", error=LogFormatError,
        required=_FIXED_COLUMNS, numbered=(("q", 1, "joint"), ("s", 0, "raw channel")), allow_other=True,
        expected="timestamp,run,config,pose,q1,...,qJ,s0,...,s{N-1}",
    )
    header = list(head.names)
    q_cols = [header[i] for i in head.numbered("q")]
    s_cols = [header[i] for i in head.numbered("s")]
    if len(s_cols) < 3:
        raise LogFormatError(f"{path}: line {head_line}: {len(s_cols)} raw channels; a sensor needs at least 3.")
    if n_channels is not None and len(s_cols) != n_channels:
        raise LogFormatError(f"{path}: line {head_line}: {len(s_cols)} raw channels (s0..s{len(s_cols) - 1}) "
                             f"but {n_channels} expected; is this the right sensor's log?")
    if n_joints is not None and len(q_cols) != n_joints:
        raise LogFormatError(f"{path}: line {head_line}: {len(q_cols)} joint columns but the robot has "
                             f"{n_joints} joints.")
    return header, q_cols, s_cols


def _log_rows(path: Path, rows: list[tuple[int, list[str]]], col: dict[str, int], q_cols: list[str],
              s_cols: list[str], units: dict[str, float]) -> RunLog:
    """The rows' values (every field checked, named by its line and column), the time in [s], the joints as
    written."""

    def number(lineno: int, fields: list[str], name: str) -> float:
        text = fields[col[name]]
        value = parse_number(text, f"{path}: line {lineno}: column {name}", LogFormatError)
        if not np.isfinite(value):
            raise LogFormatError(f"{path}: line {lineno}: column {name} is {text!r} (NaN or inf); "
                                 "repair or remove that row.")
        return value

    def integer(lineno: int, fields: list[str], name: str) -> int:
        # parsed exactly (never through float64, which merges 100000000000000001 with ...000), and within int64
        text = fields[col[name]].strip()
        if _INTEGER.fullmatch(text):
            value = int(text)
        else:
            number_value = number(lineno, fields, name)
            if number_value != int(number_value) or abs(number_value) > 2**53:
                raise LogFormatError(f"{path}: line {lineno}: column {name} must be an integer; got {text!r}.")
            value = int(number_value)
        if not -(2**63) <= value < 2**63:
            raise LogFormatError(f"{path}: line {lineno}: column {name} is {text}, beyond the 64-bit integers "
                                 "ftcal stores; number the configurations and poses 0, 1, 2, ...")
        return value

    n = len(rows)
    ts, kind = np.empty(n), np.empty(n, dtype=object)
    config, pose = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
    line = np.array([lineno for lineno, _ in rows], dtype=np.int64)
    q, raw = np.empty((n, len(q_cols))), np.empty((n, len(s_cols)))
    temp = np.empty(n) if "temperature" in col else None
    for i, (lineno, fields) in enumerate(rows):
        kind[i] = fields[col["run"]].lower()
        if kind[i] not in RUN_KINDS:
            raise LogFormatError(f"{path}: line {lineno}: run is {fields[col['run']]!r}; use 'load' or 'no-load'.")
        ts[i] = number(lineno, fields, "timestamp") * units["time_unit"]
        config[i] = integer(lineno, fields, "config")
        pose[i] = integer(lineno, fields, "pose")
        if config[i] < SHARED_NO_LOAD_CONFIG or (kind[i] == "load" and config[i] < 0):
            raise LogFormatError(f"{path}: line {lineno}: config {config[i]} is invalid; load rows need an id >= 0, "
                                 "no-load rows an id >= 0 or -1 (shared).")
        if pose[i] < 0:
            raise LogFormatError(f"{path}: line {lineno}: pose {pose[i]} is negative.")
        q[i] = [number(lineno, fields, c) for c in q_cols]
        raw[i] = [number(lineno, fields, c) for c in s_cols]
        if temp is not None:
            temp[i] = number(lineno, fields, "temperature")
    return RunLog(path=path, timestamp=ts, run_kind=kind.astype(str), config=config, pose=pose, q=q, raw=raw,
                  line=line, temperature=temp)


def _check_log_values(log: RunLog, q_cols: list[str], s_cols: list[str], radians: bool) -> None:
    """Refused: joint angles beyond 2*pi in a log in radians (degrees?), raw values a calibration cannot square;
    each named by its line."""
    path, line, q, raw = log.path, log.line, log.q, log.raw
    if radians:
        bad = np.argwhere(np.abs(q) > _MAX_PLAUSIBLE_RAD)
        if bad.size:
            r, c = bad[0]
            raise LogFormatError(f"{path}: line {line[r]}: {q_cols[c]} = {q[r, c]:g} exceeds 2*pi although the file "
                                 "declares '# joint_unit: rad'; were the angles logged in degrees? "
                                 "Then declare '# joint_unit: deg'.")
    from ..core._validation import MAX_TRAINING_MAGNITUDE  # the bound `ftcal fit` refuses the dataset by

    big = np.argwhere(np.abs(raw) > MAX_TRAINING_MAGNITUDE)
    if big.size:
        r, c = (int(v) for v in big[0])
        raise LogFormatError(f"{path}: line {line[r]}: column {s_cols[c]} is {raw[r, c]:g}, beyond the "
                             f"{MAX_TRAINING_MAGNITUDE:g} a calibration can square without overflow; check the units "
                             "and that line.")


def _log_mass_and_meta(path: Path, info: dict[str, str], info_line: dict[str, int]) -> tuple[float | None, dict]:
    """The ``load_mass_kg`` [kg] and ``meta`` comments, checked."""
    mass = None
    if "load_mass_kg" in info:
        try:
            mass = float(info["load_mass_kg"])
        except ValueError:
            mass = float("nan")
        if not np.isfinite(mass) or mass <= 0 or mass > MAX_LOAD_MASS_KG:
            # the mass of the load rows' external load: zero would be no load (prepare_dataset refuses it), and a
            # log without load rows leaves the comment out
            raise LogFormatError(f"{path}: line {info_line['load_mass_kg']}: load_mass_kg is "
                                 f"{info['load_mass_kg']!r}; it must be the positive mass of the load in kg, at most "
                                 f"{MAX_LOAD_MASS_KG:g} (leave the comment out of a log without load).")
    meta: dict = {}
    if "meta" in info:
        try:
            meta = json.loads(info["meta"])
        except json.JSONDecodeError as exc:
            raise LogFormatError(f"{path}: the '# meta:' comment is not valid JSON ({exc}).") from exc
    return mass, meta


def write_run_log(path: str | Path, *, timestamp: ArrayLike, run_kind: ArrayLike, config: ArrayLike, pose: ArrayLike,
                  q: ArrayLike, raw: ArrayLike, raw_unit: str = "counts", load_mass: float | None = None,
                  robot: str | None = None, sensor_frame: str | None = None, meta: dict | None = None,
                  overwrite: bool = False, temperature: ArrayLike | None = None) -> Path:
    """Write samples as a run log (timestamps [s], joint angles [rad]) and return the path.

    Parameters
    ----------
    path : str or path
        Destination ``.csv``; an existing file is kept unless ``overwrite``.
    timestamp : array-like of shape (n,)
        [s].
    run_kind : array-like of shape (n,)
        ``"load"`` or ``"no-load"``.
    config, pose : array-like of shape (n,)
        Integer load configuration id and pose index.
    q : array-like of shape (n, n_joints)
        Joint angles [rad].
    raw : array-like of shape (n, n_channels)
        Raw readings.
    raw_unit, load_mass, robot, sensor_frame, meta
        Header comments (``load_mass`` in [kg]).
    overwrite : bool, default=False
        Replace an existing file.
    temperature : array-like of shape (n,), optional
        Sensor temperature [deg C] per row (an optional ``temperature`` column).
    """
    path = Path(path)
    if path.exists() and not overwrite:
        raise LogFormatError(f"{path}: file exists.", parameter="path", value=str(path), fix="pass {overwrite} to replace it, or choose another path", settings={"overwrite": True})
    q_arr, raw_arr = np.atleast_2d(np.asarray(q, dtype=float)), np.atleast_2d(np.asarray(raw, dtype=float))
    n = q_arr.shape[0]
    cols = {"timestamp": np.asarray(timestamp, dtype=float), "run": np.asarray(run_kind, dtype=str),
            "config": np.asarray(config), "pose": np.asarray(pose)}
    for name, arr in list(cols.items()) + [("raw", raw_arr)]:
        if arr.shape[0] != n:
            raise LogFormatError(f"{path}: {name} has {arr.shape[0]} rows but q has {n}; they must match.")
    bad_kind = sorted(set(cols["run"]) - set(RUN_KINDS))
    if bad_kind:
        raise LogFormatError(f"{path}: run_kind holds {bad_kind}; use 'load' or 'no-load'.")
    header = [f"# ftcal-run-log: {LOG_FORMAT_VERSION}", "# time_unit: s", "# joint_unit: rad", f"# raw_unit: {raw_unit}"]
    if load_mass is not None:
        if not (np.isfinite(float(load_mass)) and 0 < float(load_mass) <= MAX_LOAD_MASS_KG):  # read_run_log's rule
            raise LogFormatError(f"{path}: load_mass {load_mass!r}: give the positive mass of the load in kg (at most "
                                 f"{MAX_LOAD_MASS_KG:g}), or None for a log without load.")
        header.append(f"# load_mass_kg: {float(load_mass)!r}")
    comments = {"robot": robot, "sensor_frame": sensor_frame, "meta": json.dumps(meta) if meta else None}
    header += [f"# {key}: {value}" for key, value in comments.items() if value is not None]
    names = list(_FIXED_COLUMNS) + [f"q{j + 1}" for j in range(q_arr.shape[1])] + [f"s{k}" for k in range(raw_arr.shape[1])]
    temp = None
    if temperature is not None:
        try:
            temp = check_temperature(temperature, n)
        except CalibrationInputError as exc:
            raise LogFormatError(f"{path}: {exc}") from None
        names.append("temperature")
    out = header + [",".join(names)]
    numbers = np.column_stack([q_arr, raw_arr] + ([] if temp is None else [temp]))
    for i in range(n):
        vals = [f"{cols['timestamp'][i]:.6f}", cols["run"][i], str(int(cols["config"][i])), str(int(cols["pose"][i]))]
        vals += [repr(v) for v in numbers[i].tolist()]  # exact: reads back bit for bit
        out.append(",".join(vals))
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(out) + "\n", encoding="utf-8")
    return path
