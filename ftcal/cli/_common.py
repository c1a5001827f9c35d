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
import os
import re
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from ..core import FtcalError
from ..core import OutputSet, atomic_output, atomic_output_set, check_writable_dir, write_json
from ._messages import CliError, UsageError  # noqa: F401  (defined beside the messages; re-exported for every command)

__all__ = ["CliError", "UsageError", "Interrupted", "signals_interrupt", "standard_streams", "Parser", "EXIT_USAGE",
           "EXIT_FAILURE", "add_output_file_options", "add_name_option", "file_stem", "finish_command",
           "add_jobs_option", "add_scheduler_option", "add_robot_options",
           "load_robot_from_args", "OutputPlan", "note_inputs", "note_dataset", "name_the_dataset",
           "check_not_an_input", "Console", "write_json", "numbers", "positive_int", "nonnegative_int",
           "positive_float", "int_in_range", "existing_file", "path_problem"]

#: Exit status of a run refused because of the user's arguments or files.
EXIT_USAGE = 2
#: Exit status of a run that failed for another reason (an unexpected error).
EXIT_FAILURE = 1


class _Formatter(argparse.RawDescriptionHelpFormatter):
    """Keeps the epilog's example lines as written and shows each option's meaningful default."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if "%(default)" in text or default in (None, False, argparse.SUPPRESS) or not action.option_strings:
            return text
        return f"{text} (default: %(default)s)"


#: Spellings removed before the first release -> what to write now (said when one is given).
REMOVED_SPELLINGS = {"--group-folds": "--folds group", "--random-folds": "--folds kfold", "--drift-cv": "--cv K",
                     "--channels": "--n-channels N on prepare (--channels names columns on the other commands)"}


class Parser(argparse.ArgumentParser):
    """An ArgumentParser that raises :class:`UsageError` instead of printing usage and exiting."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)
        # A value that starts with a minus and a digit is a value, not an option (no ftcal option name starts
        # with a digit): argparse's own rule takes only a lone number, so `--tare -0.001,0.2` or
        # `--gravity -9.81,0,0` would fail with "expected one argument".
        self._negative_number_matcher = re.compile(r"^-\.?\d")

    def error(self, message: str) -> None:  # type: ignore[override]
        given = message.split() if message.startswith("unrecognized arguments:") else []
        hints = "".join(f"; {old} is now {new}" for old, new in REMOVED_SPELLINGS.items() if old in given)
        raise UsageError(f"{message}{hints} (see '{self.prog} --help')")

    def _get_values(self, action, arg_strings):
        # argparse drops a value of exactly "--" (`--name=--`) and hands the option an empty list; an empty value
        # (`--torque-unit=` with an unset shell variable) would silently mean the default
        if arg_strings in (["--"], [""]) and action.nargs is None and action.option_strings:
            got = "'--'" if arg_strings == ["--"] else "an empty value"
            self.error(f"argument {'/'.join(action.option_strings)}: expected a value, got {got}")
        return super()._get_values(action, arg_strings)


# ------------------------------------------------------------------ signals
class Interrupted(BaseException):
    """SIGINT (Ctrl-C), SIGTERM or SIGHUP received by the ``ftcal`` command.

    Raised by the handlers of :func:`signals_interrupt` in the main thread. It unwinds the run like
    ``KeyboardInterrupt`` (every ``finally`` runs, so outputs being written are removed, SIGTERM as SIGINT)
    but is not one: skorch's fit loop swallows ``KeyboardInterrupt`` (its callbacks stop training that way),
    and CPython ends a process whose ``KeyboardInterrupt`` was once left unhandled in code it ran through
    ``PyRun_*`` by killing itself with SIGINT (status -2 instead of 130).
    """

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum

    @property
    def exit_status(self) -> int:
        """``128 + signal number`` (130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP), as a shell reports a signal."""
        return 128 + self.signum


