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
a setting of :data:`NO_SETTING` names an argument without proposing a value), so
a file name or a value with braces in the message stays as it is.

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
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

__all__ = [
    "NO_SETTING",
    "Placeholder",
    "FtcalError",
    "CalibrationInputError",
    "ModelFileError",
    "LogFormatError",
    "CalFileError",
    "KinematicsError",
    "DatasetFileError",
    "BenchmarkOutputExistsError",
    "ExportError",
    "PlanningError",
]


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
    """

    def __init__(self, message: str = "", *, parameter: str | None = None, value: Any = None,
                 fix: str | None = None, settings: Mapping[str, Any] | None = None) -> None:
        self.template = str(message)
        self.parameter = parameter
        self.value = value
        self.fix = fix
        self.settings = dict(settings or {})
        self.has_fields = parameter is not None or bool(self.settings)
        super().__init__(self.render(api_spelling))

    @property
    def fields(self) -> list[str]:
        """The argument names the message and the fix may refer to as ``{name}``: ``parameter``, then ``settings``."""
        return ([self.parameter] if self.parameter is not None else []) + [n for n in self.settings
                                                                            if n != self.parameter]

    def render(self, spell: Callable[[str, Any], str], fix: str | None = None) -> str:
        """The message (and fix) with each field spelled by ``spell(name, setting)``; ``setting`` is the value
        the error proposes for that argument, or :data:`NO_SETTING`. ``fix`` replaces the error's own fix (a
        front end's advice where it has no equivalent of the argument)."""
        def fill(text: str) -> str:
            for name in self.fields:
                text = text.replace("{" + name + "}", spell(name, self.settings.get(name, NO_SETTING)))
            return text

        text = fill(self.template)
        advice = fix if fix is not None else (fill(self.fix) if self.fix else None)
        if advice:
            advice = advice if advice.endswith((".", "!", "?")) else f"{advice}."
            text = text.rstrip()
            text = f"{text} Fix: {advice}" if text.endswith((".", ":", ";")) else f"{text}. Fix: {advice}"
        return text


class CalibrationInputError(FtcalError, ValueError):
    """Raw readings or wrenches that a calibrator cannot use (shape, NaN, inf, ...)."""


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
