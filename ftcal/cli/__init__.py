"""The ``ftcal`` command line: the whole calibration workflow from a shell.

Subcommands
-----------
``simulate``   artificial datasets (presets) or virtual-experiment logs, to files
``plan``       calibration poses / joint configurations for a robot, to CSV
``prepare``    recorded load / no-load logs -> calibration dataset
``fit``        train a calibrator on a dataset -> model file
``tune``       hyperparameter search (cross-validated) -> tuned model file
``evaluate``   metrics and plots of model(s) on a dataset
``predict``    raw readings (file or stdin) -> wrenches (file or stdout)
``benchmark``  the artificial and the real-world benchmark
``demo``       simulate, fit the three calibrators, compare, plot
``identify-load``  a tool's mass, centre of mass and the sensor bias from static poses
``compensate``     run logs -> external wrenches (tool weight and bias removed)
``retare``         re-zero a model from zero-load readings (no refit)
``export``         a model as an ONNX file (raw readings -> wrench) or a 6xN matrix for deployment
``report``         the calibration report (HTML): held-out accuracy per axis, model choice, range

Run ``ftcal SUBCOMMAND --help`` for the options and an example of each.

The top layer: may import every ftcal package, but only inside the subcommand handlers that need
them (``ftcal --help`` imports neither torch nor pinocchio).

Examples
--------
>>> from ftcal.cli import main
>>> main(["--version"])
ftcal ...
0
"""

from __future__ import annotations

import contextlib
import errno
import sys
from collections.abc import Sequence

from ..core import FtcalError
from ._common import (EXIT_FAILURE, EXIT_USAGE, Interrupted, Parser, name_the_dataset, note_inputs, signals_interrupt,
                      standard_streams)
from ._messages import cli_message, one_line_warnings

__all__ = ["main", "build_parser", "cli_message"]

#: Modules of the subcommands, in the order ``ftcal --help`` lists them.
_SUBCOMMANDS = ("simulate", "plan", "prepare", "fit", "tune", "evaluate", "predict", "benchmark", "demo",
                "identify_load", "retare", "export", "report")


def build_parser() -> Parser:
    """The top-level argument parser with every subcommand registered."""
    from importlib import import_module, metadata

    try:
        version = metadata.version("ftcal")
    except metadata.PackageNotFoundError:  # running from a source tree
        version = "unknown"
    parser = Parser(prog="ftcal",
                    description="Calibrate multi-axis force/torque sensors: raw channels -> wrench [N, N·m].",
                    epilog="workflow (artificial data):\n"
                    "  ftcal simulate dataset --preset thesis --out data\n"
                    "  ftcal fit data/train.csv --model directional --out models\n"
                    "  ftcal evaluate data/test.csv models/directional.model.npz --out eval\n"
                    "  cat raw.csv | ftcal predict models/directional.model.npz > wrench.csv\n\n"
                    "start here:  ftcal demo")
    parser.add_argument("--version", action="version", version=f"ftcal {version}")
    sub = parser.add_subparsers(dest="command", metavar="SUBCOMMAND", parser_class=Parser)
    sub.required = True
    for name in _SUBCOMMANDS:
        import_module(f"{__name__}._{name}").register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``ftcal`` command line and return its exit status.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments after ``ftcal``; ``sys.argv[1:]`` when omitted.

    Returns
    -------
    int
        0 on success, 2 when the arguments or input files are unusable
        (after one ``ftcal: error: ...`` line on stderr), 130 after SIGINT
        (Ctrl-C), 143 after SIGTERM and 129 after SIGHUP (the output being written is removed),
        1 on an unexpected failure.
    """
    args_list = list(sys.argv[1:] if argv is None else argv)
    args = None
    try:
        with signals_interrupt(), standard_streams(), one_line_warnings(lambda: args):
            parser = build_parser()
            args = parser.parse_args(args_list)
            note_inputs(args, parser)  # no output may replace one of these (OutputPlan checks)
            with _thread_policy():
                return int(args.handler(args) or 0)
    except SystemExit as exc:  # --help and --version exit through argparse
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else EXIT_FAILURE)
    except Interrupted as exc:  # SIGINT / SIGTERM / SIGHUP: outputs in progress were removed while unwinding
        import signal

        with contextlib.suppress(OSError, ValueError):  # a closed terminal (SIGHUP) may take stderr with it
            print(f"ftcal: interrupted by {signal.Signals(exc.signum).name} (no half-written file is left)",
                  file=sys.stderr)
        return exc.exit_status
    except KeyboardInterrupt:  # a Ctrl-C from a library (or before the handlers were installed)
        with contextlib.suppress(OSError, ValueError):
            print("ftcal: interrupted (no half-written file is left)", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `ftcal predict ... | head`: the reader left, not an error
        _silence_stdout()
        return 0
    except (FtcalError, OSError, ValueError) as exc:
        print(f"ftcal: error: {name_the_dataset(_one_line(exc, args), exc)}", file=sys.stderr)
        return EXIT_USAGE
    except MemoryError as exc:  # a step whose size no guard estimated: still the user's input that is too large
        detail = f" ({_one_line(exc)})" if str(exc) else ""
        print(f"ftcal: error: out of memory{detail}; the input is too large for this machine: use a smaller file "
              "or fewer samples (--param max_samples=... where the model has it)", file=sys.stderr)
        return EXIT_USAGE
    except Exception as exc:  # a bug: still one line, with a pointer to where to report it
        print(f"ftcal: error: unexpected {type(exc).__name__}: {_one_line(exc)} (this is a bug in ftcal; please report "
              "it with the command you ran)", file=sys.stderr)
        return EXIT_FAILURE


def _thread_policy() -> contextlib.AbstractContextManager:
    """The command's thread policy, set once for its whole run: BLAS on one thread. Its work is ftcal's small matrix
    problems, which a threaded BLAS only slows on a busy machine (``benchmarks/thread_limits.py``); the command owns
    its process, so the limit reaches every thread of it (joblib's workers are processes that limit their own).
    Restored when :func:`main` returns (a program may call it). numpy's and scipy's BLAS are loaded first: a limit
    reaches only the libraries loaded when it is set."""
    import numpy  # noqa: F401
    import scipy.linalg  # noqa: F401

    from ftcal.core import limit_threads_here  # its cached controller: a new one scans every loaded library

    return limit_threads_here(1)


#: A full disk or an exhausted quota: the file is named and the user told what to do.
_FULL = frozenset(getattr(errno, name) for name in ("ENOSPC", "EDQUOT") if hasattr(errno, name))


def _one_line(exc: BaseException, args=None) -> str:
    """The message of ``exc`` folded onto one line (OSError gets its file name), a library error's fields (the
    arguments it names, its fix) spelled as the options of the command that ran (:mod:`ftcal.cli._messages`)."""
    if isinstance(exc, OSError) and exc.filename is not None and exc.strerror:
        text = f"{exc.filename}: {exc.strerror}"
        if exc.errno in _FULL:
            text += " (the file was not written); free some space on that disk or write to another folder"
    else:
        text = cli_message(exc, args) or type(exc).__name__
    return " ".join(text.split())


def _silence_stdout() -> None:
    """After a broken pipe, point stdout at devnull so Python's exit flush stays quiet."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass
