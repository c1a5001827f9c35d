"""Raw readings in, wrenches out: the text formats of ``ftcal predict``.

Input (a file or standard input)
--------------------------------
* One sample per line, values separated by commas, or by spaces / tabs when a
  line has no comma. Blank lines and lines starting with ``#`` are skipped.
* An optional header line (any line holding a non-number). When present, the
  columns named ``s0, s1, ...`` are the raw channels (then ``temperature`` [deg C]
  if present, for temperature-compensated models) and every other column is
  ignored, so a dataset CSV written by ``ftcal simulate`` / ``prepare`` can be
  fed as is. Without a header every column is a raw channel.
* A ``.npz`` file holding an array ``raw`` of shape (n, N) is read too.

Output
------
CSV: a header ``Fx,Fy,Fz,Tx,Ty,Tz`` (unless ``--no-header``), then one line per
input sample in the same order: forces in [N], torques in [N·m].
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import IO

import numpy as np
from numpy.typing import NDArray

from ..core._wrench import WRENCH_LABELS
from ..core._columns import is_number, parse_number, read_header
from ._common import CliError

__all__ = ["iter_reading_chunks", "read_readings_npz", "write_wrench_rows"]


def _split(line: str) -> list[str]:
    return [v.strip() for v in line.split(",")] if "," in line else line.split()


def _channel_columns(fields: list[str], source: str, line_no: int, n_inputs: int) -> list[int]:
    """Positions of s0..s{N-1} in a header line (the shared header rules of :mod:`ftcal.core._columns`), then of
    ``temperature`` when the model takes one input more than there are channels."""
    header = read_header(fields, where=f"{source}: line {line_no}", error=CliError, allow_other=True,
                         expected="s0,...,s{N-1}[,temperature] (other columns are ignored)")
    channels = header.numbered("s")
    if "temperature" in header and len(channels) + 1 == n_inputs:
        channels.append(header.index["temperature"])
    return channels


def iter_reading_chunks(
    stream: IO[str], source: str, n_channels: int, chunk_size: int
) -> Iterator[NDArray[np.float64]]:
    """Yield the raw readings of a text stream in arrays of at most ``chunk_size`` rows.

    Parameters
    ----------
    stream : text file
        The open input (a file or ``sys.stdin``).
    source : str
        Its name in error messages (``"stdin"`` or the path).
    n_channels : int
        The channel count the model expects; a row with another count is an error.
    chunk_size : int
        Rows per yielded array; 1 gives one answer per input line (live streams).

    Raises
    ------
    CliError
        Naming the source and line of a value that is not a number, a row of
        the wrong width, or a NaN / inf.
    """
    columns: list[int] | None = None
    width: int | None = None
    rows: list[list[float]] = []
    seen_data = False
    for line_no, line in enumerate(stream, start=1):
        text = line.lstrip("\ufeff").strip() if line_no == 1 else line.strip()
        if not text or text.startswith("#"):
            continue
        fields = _split(text)
        first_word = next((f for f in fields if not is_number(f)), None)
        if not seen_data and columns is None and first_word is not None and first_word[:1].isalpha():
            columns = _channel_columns(fields, source, line_no, n_channels)
            width = len(fields)
            continue
        seen_data = True
        if width is not None and len(fields) != width:
            raise CliError(f"{source}: line {line_no}: {len(fields)} values but the header names {width} columns")
        where = f"{source}: line {line_no}"
        values = [parse_number(f, where, CliError) for f in fields]
        if columns is not None:
            values = [values[i] for i in columns]
        if len(values) != n_channels:
            raise CliError(
                f"{source}: line {line_no}: {len(values)} raw channels but the model was fitted on {n_channels}"
            )
        if not all(np.isfinite(values)):
            raise CliError(f"{source}: line {line_no}: NaN or inf in the raw reading; repair or remove that line")
        rows.append(values)
        if len(rows) >= chunk_size:
            yield np.asarray(rows, dtype=float)
            rows = []
    if rows:
        yield np.asarray(rows, dtype=float)


def read_readings_npz(path: str, n_channels: int) -> NDArray[np.float64]:
    """The array ``raw`` of a ``.npz`` file, checked for shape and finiteness."""
    try:
        with np.load(path, allow_pickle=False) as z:
            if "raw" not in z.files:
                raise CliError(f"{path}: no array 'raw' in the .npz (it holds {sorted(z.files)})")
            raw = np.asarray(z["raw"], dtype=float)
    except CliError:
        raise
    except (OSError, ValueError) as exc:
        raise CliError(f"{path}: not a readable .npz file ({exc})") from exc
    if raw.ndim != 2 or raw.shape[1] != n_channels:
        raise CliError(f"{path}: array 'raw' has shape {raw.shape}; the model needs (n_samples, {n_channels})")
    bad = np.argwhere(~np.isfinite(raw))
    if bad.size:
        raise CliError(f"{path}: raw row {int(bad[0, 0])} holds NaN or inf; repair or remove that row")
    return raw


def write_wrench_rows(out: IO[str], wrench: NDArray[np.float64], header: bool) -> None:
    """Write wrenches as CSV lines (``%.9g``), with the ``Fx,...,Tz`` header when asked."""
    if header:
        out.write(",".join(WRENCH_LABELS) + "\n")
    out.write("".join(",".join(f"{v:.9g}" for v in row) + "\n" for row in wrench))