@contextlib.contextmanager
def signals_interrupt() -> Iterator[None]:
    """Within the block, SIGINT, SIGTERM and SIGHUP raise :class:`Interrupted` in the main thread (the CLI only: the
    library installs no signal handler). Signals ignored by the caller (a background job's SIGINT) stay ignored.
    A second signal while the run unwinds is ignored so the clean-up finishes; a third ends the process."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received: list[int] = []

    def handler(signum, frame):
        received.append(signum)
        if len(received) == 1:
            raise Interrupted(signum)
        if len(received) >= 3:
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)

    previous = {}
    # Ctrl-C, ``kill``, and the hang-up of a closed terminal or SSH session (SIGHUP, whose default would kill the
    # process mid-write and leave its ``.partial`` file behind)
    for sig in (getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)):
        old = signal.getsignal(sig)
        if old is signal.SIG_IGN:
            continue
        previous[sig] = old
        signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old if old is not None else signal.SIG_DFL)


# ------------------------------------------------------------------ standard streams
class _ClosedStream:
    """Stands in for a standard stream the shell closed (``>&-``, ``<&-``; Python then sets it to ``None``).

    Without it ``print`` would drop the output silently (``sys.stdout is None``) and reading would fail with an
    ``AttributeError``. Writing or reading raises :class:`CliError` naming the stream; a command that never uses
    the stream runs as before (``flush`` does nothing, ``isatty`` is false, other attributes are absent, as on
    ``None``: pandas asks for ``sys.stdout.encoding`` at import).
    """

    def __init__(self, name: str, fix: str) -> None:
        self._name = name
        self._fix = fix

    def _closed(self, *args: Any, **kwargs: Any) -> Any:
        use = "redirect it to a file or a pipe" if self._name == "output" else "give the input as a file or pipe it in"
        raise CliError(f"standard {self._name} is closed (the command was run with {self._fix}); {use}")

    write = writelines = read = readline = readlines = __iter__ = __next__ = _closed

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return False

    def __getattr__(self, attr: str) -> Any:
        raise AttributeError(attr)


class _CheckedStdout:
    """``sys.stdout`` whose write errors name standard output (``> /dev/full`` gave a bare "No space left on
    device"). A broken pipe stays a :class:`BrokenPipeError`: the reader left (``| head``), which is no error."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream

    def _checked(self, method: str, *args: Any) -> Any:
        try:
            return getattr(self._stream, method)(*args)
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise CliError(f"could not write to standard output ({exc.strerror or exc}); the output is "
                           "incomplete") from None

    def write(self, text: str) -> int:
        return self._checked("write", text)

    def writelines(self, lines: Iterable[str]) -> None:
        self._checked("writelines", lines)

    def flush(self) -> None:
        self._checked("flush")

    def __getattr__(self, attr: str) -> Any:
        return getattr(self._stream, attr)


@contextlib.contextmanager
def standard_streams() -> Iterator[None]:
    """Within the block a closed stdin / stdout raises :class:`CliError` when used, a failed write to stdout names
    standard output, and stdout is flushed at the end (so that its errors are reported here, not at exit)."""
    saved = sys.stdin, sys.stdout
    if sys.stdin is None:
        sys.stdin = _ClosedStream("input", "<&-")
    sys.stdout = _ClosedStream("output", ">&-") if sys.stdout is None else _CheckedStdout(sys.stdout)
    try:
        yield
        if isinstance(sys.stdout, _CheckedStdout):
            sys.stdout.flush()
    finally:
        sys.stdin, sys.stdout = saved


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


def finite_float(text: str) -> float:
    """argparse type: a finite number (``inf`` and ``nan`` are refused)."""
    value = _number(float, text, float("-inf"), False, "a finite number")
    if abs(value) == float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    value = _number(float, text, 0.0, True, "a positive number")
    if value == float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite positive number")
    return value


def path_problem(path: str | os.PathLike, streams: bool = False) -> str | None:
    """What keeps ``path`` from being read as an input file, or ``None`` when it can be read.

    A missing file, a broken symbolic link, a directory, a device (``/dev/null``), a named pipe or socket
    (``/dev/fd/N`` of a shell's ``<(...)``) and an unreadable file are told apart. With ``streams`` a pipe or a
    character device is fine (it is read once, line by line, as standard input would be).
    """
    import stat

    text = str(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        if os.path.islink(path):
            return f"{text} is a broken symbolic link (to {os.readlink(path)}); point it at an existing file"
        return f"{text} does not exist"
    except OSError as exc:
        return f"{text}: {exc.strerror or exc}"
    if stat.S_ISDIR(st.st_mode):
        return f"{text} is a directory, not a file; name a file in it"
    if not stat.S_ISREG(st.st_mode):
        kind = ("a named pipe" if stat.S_ISFIFO(st.st_mode) else "a socket" if stat.S_ISSOCK(st.st_mode)
                else "a device" if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode) else "not a regular file")
        if streams and (stat.S_ISFIFO(st.st_mode) or stat.S_ISCHR(st.st_mode)):
            return None
        return f"{text} is {kind}, not a regular file; save the data to a file first"
    if not os.access(path, os.R_OK):
        return f"{text}: permission denied (the file is not readable by this user)"
    return None


def existing_file(text: str) -> Path:
    """argparse type: a path to a readable regular file (a directory, device or pipe is named as such)."""
    problem = path_problem(text)
    if problem is not None:
        raise argparse.ArgumentTypeError(problem)
    return Path(text)


# ------------------------------------------------------------------ shared options
def file_stem(text: str) -> str:
    """argparse type of ``--name``: a file name stem of letters, digits, '-' and '_' (no path, no dot).

    Examples
    --------
    >>> file_stem("tool-2")
    'tool-2'
    """
    if not text.replace("-", "_").isidentifier():
        raise argparse.ArgumentTypeError(f"{text!r}: use letters, digits, '-' and '_' only")
    return text


def add_name_option(parser: argparse.ArgumentParser, what: str, default: str | None = None) -> None:
    """``--name``: the file name stem of the command's outputs (``what``), checked by :func:`file_stem`."""
    parser.add_argument("--name", type=file_stem, default=default, help=f"file name stem of {what}")


def add_output_file_options(parser: argparse.ArgumentParser) -> None:
    """``--output FILE`` (``-``: standard output, the default) and ``--force``: a command writing one stream of rows."""
    parser.add_argument("--output", default="-", metavar="FILE", help="where the wrenches go; '-' is stdout")
    parser.add_argument("-f", "--force", action="store_true", help="overwrite --output FILE if it exists")


def add_robot_options(parser: argparse.ArgumentParser) -> None:
    """``--robot`` and ``--sensor-frame``."""
    parser.add_argument("--robot", default="kuka_iiwa14",
                        help="built-in robot (kuka_iiwa14, panda, ur3, ur5, ur10) or a .urdf path")
    parser.add_argument("--sensor-frame", help="frame at the sensing origin (required for a .urdf path)")
    parser.add_argument("--sensor-mounting", metavar="RX,RY,RZ,X,Y,Z", type=_mounting,
                        help="how the sensor sits relative to --sensor-frame, without editing the URDF: a rotation "
                        "vector [deg] and an offset [m] in that frame, e.g. 0,0,45,0,0,0.012 (turned 45 deg about z "
                        "on a 12 mm adapter)")


def load_robot_from_args(args: argparse.Namespace):
    """The robot of ``--robot`` / ``--sensor-frame`` / ``--sensor-mounting``, every problem in one line.

    The library checks a ``.urdf`` path (:func:`ftcal.robot.load_robot`: a syntax error is named with its line and
    column); Pinocchio parses it with the C++ stderr of urdfdom captured here: its ``Error:`` lines would otherwise
    precede ftcal's own message; the first of them says what is wrong and joins the message. After a successful parse its
    warnings, if any, are shown as they would have been.
    """
    import ftcal

    failure = None
    with _captured_stderr_fd() as captured:
        try:
            model = ftcal.robot.load_robot(args.robot, sensor_frame=args.sensor_frame,
                                           sensor_mounting=args.sensor_mounting)
        except (FtcalError, ValueError) as exc:
            failure = exc
        text = captured()
    if failure is not None:
        errors = [line.split("Error:", 1)[1].strip() for line in text.splitlines() if line.strip().startswith("Error:")]
        if not errors:
            raise failure
        from ._messages import cli_message

        raise CliError(f"{cli_message(failure, args)} urdfdom: {errors[0]}") from None
    if text:
        sys.stderr.write(text)
    return model


@contextlib.contextmanager
def _captured_stderr_fd() -> Iterator[Any]:
    """Within the block, file descriptor 2 (C and C++ code's stderr) goes to a temporary file; yields a function
    returning what was written so far."""
    import tempfile

    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError, AttributeError):  # no usable fd 2: nothing to capture
        yield lambda: ""
        return
    with tempfile.TemporaryFile(mode="w+b") as sink:
        os.dup2(sink.fileno(), 2)

        def captured() -> str:
            sink.flush()
            sink.seek(0)
            return sink.read().decode("utf-8", "replace")

        try:
            yield captured
        finally:
            os.dup2(saved, 2)
            os.close(saved)


