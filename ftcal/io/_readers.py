"""Getting a user's calibration data in: column mappings, name aliases, bounded ``.npz``/``.mat`` reading, units.

A recording rarely arrives in ftcal's own layout. This module maps it onto
:class:`~ftcal.CalibrationDataset`:

* **column mapping** (:class:`ColumnMap`): which columns (CSV) or variables
  (``.mat``, ``.npz``) hold the raw channels and the wrench components: a list
  of names (``g1,g2,g3``), a numbered range (``s0..s7``) or a column slice of
  one 2-D array (``data[:,0:8]``); the wrench may have any number of axes
  (``Fx,Fy,Fz`` is a 3-axis calibration), named by its columns or by ``axes``;
* **name aliases**: torques may be named ``Tx/Ty/Tz`` or ``Mx/My/Mz``, forces
  ``force_x``, any letter case;
* **units** (:func:`unit_scale`): one exact, case-sensitive parser (``MN`` is
  a meganewton, ``mN`` a millinewton): ``N`` with any SI prefix, ``lbf``,
  ``ozf``, ``kip``, ``dyn``, masses as forces through standard gravity
  (``g``, ``kg``, ``gf``, ``kgf``), and torques as a force times a length
  (``N.m``, ``N·mm``, ``N*cm``, ``kN.m``, ``lbf.in``, ``Nmm``); the data are
  converted to ftcal's [N] and [N·m] on reading;
* **the lever-arm check** (:func:`lever_arm_problem`): the ratio of the
  largest torque to the largest force is a length, the lever arm of the
  loads; torques in N·mm (or forces in kN) read in the wrong unit make it a
  thousand times too long, and the check names the likely unit and the fix;
* **bounded reading** (:class:`ArrayFile`): only the variables a dataset uses
  are read, each after its declared size was checked against ftcal's memory
  limit, so an unused (or a crafted) huge variable costs nothing.
"""

from __future__ import annotations

import re
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ..core._columns import DTYPE_KIND_NAMES, is_number, repeated_names
from ..core._exceptions import NO_SETTING, DatasetFileError, Placeholder, api_spelling
from ..core._memory import check_allocation, read_npy_member
from ..core._wrench import WRENCH_LABELS, force_columns, torque_columns

__all__ = ["FORCE_UNITS", "TORQUE_UNITS", "STANDARD_GRAVITY", "ColumnMap", "unit_scale", "canonical_wrench_name",
           "expand_names", "named_axes", "parse_column_slice", "lever_arm_m", "lever_arm_problem", "ArrayFile",
           "check_real_array", "has_header", "join_headerless", "JoinedTable", "not_utf8_error", "check_separator"]

#: Standard gravity [m/s²] (ISO 80000-3): a mass unit read as a force is its weight, ``1 g`` = 9.80665 mN.
STANDARD_GRAVITY = 9.80665
#: SI prefixes, exact and case-sensitive (``M`` mega, ``m`` milli); ``u`` stands for µ.
_SI_PREFIXES: dict[str, float] = {"G": 1e9, "M": 1e6, "k": 1e3, "h": 1e2, "da": 1e1, "": 1.0, "d": 1e-1,
                                  "c": 1e-2, "m": 1e-3, "µ": 1e-6, "μ": 1e-6, "u": 1e-6, "n": 1e-9}
#: Force units without a prefix, as the factor to [N]; a gram (``g``) is read as the weight of a gram.
_FORCE_BASES: dict[str, float] = {"N": 1.0, "g": 1e-3 * STANDARD_GRAVITY, "gf": 1e-3 * STANDARD_GRAVITY}
#: Force units that take no prefix [N].
_FORCE_OTHER: dict[str, float] = {"lbf": 4.4482216152605, "ozf": 0.27801385095378125, "kip": 4448.2216152605,
                                  "dyn": 1e-5}
#: Lengths of a torque's lever [m].
_LENGTHS: dict[str, float] = {**{f"{p}m": f for p, f in _SI_PREFIXES.items() if p in ("k", "", "d", "c", "m", "µ",
                                                                                    "μ", "u")},
                              "in": 0.0254, "ft": 0.3048}
#: What a torque's force and length may be separated by.
_TORQUE_SEPARATORS = re.compile(r"\s*[.·⋅*×\s-]\s*")
#: Common force units ftcal reads, as the factor to [N] (every SI prefix of N and g is read too).
FORCE_UNITS: dict[str, float] = {"N": 1.0, "kN": 1e3, "mN": 1e-3, "MN": 1e6, "g": 1e-3 * STANDARD_GRAVITY,
                                 "kg": STANDARD_GRAVITY, "gf": 1e-3 * STANDARD_GRAVITY, "kgf": STANDARD_GRAVITY,
                                 "lbf": 4.4482216152605}
#: Common torque units ftcal reads, as the factor to [N·m] (any force unit times m, mm, cm, in, ft is read too).
TORQUE_UNITS: dict[str, float] = {
    "N.m": 1.0, "N.mm": 1e-3, "N.cm": 1e-2, "kN.m": 1e3, "mN.m": 1e-3, "kgf.m": STANDARD_GRAVITY,
    "lbf.in": 0.1129848290276167, "lbf.ft": 1.3558179483314004,
}
#: Lever arms [m] outside this range are implausible for a force/torque calibration.
PLAUSIBLE_LEVER_ARM_M = (1e-4, 2.0)


def _force_factor(text: str) -> float | None:
    """The factor of a force unit to [N], or None (exact spelling: ``MN`` is no ``mN``)."""
    if text in _FORCE_OTHER:
        return _FORCE_OTHER[text]
    for base, factor in _FORCE_BASES.items():
        if text.endswith(base) and text[: -len(base)] in _SI_PREFIXES:
            return _SI_PREFIXES[text[: -len(base)]] * factor
    return None


def _torque_factor(text: str) -> float | None:
    """The factor of a torque unit (a force unit times a length) to [N·m], or None."""
    parts = _TORQUE_SEPARATORS.split(text.strip())
    if len(parts) == 2:
        force, length = _force_factor(parts[0]), _LENGTHS.get(parts[1])
        return None if force is None or length is None else force * length
    if len(parts) != 1:
        return None
    found = {f * _LENGTHS[text[i:]] for i in range(1, len(text)) if text[i:] in _LENGTHS
             for f in [_force_factor(text[:i])] if f is not None}  # "Nmm", "kNm", "MNm"
    return found.pop() if len(found) == 1 else None


