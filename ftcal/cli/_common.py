"""What every ``ftcal`` subcommand shares: options, output files, progress bars, messages.

Conventions of the command line
-------------------------------
* Results go to files in ``--out DIR``; stdout carries only what a subcommand
  is *for* (the comparison table of ``evaluate``/``demo``, the wrenches of
  ``predict``). Status messages and progress bars go to stderr, and
  ``--quiet`` silences both.
* An output file that already exists is never overwritten without
  ``--force``. The check runs *before* any long work, so a refused run costs
  nothing. Files are written to a temporary name and renamed into place, so a
  crash never leaves a half-written file where a good one stood.
* A user mistake (bad argument, bad file) ends the run with exit status 2
  and one line ``ftcal: error: ...`` on stderr; no traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from ..core._exceptions import FtcalError
from ..core._files import atomic_output, check_writable_dir, write_json

__all__ = [
    "CliError",
    "UsageError",
    "Parser",
    "EXIT_USAGE",
    "EXIT_FAILURE",
    "add_output_options",
    "add_run_options",
    "add_scheduler_option",
    "add_robot_options",
    "OutputPlan",
    "Console",
    "write_json",
    "positive_int",
    "nonnegative_int",
    "positive_float",
    "int_in_range",
    "existing_file",
]

#: Exit status of a run refused because of the user's arguments or files.
EXIT_USAGE = 2
#: Exit status of a run that failed for another reason (an unexpected error).
EXIT_FAILURE = 1


class CliError(FtcalError):
    """A problem the user can fix, reported as one ``ftcal: error:`` line."""


class UsageError(CliError):
    """Bad command-line arguments (raised instead of argparse's own exit)."""


class _Formatter(argparse.RawDescriptionHelpFormatter):
    """Keeps the epilog's example lines as written and shows each option's meaningful default."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if "%(default)" in text or default in (None, False, argparse.SUPPRESS) or not action.option_strings:
            return text
        return f"{text} (default: %(default)s)"


class Parser(argparse.ArgumentParser):
    """An ArgumentParser that raises :class:`UsageError` instead of printing usage and exiting."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> None:  # type: ignore[override]
        raise UsageError(f"{message} (see '{self.prog} --help')")


# ------------------------------------------------------------------ argument types
def _number(kind: type, text: str, low: float, strict: bool, what: str) -> Any:
    try:
        value = kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not {what}") from None
    if value < low or (strict and value == low) or value != value:
        raise argparse.ArgumentTypeError(f"{text!r} is not {what}")
    return value


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    return _number(int, text, 0, True, "a positive integer")


def nonnegative_int(text: str) -> int:
    """argparse type: an integer >= 0."""
    return _number(int, text, 0, False, "an integer >= 0")


def int_in_range(low: int, high: int, what: str):
    """argparse type factory: an integer in ``[low, high]`` (a bound keeps a typo from exhausting memory).

    Examples
    --------
    >>> int_in_range(1, 10, "points per sphere")("3")
    3
    """

    def parse(text: str) -> int:
        value = _number(int, text, low, False, f"an integer >= {low}")
        if value > high:
            raise argparse.ArgumentTypeError(f"{text} is more {what} than ftcal handles (at most {high})")
        return value

    parse.__name__ = "integer"
    return parse


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    value = _number(float, text, 0.0, True, "a positive number")
    if value == float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite positive number")
    return value


def existing_file(text: str) -> Path:
    """argparse type: a path to a file that exists."""
    path = Path(text)
    if not path.is_file():
        what = "is a directory, not a file" if path.is_dir() else "does not exist"
        raise argparse.ArgumentTypeError(f"{text} {what}")
    return path


# ------------------------------------------------------------------ shared options
def add_output_options(parser: argparse.ArgumentParser, default_out: str) -> None:
    """``--out DIR`` and ``--force``."""
    parser.add_argument(
        "-o", "--out", type=Path, default=Path(default_out), metavar="DIR",
        help="directory for the output files (created if missing)",
    )
    parser.add_argument(
        "-f", "--force", action="store_true",
        help="overwrite output files that already exist (without it, the run stops before any work)",
    )


def add_robot_options(parser: argparse.ArgumentParser) -> None:
    """``--robot`` and ``--sensor-frame``."""
    parser.add_argument(
        "--robot", default="kuka_iiwa14", help="built-in robot (kuka_iiwa14, panda, ur3, ur5, ur10) or a .urdf path",
    )
    parser.add_argument("--sensor-frame", help="frame at the sensing origin (required for a .urdf path)")
    parser.add_argument(
        "--sensor-mounting", metavar="RX,RY,RZ,X,Y,Z", type=_mounting,
        help="how the sensor sits relative to --sensor-frame, without editing the URDF: a rotation vector [deg] "
        "and an offset [m] in that frame, e.g. 0,0,45,0,0,0.012 (turned 45 deg about z on a 12 mm adapter)",
    )


def _mounting(text: str) -> tuple[float, ...]:
    """argparse type of ``--sensor-mounting``: six numbers."""
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 6 or not all(v == v and abs(v) != float("inf") for v in values):
        raise argparse.ArgumentTypeError(f"{text!r}: give six numbers rx,ry,rz [deg],x,y,z [m], e.g. 0,0,45,0,0,0.012")
    return values


def _scheduler(text: str) -> str:
    """argparse type of ``--scheduler``: checked before any work starts (Dask is imported only to use it)."""
    from ..core._scale_out import SchedulerError, check_scheduler

    try:
        return check_scheduler(text)
    except SchedulerError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_scheduler_option(parser: argparse.ArgumentParser) -> None:
    """``--scheduler``: run the fits on a Dask cluster (see :mod:`ftcal.core._scale_out`)."""
    parser.add_argument(
        "--scheduler", metavar="ADDRESS|local", type=_scheduler,
        help="run the fits on a Dask cluster: 'local' starts one on this machine, or a scheduler address such as "
        "tcp://host:8786 (needs: pip install \"dask[distributed]\"); overrides --jobs",
    )


def add_run_options(parser: argparse.ArgumentParser, seed: bool = True) -> None:
    """``--quiet`` and (optionally) ``--seed``."""
    parser.add_argument(
        "-q", "--quiet", action="store_true", help="no progress bars and no status messages on stderr",
    )
    if seed:
        parser.add_argument(
            "--seed", type=nonnegative_int, default=0,
            help="random seed: the same seed and arguments give the same files",
        )


# ------------------------------------------------------------------ output files
class OutputPlan:
    """The files a run will write in ``out_dir``, checked before the work starts.

    Parameters
    ----------
    out_dir : Path
        The ``--out`` directory.
    names : iterable of str
        File names (relative to ``out_dir``) the run will write.
    force : bool
        Whether existing files may be replaced.

    Raises
    ------
    CliError
        When ``out_dir`` is a file, or when a planned file exists and ``force`` is false.
    """

    def __init__(self, out_dir: Path, names: Iterable[str], force: bool) -> None:
        self.out_dir = Path(out_dir)
        self.names = list(names)
        self.force = force
        if self.out_dir.exists() and not self.out_dir.is_dir():
            raise CliError(f"--out {self.out_dir} is a file, not a directory; choose another --out")
        check_writable_dir(self.out_dir, CliError)
        if not force:
            taken = [n for n in self.names if (self.out_dir / n).exists()]
            if taken:
                listed = ", ".join(str(self.out_dir / n) for n in taken[:3])
                more = f" (and {len(taken) - 3} more)" if len(taken) > 3 else ""
                raise CliError(
                    f"{listed}{more} already exist{'s' if len(taken) == 1 else ''}; "
                    "pass --force to overwrite or choose another --out"
                )

    @classmethod
    def single_file(cls, output: str | Path, force: bool) -> "OutputPlan | None":
        """The plan of one ``--output FILE`` (``None`` for ``-``, standard output)."""
        if str(output) == "-":
            return None
        out = Path(output)
        return cls(out.parent if str(out.parent) else Path("."), [out.name], force)

    def path(self, name: str) -> Path:
        """The path of planned file ``name``; creates ``out_dir`` on first use."""
        if name not in self.names:
            raise AssertionError(f"{name} was not planned; add it to the OutputPlan first")
        path = self.out_dir / name
        path.parent.mkdir(parents=True, exist_ok=True)
        return path

    @contextlib.contextmanager
    def writing(self, name: str) -> Iterator[Path]:
        """Yield a temporary path to write ``name`` to; it is renamed into place on success.

        A failure inside the block removes the temporary file and leaves any
        existing ``name`` untouched; each run gets its own temporary file, and
        without ``--force`` a file that another run wrote meanwhile is not
        replaced (:func:`ftcal.core._files.atomic_output`).
        """
        with atomic_output(self.path(name), overwrite=self.force, error=CliError) as tmp:
            yield tmp



# ------------------------------------------------------------------ messages
class Console:
    """Status messages and progress bars on stderr, both silenced by ``--quiet``."""

    def __init__(self, quiet: bool = False) -> None:
        self.quiet = quiet

    def info(self, message: str) -> None:
        """One status line on stderr."""
        if not self.quiet:
            print(message, file=sys.stderr, flush=True)

    def progress(self, iterable: Iterable | None = None, **kwargs: Any):
        """A tqdm progress bar on stderr; use it in a ``with`` block so an error closes it.

        Off with ``--quiet``, and off when stderr is not a terminal (a log
        file or a pipe gets the status lines, not bar redraws).
        """
        from tqdm import tqdm

        kwargs.setdefault("dynamic_ncols", True)
        kwargs.setdefault("leave", False)
        return tqdm(iterable, file=sys.stderr, disable=True if self.quiet else None, **kwargs)
