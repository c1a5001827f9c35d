"""A benchmark's summary files: never replacing a file the benchmark did not write, never left half-written.

A benchmark (``ftcal benchmark artificial``, the study scripts in ``benchmarks/``) writes its tables, JSON and
plots into one folder through :class:`OutputFiles`:

* before any work, :meth:`OutputFiles.check` refuses a name that exists and was not written by a benchmark
  (or was changed since): a user's notes called ``results.md`` are never replaced, unless ``force``;
* each file is written to a fresh temporary file and renamed into place, so an interrupted run leaves the
  previous file or the new one, never half of either; a link at an output's name is never followed;
* the SHA-256 of every file written is kept in the folder's manifest (``.ftcal-benchmark-manifest.json``,
  updated under a lock, so that two runs may share a folder), which is how a re-run knows the file is its
  own to rewrite; a user's file that appears during a run is left alone and the output kept beside it.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

from ..core._exceptions import BenchmarkOutputExistsError, CalibrationInputError
from ..core._files import _umask, atomic_output, check_writable_dir, link_beside
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
    ftcal.core._exceptions.BenchmarkOutputExistsError: .../table.md exists and was not written by this benchmark (or was edited since). Fix: choose another output folder or pass force=True to overwrite it.
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
        """File name -> SHA-256 of what a benchmark wrote, read anew each time (two benchmarks may share a folder);
        missing or unreadable: none (nothing here is known to be the benchmark's)."""
        self.manifest_note = ""
        if not os.path.lexists(self.manifest_path):
            return {}
        try:
            manifest = json.loads(self.manifest_path.read_text(encoding="utf-8"))
        except (OSError, ValueError, RecursionError):
            manifest = None
        if not isinstance(manifest, dict):
            self.manifest_note = f" (its record of what the benchmark wrote, {self.manifest_path}, is unreadable)"
            return {}
        # a name maps to the SHA-256 of its file, or to a list of them while a write is under way
        return {k: v for k, v in manifest.items()
                if isinstance(k, str) and (isinstance(v, str) or isinstance(v, list) and all(isinstance(h, str) for h in v))}

    def _is_own(self, path: Path, manifest: dict | None = None) -> bool:
        """Whether ``path`` is a regular file (not a link) whose SHA-256 the manifest records under its name."""
        if path.is_symlink() or not path.is_file():
            return False
        recorded = (self.manifest if manifest is None else manifest).get(path.name)
        return _sha(path) in ([recorded] if isinstance(recorded, str) else recorded or [])

    def is_own(self, name: str) -> bool:
        """Whether the file ``name`` in the folder is one this benchmark wrote, unchanged since (its SHA-256 in the
        manifest): a result a resumed run may reuse. A file it did not write, or edited, is not, ``force`` or not.

        Examples
        --------
        >>> import tempfile
        >>> files = OutputFiles(tempfile.mkdtemp())
        >>> _ = files.write_text("table.md", "| a |")
        >>> files.is_own("table.md"), files.is_own("other.md")
        (True, False)
        """
        return self._is_own(self.out_dir / name)

    def check(self, names: Sequence[str]) -> None:
        """Refuse, before any work, a name that is a folder, or a file or link the benchmark did not write (unless
        ``force``); and a folder where the manifest goes."""
        if self.manifest_path.is_dir() and not self.manifest_path.is_symlink():
            raise BenchmarkOutputExistsError(f"{self.manifest_path} is a folder, where this benchmark keeps its record "
                                             "of what it wrote; move it or choose another output folder.")
        manifest = self.manifest  # read once for every name (it also sets the note on an unreadable one)
        for name in names:
            path = self.out_dir / check_file_name(name, "an output name")
            if path.is_dir() and not path.is_symlink():
                raise BenchmarkOutputExistsError(f"{path} is a folder, where this benchmark writes a file; move it "
                                                 "or choose another output folder.")
            if os.path.lexists(path) and not self.force and not self._is_own(path, manifest):
                what = ("is a link (a benchmark writes regular files)" if path.is_symlink() else
                        f"exists and was not written by this benchmark (or was edited since){self.manifest_note}")
                raise BenchmarkOutputExistsError(f"{path} {what}.", parameter="out", value=str(path),
                                                 fix="choose another output folder or pass {force} to overwrite it",
                                                 settings={"force": True})

    @contextlib.contextmanager
    def write(self, name: str) -> Iterator[Path]:
        """Yield a temporary path to write ``name`` to; it replaces ``out_dir / name`` when the block succeeds.

        Under the manifest's lock: the file is replaced if it is missing, the benchmark's own (another run in the
        same folder may have just written it) or ``force``; otherwise (a user's file appeared after
        :meth:`check`) it is left as it is, the new output is kept beside it under a fresh name and the error
        says where. The new file's SHA-256 is recorded before the rename, so that an interrupted run still
        knows its file as its own.
        """
        path = self.out_dir / check_file_name(name, "an output name")
        fd, tmp_name = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".partial{path.suffix}", dir=self.out_dir)
        os.close(fd)
        tmp = Path(tmp_name)
        os.chmod(tmp, 0o666 & ~_umask())
        try:
            yield tmp
            digest = _sha(tmp)
            with self._manifest_lock():  # two runs in one folder: one decision and one manifest update at a time
                manifest = self.manifest
                exists = os.path.lexists(path)
                if exists and not self.force and not self._is_own(path, manifest):
                    self._keep_beside(tmp, path)
                old = manifest.get(name)
                self._write_manifest({**manifest, name: [*([old] if isinstance(old, str) else old or []), digest]})
                if exists:
                    os.replace(tmp, path)  # the benchmark's own file, or force
                else:
                    try:  # a link: a user's file made meanwhile (users take no lock) is never replaced
                        os.link(tmp, path)
                    except FileExistsError:
                        self._keep_beside(tmp, path)
                    except OSError:  # a file system without hard links
                        os.replace(tmp, path)
                self._write_manifest({**self.manifest, name: digest})
        finally:
            with contextlib.suppress(FileNotFoundError):
                tmp.unlink()

    def _keep_beside(self, tmp: Path, path: Path) -> None:
        kept = link_beside(tmp, path)
        raise BenchmarkOutputExistsError(f"{path} appeared while this run was working and was not written by a "
                                         f"benchmark; it was left as it is and this run's output was kept as {kept}.")

    def _write_manifest(self, manifest: dict) -> None:
        with atomic_output(self.manifest_path, overwrite=True, error=BenchmarkOutputExistsError) as tmp:
            tmp.write_text(json.dumps(manifest, indent=1), encoding="utf-8")

    @contextlib.contextmanager
    def _manifest_lock(self) -> Iterator[None]:
        """An exclusive lock on the manifest's lock file for a read-modify-write (POSIX; elsewhere none)."""
        try:
            import fcntl
        except ImportError:  # not POSIX: the writes stay atomic, only a concurrent run's entry may be lost
            fcntl = None
        if fcntl is None:
            yield
            return
        # O_NOFOLLOW: a link planted at the lock file's name is an error, never a file made elsewhere
        fd = os.open(self.out_dir / (MANIFEST_NAME + ".lock"), os.O_CREAT | os.O_RDONLY | os.O_NOFOLLOW, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            yield
        finally:
            os.close(fd)  # releases the lock

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
