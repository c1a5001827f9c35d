"""What the benchmark scripts share: their output files (refused if they exist and are not the script's own,
unless ``--force``; checked up front) and their count arguments."""

from __future__ import annotations

import argparse
from pathlib import Path

from ftcal import FtcalError
from ftcal.evaluation import OutputFiles


def parse_output(doc: str, default: str, argv: list[str] | None = None) -> Path:
    """Parse ``--out FILE`` (default ``default``) and ``--force``, and check ``FILE`` before any work: an existing
    file is an error (exit 2) unless ``--force`` replaces it; its folder is made."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--out", default=default, help=f"result JSON (default: {default})")
    parser.add_argument("--force", action="store_true", help="replace an existing --out file")
    args = parser.parse_args(argv)
    out = Path(args.out)
    if out.exists() and not (args.force and out.is_file()):
        parser.error(f"{out} exists; pass --force to replace it (a file), or choose another --out")
    out.parent.mkdir(parents=True, exist_ok=True)
    return out


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
        parser.error(str(exc))
    return files