def unit_scale(unit: str, kind: str) -> float:
    """The factor turning values in ``unit`` into ftcal's unit of ``kind`` (``"force"`` [N], ``"torque"`` [N·m]).

    Units are read exactly as written (``MN`` is a meganewton, ``mN`` a millinewton); a mass unit is read as a
    force through standard gravity (``g``, ``kg``, ``gf``, ``kgf``); a torque is a force unit times a length
    (``m`` with a prefix, ``in``, ``ft``), joined by ``.``, ``·``, ``*``, a space or nothing.

    Examples
    --------
    >>> unit_scale("N.mm", "torque"), unit_scale("Nmm", "torque"), unit_scale("N·m", "torque")
    (0.001, 0.001, 1.0)
    >>> unit_scale("MN", "force"), unit_scale("mN", "force"), round(unit_scale("g", "force"), 8)
    (1000000.0, 0.001, 0.00980665)
    >>> unit_scale("n.mm", "torque")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.DatasetFileError: unknown torque unit 'n.mm' (units are case-sensitive: did you mean 'N.mm'?); known: N.m, N.mm, N.cm, kN.m, mN.m, kgf.m, lbf.in, lbf.ft (any force unit times m, mm, cm, in or ft).
    """
    field = f"{kind}_unit"
    if not isinstance(unit, str):
        raise DatasetFileError(f"the {kind} unit must be text such as 'N' or 'N.m'; got {unit!r}.", parameter=field,
                               value=unit)
    text = unit.strip()
    table, parse, more = _UNIT_KINDS["force" if kind == "force" else "torque"]
    factor = parse(text)
    if factor is not None:
        return factor
    if kind == "torque" and _force_factor(text) is not None:
        raise DatasetFileError(f"{unit!r} is a force unit, not a torque unit; a torque is a force times a length, "
                               f"e.g. {text}.m or {text}.mm.", parameter=field, value=unit)
    if kind == "force" and _torque_factor(text) is not None:
        raise DatasetFileError(f"{unit!r} is a torque unit, not a force unit: give it as {{torque_unit}}, and the "
                               "forces' unit (e.g. N) as {force_unit}.", parameter="force_unit", value=unit,
                               settings={"torque_unit": NO_SETTING})
    guesses = sorted({name for name in _spellings(kind) if name.lower() == text.lower() and parse(name) is not None})
    hint = (f" (units are case-sensitive: did you mean {' or '.join(repr(g) for g in guesses)}?)" if guesses else "")
    raise DatasetFileError(f"unknown {kind} unit {unit!r}{hint}; known: {', '.join(table)} ({more}).",
                           parameter=field, value=unit)


#: Per kind of unit: the common units, the parser, and what else it reads (said in an error).
_UNIT_KINDS = {"force": (FORCE_UNITS, _force_factor, "any SI prefix of N or g"),
               "torque": (TORQUE_UNITS, _torque_factor, "any force unit times m, mm, cm, in or ft")}


def _spellings(kind: str) -> list[str]:
    """Every unit spelling the parser reads (SI prefixes, the separators as '.'), for case hints."""
    forces = [p + b for b in _FORCE_BASES for p in _SI_PREFIXES if p not in ("μ", "u")] + list(_FORCE_OTHER)
    if kind == "force":
        return forces
    return [f"{f}.{length}" for f in forces for length in _LENGTHS if length not in ("μm", "um")]


_FORCE_NAME = re.compile(r"(?:f|force)[_\s-]?([xyz])", re.IGNORECASE)
_TORQUE_NAME = re.compile(r"(?:t|m|torque|moment)[_\s-]?([xyz])", re.IGNORECASE)


def canonical_wrench_name(name: str) -> str | None:
    """``Fx``...``Tz`` for a wrench column name or its alias, else None.

    Torques may be named ``Mx`` (Bota, MATLAB naming), ``torque_x`` or ``moment_x``, forces ``force_x`` or
    ``f_x``; any letter case.

    Examples
    --------
    >>> [canonical_wrench_name(n) for n in ("fx", "Mz", "TY", "force_x", "Moment-Y", "s0")]
    ['Fx', 'Tz', 'Ty', 'Fx', 'Ty', None]
    """
    key = name.strip()
    for pattern, letter in ((_FORCE_NAME, "F"), (_TORQUE_NAME, "T")):
        found = pattern.fullmatch(key)
        if found:
            return letter + found.group(1).lower()
    return None


def named_axes(names: Sequence[str | None], clash) -> dict[str, int]:
    """Each wrench axis ``names`` holds by name or alias (:func:`canonical_wrench_name`; ``None`` entries are
    skipped) -> its position, in the order found; a second name of one axis raises ``clash(first, second, axis)``
    (the error to raise, worded for the file's kind)."""
    found: dict[str, int] = {}
    for i, name in enumerate(names):
        axis = None if name is None else canonical_wrench_name(name)
        if axis in found:
            raise clash(names[found[axis]], name, axis)
        if axis is not None:
            found[axis] = i
    return found


#: An integer as written (group labels, config and pose ids are read exactly, not through float64).
_INTEGER = re.compile(r"[+-]?[0-9]+")
_RANGE = re.compile(r"([A-Za-z_][A-Za-z0-9_\-]*?)(\d+)\s*\.\.\s*(?:\1)?(\d+)")
_SLICE = re.compile(r"([A-Za-z_][A-Za-z0-9_\-]*)\s*\[\s*:\s*,\s*(?:(-?\d+)|(-?\d*)\s*:\s*(-?\d*))\s*\]")
#: Most columns one range may name (a typo such as s0..s99999999 would otherwise build a huge list).
MAX_RANGE_COLUMNS = 100_000


def expand_names(items: Sequence[str], what: str = "channels") -> tuple[str, ...]:
    """Column names with each range ``s0..s7`` (inclusive) written out; slices ``data[:,0:8]`` are kept.

    ``what`` is the argument the names were given as (``"channels"``, ``"wrench"``): the errors carry it as their
    ``parameter``.

    Examples
    --------
    >>> expand_names(["s0..s3", "temp"])
    ('s0', 's1', 's2', 's3', 'temp')
    >>> expand_names(["ch08..ch10"])
    ('ch08', 'ch09', 'ch10')
    """
    out: list[str] = []
    for item in items:
        text = str(item).strip()
        found = _RANGE.fullmatch(text)
        if found is None:
            if ".." in text:
                raise DatasetFileError(f"{{{what}}} {text!r}: a range is written PREFIX<first>..PREFIX<last>, e.g. "
                                       "s0..s7 (both ends included).", parameter=what, value=text)
            out.append(text)
            continue
        prefix, first, last = found.group(1), found.group(2), found.group(3)
        start, stop = int(first), int(last)
        if stop < start:
            raise DatasetFileError(f"{{{what}}} {text!r}: the range runs backwards; write "
                                   f"{prefix}{last}..{prefix}{first} or list the columns in the order you want.",
                                   parameter=what, value=text)
        if stop - start + 1 > MAX_RANGE_COLUMNS:
            raise DatasetFileError(f"{{{what}}} {text!r} names {stop - start + 1} columns, more than ftcal reads "
                                   f"({MAX_RANGE_COLUMNS}); check the range.", parameter=what, value=text)
        width = len(first) if first.startswith("0") and len(first) > 1 else 0
        out.extend(f"{prefix}{k:0{width}d}" for k in range(start, stop + 1))
    return tuple(out)


