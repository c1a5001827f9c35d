"""Domain errors of ftcal, in one place.

Every error a user can cause derives from :class:`FtcalError`. Errors about bad
values also derive from :class:`ValueError`, so code written against the plain
Python and scikit-learn conventions (``except ValueError``) keeps working.

Errors carry fields
-------------------
An error may say, besides its message, which argument it is about
(``parameter``, ``value``) and what to do (``fix``, with the argument values it
proposes in ``settings``). Its ``str`` is the library's own words, in the terms
of the Python API (``n_poses``, ``overwrite=True``). A front end says the same
in its own terms without parsing that text: the message and the fix are
templates whose fields are argument names (``"{n_poses} must be ..."``,
``"pass {overwrite}"``), and :meth:`FtcalError.render` spells each field as the
front end names that argument (the command line: ``--next``, ``--force``). Only
the declared fields are filled (the ``parameter`` and the names of ``settings``;
a setting of :data:`NO_SETTING` names an argument without proposing a value; the
message only names its fields, the fix spells them with the values it proposes), so
a file name or a value with braces in the message stays as it is. An error about
one row of an array carries it as ``row`` and writes ``{row}`` where it names that
row (``X row 3`` in the library's words); a front end that knows where the row came
from (the line of a file) says it its own way (``render(..., row="the reading")``).

Examples
--------
>>> err = PlanningError("{n_poses} must be at most 642; got 100000.", parameter="n_poses", value=100000,
...                     fix="pass {candidate_subdivisions} for more candidates", settings={"candidate_subdivisions": 4})
>>> str(err)
'n_poses must be at most 642; got 100000. Fix: pass candidate_subdivisions=4 for more candidates.'
>>> err.parameter, err.value, isinstance(err, ValueError)
('n_poses', 100000, True)
>>> err.render(lambda name, setting: "--" + name.replace("_", "-") + ("" if setting is NO_SETTING else f" {setting}"))
'--n-poses must be at most 642; got 100000. Fix: pass --candidate-subdivisions 4 for more candidates.'
>>> bad = CalibrationInputError("{row} is NaN.", parameter="X", row=3)
>>> str(bad), bad.row, bad.render(api_spelling, row="the reading")
('X row 3 is NaN.', 3, 'the reading is NaN.')
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["NO_SETTING", "Placeholder", "FtcalError", "CalibrationInputError", "TooFewSamplesError", "ModelFileError",
           "LogFormatError", "CalFileError", "KinematicsError", "DatasetFileError", "BenchmarkOutputExistsError",
           "ExportError", "PlanningError"]


class _NoSetting:
    def __repr__(self) -> str:
        return "NO_SETTING"

    def __reduce__(self) -> str:  # one object, also in an error sent back by a Dask worker
        return "NO_SETTING"


#: What :meth:`FtcalError.render` passes for a field that names an argument without proposing a value for it.
NO_SETTING: Any = _NoSetting()


class Placeholder:
    """A proposed value that the user fills in (``sensor_frame=<frame at the sensing origin>``): written as its text.

    Examples
    --------
    >>> repr(Placeholder("<frame name>"))
    '<frame name>'
    """

    def __init__(self, text: str) -> None:
        self.text = text

    def __repr__(self) -> str:
        return self.text

    __str__ = __repr__


def api_spelling(name: str, setting: Any) -> str:
    """How the library writes a field: the argument's name, with ``=value`` when the error proposes a value."""
    return name if setting is NO_SETTING else f"{name}={setting!r}"