def numbers(text: str, count: int) -> list[float] | None:
    """The ``count`` comma-separated numbers of ``text``, or None when it holds another count or a non-number.

    Examples
    --------
    >>> numbers("0,0,-9.81", 3), numbers("0,0", 3), numbers("0,x,1", 3)
    ([0.0, 0.0, -9.81], None, None)
    """
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        return None
    return values if len(values) == count else None


def _mounting(text: str) -> tuple[float, ...]:
    """argparse type of ``--sensor-mounting``: six numbers."""
    values = numbers(text, 6)
    if values is None or not all(v == v and abs(v) != float("inf") for v in values):
        raise argparse.ArgumentTypeError(f"{text!r}: give six numbers rx,ry,rz [deg],x,y,z [m], e.g. 0,0,45,0,0,0.012")
    return tuple(values)


def _scheduler(text: str) -> str:
    """argparse type of ``--scheduler``: checked before any work starts (Dask is imported only to use it)."""
    from ._messages import cli_message
    from ._scale_out import SchedulerError, check_scheduler

    try:
        return check_scheduler(text)
    except SchedulerError as exc:
        raise argparse.ArgumentTypeError(cli_message(exc)) from None


def add_scheduler_option(parser: argparse.ArgumentParser) -> None:
    """``--scheduler``: run the fits on a Dask cluster (see :mod:`ftcal.cli._scale_out`)."""
    parser.add_argument("--scheduler", metavar="ADDRESS|local", type=_scheduler,
                        help="run the fits on a Dask cluster: 'local' starts one on this machine, or a scheduler "
                        "address such as tcp://host:8786 (needs: pip install \"dask[distributed]\"); overrides --jobs")