def parse_column_slice(text: str) -> tuple[str, int | None, int | None] | None:
    """``(variable, start, stop)`` of a column slice ``data[:,0:8]`` (Python's half-open columns), else None.

    Examples
    --------
    >>> parse_column_slice("data[:,8:14]"), parse_column_slice("data[:, 3]"), parse_column_slice("raw")
    (('data', 8, 14), ('data', 3, 4), None)
    """
    found = _SLICE.fullmatch(str(text).strip())
    if found is None:
        return None
    name, single, start, stop = found.groups()
    if single is not None:
        k = int(single)
        return name, k, (k + 1) if k != -1 else None
    return name, int(start) if start else None, int(stop) if stop else None


def _slice_columns(spec: tuple[str, int | None, int | None], width: int, where: str, option: str) -> range:
    """The columns of a 2-D array of ``width`` columns a slice selects; a slice beyond the array is an error
    about the argument ``option`` (``"channels"``, ``"wrench"``)."""
    name, start, stop = spec
    begin = 0 if start is None else start
    end = width if stop is None else stop
    b = begin + width if begin < 0 else begin
    e = end + width if end < 0 else end
    if not (0 <= b < e <= width):
        raise DatasetFileError(f"{where}: {{{option}}} {name}[:,{'' if start is None else start}:"
                               f"{'' if stop is None else stop}] selects no columns of {name!r}, which has {width} "
                               f"columns (0..{width - 1}). Fix: give a slice within them, e.g. {name}[:,0:{width}].",
                               parameter=option, value=f"{name}[:,{start}:{stop}]")
    return range(b, e)


def _refuse_repeated(names: tuple[str, ...], said: str, parameter: str, fix: str = "each column once") -> None:
    """Refuse a name given twice (the first in sorted order): ``said`` begins the message."""
    dups = repeated_names(names)
    if dups:
        raise DatasetFileError(f"{said} {dups[0][0]!r} twice; {fix}.", parameter=parameter, value=names)


#: The field of an error about the group column of a :class:`ColumnMap` (``columns.groups``; ``groups`` alone are
#: the group labels of a fit).
GROUPS = "columns.groups"


def _slice_settings(array: str, first: int, split: int, stop: int) -> dict:
    """An example mapping of one array's columns as channels ``first:split`` and wrench ``split:stop``."""
    return {"channels": Placeholder(f"'{array}[:,{first}:{split}]'"),
            "wrench": Placeholder(f"'{array}[:,{split}:{stop}]'")}


@dataclass(frozen=True)
class ColumnMap:
    """Which columns (CSV) or variables (``.mat``/``.npz``) hold what, and in which units.

    Parameters
    ----------
    channels : sequence of str, optional
        The raw-channel columns in channel order: names (``g1,...,g8``), ranges
        (``s0..s7``), or a column slice of one 2-D variable of a ``.mat``/``.npz``
        (``data[:,0:8]``); one name may be a 2-D variable holding every channel.
        Default: ``s0, s1, ...`` (CSV) or the variable ``raw``.
    wrench : sequence of str, optional
        The wrench columns, any number of axes (a 3-axis load cell has three):
        names, a range, or a column slice (``data[:,8:14]``). Default: every
        column named like a wrench axis (``Fx ... Tz``, ``Mx``, ``force_x``), or the
        variable ``wrench``.
    force_unit, torque_unit : str
        The units the file's forces and torques are written in (:func:`unit_scale`); converted to [N] and [N·m].
    axes : sequence of str, optional
        The output axes (``Fx``...``Tz``) of the wrench columns, in their order, when their names do not say
        (``load`` of a 1-axis cell: ``axes=("Fz",)``); six unnamed columns are Fx, Fy, Fz, Tx, Ty, Tz.
    groups : str, optional
        The column holding each row's group (pose, session): integers or text labels. Default: ``group``.
        ``"file"`` makes each file of a folder a group.

    Examples
    --------
    >>> ColumnMap(channels=("s0..s2",), torque_unit="N.mm").channels
    ('s0', 's1', 's2')
    >>> ColumnMap(torque_unit="N.mm").torque_factor
    0.001
    """

    channels: tuple[str, ...] | None = None
    wrench: tuple[str, ...] | None = None
    force_unit: str = "N"
    torque_unit: str = "N.m"
    axes: tuple[str, ...] | None = None
    groups: str | None = None

    def __post_init__(self) -> None:
        for field in ("channels", "wrench"):
            value = getattr(self, field)
            if value is None:
                continue
            if isinstance(value, str):
                value = value.split(",")
            names = expand_names(value, field)
            object.__setattr__(self, field, names)
            if not names or any(not n for n in names):
                raise DatasetFileError(f"{{{field}}} mapping {','.join(value)!r} holds an empty name; give "
                                       "comma-separated names, e.g. s0,s1,s2 or s0..s7.", parameter=field,
                                       value=tuple(value))
            _refuse_repeated(names, f"{{{field}}} mapping names", field)
            slices = [n for n in names if parse_column_slice(n) is not None]
            if slices and len(names) > 1:
                raise DatasetFileError(f"{{{field}}} {','.join(names)!r}: a column slice such as {slices[0]} stands "
                                       "alone (it selects every column it needs).", parameter=field, value=names)
            if any("[" in n for n in names) and not slices:
                bad = next(n for n in names if "[" in n)
                raise DatasetFileError(f"{{{field}}} {bad!r} is no column slice; write NAME[:,FIRST:STOP] (columns "
                                       "FIRST..STOP-1 counted from 0, e.g. data[:,0:8]).", parameter=field,
                                       value=bad)
        if self.axes is not None:
            axes = tuple(str(v).strip() for v in (self.axes.split(",") if isinstance(self.axes, str) else self.axes))
            if not axes or any(n not in WRENCH_LABELS for n in axes):
                raise DatasetFileError(f"{{axes}} {','.join(axes)!r}: name each output axis as one of "
                                       f"{', '.join(WRENCH_LABELS)} (e.g. {{axes}} Fx,Fy,Fz for a 3-axis load cell).",
                                       parameter="axes", value=axes)
            _refuse_repeated(axes, "{axes} names the axis", "axes", "each axis once")
            object.__setattr__(self, "axes", axes)
        if self.channels and self.wrench:
            self._check_no_overlap()
        if self.groups is not None:
            used = set(self.channels or ()) | set(self.wrench or ())
            if self.groups in used:
                raise DatasetFileError(f"{{{GROUPS}}} {self.groups!r} is also mapped as a channel or wrench column; "
                                       "the group column must be another one.", parameter=GROUPS, value=self.groups)
        unit_scale(self.force_unit, "force")
        unit_scale(self.torque_unit, "torque")

    def _check_no_overlap(self) -> None:
        """A column (or columns of one array) mapped both as a channel and as a wrench component is an error."""
        common = sorted(set(self.channels) & set(self.wrench))
        if common:
            raise DatasetFileError(
                f"column {common[0]!r} is mapped both as a channel and as a wrench component.", parameter="channels",
                value=common[0], fix="when one array holds both, give column slices, e.g. {channels} {wrench}",
                settings=_slice_settings(common[0], 0, 8, 14))
        a, b = parse_column_slice(self.channels[0]), parse_column_slice(self.wrench[0])
        whole = {n for n in self.channels + self.wrench if parse_column_slice(n) is None}
        for spec in (a, b):
            if spec is not None and spec[0] in whole:
                raise DatasetFileError(f"{spec[0]!r} is mapped whole and as a column slice.", parameter="channels",
                                       value=spec[0], fix="map its columns once, each as a slice, e.g. {channels} "
                                       "{wrench}", settings=_slice_settings("data", 0, 8, 14))
        if a is not None and b is not None and a[0] == b[0]:
            starts_known = all(v is not None and v >= 0 for v in (a[1], a[2], b[1], b[2]))
            if starts_known and max(a[1], b[1]) < min(a[2], b[2]):
                raise DatasetFileError(
                    f"{{channels}} {self.channels[0]} and {{wrench}} {self.wrench[0]} overlap (columns "
                    f"{max(a[1], b[1])}..{min(a[2], b[2]) - 1} of {a[0]!r} would be both).", parameter="channels",
                    value=self.channels[0], fix="give disjoint slices, e.g. {channels} {wrench}",
                    settings=_slice_settings(a[0], 0, b[1], b[2]))

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
        return (self.channels is None and self.wrench is None and self.axes is None and self.groups is None
                and self.force_factor == 1.0 and self.torque_factor == 1.0)

    def to_si(self, wrench: np.ndarray, axes: Sequence[str] = WRENCH_LABELS) -> np.ndarray:
        """The wrench (columns ``axes``) converted from the declared units to [N] and [N·m]."""
        out = np.array(wrench, dtype=float)
        out[:, force_columns(axes)] *= self.force_factor
        out[:, torque_columns(axes)] *= self.torque_factor
        return out

    def units_meta(self) -> dict:
        """What the file declared, for the dataset's ``meta`` (the data themselves are in N and N·m)."""
        return {"source_force_unit": self.force_unit, "source_torque_unit": self.torque_unit}

    def to_dict(self) -> dict:
        """The mapping as plain JSON (stored in a model file, so that a model reads its data as it was fitted)."""
        names = {key: None if getattr(self, key) is None else list(getattr(self, key))
                 for key in ("channels", "wrench", "axes")}
        return {**names, "groups": self.groups, "force_unit": self.force_unit, "torque_unit": self.torque_unit}

    @classmethod
    def from_dict(cls, facts: dict, where: str = "the model file") -> "ColumnMap":
        """The mapping :meth:`to_dict` wrote; a damaged entry is a :class:`DatasetFileError` naming ``where``."""
        if not isinstance(facts, dict):
            raise DatasetFileError(f"{where}: the stored column mapping is not a JSON object; fit the model again.")
        kwargs = {}
        for key in ("channels", "wrench", "axes"):
            value = facts.get(key)
            if value is not None and not (isinstance(value, list) and all(isinstance(v, str) for v in value)
                                          and len(value) <= MAX_RANGE_COLUMNS):
                raise DatasetFileError(f"{where}: the stored {key} mapping is not a list of names; fit the model "
                                       "again.")
            kwargs[key] = None if value is None else tuple(value)
        for key, default in (("groups", None), ("force_unit", "N"), ("torque_unit", "N.m")):
            value = facts.get(key, default)
            if value is not None and not isinstance(value, str):
                raise DatasetFileError(f"{where}: the stored {key} is not text; fit the model again.")
            kwargs[key] = value
        return cls(**kwargs)

    def resolve_axes(self, names: Sequence[str], width: int, where: str) -> tuple[str, ...]:
        """The output axes of ``width`` wrench columns read from ``names`` (column names, or one variable):
        ``axes`` if given, else the axes the names say (``Fx``, ``Mz``, ``force_y``), else Fx..Tz for six."""
        if self.axes is not None:
            if len(self.axes) != width:
                raise DatasetFileError(f"{where}: {{axes}} names {len(self.axes)} axes ({','.join(self.axes)}) but "
                                       f"the wrench has {width} columns ({', '.join(names)}); name one axis per "
                                       "column.", parameter="axes", value=self.axes)
            return self.axes
        said = [canonical_wrench_name(n) for n in names] if len(names) == width else []
        if said and all(said) and len(set(said)) == width:
            return tuple(said)
        if width == len(WRENCH_LABELS):
            return WRENCH_LABELS
        example = ','.join(('Fx', 'Fy', 'Fz', 'Tx', 'Ty', 'Tz')[:width]) if width < 6 else 'Fx,...'
        raise DatasetFileError(
            f"{where}: the wrench has {width} column(s) ({', '.join(names)}), which do not say their axes; a "
            f"calibration of {width} axes needs their names.", parameter="axes",
            fix=f"pass {{axes}}, e.g. {{axes}} {example}", settings={"axes": NO_SETTING})


