"""Getting a user's calibration data in: column mappings, name aliases, ``.mat`` files, declared units.

A recording rarely arrives in ftcal's own layout. This module maps it onto
:class:`~ftcal.CalibrationDataset`:

* **column mapping** (:class:`ColumnMap`): which columns (CSV) or variables
  (``.mat``, ``.npz``) hold the raw channels and the six wrench components,
  e.g. ``channels=("s1", ..., "s8")``, ``wrench=("Fx", "Fy", "Fz", "Mx", "My", "Mz")``;
* **name aliases**: without a mapping, torques may be named ``Tx/Ty/Tz`` or
  ``Mx/My/Mz`` (Bota, MATLAB naming), any letter case;
* **units** (:func:`unit_scale`): forces in ``N``, ``kN``, ``mN`` or ``lbf``,
  torques in ``N.m``, ``N.mm``, ``N.cm``, ``kN.m``, ``lbf.in`` or ``lbf.ft``;
  the data are converted to ftcal's [N] and [N·m] on reading;
* **the lever-arm check** (:func:`lever_arm_problem`): the ratio of the
  largest torque to the largest force is a length, the lever arm of the
  loads. Torques written in N·mm but read as N·m make it a thousand times too
  long (a 4 m arm); the check names the likely unit and the fix.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..core._exceptions import DatasetFileError
from ..core._columns import DTYPE_KIND_NAMES
from ..core._wrench import FORCE, TORQUE, WRENCH_LABELS

__all__ = [
    "FORCE_UNITS",
    "TORQUE_UNITS",
    "ColumnMap",
    "unit_scale",
    "canonical_wrench_name",
    "lever_arm_m",
    "lever_arm_problem",
    "read_mat_arrays",
    "check_real_array",
]

#: Force units ftcal reads, as the factor to [N].
FORCE_UNITS: dict[str, float] = {"N": 1.0, "kN": 1e3, "mN": 1e-3, "lbf": 4.4482216152605}
#: Torque units ftcal reads, as the factor to [N·m] (``.``, ``*``, ``·`` or nothing between N and m).
TORQUE_UNITS: dict[str, float] = {
    "N.m": 1.0, "N.mm": 1e-3, "N.cm": 1e-2, "kN.m": 1e3, "mN.m": 1e-3,
    "lbf.in": 0.1129848290276167, "lbf.ft": 1.3558179483314004,
}
#: Lever arms [m] outside this range are implausible for a force/torque calibration.
PLAUSIBLE_LEVER_ARM_M = (1e-4, 2.0)


def _unit_key(text: str) -> str:
    return re.sub(r"[\s*·⋅x-]", ".", text.strip()).replace("..", ".")


def unit_scale(unit: str, kind: str) -> float:
    """The factor turning values in ``unit`` into ftcal's unit of ``kind`` (``"force"`` [N], ``"torque"`` [N·m]).

    Examples
    --------
    >>> unit_scale("N.mm", "torque"), unit_scale("Nmm", "torque"), unit_scale("N·m", "torque")
    (0.001, 0.001, 1.0)
    >>> unit_scale("furlong", "force")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.DatasetFileError: unknown force unit 'furlong'; known: N, kN, mN, lbf.
    """
    table = FORCE_UNITS if kind == "force" else TORQUE_UNITS
    key = _unit_key(unit)
    if kind == "torque" and "." not in key:  # "Nmm", "Nm", "kNm", "lbfin"
        key = re.sub(r"^(k|m)?(N|lbf)(m|mm|cm|in|ft)$", r"\1\2.\3", key)
    if key in table:
        return table[key]
    folded = [name for name in table if name.lower() == key.lower()]
    if len(folded) == 1:  # "n.mm", "LBF": case does not matter where it cannot change the meaning
        return table[folded[0]]
    raise DatasetFileError(f"unknown {kind} unit {unit!r}; known: {', '.join(table)}.")


_ALIASES = {f"{p}{a}": name for name in WRENCH_LABELS for a in (name[1],)
            for p in ((name[0], "M") if name[0] == "T" else (name[0],))}


def canonical_wrench_name(name: str) -> str | None:
    """``Fx``...``Tz`` for a wrench column name or its alias (``Mx`` for ``Tx``, any case), else None.

    Examples
    --------
    >>> [canonical_wrench_name(n) for n in ("fx", "Mz", "TY", "s0")]
    ['Fx', 'Tz', 'Ty', None]
    """
    key = name.strip()
    for alias, canonical in _ALIASES.items():
        if key.lower() == alias.lower():
            return canonical
    return None


@dataclass(frozen=True)
class ColumnMap:
    """Which columns (CSV) or variables (``.mat``/``.npz``) hold what, and in which units.

    Parameters
    ----------
    channels : sequence of str, optional
        The raw-channel columns in channel order (``s1,...,s8``); in a ``.mat`` or
        ``.npz`` one name may be a 2-D variable holding every channel. Default:
        ``s0, s1, ...`` (CSV) or the variable ``raw``.
    wrench : sequence of str, optional
        The six wrench columns in the order Fx, Fy, Fz, Tx, Ty, Tz (or one 2-D
        variable). Default: ``Fx ... Tz`` or their aliases (``Mx/My/Mz``), or the
        variable ``wrench``.
    force_unit, torque_unit : str
        The units the file's forces and torques are written in (see
        :data:`FORCE_UNITS`, :data:`TORQUE_UNITS`); converted to [N] and [N·m].

    Examples
    --------
    >>> ColumnMap(channels=("a", "b", "c"), torque_unit="N.mm").torque_factor
    0.001
    """

    channels: tuple[str, ...] | None = None
    wrench: tuple[str, ...] | None = None
    force_unit: str = "N"
    torque_unit: str = "N.m"

    def __post_init__(self) -> None:
        for field, value in (("channels", self.channels), ("wrench", self.wrench)):
            if value is None:
                continue
            names = tuple(str(v).strip() for v in value)
            object.__setattr__(self, field, names)
            if not names or any(not n for n in names):
                raise DatasetFileError(f"{field} mapping {value!r} holds an empty name; give comma-separated names.")
            dups = sorted({n for n in names if names.count(n) > 1})
            if dups:
                raise DatasetFileError(f"{field} mapping names {dups[0]!r} twice; each column once.")
        if self.wrench is not None and len(self.wrench) not in (1, 6):
            raise DatasetFileError(
                f"wrench mapping {','.join(self.wrench)!r} names {len(self.wrench)} columns; give the six columns "
                "in the order Fx,Fy,Fz,Tx,Ty,Tz (or one variable holding all six)."
            )
        if self.channels and self.wrench and set(self.channels) & set(self.wrench):
            raise DatasetFileError(f"column {sorted(set(self.channels) & set(self.wrench))[0]!r} is mapped both "
                                   "as a channel and as a wrench component.")
        unit_scale(self.force_unit, "force")
        unit_scale(self.torque_unit, "torque")

    @property
    def force_factor(self) -> float:
        """Factor from the file's force unit to [N]."""
        return unit_scale(self.force_unit, "force")

    @property
    def torque_factor(self) -> float:
        """Factor from the file's torque unit to [N·m]."""
        return unit_scale(self.torque_unit, "torque")

    @property
    def is_default(self) -> bool:
        """Whether nothing is mapped and the units are ftcal's own."""
        return (self.channels is None and self.wrench is None and self.force_factor == 1.0
                and self.torque_factor == 1.0)

    def to_si(self, wrench: np.ndarray) -> np.ndarray:
        """The wrench converted from the declared units to [N] and [N·m]."""
        out = np.array(wrench, dtype=float)
        out[:, FORCE] *= self.force_factor
        out[:, TORQUE] *= self.torque_factor
        return out

    def units_meta(self) -> dict:
        """What the file declared, for the dataset's ``meta`` (the data themselves are in N and N·m)."""
        return {"source_force_unit": self.force_unit, "source_torque_unit": self.torque_unit}