def add_jobs_option(parser, help: str, default: int | None = None) -> None:
    """``--jobs N``: how many processes (or joblib workers) work at once, 1 to 256."""
    parser.add_argument("--jobs", type=int_in_range(1, 256, "jobs"), default=default, help=help)


def finish_command(parser: argparse.ArgumentParser, handler, out: str | None = None, seed: bool = True) -> None:
    """The options every command ends with, then its handler: ``--out DIR`` / ``--force`` (a command writing to a
    folder, ``out`` its default), ``--quiet`` and, with ``seed``, ``--seed``."""
    if out is not None:
        parser.add_argument("-o", "--out", type=Path, default=Path(out), metavar="DIR",
                            help="directory for the output files (created if missing)")
        parser.add_argument("-f", "--force", action="store_true",
                            help="overwrite output files that already exist (without it, the run stops before any "
                            "work)")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress bars and no status messages on stderr")
    if seed:
        parser.add_argument("--seed", type=nonnegative_int, default=0,
                            help="random seed: the same seed and arguments give the same files")
    parser.set_defaults(handler=handler)


# ------------------------------------------------------------------ output files
#: Arguments that name outputs (a directory or a file); every other argument that names an existing file, or a
#: directory of files, is an input of the run.
OUTPUT_ARGUMENTS = ("out", "output")
#: The regular files the current command reads: (device, inode) -> which input it is, for the message.
_input_files: dict[tuple[int, int], str] = {}
#: The directories the current command reads files of (logs folders): (device, inode) -> which input.
_input_dirs: dict[tuple[int, int], str] = {}
#: The dataset files the current command loaded (:func:`note_dataset`), to name in the library's errors about X / y.
_datasets: list[str] = []


def note_dataset(path: str | os.PathLike) -> None:
    """Record that the command loaded the dataset ``path``; :func:`name_the_dataset` puts it into the library's
    errors about the data (``X (raw readings, shape (200, 6)) spans only 5 ...`` names no file)."""
    if str(path) not in _datasets:
        _datasets.append(str(path))


def name_the_dataset(message: str, exc: BaseException) -> str:
    """``message`` with the file of the one dataset the command loaded in front, when ``exc`` is the library's
    error about the data (a :class:`~ftcal.core.CalibrationInputError` whose ``parameter`` is ``X`` or ``y``) and names
    no loaded file.

    Examples
    --------
    >>> from ftcal.core._exceptions import CalibrationInputError
    >>> _datasets[:] = ["d.csv"]
    >>> name_the_dataset("X (raw readings) spans only 5 directions", CalibrationInputError(parameter="X"))
    'd.csv: X (raw readings) spans only 5 directions'
    >>> name_the_dataset("The 'ridge' parameter must be >= 0", CalibrationInputError(parameter="ridge"))
    "The 'ridge' parameter must be >= 0"
    >>> _datasets.clear()
    """
    from ..core import CalibrationInputError

    about_data = isinstance(exc, CalibrationInputError) and exc.parameter in ("X", "y")
    if about_data and len(_datasets) == 1 and _datasets[0] not in message:  # not a --param value's error
        return f"{_datasets[0]}: {message}"
    return message