def lever_arm_m(wrench: ArrayLike, axes: Sequence[str] = WRENCH_LABELS) -> float | None:
    """The loads' lever arm [m]: the largest torque norm over the largest force norm (None without both).

    Examples
    --------
    >>> lever_arm_m([[10.0, 0, 0, 0, 0.5, 0]])
    0.05
    >>> lever_arm_m([[10.0, 0, 0]], axes=("Fx", "Fy", "Fz")) is None
    True
    """
    w = np.asarray(wrench, dtype=float)
    fc, tc = force_columns(axes), torque_columns(axes)
    if not fc or not tc or w.shape[0] == 0:
        return None
    f, t = (float(np.max(np.linalg.norm(w[:, c], axis=1), initial=0.0)) for c in (fc, tc))
    if not (f > 0 and t > 0 and np.isfinite(f) and np.isfinite(t)):
        return None
    return t / f


#: Largest force [N] a force/torque calibration plausibly applies (a 10 t load); beyond, the forces are probably
#: in a smaller unit (mN, g); below 0.01 N for the largest load, in a larger one (kN).
_PLAUSIBLE_FORCE_N = (1e-2, 1e5)


def lever_arm_problem(wrench: ArrayLike, torque_unit: str = "N.m", axes: Sequence[str] = WRENCH_LABELS,
                      force_unit: str = "N") -> DatasetFileError | None:
    """What looks wrong with the units of ``wrench`` ([N], [N·m] after conversion), or None when plausible.

    The ratio max‖T‖ / max‖F‖ is the lever arm [m] of the loads. A calibration
    fixture holds its loads within about two metres of the sensor and not closer
    than 0.1 mm; outside that range the torques or the forces are probably in
    another unit. Which one is told by the forces' size: forces in kN read as N
    are tiny (the largest below 0.01 N), torques in N·mm read as N·m large. The
    problem is returned as an error (raise it, or show it as a warning): its fix
    proposes the likely unit (``settings``: ``force_unit`` or ``torque_unit``).

    Examples
    --------
    >>> print(lever_arm_problem([[10.0, 0, 0, 0, 500.0, 0]]))  # doctest: +ELLIPSIS
    the loads' lever arm max|T|/max|F| is 50 m (alpha = 0.02 1/m), implausible ... the torques look like N.mm...
    >>> problem = lever_arm_problem([[0.002, 0, 0, 0, 0.05, 0]])
    >>> print(problem)  # doctest: +ELLIPSIS
    the loads' ... the forces look like kN (the largest is 0.002 N read as N), not N. Fix: pass force_unit='kN'...
    >>> problem.parameter, problem.settings["force_unit"]
    ('force_unit', 'kN')
    >>> lever_arm_problem([[10.0, 0, 0, 0, 0.5, 0]]) is None
    True
    """
    arm = lever_arm_m(wrench, axes)
    if arm is None:
        return None
    low, high = PLAUSIBLE_LEVER_ARM_M
    if low <= arm <= high:
        return None
    w = np.asarray(wrench, dtype=float)
    fmax = float(np.max(np.linalg.norm(w[:, force_columns(axes)], axis=1)))
    head = (f"the loads' lever arm max|T|/max|F| is {arm:.3g} m (alpha = {1.0 / arm:.3g} 1/m), implausible for a "
            f"force/torque calibration (expected {low * 1e3:g} mm to {high:g} m) with forces read as {force_unit} "
            f"and torques as {torque_unit}")
    found = _unit_proposals(arm, fmax, force_unit, torque_unit)
    if not found:
        return DatasetFileError(
            f"{head}, and no common unit of the forces or of the torques makes it plausible (the largest force is "
            f"{fmax:.3g} N read as {force_unit}).", parameter="torque_unit", value=torque_unit,
            fix="check which columns hold the wrench ({wrench}) and declare the units with {force_unit} / "
                "{torque_unit}", settings={"force_unit": NO_SETTING, "wrench": NO_SETTING})
    best = found[0]
    other = next((p for p in found if p.kind != best.kind and (p.fmax >= _PLAUSIBLE_FORCE_N[0]
                                                              or best.fmax < _PLAUSIBLE_FORCE_N[0])), None)
    settings = {f"{best.kind}_unit": best.unit, **({f"{other.kind}_unit": other.unit} if other else {})}
    also = f" (or the {other.kind}s are in {other.unit}: {{{other.kind}_unit}})" if other else ""
    read_as = force_unit if best.kind == "force" else torque_unit
    largest = (f" (the largest is {fmax:.3g} N read as {force_unit})", f", the largest force {best.fmax:.3g} N") \
        if best.kind == "force" else ("", "")  # the forces' size tells a force unit
    return DatasetFileError(
        f"{head}: the {best.kind}s look like {best.unit}{largest[0]}, not {read_as}.", parameter=f"{best.kind}_unit",
        value=read_as, fix=f"pass {{{best.kind}_unit}} (the lever arm would be {best.arm * 1e3:.3g} mm{largest[1]})"
        f"{also}", settings=settings)