def lever_arm_m(wrench: ArrayLike) -> float | None:
    """The loads' lever arm [m]: the largest torque norm over the largest force norm (None without both).

    Examples
    --------
    >>> lever_arm_m([[10.0, 0, 0, 0, 0.5, 0]])
    0.05
    """
    w = np.asarray(wrench, dtype=float)
    f = float(np.max(np.linalg.norm(w[:, FORCE], axis=1), initial=0.0))
    t = float(np.max(np.linalg.norm(w[:, TORQUE], axis=1), initial=0.0))
    if not (f > 0 and t > 0 and np.isfinite(f) and np.isfinite(t)):
        return None
    return t / f


def lever_arm_problem(wrench: ArrayLike, torque_unit: str = "N.m") -> str | None:
    """What looks wrong with the units of ``wrench`` ([N], [N·m] after conversion), or None when plausible.

    The ratio max‖T‖ / max‖F‖ is the lever arm [m] of the loads. A calibration
    fixture holds its loads within about two metres of the sensor and not closer
    than 0.1 mm; outside that range the torques (or forces) are probably in
    another unit, and the message says which and how to declare it. (Beyond 2 m
    is what torques in N·mm read as N·m give for any arm over 2 mm.)

    Examples
    --------
    >>> print(lever_arm_problem([[10.0, 0, 0, 0, 500.0, 0]]))  # doctest: +ELLIPSIS
    the loads' lever arm max|T|/max|F| is 50 m (alpha = 0.02 1/m), implausible for a force/torque ...
    >>> lever_arm_problem([[10.0, 0, 0, 0, 0.5, 0]]) is None
    True
    """
    arm = lever_arm_m(wrench)
    if arm is None:
        return None
    low, high = PLAUSIBLE_LEVER_ARM_M
    if low <= arm <= high:
        return None
    head = (f"the loads' lever arm max|T|/max|F| is {arm:.3g} m (alpha = {1.0 / arm:.3g} 1/m), implausible for a "
            f"force/torque calibration (expected {low * 1e3:g} mm to {high:g} m) with torques read as {torque_unit}")
    if arm > high:
        guesses = [(u, arm * f) for u, f in (("N.mm", 1e-3), ("N.cm", 1e-2)) if low <= arm * f <= high]
        unit = guesses[0][0] if guesses else "N.mm"
        return (f"{head}: the torques look like {unit}, not N·m. Fix: pass --torque-unit {unit} (the lever arm would "
                f"be {arm * unit_scale(unit, 'torque') * 1e3:.3g} mm); if they really are in N·m, confirm with "
                "--torque-unit N.m.")
    return (f"{head}: the torques look too small for the forces (forces in mN? torques in kN·m?). Fix: declare the "
            "units with --force-unit / --torque-unit; if the values are right, confirm with --torque-unit N.m.")


