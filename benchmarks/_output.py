"""The output file of a benchmark script: refused if it exists (unless ``--force``), its folder made, up front."""

from __future__ import annotations

import argparse
from pathlib import Path


def add_output_arguments(parser: argparse.ArgumentParser, default: str) -> None:
    """``--out FILE`` (default ``default``) and ``--force`` (replace an existing ``FILE``)."""
    parser.add_argument("--out", default=default, help=f"result JSON (default: {default})")
    parser.add_argument("--force", action="store_true", help="replace an existing --out file")


def new_output(args: argparse.Namespace, parser: argparse.ArgumentParser) -> Path:
    """``args.out`` checked before any work: an existing file is an error (exit 2) unless ``--force``."""
    out = Path(args.out)
    if out.exists() and not args.force:
        parser.error(f"{out} exists; pass --force to replace it, or choose another --out")
    if out.exists() and not out.is_file():
        parser.error(f"{out} is not a file; choose another --out")
    out.parent.mkdir(parents=True, exist_ok=True)
    return out