@dataclass(frozen=True)
class _UnitProposal:
    """A unit that would make the loads plausible: ``kind`` ("force"/"torque"), its spelling, and the lever arm
    [m] and largest force [N] the loads would then have."""

    kind: str
    unit: str
    arm: float
    fmax: float


#: The force units proposed for a wrong one (their spellings as typed on a keyboard).
_PROPOSED_FORCE_UNITS = ("N", "kN", "mN", "uN", "MN", "g", "kg", "lbf", "kip")
#: The torque units proposed for a wrong one.
_PROPOSED_TORQUE_UNITS = ("N.m", "N.mm", "N.cm", "kN.m", "mN.m", "uN.m", "MN.m", "kN.mm", "mN.mm", "lbf.in",
                          "lbf.ft")
#: A typical lever arm [m] and largest force [N] of a calibration: of two units that both make the loads plausible,
#: the one whose loads lie nearer these (in decades) is proposed first.
_TYPICAL_ARM_M, _TYPICAL_FORCE_N = 0.05, 100.0


def _unit_proposals(arm: float, fmax: float, force_unit: str, torque_unit: str) -> list[_UnitProposal]:
    """The units (of the forces or of the torques, one changed at a time) under which the loads' lever arm is
    plausible and their largest force no more than :data:`_PLAUSIBLE_FORCE_N` allows, checked by converting the
    loads: the likeliest first (loads nearest a typical calibration's). A unit whose result would fail the same
    check, or give absurd forces, is never proposed."""
    low, high = PLAUSIBLE_LEVER_ARM_M
    f_now, t_now = unit_scale(force_unit, "force"), unit_scale(torque_unit, "torque")
    out = []
    for kind, units, now in (("force", _PROPOSED_FORCE_UNITS, f_now), ("torque", _PROPOSED_TORQUE_UNITS, t_now)):
        for unit in units:
            ratio = unit_scale(unit, kind) / now
            if np.isclose(ratio, 1.0, rtol=1e-9):
                continue
            new_arm, new_fmax = (arm / ratio, fmax * ratio) if kind == "force" else (arm * ratio, fmax)
            if low <= new_arm <= high and new_fmax <= _PLAUSIBLE_FORCE_N[1]:
                out.append(_UnitProposal(kind, unit, new_arm, new_fmax))
    fmax_floor = _PLAUSIBLE_FORCE_N[0]
    out.sort(key=lambda p: (p.fmax < fmax_floor, abs(np.log10(p.arm / _TYPICAL_ARM_M))
                            + abs(np.log10(max(p.fmax, 1e-300) / _TYPICAL_FORCE_N))))
    return out


def checked_temperature(values, path, lines, error: type[Exception]):
    """``values`` checked as the temperatures [deg C] of a text file's rows (:func:`check_temperature`), else
    ``error`` naming the file and, for a row, its ``lines`` entry and the column (the library's "{row}" said as
    the column)."""
    from ..core._temperature import TemperatureValueError, check_temperature

    try:
        return check_temperature(values, len(lines))
    except TemperatureValueError as exc:
        if exc.row is None:
            raise error(f"{path}: {exc}") from None
        raise error(f"{path}: line {int(lines[exc.row])}, column temperature: "
                    f"{exc.render(api_spelling, row='temperature')}") from None


# ------------------------------------------------------------------ bounded reading of .npz and .mat
#: The item size [bytes] of MATLAB's numeric classes (as :func:`scipy.io.whosmat` names them).
_MAT_ITEM_BYTES = {"double": 8, "single": 4, "int8": 1, "uint8": 1, "int16": 2, "uint16": 2, "int32": 4,
                   "uint32": 4, "int64": 8, "uint64": 8}


def _mat_cut(path) -> tuple[int, int] | None:
    """``(the file's size, the size its variables declare)`` [bytes] when a MATLAB v5-v7 file ends before its last
    variable does (a truncated copy or download), else ``None``: the variables' tags are walked, none is read."""
    import struct

    from scipy.io.matlab import matfile_version

    with open(path, "rb") as fh:
        try:
            if matfile_version(fh)[0] != 1:  # v4 files have no tags to walk
                return None
        except Exception:  # scipy raises ValueError/TypeError on foreign files
            return None
        size = fh.seek(0, 2)
        fh.seek(126)
        order = "<" if fh.read(2) == b"IM" else ">"
        pos = 128
        while pos + 8 <= size:
            fh.seek(pos)
            kind, n_bytes = struct.unpack(order + "II", fh.read(8))
            pos += 8 + n_bytes
            if kind == 14 and pos % 8:  # an uncompressed matrix is padded to 8 bytes
                pos += 8 - pos % 8
    return (size, pos) if pos > size else None


