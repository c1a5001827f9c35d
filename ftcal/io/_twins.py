"""Recordings given twice: run logs, pose files or ROS bags whose values are the same.

One recording given twice (under two names, twice in a folder, in two formats, with other number formatting, its
rows in another order, a bag with its receive times shifted or a log topic added) would count its poses twice, and
its twins would fall in different folds, so a model would be judged on its own training rows.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from ..core._exceptions import CalibrationInputError, DatasetFileError
from ..core._files import content_twins, values_sha256

__all__ = ["refuse_twin_recordings"]

#: What each kind of recording is compared by: the values its reader reads.
_KINDS = ("ROS bag", "run log", "pose file")


def _rows(path: Path) -> int:
    """A text file's data rows (not blank, not ``#`` comments): the cheap key of its twin check."""
    with open(path, "rb") as fh:
        lines = (line.strip().removeprefix(b"\xef\xbb\xbf") for line in fh)
        return sum(1 for line in lines if line and not line.startswith(b"#"))


def refuse_twin_recordings(paths: Iterable[str | os.PathLike], what: str,
                           error: type[Exception] = DatasetFileError) -> None:
    """Refuse recordings that hold the same values (see the module): ``what`` is ``"ROS bag"``, ``"run log"`` or
    ``"pose file"``; they are compared by what their reader reads, as sets of rows, each number within 1e-7 of
    itself (:func:`ftcal.core.content_twins`: a truncated copy or another recording sharing most rows is not a twin;
    a bag by a streamed digest of each usable topic's values, :func:`ftcal.io.bag_values`), after a cheap key (a
    bag's usable topics and first messages, a text file's row count: only inputs alike in it are read).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> for name in ("a.csv", "b.csv"):
    ...     _ = (d / name).write_text("qw,qx,qy,qz,Fx,Fy,Fz,Tx,Ty,Tz\\n1,0,0,0,1,2,3,0.1,0.2,0.3\\n")
    >>> refuse_twin_recordings([d / "a.csv", d / "b.csv"], "pose file")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.DatasetFileError: .../b.csv holds the same pose file as .../a.csv (the same values read from both): one recording given twice would count its poses twice and judge a model on its own rows; give each recording once
    """
    from ._bags import bag_values
    from ._logs import read_run_log
    from ._poses import read_pose_file

    if what not in _KINDS:
        raise CalibrationInputError(f"what must be one of {_KINDS}; got {what!r}", parameter="what", value=what)

    def text_values(path: Path):
        if what == "run log":
            log = read_run_log(path)
            return [log.timestamp, log.run_kind, log.config, log.pose, log.q, log.raw, log.temperature,
                    log.load_mass]  # the declared load makes the reference wrenches: another mass, another run
        rec = read_pose_file(path, orientation_required=False)
        return [rec.rotation, rec.wrench, rec.raw, rec.time, rec.temperature]

    if what == "ROS bag":
        twins = content_twins(paths, bag_values, key=lambda p: values_sha256(bag_values(p, head=20)))
    else:
        twins = content_twins(paths, text_values, key=_rows)
    if twins:
        first, second = twins[0]
        more = f" (and {len(twins) - 1} more pairs)" if len(twins) > 1 else ""
        raise error(f"{second} holds the same {what} as {first} (the same values read from both){more}: one "
                    "recording given twice would count its poses twice and judge a model on its own rows; give "
                    "each recording once")