class FtcalError(Exception):
    """Base class of every error ftcal raises on purpose.

    Parameters
    ----------
    message : str
        What is wrong, in the library's words. With fields (``parameter`` or ``settings`` given) it is a template:
        ``{name}`` stands for the argument ``name`` (module docstring).
    parameter : str, optional
        The argument the error is about, by its name in the Python API (``"n_poses"``, ``"X"``).
    value : object, optional
        The offending value of ``parameter``.
    fix : str, optional
        What to do, in the API's terms (a template as ``message``); ``str(error)`` ends with ``Fix: <fix>``.
    settings : mapping, optional
        The argument values the fix proposes (``{"overwrite": True}``): its fields are spelled with their value.
    row : int, optional
        The offending row of ``parameter`` (counted from 0); the message writes it as ``{row}``.
    """

    def __init__(self, message: str = "", *, parameter: str | None = None, value: Any = None,
                 fix: str | None = None, settings: Mapping[str, Any] | None = None, row: int | None = None) -> None:
        self.template = str(message)
        self.parameter = parameter
        self.value = value
        self.fix = fix
        self.settings = dict(settings or {})
        self.row = row
        self.has_fields = parameter is not None or bool(self.settings) or row is not None
        super().__init__(self.render(api_spelling))

    def located(self, prefix: str) -> "FtcalError":
        """The same error (class and fields) with ``prefix`` in front of its message: where it happened
        (``"data.csv: "``), for a caller that knows more than the function that raised it."""
        copy = type(self).__new__(type(self))
        copy.__dict__.update(self.__dict__)
        copy.template = prefix + self.template
        Exception.__init__(copy, copy.render(api_spelling))
        return copy

    @property
    def fields(self) -> list[str]:
        """The argument names the message and the fix may refer to as ``{name}``: ``parameter``, then ``settings``."""
        return ([self.parameter] if self.parameter is not None else []) + [n for n in self.settings
                                                                            if n != self.parameter]

    def _fill(self, text: str, spell: Callable[[str, Any], str], row: str | None = None, *,
              proposing: bool = True) -> str:
        for name in self.fields:
            setting = self.settings.get(name, NO_SETTING) if proposing else NO_SETTING
            text = text.replace("{" + name + "}", spell(name, setting))
        if self.row is not None:
            own = f"{spell(self.parameter, NO_SETTING)} row {self.row}" if self.parameter else f"row {self.row}"
            text = text.replace("{row}", own if row is None else row)
        return text

    def render_fix(self, spell: Callable[[str, Any], str]) -> str | None:
        """The fix alone, its fields spelled by ``spell`` (None without a fix)."""
        return self._fill(self.fix, spell) if self.fix else None

    def render(self, spell: Callable[[str, Any], str], fix: str | None = None, row: str | None = None) -> str:
        """The message (and fix) with each field spelled by ``spell(name, setting)``; ``setting`` is the value
        the error proposes for that argument, or :data:`NO_SETTING`. ``fix`` replaces the error's own fix (a
        front end's advice where it has no equivalent of the argument); ``row`` replaces the error's words for
        its ``{row}`` (``"the reading"`` where the front end names the line of a file)."""
        text = self._fill(self.template, spell, row, proposing=False)  # the message names; the fix proposes
        advice = fix if fix is not None else self.render_fix(spell)
        if advice:
            advice = advice if advice.endswith((".", "!", "?")) else f"{advice}."
            text = text.rstrip()
            text = f"{text} Fix: {advice}" if text.endswith((".", ":", ";", "?", "!")) else f"{text}. Fix: {advice}"
        return text


class CalibrationInputError(FtcalError, ValueError):
    """Raw readings or wrenches that a calibrator cannot use (shape, NaN, inf, ...)."""


class TooFewSamplesError(CalibrationInputError):
    """Fewer training rows (``value``) than an estimator (named ``estimator``) needs (``needed``).

    Examples
    --------
    >>> err = TooFewSamplesError("X has 5 sample(s), but M needs at least 7.", parameter="X", value=5, needed=7,
    ...                          estimator="M")
    >>> err.value, err.needed, err.estimator, isinstance(err, CalibrationInputError)
    (5, 7, 'M', True)
    """

    def __init__(self, message: str = "", *, needed: int | None = None, estimator: str | None = None,
                 **fields: Any) -> None:
        super().__init__(message, **fields)
        self.needed = needed
        self.estimator = estimator


class ModelFileError(FtcalError, ValueError):
    """A model file that is missing, truncated, of another version or another model type."""


class LogFormatError(FtcalError, ValueError):
    """A recorded-run log file that does not follow the documented layout."""


class CalFileError(FtcalError, ValueError):
    """A vendor calibration file (for example an ATI ``.cal``) that cannot be read."""


class KinematicsError(FtcalError, ValueError):
    """A robot model, frame name, joint vector or pose target that cannot be used."""


class DatasetFileError(FtcalError, ValueError):
    """A calibration dataset file that is missing columns, values or is malformed."""


class BenchmarkOutputExistsError(FtcalError, FileExistsError):
    """A benchmark output file exists that the benchmark did not write (or that was changed since)."""


class ExportError(FtcalError, ValueError):
    """A calibrator that cannot be exported (to ONNX): its type, a missing optional package, or an existing file."""


class ExportExistsError(ExportError, FileExistsError):
    """The export's target file exists and ``overwrite`` is False: an :class:`ExportError` and a ``FileExistsError``."""


class PlanningError(FtcalError, ValueError):
    """A pose plan or proposal that cannot be made: more poses than reachable candidates, fewer than the
    calibration model's parameters, a dataset and a model of different channel counts."""
