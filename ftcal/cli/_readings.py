"""Raw readings in, wrenches out: the text formats of ``ftcal predict``.

Input (a file or standard input)
--------------------------------
* One sample per line, values separated by commas, or by spaces when a line
  has no comma. Fields separated by tabs or ``;`` are refused with the conversion
  to commas, in the words of ``ftcal fit`` (a spreadsheet export, maybe with
  decimal commas). Blank lines and lines starting with ``#`` are skipped.
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

import io
from collections.abc import Iterator
from pathlib import Path
from typing import IO

import numpy as np
from numpy.typing import NDArray

from ..core import is_number, parse_number, read_header
from ..io import check_separator, not_utf8_error
from ._common import CliError

__all__ = ["iter_reading_chunks", "read_readings_npz", "write_wrench_rows", "takes_temperature", "located_error"]


def _split(line: str) -> list[str]:
    return [v.strip() for v in line.split(",")] if "," in line else line.split()


def _channel_columns(fields: list[str], source: str, line_no: int, n_inputs: int,
                     names: tuple[str, ...] | None = None) -> list[int]:
    """Positions of s0..s{N-1} (or of the columns ``names``: ``--channels``, or the model's mapping) in a header
    line, then of ``temperature`` when the model takes one input more than there are channels."""
    if names is not None:
        header_names = [f.strip().lstrip("\ufeff") for f in fields]
        missing = [n for n in names if n not in header_names]
        if missing:
            raise CliError(f"{source}: line {line_no}: no column {missing[0]!r} (the model reads the channels "
                           f"{','.join(names)}); the header has {', '.join(header_names)}. Fix: name the input's "
                           "channel columns with --channels")
        channels = [header_names.index(n) for n in names]
        if "temperature" in header_names and len(channels) + 1 == n_inputs:
            channels.append(header_names.index("temperature"))
        return channels
    header = read_header(fields, where=f"{source}: line {line_no}", error=CliError, allow_other=True,
                         expected="s0,...,s{N-1}[,temperature] (other columns are ignored)")
    channels = header.numbered("s")
    if "temperature" in header and len(channels) + 1 == n_inputs:
        channels.append(header.index["temperature"])
    return channels


def iter_reading_chunks(stream: IO[str], source: str, n_channels: int, chunk_size: int, *, temperature: bool = False,
                        names: tuple[str, ...] | None = None) -> Iterator[tuple[NDArray[np.float64], NDArray]]:
    """Yield the raw readings of a text stream in arrays of at most ``chunk_size`` rows, each with the line of the
    input each of its rows came from (for messages): ``(array, line_numbers)``.

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
    temperature : bool
        Whether the model's last input is the temperature [deg C] (a temperature-compensated model): the
        messages then count ``n_channels - 1`` raw channels plus the temperature.
    names : tuple of str, optional
        The channel columns of a header (``--channels``, or the model's stored mapping); default s0..s{N-1}.
        An input without a header is read column by column in the model's channel order.

    Raises
    ------
    CliError
        Naming the source and line of a value that is not a number, a row of
        the wrong width, or a NaN / inf.
    """
    # a chunk is held as Python floats (~32 bytes each) before it becomes an array: bound its memory, whatever
    # --chunk-size and the channel count (the answers do not depend on how rows are grouped)
    chunk_size = max(1, min(chunk_size, _CHUNK_BYTES // (32 * max(n_channels, 1))))
    columns: list[int] | None = None
    width: int | None = None
    rows: list[list[float]] = []
    lines: list[int] = []
    seen_data = False
    n_raw = n_channels - 1 if temperature else n_channels
    expected = f"{n_raw} raw channels and the temperature" if temperature else f"{n_raw} raw channels"
    numbered = enumerate(_bounded_lines(stream, source), start=1)
    for line_no, line in numbered:
        text = line.lstrip("\ufeff").strip() if line_no == 1 else line.strip()
        if not text or text.startswith("#"):
            continue
        if columns is None and not seen_data:  # the first line read: its separator, in fit's words
            _check_separator(text, numbered, f"{source}: line {line_no}")
        fields = _split(text)
        first_word = next((f for f in fields if f and not is_number(f)), None)
        if not seen_data and columns is None and first_word is not None and first_word[:1].isalpha():
            columns = _channel_columns(fields, source, line_no, n_channels, names)
            width = len(fields)
            continue
        seen_data = True
        if width is not None and len(fields) != width:
            raise CliError(f"{source}: line {line_no}: {len(fields)} values but the header names {width} columns")
        where = f"{source}: line {line_no}"
        picked = fields if columns is None else [fields[i] for i in columns]  # other columns are ignored, unread
        values = [parse_number(f, where, CliError) for f in picked]
        if len(values) != n_channels:
            read = ",".join(names) if names is not None else "s0,s1,..." + (",temperature" if temperature else "")
            given = f"{len(values)} values" if columns is None else f"{len(values)} channel columns ({read})"
            raise CliError(
                f"{source}: line {line_no}: {given} but the model takes {expected} per line; check the file is "
                "for this model"
            )
        if not all(np.isfinite(values)):
            raise CliError(f"{source}: line {line_no}: NaN or inf in the raw reading; repair or remove that line")
        rows.append(values)
        lines.append(line_no)
        if len(rows) >= chunk_size:
            yield np.asarray(rows, dtype=float), np.asarray(lines)
            rows, lines = [], []
    if rows:
        yield np.asarray(rows, dtype=float), np.asarray(lines)


#: Largest chunk of text readings held at once [bytes].
_CHUNK_BYTES = 256 * 2**20
#: Longest input line read [characters] (1000 channels of 25-character numbers take 26 000).
MAX_LINE_CHARS = 1 << 20


def _check_separator(text: str, rest, where: str) -> None:
    """:func:`ftcal.io.check_separator` on a first line: a header (its first data row, read from the numbered
    lines ``rest`` only when the header is refused, tells decimal commas) or a first line of data."""
    fields, header = [f.strip() for f in text.split(",")], text[:1].isalpha()
    refused = header and len(fields) == 1 and any(sep in text for sep in ";\t")
    following = ""
    if refused:  # read on only for the refusal's words
        following = next((t for t in (line.strip() for _, line in rest) if t and not t.startswith("#")), "")
    check_separator(fields, where, header=header, next_row=following, error=CliError)


def utf8_lines(stream: IO[str]) -> IO[str]:
    """A text stream reading the bytes under ``stream`` (standard input) as :func:`_bounded_lines` reads a file:
    UTF-8, undecodable bytes kept (``surrogateescape``) to be named by their byte offset, line endings as written."""
    buffer = getattr(stream, "buffer", None)  # none: a stream of text already (a test's StringIO, a closed stdin)
    return stream if buffer is None else io.TextIOWrapper(buffer, encoding="utf-8", errors="surrogateescape",
                                                          newline="")


def _not_utf8(source: str, line_no: int, line: str, offset: int) -> CliError:
    """The refusal of a line holding bytes that are not UTF-8 (``line`` decoded with ``surrogateescape``, starting at
    byte ``offset``), in the words of the library's readers: the line, the byte and the conversion."""
    import codecs

    data = line.encode("utf-8", "surrogateescape")
    what = "raw readings are a text file in UTF-8 (or a .npz with array 'raw')"
    if line_no == 1 and data[:2] in (codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE):
        return not_utf8_error(source, what, utf16=True, error=CliError)
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as exc:  # always: the surrogates stand for bytes that are not UTF-8
        return not_utf8_error(source, what, line=line_no, byte=offset + exc.start, reason=exc.reason, error=CliError)
    raise AssertionError("a line with a lone surrogate decoded as UTF-8")


def _bounded_lines(stream: IO[str], source: str) -> Iterator[str]:
    """The lines of ``stream``, refusing one longer than :data:`MAX_LINE_CHARS` (a binary file or a file without
    line breaks would otherwise be read whole into memory); bytes that are not UTF-8 (read with
    ``surrogateescape``: :func:`utf8_lines`) are named with their line and byte offset."""
    line_no, offset = 0, 0
    while True:
        line_no += 1
        line = stream.readline(MAX_LINE_CHARS + 1)
        if not line:
            return
        if not line.isascii():
            try:
                size = len(line.encode("utf-8"))
            except UnicodeEncodeError:  # an undecodable byte, kept as a lone surrogate
                raise _not_utf8(source, line_no, line, offset) from None
            offset += size - len(line)
        offset += len(line)
        if len(line) > MAX_LINE_CHARS:
            raise CliError(f"{source}: line {line_no} is longer than {MAX_LINE_CHARS} characters; raw readings are "
                           "one reading per line (is it a binary file?)")
        if "\0" in line:
            raise CliError(f"{source}: line {line_no} holds a NUL byte: a binary file, not raw readings as text")
        yield line


def read_readings_npz(path: str, n_channels: int) -> NDArray[np.float64]:
    """The array ``raw`` of a ``.npz`` file, checked for type, shape and finiteness; the library's
    :class:`ftcal.io.ArrayFile` refuses a file that is not a readable archive and reads the array bounded (its
    declared size checked against the stored bytes and the memory limit before anything is decompressed).

    ``raw`` is read as stored, one reading per row: not transposed when it has fewer rows than columns (as
    :func:`ftcal.io.read_channels` does for MATLAB's layout), since a few readings of many channels are common here.
    """
    from ..io import ArrayFile

    with ArrayFile(path, holds=("readings", ("raw",))) as archive:
        if "raw" not in archive.names():
            raise CliError(f"{path}: no array 'raw' in the .npz (it holds {sorted(archive.names())}); save the "
                           "readings with numpy.savez(path, raw=readings)")
        raw = archive.read("raw")
    if raw.dtype.kind not in "iuf":
        kind = "complex numbers" if raw.dtype.kind == "c" else f"values of type {raw.dtype}"
        raise CliError(f"{path}: array 'raw' holds {kind}; raw readings are real numbers (float or int)")
    raw = raw.astype(float)
    if raw.ndim != 2 or raw.shape[1] != n_channels:
        raise CliError(f"{path}: array 'raw' has shape {raw.shape}; the model needs (n_samples, {n_channels})")
    bad = np.argwhere(~np.isfinite(raw))
    if bad.size:
        raise CliError(f"{path}: raw row {int(bad[0, 0])} holds NaN or inf; repair or remove that row")
    return raw


def takes_temperature(model) -> bool:
    """Whether the model's last input is the temperature [deg C] (a temperature-compensated model), as its tags say."""
    from ..calibrators import calibration_tags

    return calibration_tags(model).temperature_column


def located_error(exc: Exception, source: str, lines: NDArray, args=None) -> CliError:
    """``exc`` of a model's ``predict`` on one chunk, with the offending row it carries (its ``row`` field, a row of
    the chunk) said as the input's line (or the ``.npz`` row) it came from, and the input named."""
    from ..core import FtcalError
    from ._messages import cli_error

    row = exc.row if isinstance(exc, FtcalError) else None
    unit = "row" if Path(source).suffix.lower() in (".npz", ".mat") else "line"
    if row is not None and 0 <= row < len(lines):
        reading = "the reading" if exc.parameter in (None, "X") else f"the reading's {exc.parameter}"
        return cli_error(exc, args, f"{source}: {unit} {int(lines[row])}", row=reading)
    where = f"{unit}s {int(lines[0])}-{int(lines[-1])}" if len(lines) else "no readings"
    return cli_error(exc, args, f"{source}: {where}")


def write_wrench_rows(out: IO[str], wrench: NDArray[np.float64], flags: NDArray[np.bool_] | None = None) -> None:
    """Write wrenches as CSV lines (``%.9g``), each followed by its ``out_of_range`` flag (0 or 1) when ``flags``
    are given."""
    ends = ["\n"] * len(wrench) if flags is None else [f",{int(f)}\n" for f in flags]
    out.write("".join(",".join(f"{v:.9g}" for v in row) + end for row, end in zip(wrench, ends)))
