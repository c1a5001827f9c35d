"""Typed fields of the files and settings a user writes (a tool file's JSON, a report's conditions): a number is a
number, not ``true``; a huge integer gets ftcal's message, not Python's; a physical quantity lies in its range.

JSON and YAML read ``true`` as a bool, which Python counts as the integer 1 (``"mass_kg": true`` would be a 1 kg
tool), and an integer of 400 digits as an int that no float holds (``OverflowError``). These helpers refuse both
with a :class:`~ftcal.core.CalibrationInputError` that names the field and the file.

Examples
--------
>>> number_field(1.25, "mass_kg", where="t.tool.json")
1.25
>>> number_field(True, "mass_kg", where="t.tool.json")
Traceback (most recent call last):
...
ftcal.core._exceptions.CalibrationInputError: t.tool.json: mass_kg must be a number; got true (a bool).
>>> celsius_field("296", "ambient_temperature")
Traceback (most recent call last):
...
ftcal.core._exceptions.CalibrationInputError: ambient_temperature 296 °C is not an ambient temperature (-60 to 80 °C); if it is in kelvin (22.85 °C), write '296 K'.
>>> celsius_field("296 K", "ambient_temperature"), celsius_field(21.5, "ambient_temperature")
(22.85, 21.5)
"""

from __future__ import annotations

import math
import numbers
import re

import numpy as np
from numpy.typing import NDArray

from ._exceptions import CalibrationInputError

__all__ = ["number_field", "numbers_field", "celsius_field", "AMBIENT_CELSIUS"]

#: The ambient temperatures [°C] a calibration is done at (a lab, a shop floor, a cold store, a hot cell).
AMBIENT_CELSIUS = (-60.0, 80.0)
_KELVIN_OFFSET = 273.15
_TEMPERATURE = re.compile(r"\s*([+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?|[+-]?nan|[+-]?inf(?:inity)?)\s*"
                          r"(°\s*C|°C|º\s*C|C|degC|deg C|K|°\s*F|F|degF)?\s*", re.IGNORECASE)


def _shown(value) -> str:
    if isinstance(value, bool):
        return f"{str(value).lower()} (a bool)"
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _prefix(where: str) -> str:
    return f"{where}: " if where else ""


def number_field(value, name: str, *, where: str = "", low: float | None = None, high: float | None = None) -> float:
    """``value`` as a finite float: an int or float (not a bool, not text), within ``[low, high]`` when given.

    Raises
    ------
    CalibrationInputError
        A bool, text or another type; an integer too large for a float; NaN or inf; a value outside the range.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise CalibrationInputError(f"{_prefix(where)}{name} must be a number; got {_shown(value)}.")
    try:
        out = float(value)
    except OverflowError:
        raise CalibrationInputError(f"{_prefix(where)}{name} must be a number a float holds; got an integer of "
                                    f"{len(str(abs(int(value))))} digits.") from None
    if not math.isfinite(out):
        raise CalibrationInputError(f"{_prefix(where)}{name} must be a finite number; got {out!r}.")
    if (low is not None and out < low) or (high is not None and out > high):
        raise CalibrationInputError(f"{_prefix(where)}{name} must lie in [{low:g}, {high:g}]; got {out:g}."
                                    if low is not None and high is not None else
                                    f"{_prefix(where)}{name} must be {'>= ' + format(low, 'g') if low is not None else '<= ' + format(high, 'g')}; got {out:g}.")
    return out


def numbers_field(value, name: str, shape: tuple[int, ...], *, where: str = "") -> NDArray[np.float64]:
    """``value`` (a list of numbers, nested for 2-D) as a finite float array of ``shape``; each element as
    :func:`number_field` (a bool or text refused). The shape is checked before any element is converted."""
    def flat(v, depth: int) -> list:
        if depth == len(shape):
            return [number_field(v, name, where=where)]
        if not isinstance(v, (list, tuple)) or len(v) != shape[depth]:
            raise CalibrationInputError(f"{_prefix(where)}{name} must be {' x '.join(map(str, shape))} numbers; got "
                                        f"{_shown(v)}.")
        return [x for item in v for x in flat(item, depth + 1)]

    return np.array(flat(value, 0), dtype=float).reshape(shape)


def celsius_field(value, name: str, *, where: str = "", low: float = AMBIENT_CELSIUS[0],
                  high: float = AMBIENT_CELSIUS[1]) -> float:
    """A temperature [°C] from a number (°C) or a text with its unit (``"22.5"``, ``"22.5 °C"``, ``"296 K"``,
    ``"72 °F"``: converted), within ``[low, high]`` °C. A value outside that says which unit it would fit."""
    if isinstance(value, bool):
        raise CalibrationInputError(f"{_prefix(where)}{name} must be a temperature; got {_shown(value)}.")
    if isinstance(value, numbers.Real):
        number, unit = number_field(value, name, where=where), "C"
    else:
        m = _TEMPERATURE.fullmatch(str(value)) if isinstance(value, str) else None
        if m is None:
            raise CalibrationInputError(f"{_prefix(where)}{name} {_shown(value)} is not a temperature; give a number "
                                        "in °C, or a number and its unit ('22.5 °C', '295.6 K').")
        number = float(m.group(1))
        if not math.isfinite(number):
            raise CalibrationInputError(f"{_prefix(where)}{name} must be a finite temperature; got {m.group(1)!r}.")
        unit = re.sub(r"[°º\s]|deg", "", m.group(2) or "C", flags=re.IGNORECASE).upper()
    celsius = {"C": number, "K": number - _KELVIN_OFFSET, "F": (number - 32.0) * 5.0 / 9.0}[unit]
    if not low <= celsius <= high:
        said = {"C": "°C", "K": "K", "F": "°F"}[unit]
        hint = ""
        if unit == "C" and low <= number - _KELVIN_OFFSET <= high:
            hint = f"; if it is in kelvin ({number - _KELVIN_OFFSET:.4g} °C), write '{number:g} K'"
        elif unit == "C" and low <= (number - 32.0) * 5.0 / 9.0 <= high:
            hint = f"; if it is in °F ({(number - 32.0) * 5.0 / 9.0:.3g} °C), write '{number:g} °F'"
        raise CalibrationInputError(f"{_prefix(where)}{name} {number:g} {said} is not an ambient temperature "
                                    f"({low:g} to {high:g} °C){hint}.")
    return round(celsius, 10)
