"""Pose files: the sensor's orientation and its reading, row by row (static poses or a continuous recording).

Layout (CSV, UTF-8; ``#`` comment lines before the header are skipped)
----------------------------------------------------------------------
One header line, then one row per sample. The orientation of the sensor frame in the robot's base frame
(the rotation that maps sensor-frame vectors to base-frame vectors), in one of three forms:

===================  =================================================================================
columns              meaning
===================  =================================================================================
``qx,qy,qz,qw``      unit quaternion, scalar last, as ROS writes it (``geometry_msgs/Quaternion``, tf)
``R00,R01,...,R22``  the rotation matrix, ``Rij`` = row ``i``, column ``j``
``roll,pitch,yaw``   [rad], rotations about the *fixed* base axes x, then y, then z:
                     ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (the URDF / ROS ``rpy`` convention)
===================  =================================================================================

and the reading, one of:

* ``Fx,Fy,Fz,Tx,Ty,Tz`` (or ``Mx,My,Mz`` for the torques, any case): the wrench [N, N·m] of a
  factory-calibrated sensor, in the sensor frame or in the base frame (say which:
  ``--wrench-frame sensor|base``; a base-frame wrench is turned back into the sensor frame with the row's
  orientation, its torque taken about the sensor origin);
* ``s0,...,s{N-1}``: raw channels, calibrated with a model (``--model``).

Optional columns: ``time`` [s] (a continuous recording: the still poses are found in it, see
:func:`ftcal.experiment.find_still_poses`), ``temperature`` [deg C]. Other columns are ignored.

Every error is a :class:`~ftcal.core.LogFormatError` naming the file, the line and the column.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..core._columns import parse_number, read_header
from ..core._exceptions import LogFormatError
from ..core._wrench import WRENCH_LABELS
from ._logs import _parse_comments, read_text_lines, text_rows
from ._readers import ColumnMap, check_separator, named_axes

__all__ = ["PoseRecording", "read_pose_file", "ORIENTATION_LAYOUTS", "is_pose_file"]

#: The orientation column groups a pose file may use, by name.
ORIENTATION_LAYOUTS: dict[str, tuple[str, ...]] = {
    "quaternion (x, y, z, w)": ("qx", "qy", "qz", "qw"),
    "rotation matrix": tuple(f"R{i}{j}" for i in range(3) for j in range(3)),
    "roll, pitch, yaw [rad] (fixed axes x, y, z)": ("roll", "pitch", "yaw"),
}
#: A quaternion whose norm is this far from 1 is not a rounded unit quaternion (a wrong column, a typo).
QUATERNION_NORM_TOLERANCE = 0.01
#: Largest entry of ``RᵀR - I`` accepted as rounding of a written rotation matrix.
MATRIX_TOLERANCE = 5e-3
_EXPECTED = "qx,qy,qz,qw (or R00..R22, or roll,pitch,yaw) and Fx,Fy,Fz,Tx,Ty,Tz (or s0..s{N-1})[,time][,temperature]"


@dataclass
class PoseRecording:
    """The rows of a pose file, checked and in SI units.

    Attributes
    ----------
    path : pathlib.Path
    rotation : ndarray of shape (n, 3, 3) or None
        Sensor frame to base frame, per row (a proper rotation); None for a file without orientation columns
        (read with ``orientation_required=False``).
    wrench : ndarray of shape (n, 6) or None
        [N, N·m], in the frame the file was written in (see ``--wrench-frame``).
    raw : ndarray of shape (n, n_channels) or None
        Raw channels, when the file has ``s0..`` instead of a wrench.
    time : ndarray of shape (n,) or None
        [s], when the file has a ``time`` column.
    temperature : ndarray of shape (n,) or None
        [deg C].
    line : ndarray of shape (n,), int
        1-based line number of each row.
    orientation : str
        Which orientation layout the file used (a key of :data:`ORIENTATION_LAYOUTS`; '' for none).
    """

    path: Path
    rotation: NDArray[np.float64] | None
    wrench: NDArray[np.float64] | None
    raw: NDArray[np.float64] | None
    time: NDArray[np.float64] | None
    temperature: NDArray[np.float64] | None
    line: NDArray[np.int64]
    orientation: str

    @property
    def n_rows(self) -> int:
        """Number of rows."""
        return int(len(self.line))

    @property
    def reading(self) -> NDArray[np.float64]:
        """The wrench, or the raw channels when the file has no wrench."""
        return self.wrench if self.wrench is not None else self.raw


def is_pose_file(path: str | Path) -> bool:
    """Whether the CSV at ``path`` is meant as a pose file: its header names an orientation column (qx, R00, roll, ...).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "poses.csv"
    >>> _ = p.write_text("qx,qy,qz,qw,Fx,Fy,Fz,Tx,Ty,Tz\\n0,0,0,1,0,0,-9.81,0,0,0\\n")
    >>> is_pose_file(p)
    True
    """
    try:
        with open(path, encoding="utf-8-sig") as f:
            for text in f:
                if not text.startswith("#"):
                    names = {n.strip() for n in text.split(",")}
                    return any(names & set(cols) for cols in ORIENTATION_LAYOUTS.values())
    except (OSError, UnicodeDecodeError):
        return False
    return False


def read_pose_file(path: str | Path, *, force_unit: str = "N", torque_unit: str = "N.m",
                   orientation_required: bool = True, repeated_times: bool = False) -> PoseRecording:
    """Read and check a pose file (layout in the module docstring).

    Parameters
    ----------
    path : str or path
        The ``.csv`` file.
    force_unit, torque_unit : str
        Units of the file's forces and torques (``N``, ``kN``, ``lbf``; ``N.m``, ``N.mm``, ...), converted to
        [N] and [N·m].
    orientation_required : bool, default=True
        False: a file without orientation columns is read too (``rotation`` None), as the no-load readings of a
        tool re-tare with the tool taken off; orientation columns present are checked as always.
    repeated_times : bool, default=False
        True: consecutive rows may share a time (readings taken together, as a re-tare's); times never go back.

    Returns
    -------
    PoseRecording

    Raises
    ------
    LogFormatError
        Missing file or columns, two orientation layouts at once, a value that is not a finite number, a
        quaternion that is not of unit norm, a matrix that is not a rotation, angles that look like degrees.
        The message names the file, the line and the column.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "poses.csv"
    >>> _ = p.write_text("qx,qy,qz,qw,Fx,Fy,Fz,Mx,My,Mz\\n0,0,0,1,0,0,-9.81,0,0,0\\n1,0,0,0,0,0,9.81,0,0,0\\n")
    >>> rec = read_pose_file(p)
    >>> rec.n_rows, rec.orientation, rec.rotation[1].round(6).tolist()[2]
    (2, 'quaternion (x, y, z, w)', [0.0, 0.0, -1.0])
    """
    path = Path(path)
    lines = read_text_lines(path, "pose file", "split the recording into several files")
    head_line = _parse_comments(path, lines)[1] + 1  # the header follows the comments
    if head_line > len(lines) or not lines[head_line - 1].strip():
        raise LogFormatError(f"{path}: line {head_line}: no header line; expected {_EXPECTED}.")
    fields, rows = next(csv.reader([lines[head_line - 1]])), text_rows(lines, head_line)
    where = f"{path}: line {head_line}"
    check_separator(fields, where, next_row=lines[head_line] if head_line < len(lines) else "", error=LogFormatError)
    head = read_header(fields, where=where, error=LogFormatError, numbered=(), allow_other=True, expected=_EXPECTED)
    names = list(head.names)
    layouts = [name for name, cols in ORIENTATION_LAYOUTS.items() if all(c in head for c in cols)]
    partial = [name for name, cols in ORIENTATION_LAYOUTS.items() if any(c in head for c in cols)
               and name not in layouts]
    if len(layouts) != 1 and not (not layouts and not partial and not orientation_required):
        if layouts:
            raise LogFormatError(f"{where}: the header holds two orientations ({' and '.join(layouts)}); keep one.")
        hint = f" (it has part of the {partial[0]}: {','.join(ORIENTATION_LAYOUTS[partial[0]])})" if partial else ""
        raise LogFormatError(f"{where}: the header names no orientation of the sensor{hint}; expected {_EXPECTED}.")
    layout = layouts[0] if layouts else ""
    wrench_cols = named_axes(names, lambda first, n, axis: LogFormatError(
        f"{where}: columns {first!r} and {n!r} both hold {axis}."))
    channels = [n for n in names if n[:1] == "s" and n[1:].isdigit()]
    if wrench_cols and len(wrench_cols) != 6:
        missing = [c for c in WRENCH_LABELS if c not in wrench_cols]
        raise LogFormatError(f"{where}: the wrench lacks {','.join(missing)}; give all six of Fx,Fy,Fz,Tx,Ty,Tz "
                             "(or Mx,My,Mz).")
    if not wrench_cols:
        if not channels:
            raise LogFormatError(f"{where}: the header names no reading: give the wrench Fx,Fy,Fz,Tx,Ty,Tz (or "
                                 "Mx,My,Mz) or the raw channels s0..s{N-1}.")
        read_header(fields, where=where, error=LogFormatError, numbered=(("s", 0, "raw channel"),), allow_other=True)
        channels = sorted(channels, key=lambda n: int(n[1:]))
        if len(channels) < 3:
            raise LogFormatError(f"{where}: {len(channels)} raw channels; a sensor needs at least 3.")
    if not rows:
        raise LogFormatError(f"{path}: no data rows after the header (line {head_line}).")
    orientation_cols = ORIENTATION_LAYOUTS[layout] if layout else ()
    value_cols = list(orientation_cols) + ([names[wrench_cols[c]] for c in WRENCH_LABELS] if wrench_cols else channels)
    value_cols += [c for c in ("time", "temperature") if c in head]
    values = np.empty((len(rows), len(value_cols)))
    line = np.array([lineno for lineno, _ in rows], dtype=np.int64)
    for i, (lineno, row) in enumerate(rows):
        if len(row) != len(names):
            raise LogFormatError(f"{path}: line {lineno}: {len(row)} fields but the header names {len(names)}.")
        for k, c in enumerate(value_cols):
            text = row[head.index[c]]
            v = parse_number(text, f"{path}: line {lineno}, column {c}", LogFormatError) if text else float("nan")
            if not np.isfinite(v):
                raise LogFormatError(f"{path}: line {lineno}, column {c}: {text!r} is not a finite number; repair "
                                     "or remove that row.")
            values[i, k] = v
    k = len(orientation_cols)
    rotation = _rotations(path, layout, values[:, :k], line, orientation_cols) if layout else None
    reading = values[:, k:k + (6 if wrench_cols else len(channels))]
    wrench = ColumnMap(force_unit=force_unit, torque_unit=torque_unit).to_si(reading) if wrench_cols else None
    raw = None if wrench_cols else reading.copy()
    extra = {c: values[:, value_cols.index(c)].copy() for c in ("time", "temperature") if c in head}
    time = extra.get("time")
    if time is not None:
        back = np.flatnonzero(np.diff(time) < 0 if repeated_times else np.diff(time) <= 0)
        if back.size:
            i = int(back[0]) + 1
            rule = "times must not go back" if repeated_times else "times must increase row by row"
            raise LogFormatError(f"{path}: line {line[i]}, column time: {time[i]:g} s does not follow "
                                 f"{time[i - 1]:g} s on line {line[i - 1]}; {rule}.")
    return PoseRecording(path=path, rotation=rotation, wrench=wrench, raw=raw, time=time,
                         temperature=extra.get("temperature"), line=line, orientation=layout)


def _rotations(path: Path, layout: str, o: NDArray[np.float64], line: NDArray[np.int64],
               columns: tuple[str, ...]) -> NDArray[np.float64]:
    """The rotations (sensor to base) of the orientation columns ``o`` in ``layout``, checked row by row (a
    quaternion of unit norm, a proper rotation matrix, angles in radians), errors naming the row's line."""
    from scipy.spatial.transform import Rotation

    n = len(o)
    if layout.startswith("quaternion"):
        norm = np.linalg.norm(o, axis=1)
        bad = np.flatnonzero(np.abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE)
        if bad.size:
            i = int(bad[0])
            raise LogFormatError(f"{path}: line {line[i]}: the quaternion (qx,qy,qz,qw) has norm {norm[i]:.4g}, not 1; "
                                 "is a column swapped or missing?")
        return Rotation.from_quat(o).as_matrix()  # scalar last (x, y, z, w), as ROS writes it
    if layout == "rotation matrix":
        R = o.reshape(n, 3, 3)
        err = np.abs(np.einsum("nki,nkj->nij", R, R) - np.eye(3)).max(axis=(1, 2))
        det = np.linalg.det(R)
        bad = np.flatnonzero((err > MATRIX_TOLERANCE) | (det < 0))
        if bad.size:
            i = int(bad[0])
            what = f"a reflection (determinant {det[i]:.3g})" if det[i] < 0 else \
                f"not orthonormal (RᵀR differs from the identity by {err[i]:.2g})"
            raise LogFormatError(f"{path}: line {line[i]}: R00..R22 is {what}, not a rotation matrix; check the "
                                 "column order (Rij = row i, column j).")
        return Rotation.from_matrix(R).as_matrix()  # the nearest rotation of a rounded one
    big = np.argwhere(np.abs(o) > 2 * np.pi + 1e-6)
    if big.size:
        i, j = (int(v) for v in big[0])
        raise LogFormatError(f"{path}: line {line[i]}, column {columns[j]}: {o[i, j]:g} exceeds 2*pi; "
                             "roll, pitch and yaw are in radians (were they written in degrees?).")
    return Rotation.from_euler("xyz", o).as_matrix()  # extrinsic x, y, z: Rz(yaw) Ry(pitch) Rx(roll)
