"""The output file of a benchmark script: refused if it exists (unless ``--force``), its folder made, up front."""

from __future__ import annotations

import argparse
from pathlib import Path


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