def _file_id(path: str | os.PathLike, regular: bool = True) -> tuple[int, int] | None:
    """``(device, inode)`` of the file at ``path`` (with ``regular``, of a regular file only), or None."""
    import stat

    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    return (st.st_dev, st.st_ino) if not regular or stat.S_ISREG(st.st_mode) else None


def _choice_arguments(parser: argparse.ArgumentParser, handler) -> set[str]:
    """The destinations of the options with fixed choices (``--model linear``) of the (sub)command run by
    ``handler``: their values are names, not paths, even where a folder of that name exists."""
    found: set[str] = set()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                found |= _choice_arguments(sub, handler)
    if not found and parser.get_default("handler") is handler:
        found = {a.dest for a in parser._actions if a.choices is not None
                 and not isinstance(a, argparse._SubParsersAction)}
    return found


def note_inputs(args: argparse.Namespace, parser: argparse.ArgumentParser | None = None) -> None:
    """Record every file the parsed command may read, so that no output replaces one (``--force`` or not).

    Every argument but the outputs (:data:`OUTPUT_ARGUMENTS`) and the options with fixed choices of ``parser``
    (a model name is no path) is looked at: a value naming an existing regular file is an input, a directory
    contributes the files directly in it (logs directories). Files are compared by device and inode, so another
    spelling of the path, a symbolic link or a hard link is the same file.
    """
    _input_files.clear()
    _input_dirs.clear()
    _datasets.clear()
    names = set() if parser is None else _choice_arguments(parser, getattr(args, "handler", None))
    for dest, value in vars(args).items():
        if dest in OUTPUT_ARGUMENTS or dest in names or callable(value):
            continue
        for item in value if isinstance(value, (list, tuple)) else [value]:
            if not isinstance(item, (str, Path)) or str(item) in ("", "-"):
                continue
            path = Path(item)
            try:
                children = sorted(path.iterdir()) if path.is_dir() else [path]
            except OSError:
                continue
            role = dest.replace("_", " ")
            if path.is_dir() and (dir_id := _file_id(path, regular=False)) is not None:
                _input_dirs.setdefault(dir_id, f"the {role} folder {path}")
            for child in children[:100_000]:
                if (file_id := _file_id(child)) is not None:
                    _input_files.setdefault(
                        file_id, f"the {role} file itself" if child is path else f"one of the {role} files ({child})")


def check_not_an_input(output: str | os.PathLike) -> None:
    """Raise :class:`CliError` when ``output`` is (a link to, another name of) a file the command reads."""
    file_id = _file_id(output)
    if file_id is not None and file_id in _input_files:
        raise CliError(f"{output} is {_input_files[file_id]}, an input of this command; writing there would destroy "
                       "it, --force or not. Choose another output name or directory")


