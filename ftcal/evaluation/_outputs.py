"""A benchmark's summary files: never replacing a file the benchmark did not write, never left half-written.

A benchmark (``ftcal benchmark artificial``, the study scripts in ``benchmarks/``) writes its tables, JSON and
plots into one folder through :class:`OutputFiles`:

* before any work, :meth:`OutputFiles.check` refuses a name that exists and was not written by a benchmark
  (or was changed since): a user's notes called ``results.md`` are never replaced, unless ``force``;
* each file is written to a temporary file and renamed into place (:func:`ftcal.core.atomic_output`), so an
  interrupted run leaves the previous file or the new one, never half of either;
* the SHA-256 of every file written is kept in the folder's manifest (``.ftcal-benchmark-manifest.json``),
  which is how a re-run knows the file is its own to rewrite.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
from collections.abc import Iterator, Sequence
from pathlib import Path

from ..core._exceptions import BenchmarkOutputExistsError, CalibrationInputError
from ..core._files import atomic_output, check_writable_dir
from ..core._validation import check_bool

__all__ = ["OutputFiles", "MANIFEST_NAME"]

#: The manifest of a benchmark's output folder: file name -> SHA-256 of what the benchmark wrote.
MANIFEST_NAME = ".ftcal-benchmark-manifest.json"


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def check_file_name(name, what: str) -> str:
    """``name`` if it can be one file's name inside a folder (no separator, not ``.``/``..``), else an error."""
    if not isinstance(name, str) or not name.strip() or name in (".", "..") or any(c in name for c in "/\\\0"):
        raise CalibrationInputError(f"{what} must be a plain name, used in file names (no '/', '\\', '..' or NUL); "
                                    f"got {name!r}.")
    return name


class OutputFiles:
    """The summary files of a benchmark in ``out_dir`` (see the module notes).

    Parameters
    ----------
    out_dir : str or path-like
        The folder (made if missing). An empty path is refused (it would be the working directory).
    force : bool, default=False
        Replace files of the same names that the benchmark did not write.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (out / "table.md").write_text("my notes")
    >>> files = OutputFiles(out)
    >>> files.check(["table.md"])
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.BenchmarkOutputExistsError: .../table.md exists and was not written by this benchmark (or was edited since); choose another output folder or pass --force (force=True) to overwrite it.
    >>> OutputFiles(out / "run").write_text("table.md", "| a |").read_text()
    '| a |'
    """

    def __init__(self, out_dir: str | os.PathLike, *, force: bool = False) -> None:
        if not isinstance(out_dir, (str, os.PathLike)) or not str(out_dir).strip():
            raise CalibrationInputError(f"out_dir must be a folder path (an empty one would be the working "
                                        f"directory); got {out_dir!r}.")
        self.out_dir = Path(out_dir)
        self.force = check_bool(force, "force")
        check_writable_dir(self.out_dir, CalibrationInputError, "output folder")
        self.out_dir.mkdir(parents=True, exist_ok=True)
        self.manifest_path = self.out_dir / MANIFEST_NAME
        self.manifest_note = ""

    @property
    def manifest(self) -> dict:
        """File name -> SHA-256 of what a benchmark wrote, read anew each time (two benchmarks may share a folder)."""
        return self._read_manifest()

    def _read_manifest(self) -> dict:
        """The manifest's entries; missing or unreadable: none (nothing here is known to be the benchmark's)."""
        self.manifest_note = ""
        if not self.manifest_path.exists():
            return {}
        try:
            manifest = json.loads(self.manifest_path.read_text(encoding="utf-8"))
        except (OSError, ValueError, RecursionError):
            manifest = None
        if not isinstance(manifest, dict):
            self.manifest_note = f" (its record of what the benchmark wrote, {self.manifest_path}, is unreadable)"
            return {}
        return {k: v for k, v in manifest.items() if isinstance(k, str) and isinstance(v, str)}

    def _is_own(self, path: Path) -> bool:
        return path.is_file() and self.manifest.get(path.name) == _sha(path)

    def check(self, names: Sequence[str]) -> None:
        """Refuse, before any work, a name that is a folder, or a file the benchmark did not write (unless ``force``)."""
        for name in names:
            path = self.out_dir / check_file_name(name, "an output name")
            if path.is_dir():
                raise BenchmarkOutputExistsError(f"{path} is a folder, where this benchmark writes a file; move it "
                                                 "or choose another output folder.")
            if path.exists() and not self.force and not self._is_own(path):
                raise BenchmarkOutputExistsError(
                    f"{path} exists and was not written by this benchmark (or was edited since){self.manifest_note}; "
                    "choose another output folder or pass --force (force=True) to overwrite it.")

    @contextlib.contextmanager
    def write(self, name: str) -> Iterator[Path]:
        """Yield a temporary path to write ``name`` to; it replaces ``out_dir / name`` when the block succeeds.

        A file of that name that is not the benchmark's own and appeared after :meth:`check` is not replaced
        (unless ``force``): the new output is kept beside it and the error says where.
        """
        path = self.out_dir / check_file_name(name, "an output name")
        # a missing file goes in by a link that fails if one appeared meanwhile (kept, ours put beside it)
        overwrite = self.force or (path.exists() and self._is_own(path))
        with atomic_output(path, overwrite=overwrite, error=BenchmarkOutputExistsError) as tmp:
            yield tmp
        with self._manifest_lock():  # two runs in one folder: neither loses the other's entry
            manifest = {**self.manifest, name: _sha(path)}
            with atomic_output(self.manifest_path, overwrite=True, error=BenchmarkOutputExistsError) as tmp:
                tmp.write_text(json.dumps(manifest, indent=1), encoding="utf-8")

    @contextlib.contextmanager
    def _manifest_lock(self) -> Iterator[None]:
        """An exclusive lock on the manifest's lock file for a read-modify-write (POSIX; elsewhere none)."""
        try:
            import fcntl
        except ImportError:  # not POSIX: the write stays atomic, only a concurrent run's entry may be lost
            yield
            return
        with open(self.out_dir / (MANIFEST_NAME + ".lock"), "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            try:
                yield
            finally:
                fcntl.flock(lock, fcntl.LOCK_UN)

    def write_text(self, name: str, text: str) -> Path:
        """Write ``text`` (UTF-8) as ``name``; the final path."""
        with self.write(name) as tmp:
            tmp.write_text(text, encoding="utf-8")
        return self.out_dir / name

    def save_figure(self, name: str, fig, **savefig_kwargs) -> Path:
        """Save a matplotlib figure as ``name`` (PNG); the final path."""
        with self.write(name) as tmp:
            fig.savefig(tmp, format="png", **savefig_kwargs)
        return self.out_dir / name