class ArrayFile:
    """The named arrays of an ``.npz`` or ``.mat`` file: listed without reading them, read one at a time.

    Only the arrays a dataset uses are read (:meth:`read`), each after its declared size was checked against
    ftcal's memory limit: an unused variable, however large or however well compressed, costs nothing.

    Parameters
    ----------
    path : path
        The file; ``.npz`` (any letter case) is a zip of ``.npy`` members, ``.mat`` a MATLAB v4-v7 file (v7.3 is
        HDF5, which ftcal does not read: refused with the fix).
    holds : (str, tuple of str), default=("dataset", ("raw", "wrench"))
        What the file is and the arrays it holds, for the advice of a refusal (``("readings", ("raw",))`` for
        raw readings to predict).
    """

    def __init__(self, path, holds: tuple[str, tuple[str, ...]] = ("dataset", ("raw", "wrench"))) -> None:
        self.holds = holds
        self.path = Path(path)
        self.where = str(path)
        self.is_npz = self.path.suffix.lower() == ".npz"
        self.kind = "array" if self.is_npz else "variable"
        self._zip: zipfile.ZipFile | None = None
        #: for a .mat file cut short: (the bytes it holds, the bytes its variables declare)
        self.cut: tuple[int, int] | None = None
        #: name -> (shape, dtype kind letter or MATLAB class)
        self.entries: dict[str, tuple[tuple[int, ...], str]] = {}
        if self.is_npz:
            self._list_npz()
        else:
            self._list_mat()

    # -- .npz
    def _list_npz(self) -> None:
        from ..core._files import describe_file_start

        if not zipfile.is_zipfile(self.path):  # np.load would try it as a pickle and advise allow_pickle=True
            what, arrays = self.holds
            said = f"the arrays {' and '.join(arrays)}" if len(arrays) > 1 else f"the array {arrays[0]}"
            text = f"a .csv {what} must keep its .csv suffix" if what == "dataset" else f"{what} as text are not .npz"
            raise DatasetFileError(f"{self.where}: not an .npz (zip) archive: {describe_file_start(self.path)}. A "
                                   f"{what} .npz holds {said} (numpy.savez); {text}.")
        try:
            self._zip = zipfile.ZipFile(self.path)
        except (OSError, zipfile.BadZipFile) as exc:
            raise DatasetFileError(f"{self.where}: not a readable .npz {self.holds[0]} ({exc}).") from None
        for member in self._zip.namelist():
            if member.endswith(".npy"):
                self.entries[member[:-4]] = ((), "?")  # the header is read when the array is used

    # -- .mat
    def _list_mat(self) -> None:
        """Each variable's name, shape and class from its header (:func:`scipy.io.whosmat` reads no variable's data:
        a compressed one is inflated only as far as its header, so a crafted or huge unused variable costs nothing);
        a v7.3 (HDF5) file is refused with the fix."""
        from scipy.io import whosmat

        with open(self.path, "rb") as fh:
            head = fh.read(128)
        if b"7.3" in head[:20] or head[124:126] in (b"\x00\x02", b"\x02\x00"):
            self._refuse_hdf5()
        try:
            found = whosmat(self.path)
        except NotImplementedError:
            self._refuse_hdf5()
        except Exception as exc:  # scipy raises ValueError/TypeError/OSError/zlib.error on foreign or damaged files
            raise DatasetFileError(f"{self.where}: not a readable .mat file ({str(exc)[:100]}).") from None
        for name, shape, cls in found:
            self.entries[name] = (tuple(shape), cls)
        self.cut = _mat_cut(self.path)

    def refuse_if_cut(self, sought: str) -> None:
        """A file cut short lists only the variables before the cut: a variable ``sought`` (e.g. ``"variable
        'wrench'"``) missing from it is said to be lost to the cut, not absent."""
        if self.cut is None:
            return
        ends, declared = self.cut
        listed = ", ".join(self.entries) or "no variable"
        raise DatasetFileError(f"{self.where}: the file is truncated or damaged: it ends at byte {ends}, inside a "
                               f"variable that runs to byte {declared}, so only {listed} can be read and {sought} is not "
                               "among them. Fix: copy or save the whole file again.")

    def refuse_missing(self, name: str, option: str) -> None:
        """Refuse the array ``name`` that the argument ``option`` names and the file lacks (or lost to a cut)."""
        self.refuse_if_cut(f"{self.kind} {name!r}")
        raise DatasetFileError(f"{self.where}: {{{option}}} names {self.kind} {name!r}, which the file lacks; the file "
                               f"has {', '.join(n for n in self.entries if n != 'meta_json')}.", parameter=option,
                               value=name)

    def _refuse_hdf5(self) -> None:
        raise DatasetFileError(f"{self.where}: a MATLAB v7.3 (HDF5) file, which ftcal cannot read without the h5py "
                               "package. Fix: save it in MATLAB with save(FILE, ..., '-v7') and retry.")

    # -- both
    def names(self) -> list[str]:
        """The arrays' names, in file order."""
        return list(self.entries)

    def read(self, name: str) -> np.ndarray:
        """The array ``name`` (its size checked before it is read); a non-numeric one is refused by
        :func:`check_real_array` when it is used."""
        if self.is_npz:
            return read_npy_member(self._zip, f"{name}.npy", f"{self.where}: array {name!r}", DatasetFileError,
                                   "save numeric arrays (numpy.savez(path, "
                                   f"{', '.join(f'{a}=...' for a in self.holds[1])}))",
                                   "split the data into smaller files")
        shape, cls = self.entries[name]
        check_allocation(float(np.prod([float(d) for d in shape])) * _MAT_ITEM_BYTES.get(cls, 8),
                         f"{self.where}: variable {name!r} of shape {shape}", "split the data into smaller files")
        if cls == "cell":  # refused unread: a 1x1 cell can hold a compressed bomb its listing does not show
            check_real_array(np.empty(0, dtype=object), name, self.where)
        if cls in ("struct", "object", "function_handle", "opaque"):
            raise DatasetFileError(f"{self.where}: variable {name!r} is a MATLAB {cls} (fields, not an array of "
                                   "numbers); it must be an array of real numbers (double, single or integer).")
        if cls == "logical":  # scipy reads it as uint8: refused here, not fitted as 0/1 numbers
            raise DatasetFileError(f"{self.where}: variable {name!r} is a MATLAB logical array (booleans); it must "
                                   "hold real numbers (double, single or integer).")
        from scipy.io import loadmat

        try:  # scipy skips the other variables unread (a compressed one inflated only as far as its header)
            found = loadmat(self.path, variable_names=[name], squeeze_me=False)
        except Exception as exc:  # scipy raises ValueError/TypeError/OSError/zlib.error on damaged files
            raise DatasetFileError(f"{self.where}: variable {name!r} cannot be read ({str(exc)[:100]}).") from None
        if name not in found:
            raise DatasetFileError(f"{self.where}: variable {name!r} cannot be read; the file is damaged.")
        return found[name]

    def close(self) -> None:
        if self._zip is not None:
            self._zip.close()

    def __enter__(self) -> "ArrayFile":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


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