def temperature_message(exc: Exception, path, line_no: int) -> str:
    """The library's "temperature row 5 is NaN ..." (a row of the array) as the text file's line and column."""
    text = re.sub(r"^temperature row \d+ ", "temperature ", str(exc)).replace("that row", "that line")
    return f"{path}: line {line_no}, column temperature: {text}"


def read_mat_arrays(path) -> dict:
    """The variables of a MATLAB ``.mat`` file (v4-v7; v7.3 is HDF5 and refused with the fix).

    Every variable is returned, whatever its type (a cell, struct, char, sparse or complex variable is refused
    by :func:`check_real_array` when it is used, naming it, instead of looking absent).
    """
    from scipy.io import loadmat

    try:
        data = loadmat(path, squeeze_me=False)
    except NotImplementedError:
        raise DatasetFileError(f"{path}: a MATLAB v7.3 (HDF5) file; save it with save(..., '-v7') and retry.") from None
    except Exception as exc:  # scipy raises ValueError/TypeError/OSError on foreign files
        raise DatasetFileError(f"{path}: not a readable .mat file ({str(exc)[:100]}).") from None
    return {key: value for key, value in data.items() if not key.startswith("__")}


def check_real_array(value, name: str, where: str, kind: str = "variable") -> np.ndarray:
    """``value`` as an array of real numbers (float or integer), else :class:`DatasetFileError` naming the file,
    the array and its type: complex, boolean, date, text, object (MATLAB cell), struct and sparse arrays are refused
    rather than silently converted (a complex array would lose its imaginary part, a boolean become 0/1).

    Examples
    --------
    >>> check_real_array(np.array([1, 2]), "raw", "d.npz", "array").dtype.kind
    'i'
    >>> check_real_array(np.array([1j]), "raw", "d.npz", "array")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.DatasetFileError: d.npz: array 'raw' has dtype complex128 (complex numbers); it must hold real numbers (float or integer).
    """
    if not isinstance(value, np.ndarray):
        what = "a sparse matrix; save it full (full(...) in MATLAB)" if hasattr(value, "toarray") else \
            f"a {type(value).__name__}"
        raise DatasetFileError(f"{where}: {kind} {name!r} is {what}; it must be an array of real numbers.")
    if value.dtype.kind not in "iuf":
        shown = DTYPE_KIND_NAMES.get(value.dtype.kind, "not real numbers")
        raise DatasetFileError(f"{where}: {kind} {name!r} has dtype {value.dtype} ({shown}); it must hold real "
                               "numbers (float or integer).")
    return value