def _check_regular_target(path: Path) -> None:
    """An existing output must be a regular file: ftcal writes beside it and renames into place, which would
    replace a device (``/dev/null``), a named pipe or a directory entry instead of writing into it."""
    import stat

    try:
        st = os.lstat(path)
    except OSError:
        return
    if stat.S_ISLNK(st.st_mode):
        try:
            st = os.stat(path)
        except OSError:
            raise CliError(f"{path} is a symbolic link to {os.readlink(path)}, which does not exist; ftcal would "
                           "replace the link itself. Remove the link or choose another name") from None
    if stat.S_ISREG(st.st_mode) and not st.st_mode & (stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH):
        raise CliError(f"{path} is read-only (write-protected), and ftcal does not replace a protected file, "
                       "--force or not; make it writable (chmod u+w) or choose another name")
    if stat.S_ISDIR(st.st_mode):
        raise CliError(f"{path} is a directory; name a file to write")
    if not stat.S_ISREG(st.st_mode):
        raise CliError(f"{path} is not a regular file (a device or a pipe); ftcal writes a new file and renames "
                       "it into place. Write to '-' (standard output) and redirect it instead")


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

    def __init__(self, out_dir: Path, names: Iterable[str], force: bool, option: str = "--out") -> None:
        self.out_dir = Path(out_dir)
        self.names = list(names)
        self.force = force
        self._set: OutputSet | None = None  # the set being written (as_one_set)
        if self.out_dir.exists() and not self.out_dir.is_dir():
            raise CliError(f"{option} {self.out_dir} is a file, not a directory; choose another {option}")
        dir_id = _file_id(self.out_dir, regular=False)
        if dir_id is not None and dir_id in _input_dirs:
            raise CliError(f"{option} {self.out_dir} is {_input_dirs[dir_id]}, an input of this "
                           f"command: its outputs would mix with (and be read as) its inputs. Choose another {option}")
        check_writable_dir(self.out_dir, CliError, option)
        for n in self.names:
            for folder in list((self.out_dir / n).parents)[:len(Path(n).parts) - 1]:  # its folders inside out_dir
                if folder.exists() and not folder.is_dir():
                    raise CliError(f"{folder} is a file, where this run makes a folder (for {self.out_dir / n}); "
                                   f"move it or choose another {option}")
            check_not_an_input(self.out_dir / n)
            _check_regular_target(self.out_dir / n)
        if not force:
            taken = [n for n in self.names if (self.out_dir / n).exists()]
            if taken:
                listed = ", ".join(str(self.out_dir / n) for n in taken[:3])
                more = f" (and {len(taken) - 3} more)" if len(taken) > 3 else ""
                raise CliError(f"{listed}{more} already exist{'s' if len(taken) == 1 else ''}; pass --force to "
                               f"overwrite or choose another {option}")

    @classmethod
    def single_file(cls, output: str | Path, force: bool) -> "OutputPlan | None":
        """The plan of one ``--output FILE`` (``None`` for ``-``, standard output)."""
        if str(output) == "-":
            return None
        out = Path(output)
        return cls(out.parent if str(out.parent) else Path("."), [out.name], force, option="--output")

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
        replaced (:func:`ftcal.core._files.atomic_output`). Within
        :meth:`as_one_set` the file is put in place with the others of the set, at its end.
        """
        target = self.path(name)
        if self._set is not None:
            with self._set.writing(target) as tmp:
                yield tmp
            return
        with atomic_output(target, overwrite=self.force, error=CliError) as tmp:
            yield tmp

    def write_text(self, name: str, text: str) -> None:
        """Write the planned file ``name`` holding ``text`` (UTF-8) through :meth:`writing`."""
        with self.writing(name) as tmp:
            tmp.write_text(text, encoding="utf-8")

    def write_json(self, name: str, obj: Any) -> None:
        """Write the planned file ``name`` holding ``obj`` as JSON (:func:`ftcal.core.write_json`) through
        :meth:`writing`."""
        with self.writing(name) as tmp:
            write_json(tmp, obj)

    @contextlib.contextmanager
    def staging(self) -> Iterator[Path]:
        """Within :meth:`as_one_set`: a private folder inside ``out_dir`` for a library function that writes its
        files itself (the virtual experiment's logs, the demo's files); the planned files it holds when the block
        ends join the set, and the folder is removed whatever happens."""
        import shutil
        import tempfile

        if self._set is None:
            raise AssertionError("staging() outside as_one_set()")
        self.out_dir.mkdir(parents=True, exist_ok=True)
        stage = Path(tempfile.mkdtemp(prefix=".ftcal-run.", suffix=".partial", dir=self.out_dir))
        try:
            yield stage
            for name in self.names:
                if (stage / name).is_file():
                    with self.writing(name) as tmp:
                        os.replace(stage / name, tmp)
        finally:
            shutil.rmtree(stage, ignore_errors=True)

    def leaving_out(self, *names: str) -> None:
        """Planned files this run does not write after all (a report it has no data for). An output set replaces
        only the files it writes: a file of such a name is never removed (ftcal cannot tell an earlier run's report
        from a user's own file of that name), and a warning names it, since it does not describe this run."""
        import warnings

        if self._set is None:
            raise AssertionError("leaving_out() outside as_one_set()")
        for path in (self.out_dir / name for name in names):
            if path.exists() or path.is_symlink():
                warnings.warn(f"{path} was kept as it is: this run does not write it, so it does not describe this "
                              "run (an earlier run's, or your own file); remove it if it is an earlier run's",
                              UserWarning, stacklevel=2)

    @contextlib.contextmanager
    def as_one_set(self) -> Iterator[OutputSet]:
        """Within the block, the files written with :meth:`writing` are put in place together when it ends, and
        none of them when it fails (an error, a full disk, a signal): a run leaves all its outputs or none, and a
        replaced set is never half old, half new (:class:`ftcal.core._files.OutputSet`: the renames under a lock on
        the folder, the termination signals held back, a failed rename puts the old set back)."""
        if self._set is not None:
            raise AssertionError("as_one_set() is already active on this OutputPlan")
        with atomic_output_set(overwrite=self.force, error=CliError) as files:
            self._set = files
            try:
                yield files
            finally:
                self._set = None



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