# ------------------------------------------------------------------ text files
def read_utf8_text(path, what: str, error: type[Exception] = DatasetFileError) -> str:
    """The text of the UTF-8 file ``path`` (a byte-order mark dropped: spreadsheet exports write one), newlines
    as ``\\n``; a file in another encoding raises ``error`` naming the line and byte where it stops being UTF-8 and
    the conversion that fixes it (UTF-16, told by its byte-order mark, said as such). ``what`` ends the message
    (e.g. ``"a dataset CSV is a text file"``).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "d.csv"
    >>> _ = path.write_bytes("s0,Fx\\n1,2\\n".encode("utf-16"))
    >>> read_utf8_text(path, "a dataset CSV is a text file")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.DatasetFileError: ...: UTF-16 text (it starts with a UTF-16 byte-order mark), not UTF-8; a dataset CSV is a text file in UTF-8. Fix: save it as UTF-8, e.g. iconv -f UTF-16 -t UTF-8 d.csv > d-utf8.csv.
    >>> _ = path.write_bytes(b"# temp\\xe9rature\\ns0,Fx\\n")
    >>> read_utf8_text(path, "a dataset CSV is a text file")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.DatasetFileError: ...: line 1 (byte 6): not UTF-8 text (invalid continuation byte); a dataset CSV is a text file in UTF-8. Fix: save it as UTF-8, e.g. iconv -f LATIN1 -t UTF-8 d.csv > d-utf8.csv if it is Latin-1 (Windows-1252: -f CP1252).
    """
    import codecs
    path = Path(path)
    data = path.read_bytes()
    try:
        return data.decode("utf-8-sig").replace("\r\n", "\n").replace("\r", "\n")
    except UnicodeDecodeError as exc:
        if data[:2] in (codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE):
            raise not_utf8_error(str(path), f"{what} in UTF-8", utf16=True, error=error) from None
        at = exc.start + (3 if data.startswith(codecs.BOM_UTF8) else 0)  # counted after the mark
        raise not_utf8_error(str(path), f"{what} in UTF-8", line=data[:at].count(b"\n") + 1, byte=at,
                             reason=exc.reason, error=error) from None


def not_utf8_error(source: str, what: str, *, line: int = 0, byte: int = 0, reason: str = "", utf16: bool = False,
                   error: type[Exception] = DatasetFileError) -> Exception:
    """The refusal of text that is not UTF-8: ``source`` (a path, or ``"stdin"``), where it stops being UTF-8
    (1-based ``line``, 0-based ``byte``, the decoder's ``reason``) or that it is UTF-16 (``utf16``, told by its
    byte-order mark), ``what`` the file must be, and the ``iconv`` conversion that fixes it.

    Examples
    --------
    >>> str(not_utf8_error("stdin", "readings are UTF-8 text", line=2, byte=9, reason="invalid start byte"))
    'stdin: line 2 (byte 9): not UTF-8 text (invalid start byte); readings are UTF-8 text. Fix: pipe it through iconv -f LATIN1 -t UTF-8 if it is Latin-1 (Windows-1252: -f CP1252).'
    """
    path, iconv = Path(source), f"iconv -f {'UTF-16' if utf16 else 'LATIN1'} -t UTF-8"
    fix = f"pipe it through {iconv}" if source == "stdin" else \
        f"save it as UTF-8, e.g. {iconv} {path.name} > {path.stem}-utf8{path.suffix}"
    if utf16:
        return error(f"{source}: UTF-16 text (it starts with a UTF-16 byte-order mark), not UTF-8; {what}. Fix: {fix}.")
    return error(f"{source}: line {line} (byte {byte}): not UTF-8 text ({reason}); {what}. Fix: {fix} if it is "
                 "Latin-1 (Windows-1252: -f CP1252).")


def check_separator(fields: Sequence[str], where: str, *, header: bool = True, next_row: str = "",
                    error: type[Exception] = DatasetFileError) -> None:
    """Refuse a table whose fields are separated by ``;`` (a spreadsheet's export where the decimal mark is a
    comma) or tabs, naming the conversion that makes it comma-separated with decimal points. ``fields``: the first
    line's comma-separated fields; a ``header`` is refused only as one field, and its ``next_row`` (the first data
    row) tells a decimal comma; a first line of data tells it itself.

    Examples
    --------
    >>> check_separator(["s0", "s1", "Fx"], "d.csv: line 1")  # comma-separated: nothing to say
    >>> check_separator(["s0;s1;Fx"], "d.csv: line 1", next_row="1,5;2;3")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.DatasetFileError: d.csv: line 1: the fields are separated by ';' with decimal commas (a spreadsheet export in a locale with a decimal comma?); ftcal reads comma-separated values with decimal points. Fix: convert the file: decimal commas to points and ';' to ',', e.g. tr ',;' '.,' < IN.csv > OUT.csv.
    """
    separator = next((sep for sep in (";", "\t") if any(sep in f for f in fields)), None)
    if separator is None or (header and len(fields) > 1):
        return
    said, typed = ("';'", ";") if separator == ";" else ("tabs", "\\t")  # as said, and as typed for tr
    decimal_comma = "," in next_row if header else len(fields) > 1
    how = (f"decimal commas to points and {said} to ',', e.g. tr ',{typed}' '.,'" if decimal_comma else
           f"{said} to ',', e.g. tr '{typed}' ','") + " < IN.csv > OUT.csv"
    raise error(
        f"{where}: the fields are separated by {said}{' with decimal commas' if decimal_comma else ''}"
        f"{' (a spreadsheet export in a locale with a decimal comma?)' if separator == ';' else ''}; ftcal reads "
        f"comma-separated values with decimal points. Fix: convert the file: {how}.")