def select_arrays(arrays: dict[str, np.ndarray], names: Sequence[str] | None, default: str,
                  vector_names: Sequence[str], what: str, where: str, width: int | None,
                  kind: str = "variable") -> np.ndarray:
    """One (n, k) array from a file's named arrays: one 2-D variable, or a list of 1-D ones (real numbers only)."""
    def column(name: str) -> np.ndarray:
        v = check_real_array(arrays[name], name, where, kind)
        if v.ndim == 2 and 1 in v.shape:
            v = v.ravel()
        if v.ndim != 1:
            raise DatasetFileError(f"{where}: {kind} {name!r} has shape {v.shape}; a {what} column must be a vector.")
        return v

    if names is None:
        if default in arrays:
            names = (default,)
        elif vector_names and all(n in arrays for n in vector_names):
            names = tuple(vector_names)
        else:
            raise DatasetFileError(
                f"{where}: no {kind} {default!r} holding the {what}; the file has "
                f"{', '.join(sorted(arrays)) or f'no {kind}s'}. Fix: name them with "
                f"--{'channels' if what == 'raw channels' else 'wrench'} NAME[,NAME...]."
            )
    missing = [n for n in names if n not in arrays]
    if missing:
        raise DatasetFileError(f"{where}: no {kind} {missing[0]!r}; the file has {', '.join(sorted(arrays))}.")
    if len(names) == 1:
        a = check_real_array(arrays[names[0]], names[0], where, kind).astype(float)
        if a.ndim == 1:
            a = a[:, None]
        if a.ndim != 2:
            raise DatasetFileError(f"{where}: {kind} {names[0]!r} has shape {a.shape}; expected (n_samples, k).")
        if width is not None and a.shape[1] != width and a.shape[0] == width:
            a = a.T  # MATLAB users often store one row per component
        return a
    cols = [column(n) for n in names]
    if len({c.size for c in cols}) != 1:
        raise DatasetFileError(f"{where}: the {what} {kind}s have different lengths "
                               f"({', '.join(f'{n}: {c.size}' for n, c in zip(names, cols))}).")
    return np.column_stack(cols).astype(float)
