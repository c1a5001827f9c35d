"""Domain errors of ftcal, in one place.

Every error a user can cause derives from :class:`FtcalError`. Errors about bad
values also derive from :class:`ValueError`, so code written against the plain
Python and scikit-learn conventions (``except ValueError``) keeps working.
"""

from __future__ import annotations

__all__ = [
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


class FtcalError(Exception):
    """Base class of every error ftcal raises on purpose."""


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
