"""The calibration dataset: raw readings paired with reference wrenches, and its file formats.

File formats
------------
CSV (``.csv``)
    One header line, then one row per sample. Columns ``s0 ... s{N-1}`` hold
    the raw channels (any unit the sensor gives: counts, mV, ...), then
    ``Fx, Fy, Fz`` in [N] and ``Tx, Ty, Tz`` in [N·m]; an optional ``group``
    column holds an integer label per row (a load configuration, a sphere,
    ...). Lines starting with ``#`` before the header are comments; a comment
    ``# meta: {...}`` carries JSON metadata.
NumPy archive (``.npz``)
    Arrays ``raw`` (n, N), ``wrench`` (n, 6), optional ``group`` (n,), and
    ``meta_json`` (a JSON string). Read with ``allow_pickle=False``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ._exceptions import DatasetFileError
from ._wrench import WRENCH_LABELS

__all__ = ["CalibrationDataset"]


@dataclass
class CalibrationDataset:
    """Raw readings and the reference wrenches they were recorded under.

    Parameters
    ----------
    raw : ndarray of shape (n_samples, n_channels)
        Raw sensor readings, one row per sample.
    wrench : ndarray of shape (n_samples, 6)
        Reference wrench ``[Fx, Fy, Fz, Tx, Ty, Tz]`` in [N] and [N·m].
    group : ndarray of shape (n_samples,), optional
        Integer label per sample (load configuration, sphere index, ...), for
        grouped splits such as ``GroupKFold``.
    meta : dict
        JSON-serialisable facts about where the data came from.

    Examples
    --------
    >>> import numpy as np
    >>> ds = CalibrationDataset(raw=np.ones((4, 6)), wrench=np.zeros((4, 6)))
    >>> ds.n_samples, ds.n_channels
    (4, 6)
    """

    raw: NDArray[np.float64]
    wrench: NDArray[np.float64]
    group: NDArray[np.int64] | None = None
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.raw = np.asarray(self.raw, dtype=float)
        self.wrench = np.asarray(self.wrench, dtype=float)
        if self.raw.ndim != 2:
            raise DatasetFileError(f"raw must be 2-D (n_samples, n_channels); got shape {self.raw.shape}.")
        if self.wrench.ndim != 2 or self.wrench.shape[1] != 6:
            raise DatasetFileError(f"wrench must have shape (n_samples, 6); got shape {self.wrench.shape}.")
        if self.raw.shape[0] != self.wrench.shape[0]:
            raise DatasetFileError(
                f"raw has {self.raw.shape[0]} rows but wrench has {self.wrench.shape[0]}; they must match."
            )
        if self.group is not None:
            self.group = np.asarray(self.group).astype(np.int64)
            if self.group.shape != (self.raw.shape[0],):
                raise DatasetFileError(
                    f"group must have shape ({self.raw.shape[0]},); got shape {self.group.shape}."
                )

    @property
    def n_samples(self) -> int:
        """Number of rows."""
        return int(self.raw.shape[0])

    @property
    def n_channels(self) -> int:
        """Number of raw channels."""
        return int(self.raw.shape[1])

    def subset(self, index: NDArray) -> "CalibrationDataset":
        """The rows selected by ``index`` (a boolean mask or integer indices), as a new dataset."""
        return CalibrationDataset(
            raw=self.raw[index],
            wrench=self.wrench[index],
            group=None if self.group is None else self.group[index],
            meta=dict(self.meta),
        )

    # ------------------------------------------------------------------ files
    def save(self, path: str | Path) -> Path:
        """Write the dataset to ``path`` (``.csv`` or ``.npz``, chosen by suffix) and return it."""
        path = Path(path)
        if path.suffix == ".npz":
            arrays = {"raw": self.raw, "wrench": self.wrench, "meta_json": np.array(json.dumps(self.meta))}
            if self.group is not None:
                arrays["group"] = self.group
            with open(path, "wb") as fh:
                np.savez(fh, **arrays)
        elif path.suffix == ".csv":
            cols = [f"s{i}" for i in range(self.n_channels)] + list(WRENCH_LABELS)
            data = np.hstack([self.raw, self.wrench])
            fmt = ["%.10g"] * data.shape[1]
            if self.group is not None:
                cols.append("group")
                data = np.hstack([data, self.group[:, None].astype(float)])
                fmt.append("%d")
            header = f"meta: {json.dumps(self.meta)}\n" + ",".join(cols)
            np.savetxt(path, data, delimiter=",", header=header, comments="", fmt=fmt)
            # np.savetxt does not prefix the meta line with '#': do it here.
            text = path.read_text()
            path.write_text("# " + text)
        else:
            raise DatasetFileError(f"{path}: unknown dataset suffix {path.suffix!r}; use .csv or .npz.")
        return path

    @classmethod
    def load(cls, path: str | Path) -> "CalibrationDataset":
        """Read a dataset written by :meth:`save` (or by hand in the CSV layout above)."""
        path = Path(path)
        if not path.is_file():
            raise DatasetFileError(f"{path}: no such dataset file.")
        if path.suffix == ".npz":
            return cls._load_npz(path)
        if path.suffix == ".csv":
            return cls._load_csv(path)
        raise DatasetFileError(f"{path}: unknown dataset suffix {path.suffix!r}; use .csv or .npz.")

    @classmethod
    def _load_npz(cls, path: Path) -> "CalibrationDataset":
        try:
            with np.load(path, allow_pickle=False) as z:
                missing = {"raw", "wrench"} - set(z.files)
                if missing:
                    raise DatasetFileError(f"{path}: missing arrays {sorted(missing)}; expected raw and wrench.")
                raw, wrench = z["raw"], z["wrench"]
                group = z["group"] if "group" in z.files else None
                meta = json.loads(str(z["meta_json"])) if "meta_json" in z.files else {}
        except DatasetFileError:
            raise
        except Exception as exc:  # zipfile/numpy errors on truncated or foreign files
            raise DatasetFileError(f"{path}: not a readable .npz dataset ({exc}).") from exc
        ds = cls(raw=raw, wrench=wrench, group=group, meta=meta)
        ds._check_finite(path)
        return ds

    @classmethod
    def _load_csv(cls, path: Path) -> "CalibrationDataset":
        meta: dict = {}
        header: list[str] | None = None
        n_comment = 0
        with open(path, encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("#"):
                    n_comment += 1
                    body = line[1:].strip()
                    if body.startswith("meta:"):
                        try:
                            meta = json.loads(body[len("meta:"):])
                        except json.JSONDecodeError as exc:
                            raise DatasetFileError(f"{path}: line {n_comment}: bad JSON in meta comment ({exc}).") from exc
                    continue
                header = [c.strip() for c in line.strip().split(",")]
                break
        if not header or header == [""]:
            raise DatasetFileError(f"{path}: no header line; expected s0,...,s{{N-1}},Fx,Fy,Fz,Tx,Ty,Tz[,group].")
        missing = [c for c in WRENCH_LABELS if c not in header]
        if missing:
            raise DatasetFileError(f"{path}: header lacks wrench columns {missing}; expected Fx,Fy,Fz,Tx,Ty,Tz.")
        chan = [c for c in header if c.startswith("s") and c[1:].isdigit()]
        if not chan:
            raise DatasetFileError(f"{path}: header has no raw channel columns s0, s1, ...")
        try:
            data = np.loadtxt(path, delimiter=",", skiprows=n_comment + 1, ndmin=2)
        except ValueError as exc:
            raise DatasetFileError(f"{path}: unreadable number ({exc}).") from exc
        if data.shape[0] == 0:
            raise DatasetFileError(f"{path}: no data rows after the header.")
        if data.shape[1] != len(header):
            raise DatasetFileError(f"{path}: rows have {data.shape[1]} values but the header names {len(header)} columns.")
        col = {c: i for i, c in enumerate(header)}
        raw = data[:, [col[c] for c in sorted(chan, key=lambda c: int(c[1:]))]]
        wrench = data[:, [col[c] for c in WRENCH_LABELS]]
        group = data[:, col["group"]].astype(np.int64) if "group" in col else None
        ds = cls(raw=raw, wrench=wrench, group=group, meta=meta)
        ds._check_finite(path, first_data_line=n_comment + 2)
        return ds

    def _check_finite(self, path: Path, first_data_line: int | None = None) -> None:
        for name, arr in (("raw", self.raw), ("wrench", self.wrench)):
            bad = np.argwhere(~np.isfinite(arr))
            if bad.size:
                row = int(bad[0, 0])
                where = f"line {row + first_data_line}" if first_data_line else f"row {row}"
                raise DatasetFileError(f"{path}: {where}: {name} holds NaN or inf; remove or repair that row.")
