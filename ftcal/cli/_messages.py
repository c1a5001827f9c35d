"""The library's errors in the command line's terms: one table from the Python API's argument names to the options.

A library error names the arguments of the Python API (``n_poses``, ``overwrite=True``) and carries them as
fields (:class:`ftcal.core._exceptions.FtcalError`); the command line spells each field as its option
(``--next``, ``--force``) through :data:`CLI_NAMES`, without reading the library's prose. An argument the command
line has no option for gets the command line's own advice instead of the library's fix.

Examples
--------
>>> from ftcal.core._exceptions import ModelFileError
>>> err = ModelFileError("m.npz already exists.", parameter="path", value="m.npz",
...                      fix="pass {overwrite} to replace it", settings={"overwrite": True})
>>> str(err)
'm.npz already exists. Fix: pass overwrite=True to replace it.'
>>> cli_message(err)
'm.npz already exists. Fix: pass --force to replace it.'
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

from ..core import NO_SETTING, FtcalError, Placeholder

__all__ = ["CliError", "UsageError", "Option", "CLI_NAMES", "cli_message", "cli_spelling", "cli_error", "fix_names", "one_line_warnings"]


class CliError(FtcalError):
    """A problem the user can fix, reported as one ``ftcal: error:`` line."""


class UsageError(CliError):
    """Bad command-line arguments (raised instead of argparse's own exit)."""


@dataclass(frozen=True)
class Option:
    """How the command line names one argument of the library.

    Attributes
    ----------
    flags : tuple of (dest, flag)
        The option, or options by subcommand: the first whose destination is set in the parsed arguments (or the
        last, as the default) names the argument (``n_poses`` is ``--next`` in ``plan --next``, else ``--poses``).
    advice : str, optional
        The command line's own fix where the library's fix proposes this argument and no option sets it
        (``groups`` come from the dataset's group column).
    metavar : str, optional
        How the option's value is written where the library proposes a :class:`Placeholder` (``NAME``).
    words : str, optional
        How the command line says an argument that comes from its input files, not an option (the drift's
        ``temperatures``: a ``temperature`` column).
    """

    flags: tuple[tuple[str, str], ...] = ()
    advice: str | None = None
    metavar: str | None = None
    words: str | None = None

    def flag(self, args: argparse.Namespace | None) -> str | None:
        """The option naming the argument in the command that ran (``args``), or None when there is none."""
        for dest, flag in self.flags:
            if args is not None and getattr(args, dest, None) not in (None, False):
                return flag
        for dest, flag in self.flags:  # none given: the option the command has (prepare's --mass, plan's --load-mass)
            if args is not None and hasattr(args, dest):
                return flag
        return self.flags[-1][1] if self.flags else None


def _option(flag: str, metavar: str | None = None) -> Option:
    return Option(((flag.lstrip("-").replace("-", "_"), flag),), metavar=metavar)


#: The library's arguments that an option of the same name sets (``force_unit``: ``--force-unit``), with the metavar
#: the option's value is written as where there is one.
_SAME_NAMES = {"force": None, "sensor_frame": "NAME", "world_frame": None, "subdivisions": None,
               "candidate_subdivisions": None, "cv": "K", "model": None, "output": None, "scheduler": None,
               "channels": None, "columns": None, "wrench": None, "axes": None, "force_unit": None,
               "torque_unit": None, "sensor": None, "wrench_topic": "TOPIC", "raw_topic": "TOPIC", "raw_field": "FIELD",
               "joint_topic": "TOPIC",
               "tf": "BASE,SENSOR", "stamps": None, "time": None, "temperature": None, "drift": None, "mounting": None}

#: The library's argument names and the command line's options for them: the one table of the mapping.
CLI_NAMES: dict[str, Option] = {
    **{name: _option("--" + name.replace("_", "-"), metavar) for name, metavar in _SAME_NAMES.items()},
    "overwrite": _option("--force"),
    "declared_frame": Option((("wrench_frame", "--wrench-frame"),)),
    "n_poses": Option((("next_poses", "--next"), ("poses", "--poses"))),
    "load_mass": Option((("mass", "--mass"), ("load_mass", "--load-mass")), metavar="KG"),
    "load_positions_in_sensor": Option(advice="prepare the dataset from the run logs with 'ftcal prepare', which "
                                              "records the load positions, or measure with the thesis fixture"),
    "space": _option("--grid", "KEY=[values]"),
    "groups": Option(advice="give the dataset's group column at least 2 distinct groups, or remove that column "
                            "for random folds"),
    "HistoryCalibrator": _option("--history"),
    "TemperatureCompensatedCalibrator": _option("--temperature"),
    "export_onnx": Option((("format", "--format onnx"),)),
    "columns.groups": _option("--groups"),  # the dataset's group column (``groups`` alone: a fit's group labels)
    "tolerance_deg": _option("--still-tolerance"),
    "min_duration_s": _option("--min-still"),
    "settle_s": _option("--settle"),
    # a bag's --max-samples where the command reads bags, else the model's parameter (a GP's rows)
    "max_samples": Option((("max_samples", "--max-samples"), ("param", "--param max_samples=")), metavar="N"),
    "temperatures": Option(words="a 'temperature' column (the sensor's temperature at each pose)"),
    "times": Option(words="a 'time' column (each pose's time [s])"),
}


def cli_spelling(args: argparse.Namespace | None = None):
    """A ``spell(name, setting)`` for :meth:`FtcalError.render`: the option of ``name`` (with the proposed value;
    ``--history`` / ``no --history`` for a switch), or the library's own name where the command line has none."""

    def spell(name: str, setting: Any) -> str:
        option = CLI_NAMES.get(name)
        flag = option.flag(args) if option is not None else None
        if flag is None and option is not None and option.words is not None:
            return option.words
        if flag is None:
            return name if setting is NO_SETTING else f"{name}={setting!r}"
        if setting is NO_SETTING or setting is True:
            return f"{flag}{option.metavar or 'VALUE'}" if flag.endswith("=") else flag
        if setting is False or setting is None:
            return f"no {flag}"
        joint = "" if flag.endswith("=") else " "  # --param KEY=VALUE
        if isinstance(setting, Placeholder):
            return f"{flag}{joint}{option.metavar or setting}"
        return f"{flag}{joint}{setting}"

    return spell


def fix_names(exc: BaseException, names: tuple[str, ...]) -> bool:
    """Whether the fix of ``exc`` proposes one of the arguments ``names`` (read from its fields, not its words)."""
    return isinstance(exc, FtcalError) and any("{" + name + "}" in (exc.fix or "") for name in names
                                               if name in exc.fields)


def cli_message(exc: BaseException, args: argparse.Namespace | None = None, *, fix: str | None = None,
                row: str | None = None) -> str:
    """The message of ``exc`` in the command line's terms (its fields spelled as options); the plain ``str`` of
    any error without fields. ``fix`` replaces the error's fix (``""``: none, where the command has no option the
    fix could name); ``row`` says the error's offending row in the command's terms (``"the reading"``)."""
    if not isinstance(exc, FtcalError) or not exc.has_fields:
        return str(exc)
    in_fix = [name for name in exc.fields if "{" + name + "}" in (exc.fix or "")]
    advice = next((CLI_NAMES[name].advice for name in in_fix
                   if name in CLI_NAMES and CLI_NAMES[name].advice is not None), None)
    return exc.render(cli_spelling(args), fix=fix if fix is not None else advice, row=row)


def cli_error(exc: BaseException, args: argparse.Namespace | None = None, where: str = "", **kwargs: Any):
    """A :class:`CliError` saying ``exc`` in the command line's terms (:func:`cli_message`),
    after ``where`` (the file or option it is about), on one line."""
    text = " ".join(cli_message(exc, args, **kwargs).split())
    return CliError(f"{where}: {text}" if where else text)


def _is_number(word: str) -> bool:
    """Whether ``word`` is a number, punctuation around it aside (``25``, ``(0.5,``; not a file name ``run2.csv``)."""
    try:
        float(word.strip("()[]{},.;:%'\""))
    except ValueError:
        return False
    return True


@contextlib.contextmanager
def one_line_warnings(arguments: Callable[[], argparse.Namespace | None] = lambda: None) -> Iterator[None]:
    """Show each warning the library gives while the command runs as one ``ftcal: warning: ...`` line on stderr (in
    the command's terms, :func:`cli_message`; ``arguments`` gives the parsed arguments once there are some), not in
    Python's two-line format with a source file and line.

    A warning that only differs from one already shown by its numbers (an optimizer's iteration count, a fold's
    index: scikit-learn's GP warns once per fit) is counted, not repeated; when the command ends one line says how
    many were not shown.

    Examples
    --------
    >>> import contextlib, io
    >>> err = io.StringIO()
    >>> with contextlib.redirect_stderr(err), one_line_warnings():
    ...     warnings.warn("the drift is extrapolated  beyond the covered span", UserWarning)
    ...     for n in (25, 21, 33):
    ...         warnings.warn(f"lbfgs failed to converge after {n} iteration(s)", UserWarning)
    ...     for name in ("run1.csv", "run2.csv"):  # other files: other warnings
    ...         warnings.warn(f"{name} was kept as it is", UserWarning)
    >>> print(err.getvalue(), end="")
    ftcal: warning: the drift is extrapolated beyond the covered span
    ftcal: warning: lbfgs failed to converge after 25 iteration(s)
    ftcal: warning: run1.csv was kept as it is
    ftcal: warning: run2.csv was kept as it is
    ftcal: warning: 2 more warnings like 'lbfgs failed to converge after 25 iteration(s)' (other numbers) not shown
    """
    repeats: dict[str, list] = {}

    def say(text: str, file) -> None:
        with contextlib.suppress(OSError, ValueError):  # a closed stderr loses the warning, not the command
            print(f"ftcal: warning: {text}", file=sys.stderr if file is None else file)

    def show(message, category, filename, lineno, file=None, line=None) -> None:
        text = " ".join(cli_message(message, arguments()).split()) if isinstance(message, BaseException) \
            else " ".join(str(message).split())
        if getattr(category, "__module__", "").startswith("sklearn"):  # whose words these are
            text = f"scikit-learn says: {text}"
        shape = (category.__name__, " ".join("#" if _is_number(word) else word for word in text.split()))
        if shape in repeats:
            repeats[shape][1] += 1
            return
        repeats[shape] = [text, 0, file]
        say(text, file)

    with warnings.catch_warnings():
        warnings.showwarning = show
        try:
            yield
        finally:
            for text, more, file in repeats.values():
                if more:
                    say(f"{more} more warning{'s' if more > 1 else ''} like {text!r:.160} (other numbers) not "
                        "shown", file)