# ------------------------------------------------------------------ headerless text files named by the user
def _data_lines(path, what: str) -> tuple[list[str], list[tuple[int, list[str]]], list[str] | None]:
    """A text file's leading ``#`` comment lines, its data rows ``(1-based line, fields)`` and its header's fields
    (None without one: a header is a first line holding a field that is not a number)."""
    try:
        text = read_utf8_text(path, f"{what} is a text file")
    except OSError as exc:
        raise DatasetFileError(f"{path}: cannot be read ({exc.strerror or exc}).") from None
    comments, rows = [], []
    for no, line in enumerate(text.splitlines(), 1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            if not rows:
                comments.append(stripped)
            continue
        # the fields: comma-separated, or separated by spaces / tabs when the line holds no comma
        rows.append((no, [f.strip() for f in stripped.split(",")] if "," in stripped else stripped.split()))
    if rows and _names_columns(rows[0][1], rows[1][1] if len(rows) > 1 else None):
        return comments, rows[1:], rows[0][1]
    return comments, rows, None


def _names_columns(first: list[str], second: list[str] | None) -> bool:
    """Whether a text file's first line is a header: it holds text where the next line holds a number (a column
    named above its numbers). A text column that is data (run names beside numbers: ``run_01,0.5,...``) is text in
    both lines, so a line holding numbers whose text fields line up with the next line's is data; a line without
    a number, or without a next line to compare, is a header when it holds text."""
    text = [bool(f) and not is_number(f) for f in first]
    if not any(text):
        return False
    if second is None or len(second) != len(first) or all(text):  # no number at all: names, not a log's row
        return True
    return any(t and f and is_number(f) for t, f in zip(text, second))


def has_header(path) -> bool:
    """Whether the text file ``path`` starts (after ``#`` comments and blank lines) with a line naming its columns.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (folder / "a.txt").write_text("0.1 0.2 0.3\\n"); _ = (folder / "b.csv").write_text("# x\\nFx,Fy\\n1,2\\n")
    >>> has_header(folder / "a.txt"), has_header(folder / "b.csv")
    (False, True)
    >>> _ = (folder / "empty.csv").write_text("")
    >>> has_header(folder / "empty.csv")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.DatasetFileError: ...empty.csv: the file is empty (0 bytes). Fix: give the file that holds the recording (the copy or export may have failed).

    Raises
    ------
    DatasetFileError
        When the file holds no line at all (empty, or only blank and ``#`` comment lines): neither a header nor
        numbers.
    """
    comments, rows, header = _data_lines(path, "the file")
    if not rows and header is None:
        size = Path(path).stat().st_size
        said = "is empty (0 bytes)" if size == 0 else f"holds no header and no data ({size} bytes of " + \
            ("# comments" if comments else "blank lines") + ")"
        raise DatasetFileError(f"{path}: the file {said}. Fix: give the file that holds the recording (the copy or "
                               "export may have failed).")
    return header is not None


@dataclass(frozen=True)
class JoinedTable:
    """Headerless text files joined side by side under the column names the user gave (:func:`join_headerless`).

    Attributes
    ----------
    names : tuple of str
        The columns, in order.
    rows : list of list of str
        The fields of each row (the files' fields, side by side).
    lines : tuple of int
        The 1-based line of each row in the first file (the files' rows are paired in order).
    files : tuple of str
        The files joined.
    comments : tuple of str
        The first file's leading ``#`` comment lines.
    """

    names: tuple[str, ...]
    rows: list
    lines: tuple[int, ...]
    files: tuple[str, ...]
    comments: tuple[str, ...] = ()

    @property
    def name(self) -> str:
        """The files' names joined by ``+`` (``pose.txt+wrench.txt``)."""
        return "+".join(Path(f).name for f in self.files)

    def to_csv(self) -> str:
        """The table as CSV text: the comments, a header line of :attr:`names`, one line per row."""
        body = [",".join(self.names)] + [",".join(r) for r in self.rows]
        return "\n".join([*self.comments, *body]) + "\n"

    def write(self, path) -> None:
        """Write :meth:`to_csv` to ``path`` (a new file)."""
        with open(Path(path), "x", encoding="utf-8", newline="\n") as fh:
            fh.write(self.to_csv())


def join_headerless(paths: Sequence, names: Sequence[str]) -> JoinedTable:
    """Text files without a header, joined side by side in the order given, their columns named ``names``.

    A pose file ``x,y,z,qx,qy,qz,qw`` and a wrench file ``Fx,...,Tz`` of a gravity-compensation tool, both
    without a header and one row per pose, become one table of 13 named columns. Fields are comma-separated, or
    separated by spaces / tabs; ``#`` comments and blank lines are skipped. Ranges such as ``s0..s5`` are written
    out (:func:`expand_names`).

    Raises
    ------
    DatasetFileError
        A file that has a header (its names would be lost), files of different row counts (naming both and their
        counts), a row of another width than the file's first, or names that do not count the files' columns.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (folder / "pose.txt").write_text("0 0 0.5\\n0 0.1 0.5\\n")
    >>> _ = (folder / "wrench.txt").write_text("1.0,2.0\\n1.5,2.5\\n")
    >>> table = join_headerless([folder / "pose.txt", folder / "wrench.txt"], ["x", "y", "z", "Fx", "Fz"])
    >>> print(table.to_csv(), end="")
    x,y,z,Fx,Fz
    0,0,0.5,1.0,2.0
    0,0.1,0.5,1.5,2.5
    >>> table.name, table.lines
    ('pose.txt+wrench.txt', (1, 2))
    """
    names = expand_names(list(names), "columns")
    if not names or any(not n for n in names):
        raise DatasetFileError(f"{{columns}} {','.join(names)!r} holds an empty name; give comma-separated names, "
                               "e.g. x,y,z,qx,qy,qz,qw,Fx,Fy,Fz,Tx,Ty,Tz.", parameter="columns", value=names)
    _refuse_repeated(names, "{columns} names", "columns")
    parts, widths = [], []
    for path in paths:
        comments, rows, header = _data_lines(path, "a headerless input")
        if header is not None:
            raise DatasetFileError(f"{path}: the file has a header ({','.join(header)[:80]}); {{columns}} names the "
                                   "columns of files without one. Fix: drop {columns}, or drop the header line.",
                                   parameter="columns", value=names)
        if not rows:
            raise DatasetFileError(f"{path}: no data rows.")
        width = len(rows[0][1])
        # a column whose first row is text is a text column (run names): its fields stay text; the others numbers
        textual = [bool(f) and not is_number(f) for f in rows[0][1]]
        for no, fields in rows:
            if len(fields) != width:
                raise DatasetFileError(f"{path}: line {no}: {len(fields)} values but the file's first row has "
                                       f"{width}; repair or remove that line.")
            bad = next((f for f, t in zip(fields, textual) if not t and (not is_number(f)
                                                                      or not np.isfinite(float(f)))), None)
            if bad is not None:  # said here, in the user's file and line (the joined table is ftcal's own)
                raise DatasetFileError(f"{path}: line {no}: {bad.strip()[:40]!r} is not a finite number; repair or "
                                       "remove that line.")
        parts.append((comments, rows))
        widths.append(width)
    counts = [len(rows) for _, rows in parts]
    if len(set(counts)) > 1:
        k = next(i for i, c in enumerate(counts) if c != counts[0])
        raise DatasetFileError(f"{paths[0]} holds {counts[0]} rows but {paths[k]} holds {counts[k]}; files joined "
                               "side by side need one row each per sample, in the same order.")
    if sum(widths) != len(names):
        held = " + ".join(f"{p} ({w})" for p, w in zip(paths, widths))
        raise DatasetFileError(f"{{columns}} names {len(names)} columns but the files hold {sum(widths)}: {held}; "
                               "name each column once, in file order.", parameter="columns", value=names)
    rows = [[f for _, part in parts for f in part[i][1]] for i in range(counts[0])]
    return JoinedTable(names=names, rows=rows, lines=tuple(no for no, _ in parts[0][1]),
                       files=tuple(str(p) for p in paths), comments=tuple(parts[0][0]))
