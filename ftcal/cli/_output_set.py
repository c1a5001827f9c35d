"""The outputs of one command as one unit: written into a private folder, then moved into place together.

A command that writes several files that belong together (``fit --report``: the model, ``fit.json``, the
report's HTML, JSON and CSV, each naming the model's SHA-256) writes them all into a fresh temporary folder
inside ``--out``; only when every file is complete are they renamed into place, while holding a lock on the
``--out`` folder, so that

* a failure (the report's, a full disk, a signal) before the end leaves nothing of the run behind and every
  file that stood there before untouched; a rename that fails halfway through the set (``--force``) puts the
  files it replaced back (each has a second name, a hard link, until the set is in place);
* two runs with ``--force`` into the same folder never leave a mixed set: their sets are moved one after the
  other, whole, and each file's hash is taken from the bytes this run wrote (its private copy), never from a
  path another run may have replaced meanwhile;
* without ``--force``, a file another run wrote meanwhile is not replaced, and no file of this run is left
  (the error says which file appeared).
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from ._common import CliError, OutputPlan

__all__ = ["OutputSet"]


class OutputSet:
    """The planned files of ``plan`` written as one set (a context manager; :meth:`commit` moves them in).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "out"
    >>> with OutputSet(OutputPlan(out, ["a.txt", "b.txt"], force=False)) as files:
    ...     _ = files.path("a.txt").write_text("A")
    ...     _ = files.path("b.txt").write_text("B")
    ...     files.commit()
    >>> sorted(p.name for p in out.iterdir())
    ['a.txt', 'b.txt']
    """

    def __init__(self, plan: OutputPlan) -> None:
        self.plan = plan
        self._stage: Path | None = None
        self._committed = False

    def __enter__(self) -> "OutputSet":
        out = self.plan.out_dir
        try:
            out.mkdir(parents=True, exist_ok=True)
            self._stage = Path(tempfile.mkdtemp(prefix=".ftcal-run.", suffix=".partial", dir=out))
        except OSError as exc:
            raise CliError(f"--out {out}: cannot create files there ({exc.strerror}); choose another --out") from None
        os.chmod(self._stage, 0o700)
        return self

    def __exit__(self, *exc) -> None:
        if self._stage is not None:
            shutil.rmtree(self._stage, ignore_errors=True)
            self._stage = None

    def path(self, name: str) -> Path:
        """Where this run writes planned file ``name`` (inside its private folder, until :meth:`commit`)."""
        if name not in self.plan.names:
            raise AssertionError(f"{name} was not planned; add it to the OutputPlan first")
        if self._stage is None:
            raise AssertionError("OutputSet.path outside its with-block")
        path = self._stage / name
        path.parent.mkdir(parents=True, exist_ok=True)
        return path

    @contextlib.contextmanager
    def writing(self, name: str) -> Iterator[Path]:
        """Yield the path to write ``name`` to (the same interface as :meth:`OutputPlan.writing`)."""
        yield self.path(name)

    def sha256(self, name: str) -> str:
        """SHA-256 of the bytes this run wrote for ``name`` (its private copy: no other run can change it)."""
        digest = hashlib.sha256()
        with open(self.path(name), "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                digest.update(block)
        return digest.hexdigest()

    def final_path(self, name: str) -> Path:
        """Where ``name`` will stand after :meth:`commit`."""
        return self.plan.out_dir / name

    def commit(self) -> None:
        """Move every written file into place, as one set, under a lock on the ``--out`` folder."""
        assert self._stage is not None and not self._committed
        names = [n for n in self.plan.names if (self._stage / n).exists()]
        for n in names:  # on disk before any rename: a full disk fails here, with nothing in place yet
            fd = os.open(self._stage / n, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        out = self.plan.out_dir
        lock = os.open(out, os.O_RDONLY)
        try:
            fcntl.flock(lock, fcntl.LOCK_EX)  # another ftcal run's set moves before or after this one, whole
            if not self.plan.force:
                taken = [n for n in names if (out / n).exists()]
                if taken:
                    raise CliError(f"{out / taken[0]} appeared while this run was working (another run wrote it?); "
                                   "it was left as it is and this run wrote nothing; pass --force to replace it, or "
                                   "choose another --out")
            moved: list[Path] = []
            backups: dict[Path, Path] = {}  # with --force: a second name (hard link) of each file replaced
            try:
                for i, n in enumerate(names):
                    target = out / n
                    target.parent.mkdir(parents=True, exist_ok=True)
                    if self.plan.force:
                        if target.is_file():
                            backup = self._stage / f".old.{i}"
                            os.link(target, backup)
                            backups[target] = backup
                        os.replace(self._stage / n, target)
                    else:
                        os.link(self._stage / n, target)  # fails if a non-ftcal writer made it meanwhile
                    moved.append(target)
            except BaseException as exc:  # take back what this run put in place: the old set stands whole
                for target in moved:
                    with contextlib.suppress(OSError):
                        if target in backups:
                            os.replace(backups[target], target)
                        else:
                            target.unlink()
                if not isinstance(exc, OSError):
                    raise
                raise CliError(f"{out}: could not put {exc.filename or 'the outputs'} in place ({exc.strerror}); "
                               "no file of this run was left and the files that stood there are as they were"
                               ) from None
        finally:
            os.close(lock)  # closing releases the lock
        self._committed = True
