"""Reader for ATI Industrial Automation calibration files (``.cal``, XML).

Layout (CalFileVersion 1.x)::

    <FTSensor Serial="FT8578" BodyStyle="Gamma" NumGages="6" ...>
      <Calibration PartNumber="SI-130-10" CalDate="3/5/2014"
                   ForceUnits="N" TorqueUnits="N-m" DistUnits="m" ...>
        <Axis Name="Fx" values="-0.27053 ... 32.83006" max="130" scale="2.3399"/>
        ... (Fy, Fz, Tx, Ty, Tz)
        <BasicTransform Dx="0" Dy="0" Dz="0.0120142" Rx="0" Ry="0" Rz="0"/>
        <UserAxis Name="Fx" values="-0.11562 ... 14.03035" max="130"/>
        ... (Fy, Fz, Tx, Ty, Tz)
      </Calibration>
    </FTSensor>

Two forms give the 6 x N matrix (rows ``Fx ... Tz``, one column per gauge):

* ``UserAxis`` rows (preferred, as ATI's own file comment says): the matrix
  in the user's units and frame, used as is.
* ``Axis`` rows only: each row divided by its ``scale`` gives the matrix in
  the *basic* frame; the ``BasicTransform`` then moves the torque reference
  point by ``-D`` (``T_user = T_basic - D x F``) and rotates by
  ``R = Rx(Rx) Ry(Ry) Rz(Rz)`` (angles in degrees, fixed x-y-z order, the tool
  transform of ATI's DAQ F/T library): ``F_user = Rᵀ F``,
  ``T_user = Rᵀ (T - D x F)``. The translation part reproduces the
  ``UserAxis`` rows of published ATI files to their printed digits; every
  file we have seen has zero rotations.

Units are converted to [N], [N·m] (``lbf``, ``klbf``, ``kN``, ``g``, ``kg``,
``N-mm``, ``lbf-in``, ``lbf-ft``, ``kN-m``, ``g-cm``, ``kg-cm``; distances
``m``, ``mm``, ``cm``, ``in``, ``ft``); the original units are kept in
``profile.meta``. The raw unit is [V] (ATI DAQ gauges). Each axis' ``max`` is
its rated range.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..core._exceptions import CalFileError
from ._sensor import SensorProfile
from ..core._wrench import WRENCH_LABELS

__all__ = ["read_ati_calibration"]

_FORCE_TO_N = {"n": 1.0, "kn": 1e3, "mn": 1e-3, "lbf": 4.4482216152605, "lb": 4.4482216152605,
               "klbf": 4448.2216152605, "g": 9.80665e-3, "gf": 9.80665e-3, "kg": 9.80665, "kgf": 9.80665}
_TORQUE_TO_NM = {"n-m": 1.0, "nm": 1.0, "n·m": 1.0, "n-mm": 1e-3, "nmm": 1e-3, "kn-m": 1e3,
                 "lbf-in": 0.1129848290276167, "lb-in": 0.1129848290276167, "lbf-ft": 1.3558179483314004,
                 "lb-ft": 1.3558179483314004, "klbf-in": 112.9848290276167, "g-cm": 9.80665e-5,
                 "gf-cm": 9.80665e-5, "kg-cm": 0.0980665, "kgf-cm": 0.0980665}
_DIST_TO_M = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254, "ft": 0.3048}


def _unit_factor(path: Path, cal: ET.Element, attribute: str, table: dict[str, float], default: str) -> tuple[str, float]:
    unit = cal.get(attribute, default)
    try:
        return unit, table[unit.strip().lower()]
    except KeyError:
        raise CalFileError(
            f"{path}: {attribute}={unit!r} is not a known unit; expected one of {sorted(table)}."
        ) from None


def _attribute(path: Path, element: ET.Element, attribute: str) -> tuple[str, str]:
    """The text of ``attribute`` of ``element`` and how messages name the element; an error when it is missing."""
    where = f"<{element.tag} Name={element.get('Name')!r}>" if element.get("Name") else f"<{element.tag}>"
    text = element.get(attribute)
    if text is None:
        raise CalFileError(f"{path}: {where} has no {attribute!r} attribute.")
    return text, where


def _number(path: Path, element: ET.Element, attribute: str) -> float:
    text, where = _attribute(path, element, attribute)
    try:
        value = float(text)
    except ValueError:
        raise CalFileError(f"{path}: {where} attribute {attribute}={text!r} is not a number.") from None
    if not np.isfinite(value):
        raise CalFileError(f"{path}: {where} attribute {attribute}={text!r} is not finite.")
    return value


#: Largest rated range [N or N·m] accepted from a calibration file (the largest F/T sensors are rated ~1e5 N).
_MAX_RATED_RANGE = 1e7


def _axis_rows(path: Path, cal: ET.Element, tag: str, n_gauges: int | None) -> tuple[NDArray, NDArray, list]:
    """Matrix rows (6, N), the ``max`` per axis and the elements, in Fx..Tz order."""
    elements = {}
    for el in cal.findall(tag):
        name = el.get("Name")
        if name not in WRENCH_LABELS:
            raise CalFileError(f"{path}: <{tag}> with Name={name!r}; expected one of {list(WRENCH_LABELS)}.")
        if name in elements:
            raise CalFileError(f"{path}: <{tag} Name={name!r}> appears twice; each axis must appear once.")
        elements[name] = el
    missing = [a for a in WRENCH_LABELS if a not in elements]
    if missing:
        raise CalFileError(f"{path}: <{tag}> rows for {missing} are missing; a 6-axis calibration needs Fx..Tz.")
    rows, maxima = [], []
    for name in WRENCH_LABELS:
        el = elements[name]
        text, _ = _attribute(path, el, "values")
        try:
            row = [float(v) for v in text.split()]
        except ValueError:
            raise CalFileError(f"{path}: <{tag} Name={name!r}> values={text.strip()!r} holds a non-number.") from None
        if not row or not np.all(np.isfinite(row)):
            raise CalFileError(f"{path}: <{tag} Name={name!r}> values={text.strip()!r} is empty or not finite.")
        rows.append(row)
        maxima.append(_number(path, el, "max"))
    lengths = {len(r) for r in rows}
    if len(lengths) != 1:
        counts = {n: len(r) for n, r in zip(WRENCH_LABELS, rows)}
        raise CalFileError(f"{path}: <{tag}> rows have different numbers of gauge values {counts}; all must match.")
    if n_gauges is not None and lengths != {n_gauges}:
        raise CalFileError(f"{path}: NumGages={n_gauges} but the <{tag}> rows hold {lengths.pop()} values each.")
    return np.array(rows), np.array(maxima), [elements[n] for n in WRENCH_LABELS]


def _basic_transform(path: Path, cal: ET.Element, dist_factor: float) -> NDArray[np.float64]:
    """6 x 6 map from basic-frame to user-frame wrenches [N, N·m] (identity without BasicTransform)."""
    el = cal.find("BasicTransform")
    if el is None:
        return np.eye(6)
    d = np.array([_number(path, el, k) if el.get(k) is not None else 0.0 for k in ("Dx", "Dy", "Dz")]) * dist_factor
    angles = [np.deg2rad(_number(path, el, k)) if el.get(k) is not None else 0.0 for k in ("Rx", "Ry", "Rz")]
    rt = Rotation.from_euler("XYZ", angles).as_matrix().T  # Rx Ry Rz
    skew_d = np.cross(d, np.eye(3)).T  # skew_d @ F = d x F
    return np.block([[rt, np.zeros((3, 3))], [-rt @ skew_d, rt]])


def _parse(path: Path) -> ET.Element:
    if not path.is_file():
        raise CalFileError(f"{path}: no such calibration file.")
    try:
        return ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise CalFileError(f"{path}: not well-formed XML ({exc}); is this an ATI .cal file?") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CalFileError(f"{path}: cannot be read ({exc}).") from None


def read_ati_calibration(path: str | Path, calibration_index: int = 0) -> SensorProfile:
    """Read an ATI ``.cal`` file into a :class:`SensorProfile` in [N], [N·m] and [V].

    Parameters
    ----------
    path : str or Path
        The ``.cal`` (XML) file.
    calibration_index : int, default=0
        Which ``<Calibration>`` to use when the file holds several.

    Returns
    -------
    SensorProfile
        ``calibration_matrix`` (6, NumGages), ``axis_max`` from each axis'
        ``max``, ``fmax`` / ``tmax`` the largest force / torque range, and
        ``meta`` with the serial, body style, part number, date, original
        units and which form (``UserAxis`` or ``Axis``) was used.

    Raises
    ------
    CalFileError
        Missing file, malformed XML, missing or duplicate axes, rows of
        unequal length, non-numbers, zero scales, unknown units.

    Examples
    --------
    >>> import tempfile, os
    >>> rows = "".join(f'<UserAxis Name="{a}" values="{" ".join("1" if j == i else "0" for j in range(6))}" '
    ...                f'max="{100 if i < 3 else 5}"/>' for i, a in enumerate(["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"]))
    >>> xml = f'<FTSensor NumGages="6"><Calibration ForceUnits="N" TorqueUnits="N-mm">{rows}</Calibration></FTSensor>'
    >>> with tempfile.TemporaryDirectory() as d:
    ...     p = os.path.join(d, "s.cal")
    ...     _ = open(p, "w").write(xml)
    ...     prof = read_ati_calibration(p)
    >>> float(prof.calibration_matrix[3, 3]), prof.tmax   # N-mm rows converted to N·m
    (0.001, 0.005)
    """
    path = Path(path)
    root = _parse(path)
    cals = [root] if root.tag == "Calibration" else root.findall(".//Calibration")
    if not cals:
        raise CalFileError(f"{path}: no <Calibration> element inside <{root.tag}>; an ATI .cal file holds "
                          "<FTSensor> with at least one <Calibration> (with its <Axis> or <UserAxis> rows).")
    if not 0 <= calibration_index < len(cals):
        raise CalFileError(f"{path}: calibration_index={calibration_index} but the file holds {len(cals)} <Calibration>.")
    cal = cals[calibration_index]
    n_gauges = int(_number(path, root, "NumGages")) if root.get("NumGages") is not None else None
    force_unit, f_factor = _unit_factor(path, cal, "ForceUnits", _FORCE_TO_N, "N")
    torque_unit, t_factor = _unit_factor(path, cal, "TorqueUnits", _TORQUE_TO_NM, "N-m")
    dist_unit, d_factor = _unit_factor(path, cal, "DistUnits", _DIST_TO_M, "m")
    to_si = np.array([f_factor] * 3 + [t_factor] * 3)
    form = "UserAxis" if cal.findall("UserAxis") else "Axis"
    rows, maxima, elements = _axis_rows(path, cal, form, n_gauges)
    if form == "UserAxis":
        matrix = rows * to_si[:, None]
    else:
        scales = np.array([_number(path, el, "scale") for el in elements])
        zero = [a for a, s in zip(WRENCH_LABELS, scales) if s == 0]
        if zero:
            raise CalFileError(f"{path}: <Axis> rows {zero} have scale=0; the scale divides the row and must not be 0.")
        basic = rows / scales[:, None] * to_si[:, None]
        matrix = _basic_transform(path, cal, d_factor) @ basic
    if np.any(maxima <= 0):
        bad = [a for a, m in zip(WRENCH_LABELS, maxima) if m <= 0]
        raise CalFileError(f"{path}: axes {bad} have max <= 0; 'max' is the rated range and must be positive.")
    axis_max = maxima * to_si
    implausible = [f"{a}={m:g}" for a, m in zip(WRENCH_LABELS, axis_max) if m > _MAX_RATED_RANGE]
    if implausible:
        raise CalFileError(
            f"{path}: rated ranges {implausible} (in N and N·m) exceed {_MAX_RATED_RANGE:g}, more than any "
            "force/torque sensor is rated for; check the 'max' attributes and the units."
        )
    meta = {
        "source": str(path),
        "form": form,
        "serial": root.get("Serial", ""),
        "body_style": root.get("BodyStyle", ""),
        "part_number": cal.get("PartNumber", ""),
        "cal_date": cal.get("CalDate", ""),
        "file_units": {"force": force_unit, "torque": torque_unit, "distance": dist_unit},
        "n_calibrations": len(cals),
    }
    name = " ".join(v for v in (meta["body_style"], meta["serial"], meta["part_number"]) if v) or path.name
    try:
        return SensorProfile(
            calibration_matrix=matrix,
            fmax=float(axis_max[:3].max()),
            tmax=float(axis_max[3:].max()),
            name=name,
            axis_max=tuple(axis_max),
            raw_unit="V",
            meta=meta,
        )
    except ValueError as exc:
        raise CalFileError(f"{path}: {exc}") from None
