"""What the benchmark scripts share: their output files (refused if they exist and are not the script's own,
unless ``--force``; checked up front) and their count arguments."""

from __future__ import annotations

import argparse
from pathlib import Path

from ftcal import FtcalError
from ftcal.cli import cli_message
from ftcal.benchmark import OutputFiles


class OutputFile:
    """One output file of a script, checked before any work (see :func:`single_output`)."""

    def __init__(self, files: OutputFiles, name: str) -> None:
        self.files, self.name = files, name

    @property
    def path(self) -> Path:
        return self.files.out_dir / self.name

    def write_text(self, text: str) -> Path:
        return self.files.write_text(self.name, text)

    def write(self):
        """A temporary path to write to, moved into place when the block succeeds (see ``OutputFiles.write``)."""
        return self.files.write(self.name)

    def __str__(self) -> str:
        return str(self.path)


def single_output(parser: argparse.ArgumentParser, out: str | Path, force: bool) -> OutputFile:
    """The script's one output file ``out``: an existing file the script did not write is an error (exit 2)
    unless ``force``; its folder is made."""
    if not str(out).strip() or not Path(out).name:
        parser.error(f"--out {str(out)!r} names no file")
    out = Path(out)
    return OutputFile(output_files(parser, out.parent if str(out.parent) else ".", force, [out.name]), out.name)


def parse_output(doc: str, default: str, argv: list[str] | None = None) -> OutputFile:
    """Parse ``--out FILE`` (default ``default``) and ``--force``, and check ``FILE`` before any work."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--out", default=default, help=f"result JSON (default: {default})")
    parser.add_argument("--force", action="store_true", help="replace an --out file this script did not write")
    args = parser.parse_args(argv)
    return single_output(parser, args.out, args.force)


def int_at_least(low: int, high: int | None = None):
    """An argparse ``type``: an integer from ``low`` (to ``high``), else a one-line usage error."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or value < low or (high is not None and value > high):
            raise argparse.ArgumentTypeError(f"{text!r} is not an integer from {low}" + (f" to {high}" if high else " up"))
        return value
    return parse


def jobs(text: str) -> int:
    """An argparse ``type`` for ``--jobs``: 1 to 256 worker processes, or -1 for one per core."""
    if text.strip() == "-1":
        return -1
    try:
        return int_at_least(1, 256)(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of jobs from 1 to 256, or -1 (every core)") from None


def output_files(parser: argparse.ArgumentParser, out: str, force: bool, names: list[str]) -> OutputFiles:
    """The script's output folder, its files ``names`` checked before any work (exit 2 with one message)."""
    try:
        files = OutputFiles(out, force=force)
        files.check(names)
    except (FtcalError, OSError) as exc:
        parser.error(cli_message(exc))
    return files


def table_or_stop(script: str, out: Path, build) -> str:
    """``build(out)``, the summary of the result files in ``out``; one that is not the script's stops the script
    with one line (exit 1) instead of a traceback."""
    try:
        return build(out)
    except (KeyError, TypeError, ValueError, AttributeError, RecursionError, OSError) as exc:
        raise SystemExit(f"{script}: error: a result file in {out} is not this script's ({exc!r}); move it away "
                         "and run that part again") from None
