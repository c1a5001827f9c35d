"""Safe output files: a unique temporary file, then an atomic rename that never replaces what it must not.

Every file ftcal writes (datasets, model files, CLI outputs) goes through
:func:`atomic_output`, so that

* an interrupted or failed write never leaves half a file where a good one stood;
* two runs writing the same target at once never share a temporary file
  (each gets its own from :func:`tempfile.mkstemp`);
* without ``overwrite`` a file that appeared while the run worked (another
  run finished first) is not replaced: the new output is kept beside it
  under a unique name and the error says where;
* a failed write (a full disk, a quota) names the file it was writing, not
  only ``[Errno 28] No space left on device``.

The outputs of one run that belong together (a plan's poses, its summary and
its figure; a model, its fit summary and its report) go through one
:class:`OutputSet` (:func:`atomic_output_set`; the command line's
``OutputPlan.as_one_set``): every file is written to its temporary name first
and only when all are written are they renamed into place, so that

* a failure (a full disk, a signal, an error in a later step) leaves none of
  them and every file that stood there before untouched;
* the renames run under a lock on the set's folders, with the termination
  signals held back: two runs' sets are put in place one after the other,
  whole, and a signal arriving meanwhile acts after the set is in place;
* with ``overwrite``, each file replaced keeps a second name (a hard link)
  until the whole set is in place: a rename that fails halfway (a folder made
  where a file goes) puts every old file back, so a replaced set is never
  half old and half new;
* without ``overwrite``, a file another run wrote meanwhile is not replaced,
  and none of this run's files is put in place.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import itertools
import json
import math
import numbers
import os
import signal
import tempfile
import threading
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

__all__ = ["atomic_output", "atomic_output_set", "OutputSet", "check_writable_dir", "same_file", "content_twins", "values_sha256", "plain_json", "write_json", "MODEL_SUFFIX",
           "model_file_name", "is_finite_number", "describe_file_start"]


#: Suffix of the model files ``ftcal fit`` writes (one ``.npz``: JSON metadata + weights, see :func:`ftcal.save_model`).
MODEL_SUFFIX = ".model.npz"


def model_file_name(name: str) -> str:
    """File name of a fitted model called ``name`` (``directional`` -> ``directional.model.npz``)."""
    return f"{name}{MODEL_SUFFIX}"

#: Errors of a write that name no file (``OSError.filename`` is None): the device is full, a quota is reached, the
#: file would be too large, the disk failed or became read-only. The file being written is named in their place.
_WRITE_FAILURES = frozenset(getattr(errno, name) for name in ("ENOSPC", "EDQUOT", "EFBIG", "EIO", "EROFS")
                            if hasattr(errno, name))


def _naming(exc: OSError, tmp: Path, path: Path) -> OSError | None:
    """``exc`` of a write to the temporary ``tmp`` of ``path`` as the same error naming ``path`` (the user's file),
    or None when it is about another file."""
    named = exc.filename is not None and Path(exc.filename) == tmp
    if named or (exc.filename is None and exc.errno in _WRITE_FAILURES):
        return type(exc)(exc.errno, exc.strerror or os.strerror(exc.errno or 0), str(path))
    return None


@contextlib.contextmanager
def _temporary_beside(path: Path) -> Iterator[Path]:
    """Yield a fresh, empty temporary file beside ``path`` (unique per call), readable as the umask allows; an
    ``OSError`` of writing it is raised again naming ``path``, and a block that fails removes it."""
    directory = path.parent if str(path.parent) else Path(".")
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".partial{path.suffix}", dir=directory)
    except OSError as exc:  # no such folder, not writable, a full disk: name the user's file, not the temporary one
        raise type(exc)(exc.errno, exc.strerror, str(path)) from None
    os.close(fd)
    tmp = Path(tmp_name)
    os.chmod(tmp, 0o666 & ~_umask())  # mkstemp's 0600 would make every output private
    try:
        yield tmp
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        named = _naming(exc, tmp, path) if isinstance(exc, OSError) else None
        if named is None:
            raise
        raise named from None


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, *, overwrite: bool, error: type[Exception]) -> Iterator[Path]:
    """Yield a fresh temporary path beside ``path``; move it to ``path`` when the block succeeds.

    Parameters
    ----------
    path : path-like
        The final file.
    overwrite : bool
        Whether an existing ``path`` may be replaced. Without it the final
        step is a link that fails if ``path`` exists (no window in which
        another run's file could be replaced).
    error : exception class
        Raised (with both paths named) when ``path`` appeared meanwhile.

    Raises
    ------
    OSError
        A failed write, naming ``path`` (a full disk: ``path: No space left on device``); nothing is left.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "out.txt"
    >>> with atomic_output(target, overwrite=False, error=FileExistsError) as tmp:
    ...     _ = tmp.write_text("hello")
    >>> target.read_text()
    'hello'
    """
    path = Path(path)
    with _temporary_beside(path) as tmp:
        yield tmp
    try:
        _move_into_place(tmp, path, overwrite, error)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


def _move_into_place(tmp: Path, path: Path, overwrite: bool, error: type[Exception]) -> None:
    """Rename ``tmp`` to ``path``; without ``overwrite`` never over a file that exists (it is kept beside)."""
    if overwrite:
        try:
            os.replace(tmp, path)
        except OSError as exc:  # e.g. path is a folder
            raise type(exc)(exc.errno, exc.strerror, str(path)) from None
        return
    try:
        os.link(tmp, path)
    except FileExistsError:
        kept = link_beside(tmp, path)
        raise error(
            f"{path} appeared while this run was working (another run wrote it?); it was left as it is and "
            f"this run's output was kept as {kept}."
        ) from None
    except OSError:  # a file system without hard links: check, then rename
        if path.exists():
            raise error(f"{path} appeared while this run was working; it was left as it is.") from None
        os.replace(tmp, path)


class OutputSet:
    """Files written together: each to its own temporary file, all renamed into place by :meth:`commit`.

    Made by :func:`atomic_output_set`, which commits when its block succeeds and otherwise removes every
    temporary file (so no file of the set is written). A set replaces only the files it writes: it removes none. The one implementation of a run's output set: the
    command line's ``OutputPlan.as_one_set`` yields it too.
    """

    def __init__(self, *, overwrite: bool, error: type[Exception]) -> None:
        self.overwrite = overwrite
        self.error = error
        self._pending: dict[Path, Path] = {}  # final path -> its temporary file

    @contextlib.contextmanager
    def writing(self, path: str | os.PathLike) -> Iterator[Path]:
        """Yield the temporary path of ``path`` (a new one each time: the last written wins); an ``OSError`` of
        the write names ``path``. The file is renamed into place when the whole set is committed."""
        path = Path(path)
        with _temporary_beside(path) as tmp:
            yield tmp
        previous = self._pending.pop(path, None)
        if previous is not None:
            with contextlib.suppress(FileNotFoundError):
                previous.unlink()
        self._pending[path] = tmp

    @property
    def paths(self) -> list[Path]:
        """The final paths written so far (committed or not)."""
        return list(self._pending)

    def sha256(self, path: str | os.PathLike) -> str:
        """SHA-256 of the bytes this run wrote for ``path`` (its own temporary file, which no other run can change;
        before or after the commit)."""
        path = Path(path)
        source = self._pending.get(path)
        if source is None:
            raise KeyError(f"{path} was not written in this set")
        with open(source if source.exists() else path, "rb") as fh:
            return hashlib.file_digest(fh, "sha256").hexdigest()

    def commit(self) -> None:
        """Rename every written file into place, all or none.

        Without ``overwrite`` a final path that exists (another run wrote it meanwhile) stops the commit before
        any rename: nothing is replaced, this run's files are kept beside under unique names and ``error`` says
        where. With ``overwrite``, the files that are replaced are first given a second name, so that a rename
        that fails halfway puts every old file back.
        """
        pending = list(self._pending.items())
        for _, tmp in pending:  # on disk before any rename: a full disk fails here, with nothing in place yet
            fd = os.open(tmp, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        with _locked({path.parent for path, _ in pending}), \
                _signals_held():
            self._put_in_place(pending)
        self._discard()

    def _put_in_place(self, pending: list[tuple[Path, Path]]) -> None:
        if not self.overwrite:
            placed: list[tuple[Path, Path]] = []
            for path, tmp in pending:
                try:
                    os.link(tmp, path)
                except FileExistsError:
                    self._undo_links(placed)
                    kept = keep_aside(pending)
                    raise self.error(
                        f"{path} appeared while this run was working (another run wrote it?); none of this run's "
                        f"files was put in place (they are kept in {kept}, where no reader of the folder "
                        "takes them for the other run's)."
                    ) from None
                except OSError:  # a file system without hard links: check, then rename
                    if path.exists():
                        self._undo_links(placed)
                        raise self.error(f"{path} appeared while this run was working; none of this run's files "
                                         "was put in place.") from None
                    os.replace(tmp, path)
                placed.append((path, tmp))
            return
        backups: dict[Path, Path | None] = {}
        kept: set[Path] = set()  # backups that could not be put back: never deleted (the old file lives on there)
        try:
            for path, tmp in pending:  # each file replaced keeps a second name: a hard link under a fresh hidden one
                backups[path] = _fresh_link(path, (path.with_name(f".{path.name}.{os.getpid()}.{k}.previous")
                                                   for k in itertools.count(1))) if path.is_file() else None
                try:
                    os.replace(tmp, path)
                except OSError as exc:
                    raise type(exc)(exc.errno, f"{exc.strerror or os.strerror(exc.errno or 0)}; none of this run's "
                                    "files was left and the files that stood there are as they were", str(path)
                                    ) from None
        except BaseException:
            for path, backup in backups.items():  # put the old set back
                try:
                    if backup is not None:
                        os.replace(backup, path)
                    elif path in self._pending and not self._pending[path].exists():  # put in place: remove it
                        path.unlink()
                except OSError:
                    kept.add(path)
            raise
        finally:
            for path, backup in backups.items():
                if backup is not None and path not in kept:
                    with contextlib.suppress(FileNotFoundError):
                        backup.unlink()

    @staticmethod
    def _undo_links(placed: list[tuple[Path, Path]]) -> None:
        for path, tmp in placed:  # only the files this run linked (still the same file as its temporary one)
            with contextlib.suppress(OSError):
                if os.path.samefile(path, tmp):
                    path.unlink()

    def _discard(self) -> None:
        for tmp in self._pending.values():
            with contextlib.suppress(FileNotFoundError):
                tmp.unlink()
        self._pending.clear()


@contextlib.contextmanager
def _locked(folders: Iterable[Path]) -> Iterator[None]:
    """An exclusive ``flock`` on each folder (in one order, so two runs never wait on each other crosswise): the
    sets of two ftcal runs into the same folder are put in place one after the other. Where ``flock`` is missing
    (not POSIX) or refused (some network file systems), the set is put in place without it."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    with contextlib.ExitStack() as stack:
        for folder in sorted({str(Path(f).resolve()) for f in folders}):
            try:
                fd = os.open(folder, os.O_RDONLY)
            except OSError:
                continue
            stack.callback(os.close, fd)  # closing releases the lock
            with contextlib.suppress(OSError):
                fcntl.flock(fd, fcntl.LOCK_EX)
        yield


#: The signals that end a run (Ctrl-C, ``kill``, a closed terminal).
_TERMINATING = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """Hold the terminating signals back while a set is renamed into place (in the main thread, where Python runs
    its signal handlers): one that arrives meanwhile acts right after, on a set that is whole, old or new."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    # Python-level handlers that only record, not a thread's signal mask: the kernel may hand a process-directed
    # signal to any thread that does not block it (a BLAS or torch thread), whose handler flag the main thread
    # then acts on at once, mid-set; a Python handler always runs in the main thread, and here it only records.
    caught: list[int] = []
    previous: dict[int, Any] = {}
    for sig in _TERMINATING:
        try:
            previous[sig] = signal.signal(sig, lambda signum, frame: caught.append(signum))
        except (ValueError, OSError):  # not settable here
            continue
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, signal.SIG_DFL if handler is None else handler)
        for sig in dict.fromkeys(caught):  # acted on now, by the handler that was there (default, ignore, ftcal's)
            signal.raise_signal(sig)


@contextlib.contextmanager
def atomic_output_set(*, overwrite: bool, error: type[Exception]) -> Iterator[OutputSet]:
    """Yield an :class:`OutputSet`; the files written through it are put in place together when the block
    succeeds, and none of them when it fails (an error, a full disk, a signal).

    Parameters
    ----------
    overwrite : bool
        Whether existing files may be replaced (without it, none is: see :meth:`OutputSet.commit`).
    error : exception class
        Raised when a file of the set appeared while the run worked.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_output_set(overwrite=False, error=FileExistsError) as files:
    ...     with files.writing(folder / "a.txt") as tmp:
    ...         _ = tmp.write_text("a")
    ...     print(sorted(p.name for p in folder.iterdir() if not p.name.startswith(".")))
    ...     with files.writing(folder / "b.txt") as tmp:
    ...         _ = tmp.write_text("b")
    []
    >>> sorted(p.name for p in folder.iterdir())
    ['a.txt', 'b.txt']
    """
    files = OutputSet(overwrite=overwrite, error=error)
    try:
        yield files
        files.commit()
    finally:
        files._discard()


def keep_aside(pending: list[tuple[Path, Path]]) -> Path:
    """Keep the temporaries of a set that could not be put in place in a new sub-folder ``unplaced.K`` of the
    first file's folder (``K`` = 1, 2, ...: never one that exists), under their final names; returns the folder.

    A sub-folder, not names beside the other run's files (``stem.1.csv``): whoever reads the folder's
    ``*.csv`` (run logs, a folder dataset) must not take this run's files for the other run's.
    """
    parent = pending[0][0].parent
    for k in itertools.count(1):
        folder = parent / f"unplaced.{k}"
        try:
            folder.mkdir()
            break
        except FileExistsError:
            continue
    for path, tmp in pending:  # two files of one name in different folders of the set: the second beside
        target = folder / path.name
        _fresh_link(tmp, itertools.chain([target], _names_beside(target)))
    return folder


def link_beside(tmp: Path, path: Path) -> Path:
    """Give ``tmp``'s content a fresh name beside ``path`` (``stem.1.suffix``, ``stem.2.suffix``, ...), never one
    that exists."""
    return _fresh_link(tmp, _names_beside(path))


def _names_beside(path: Path) -> Iterator[Path]:
    return (path.with_name(f"{path.stem}.{k}{path.suffix}") for k in itertools.count(1))


def _fresh_link(source: Path, names: Iterable[Path]) -> Path:
    """The first of ``names`` that does not exist, made a hard link to ``source`` (which fails where the name is
    taken; without hard links, an exclusive create of a copy)."""
    for name in names:
        try:
            os.link(source, name)
            return name
        except FileExistsError:
            continue
        except OSError:  # a file system without hard links
            try:
                with open(name, "xb") as f:
                    f.write(Path(source).read_bytes())
                return name
            except FileExistsError:
                continue
    raise AssertionError("unreachable")


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def check_writable_dir(directory: str | os.PathLike, error: type[Exception], what: str = "output folder") -> None:
    """Raise ``error`` now if files cannot be created in ``directory`` (or in its nearest existing parent)."""
    d = Path(directory)
    while not d.exists() and d.parent != d:
        d = d.parent
    if d.exists() and not d.is_dir():
        raise error(f"{what} {directory}: {d} is a file, not a directory; choose another {what}.")
    try:
        fd, probe = tempfile.mkstemp(prefix=".ftcal-write-test.", dir=d)
    except OSError as exc:
        raise error(f"{what} {directory}: cannot create files in {d} ({exc.strerror}); choose another {what}.") from None
    os.close(fd)
    os.unlink(probe)


def values_sha256(arrays: Iterable) -> str:
    """SHA-256 (hex) of the values of ``arrays`` (array-likes, or None for one that is absent), in order, each
    with its shape: the identity of data as read, whatever held it. Memory layout (order, strides, byte order)
    and the width of a dtype do not count: equal integers (``int32``, ``int64``, ``bool``) hash alike, equal
    floats (``float32`` widened exactly, ``float64``; ``-0.0`` as ``0.0``) alike, text by its characters.
    Integers and floats are kept apart (labels are not readings); ``arrays`` may be a generator (it is read
    once, array by array).

    Examples
    --------
    >>> import numpy as np
    >>> a = np.arange(6.0).reshape(2, 3)
    >>> values_sha256([a, [1, 2]]) == values_sha256([np.asfortranarray(a).astype(">f4"), np.int8([1, 2])])
    True
    >>> values_sha256([a]) == values_sha256([a.reshape(3, 2)]), values_sha256([a, None]) == values_sha256([a])
    (False, False)
    """
    import numpy as np

    digest = hashlib.sha256()
    for array in arrays:
        if array is None:
            digest.update(b"none;")
            continue
        a = np.asarray(array)
        if a.dtype.kind in "biu" and (a.dtype.kind != "u" or not a.size or a.max() <= np.iinfo(np.int64).max):
            kind, data = b"i", np.ascontiguousarray(a, dtype="<i8").tobytes()
        elif a.dtype.kind in "fc":
            wide = "<c16" if a.dtype.kind == "c" else "<f8"
            kind, data = b"f", (np.ascontiguousarray(a, dtype=wide) + 0.0).tobytes()
        else:  # text, objects, integers beyond int64: their characters
            kind, data = b"t", "\0".join(map(str, a.reshape(-1).tolist())).encode("utf-8", "surrogatepass")
        digest.update(kind + repr(a.shape).encode("ascii") + b";" + len(data).to_bytes(8, "little"))
        digest.update(data)
    return digest.hexdigest()


#: Two inputs are twins when each of their numbers agrees to this relative tolerance of its own magnitude: far below
#: any sensor's resolution relative to its reading (a bridge biased at 2.5 V resolving 0.1 µV is 4e-8 of its reading;
#: two real recordings differ by their noise, 1e-6 of the reading and more), far above float round-off (1e-16) and
#: re-formatting (``%.8g``: 5e-9). Relative to each number, not to a column's span or largest value: one large value
#: in a column, or a large offset under a small span, must not make two different recordings equal.
_TWIN_RTOL = 1e-7


def _row_tables(arrays) -> tuple[list, list] | None:
    """The values of ``arrays`` as row tables: arrays of one leading length are the columns of one table (its
    numbers as floats, its text apart), each table's rows sorted canonically (text, then the numbers on a grid
    of 1e-9 of their column's largest value); 0-d values and None are kept as they are."""
    import numpy as np

    if arrays is None:
        return None
    columns: dict[int, list] = {}
    scalars = []
    for array in arrays:
        a = None if array is None else np.asarray(array)
        if a is None or a.ndim == 0:
            scalars.append(None if a is None else a.tolist())
            continue
        columns.setdefault(len(a), []).append(a.reshape(len(a), -1))
        scalars.append(("column", len(a), a.reshape(len(a), -1).shape[1], a.dtype.kind in "biufc"))
    tables = []
    for n, parts in columns.items():
        numbers = np.hstack([np.zeros((n, 0))] + [p.astype(np.float64) for p in parts if p.dtype.kind in "biufc"])
        text = np.hstack([np.zeros((n, 0), dtype=str)] + [p.astype(str) for p in parts if p.dtype.kind not in "biufc"])
        # sorted on a grid of 1e-9 of each column's largest value: finer than any reading's noise (the samples of one
        # pose, equal in their reference wrench, are ordered by their readings), coarser than round-off (a rotation
        # matrix's zeros written as a quaternion, -1e-17 and 1e-17, must not reorder the poses that share them)
        scale = np.abs(np.where(np.isfinite(numbers), numbers, 0.0)).max(axis=0, initial=0.0)
        step = np.where(scale > 0, scale * 1e-9, 1.0)
        sortable = np.nan_to_num(np.round(numbers / step), nan=np.inf)
        keys = list(sortable.T[::-1]) + list(text.T[::-1])  # the last key sorts first: the text, then the numbers
        order = np.lexsort(keys) if keys else np.arange(n)
        tables.append((numbers[order], text[order]))
    return scalars, tables


def _row_signature(tables) -> tuple:
    """A cheap signature of :func:`_row_tables` that twins share (bar a rounding boundary, rarely): the shapes,
    the text, and each numeric column's mean on a grid of 1e-4 of the column's largest finite value; only inputs of
    one signature are compared value by value, so a folder of many files is not compared pair by pair."""
    import numpy as np

    signature = [repr(tables[0])]
    for numbers, text in tables[1]:
        finite = np.where(np.isfinite(numbers), numbers, 0.0)
        scale = np.abs(finite).max(axis=0, initial=0.0)
        step = np.where(scale > 0, scale * 1e-4, 1.0)
        means = np.round(finite.mean(axis=0) / step) if len(numbers) else np.zeros(numbers.shape[1])
        signature.append((numbers.shape, text.shape, hash(text.tobytes()), tuple(means.tolist()),
                          tuple(np.isnan(numbers).sum(axis=0).tolist()), tuple(np.isinf(numbers).sum(axis=0).tolist())))
    return tuple(signature)


def _same_rows(a, b, rtol: float) -> bool:
    """Whether two :func:`_row_tables` hold the same values: text equal, infinities and NaN in the same places,
    every other number within ``rtol`` of its own magnitude (and 1e-12 of its column's largest finite value, for
    numbers that are round-off around zero, e.g. a rotation matrix's zeros written as a quaternion)."""
    import numpy as np

    if a[0] != b[0] or len(a[1]) != len(b[1]):
        return False
    for (num_a, text_a), (num_b, text_b) in zip(a[1], b[1]):
        if num_a.shape != num_b.shape or text_a.shape != text_b.shape or not np.array_equal(text_a, text_b):
            return False
        finite_a, finite_b = np.isfinite(num_a), np.isfinite(num_b)
        if not (np.array_equal(finite_a, finite_b) and np.array_equal(num_a[~finite_a], num_b[~finite_b], equal_nan=True)):
            return False
        x, y = num_a[finite_a], num_b[finite_b]  # the same places: the finite numbers, flattened alike
        scale = np.abs(np.where(finite_a, num_a, 0.0)).max(axis=0, initial=0.0)
        floor = np.broadcast_to(1e-12 * scale, num_a.shape)[finite_a]
        if not (np.abs(x - y) <= rtol * np.maximum(np.abs(x), np.abs(y)) + floor).all():
            return False
    return True


def content_twins(paths: Iterable[str | os.PathLike], values, key=None, *, rtol: float = _TWIN_RTOL
                  ) -> list[tuple[Path, Path]]:
    """Pairs of ``paths`` that hold the same values, the later one second: one recording given twice, under two
    names, in two formats, with other number formatting or with its rows in another order. ``values(path)`` gives
    the arrays a reader reads from a path (None for one it cannot read); arrays of one length are the columns of a
    table whose rows are compared as a set (sorted canonically), each number within ``rtol`` of its own magnitude
    (default 1e-7: above round-off and re-formatting to 8 digits, below the noise of any sensor's reading), text
    exactly; only inputs of one cheap signature (shapes, text, column means) are compared value by value.
    Only a whole input equal to another is a twin: two recordings sharing most rows (a low-resolution ADC reading
    the same loads) are not, and neither is a truncated copy (it holds fewer rows). With ``key`` (a cheap
    ``key(path)``, e.g. a row count), only paths of equal keys are read; a path whose key or values cannot be had
    is passed over (its reader names the problem).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> for name, text in (("a.csv", "1,2\\n3,4\\n"), ("b.csv", "3,4\\n1,2.5\\n"), ("c.csv", "3.0, 4\\n1.0, 2e0\\n")):
    ...     _ = (d / name).write_text(text)
    >>> numbers = lambda p: [[[float(v) for v in line.split(",")] for line in p.read_text().splitlines()]]
    >>> [(a.name, b.name) for a, b in content_twins([d / "a.csv", d / "b.csv", d / "c.csv"], numbers)]
    [('a.csv', 'c.csv')]
    """
    paths = [Path(p) for p in paths]
    by_key: dict = {}
    for p in paths:
        try:
            by_key.setdefault(key(p) if key is not None else None, []).append(p)
        except (OSError, ValueError):
            continue
    twins = []
    for group in by_key.values():
        seen: dict = {}  # signature -> (path, tables) of the group's inputs read so far, each the first of its values
        for p in group if len(group) > 1 else ():
            try:
                tables = _row_tables(values(p))
            except (OSError, ValueError):
                continue
            if tables is None:
                continue
            alike = seen.setdefault(_row_signature(tables), [])
            first = next((q for q, other in alike if _same_rows(other, tables, rtol)), None)
            if first is not None:
                twins.append((first, p))
            else:
                alike.append((p, tables))
    return sorted(twins, key=lambda pair: paths.index(pair[1]))


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether two paths name the same file: the same existing file (hard links too), or, when either does
    not exist yet, the same path once links and relative parts are resolved."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return Path(a).resolve() == Path(b).resolve()


def plain_json(obj):
    """``obj`` as plain JSON values: numpy arrays and scalars to lists and numbers, tuples to lists, paths to
    strings, and NaN / inf to ``null`` (strict JSON has no such numbers). The one converter of every JSON file
    ftcal writes.

    Examples
    --------
    >>> import numpy as np
    >>> plain_json({"a": np.arange(2), "b": (np.float64(1.5), float("nan")), "c": Path("x")})
    {'a': [0, 1], 'b': [1.5, None], 'c': 'x'}
    """
    import numpy as np

    if isinstance(obj, dict):
        return {str(k): plain_json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [plain_json(v) for v in obj]
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, np.ndarray):
        return plain_json(obj.tolist())
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def write_json(path: str | os.PathLike, obj, *, indent: int | None = 2) -> Path:
    """Replace ``path`` with ``obj`` as strict JSON, atomically; create its folder. Return ``path``.

    NaN and inf are written as ``null`` (see :func:`plain_json`). The text goes to a temporary file beside
    ``path`` that is moved over it at the end (:func:`atomic_output`): a reader, or a run killed mid-write,
    sees the old file or the new one, never half of one. The one JSON writer of ftcal's outputs and of the
    benchmarks' per-fit caches.

    Examples
    --------
    >>> import json, tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "new" / "fit.json"
    >>> _ = write_json(path, {"rmse": float("nan"), "n": 3})
    >>> json.loads(path.read_text())
    {'rmse': None, 'n': 3}
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_output(path, overwrite=True, error=FileExistsError) as tmp:
        tmp.write_text(json.dumps(plain_json(obj), indent=indent) + "\n", encoding="utf-8")
    return path


def describe_file_start(path: str | os.PathLike) -> str:
    """What a file that is not the zip archive (``.npz``) it should be looks like, from its first bytes: the end of
    an error message (the model and dataset readers).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "x.npz"
    >>> _ = path.write_text("s0,s1\\n1,2\\n")
    >>> describe_file_start(path)
    "it is a text file (first line 's0,s1'), e.g. a CSV or JSON file"
    """
    with open(path, "rb") as f:
        head = f.read(512)
    if not head:
        return "the file is empty"
    for starts, words in ((b"\x93NUMPY", "it is a single .npy array, not an .npz archive"),
                          ((b"\x80", b"(dp", b"(lp", b"cnumpy", b"ccopy_reg"),
                           "it looks like a Python pickle, which ftcal never loads"),
                          (b"PK", "a damaged zip archive"), (b"\x89HDF", "it is an HDF5 file")):
        if head.startswith(starts):
            return words
    if head.startswith(b"\x08") and b"onnx" in head.lower():
        return "it looks like an ONNX file (an export of a model)"
    try:
        text = head.decode("utf-8")
    except UnicodeDecodeError:
        return f"binary data starting with {head[:8]!r}"
    first = text.splitlines()[0][:60] if text.splitlines() else ""
    return f"it is a text file (first line {first!r}), e.g. a CSV or JSON file"


def is_finite_number(value) -> bool:
    """Whether ``value`` is a finite real number (a bool, NaN, inf, a string or None is not).

    Examples
    --------
    >>> [is_finite_number(v) for v in (1, 2.5, float("nan"), True, "3", None)]
    [True, True, False, False, False, False]
    """
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)
