"""One memory guard: estimate what a step will allocate *before* allocating it, and refuse clearly.

Every step whose memory grows with the data (kernel matrices, polynomial features, decompressed model
arrays, chunked predictions) calls :func:`check_allocation` with its estimate. The limit is
:data:`MEMORY_LIMIT_BYTES` (4 GiB), or the ``FTCAL_MEMORY_LIMIT_GB`` environment variable; it is a fixed
number, never the machine's free memory, so that a result does not depend on what else is running.
"""

from __future__ import annotations

import os

from ._exceptions import FtcalError

__all__ = ["MEMORY_LIMIT_BYTES", "MemoryLimitError", "memory_limit_bytes", "check_allocation", "format_bytes",
           "rows_within_limit", "read_npy_member"]

#: Default largest single allocation ftcal makes for one step [bytes].
MEMORY_LIMIT_BYTES: int = 4 * 2**30


class MemoryLimitError(FtcalError, ValueError):
    """A step would allocate more memory than ftcal's limit; the message names the parameter to change."""


def memory_limit_bytes() -> int:
    """The limit in force [bytes]: ``FTCAL_MEMORY_LIMIT_GB`` (GiB, > 0) if set, else 4 GiB."""
    text = os.environ.get("FTCAL_MEMORY_LIMIT_GB", "").strip()
    if not text:
        return MEMORY_LIMIT_BYTES
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value > 0 or value == float("inf"):
        raise MemoryLimitError(f"FTCAL_MEMORY_LIMIT_GB must be a positive number of GiB; got {text!r}.")
    return int(value * 2**30)


def format_bytes(n_bytes: float) -> str:
    """``n_bytes`` in the largest binary unit that keeps it >= 1, e.g. ``'7.45 GiB'``.

    Examples
    --------
    >>> format_bytes(8e9)
    '7.45 GiB'
    >>> format_bytes(512)
    '512 B'
    """
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n_bytes >= size:
            return f"{n_bytes / size:.2f} {unit}"
    return f"{n_bytes:.0f} B"


def check_allocation(n_bytes: float, what: str, fix: str, *, settings: dict | None = None) -> None:
    """Raise :class:`MemoryLimitError` if ``n_bytes`` exceeds the limit.

    Parameters
    ----------
    n_bytes : float
        Estimated size of the allocation [bytes] (a float, so that huge products do not overflow).
    what : str
        What would be allocated, e.g. ``"the GP's kernel matrix (1000000 x 1000 rows)"``.
    fix : str
        How to stay under the limit, e.g. ``"lower max_samples"``; with ``settings`` a template whose fields are the
        arguments it proposes (``"pass {max_samples}"``, :class:`~ftcal.core.FtcalError`).
    settings : dict, optional
        The argument values the fix proposes (computed to fit the limit: :func:`rows_within_limit`).

    Examples
    --------
    >>> check_allocation(1e3, "a small array", "nothing")
    >>> check_allocation(1e13, "the kernel matrix", "lower max_samples")
    Traceback (most recent call last):
    ...
    ftcal.core._memory.MemoryLimitError: the kernel matrix would need 9.09 TiB, over ftcal's memory limit of 4.00 GiB; lower max_samples (or raise the limit with FTCAL_MEMORY_LIMIT_GB).
    """
    limit = memory_limit_bytes()
    if n_bytes <= limit:
        return
    need = f"{what} would need {format_bytes(n_bytes)}, over ftcal's memory limit of {format_bytes(limit)}"
    fix = f"{fix} (or raise the limit with FTCAL_MEMORY_LIMIT_GB)"
    if settings:
        raise MemoryLimitError(f"{need}.", fix=fix, settings=settings)
    raise MemoryLimitError(f"{need}; {fix}.")


def rows_within_limit(bytes_per_row_pair: float) -> int:
    """The most rows ``m`` whose ``m x m`` allocation of ``bytes_per_row_pair`` bytes per pair stays within the limit
    (a kernel matrix and what goes with it): the value a fix proposes, checked before it is given.

    Examples
    --------
    >>> import os
    >>> os.environ["FTCAL_MEMORY_LIMIT_GB"] = "1"
    >>> m = rows_within_limit(8.0 * 13)
    >>> m, 8.0 * 13 * m * m <= 2**30 < 8.0 * 13 * (m + 1) ** 2
    (3213, True)
    >>> del os.environ["FTCAL_MEMORY_LIMIT_GB"]
    """
    limit = memory_limit_bytes()
    m = int((limit / bytes_per_row_pair) ** 0.5)
    while m > 0 and bytes_per_row_pair * m * m > limit:
        m -= 1
    while bytes_per_row_pair * (m + 1) ** 2 <= limit:
        m += 1
    return m


def _read_npy_header_3_0(fh, max_header_size: int = 10000):
    """The ``(shape, fortran_order, dtype)`` of a ``.npy`` header of format 3.0 (numpy writes it when a field name
    is not Latin-1): format 2.0's layout, a 4-byte length then a Python dict literal, in UTF-8. Read as numpy reads
    it, with numpy's header-size bound; raises :class:`ValueError` on a damaged header.

    Examples
    --------
    >>> import io, numpy as np
    >>> buffer = io.BytesIO()
    >>> np.lib.format.write_array(buffer, np.zeros(2, dtype=[("\u00b5N", "<f8")]), version=(3, 0))
    >>> _ = buffer.seek(0)
    >>> np.lib.format.read_magic(buffer)
    (3, 0)
    >>> _read_npy_header_3_0(buffer)
    ((2,), False, dtype([('µN', '<f8')]))
    """
    import ast
    import struct

    import numpy as np

    length = fh.read(4)
    if len(length) != 4:
        raise EOFError("the array header length is cut short")
    n = struct.unpack("<I", length)[0]
    if n > max_header_size:
        raise ValueError(f"header of {n} bytes, larger than numpy reads safely ({max_header_size})")
    raw = fh.read(n)
    if len(raw) != n:
        raise EOFError(f"the array header is cut short ({len(raw)} of {n} bytes)")
    header = ast.literal_eval(raw.decode("utf-8"))
    if not isinstance(header, dict) or header.keys() != {"descr", "fortran_order", "shape"}:
        raise ValueError("the header is not a dictionary of descr, fortran_order and shape")
    shape, fortran = header["shape"], header["fortran_order"]  # the shape is checked by the caller, as numpy's
    if not isinstance(fortran, bool):
        raise ValueError(f"fortran_order is not a valid bool: {fortran!r}")
    try:
        return shape, fortran, np.lib.format.descr_to_dtype(header["descr"])
    except TypeError as exc:
        raise ValueError(f"descr is not a valid dtype descriptor: {header['descr']!r}") from exc


def read_npy_member(archive, member: str, what: str, error: type[Exception], fix: str, memory_fix: str, *,
                    max_empty_dim: float = float("inf")):
    """The array of the ``.npy`` member ``member`` of the zip ``archive`` (an ``.npz``; ``what`` names it in the
    errors, raised as ``error`` ending with ``fix``), bounded: its declared shape and size are checked against the
    member's stored size and the memory limit (``memory_fix`` says how to stay within) *before* anything is
    decompressed, at most the declared bytes are read, and an object (pickle) array is refused unread; a dimension
    longer than both the values the array holds and ``max_empty_dim`` (a shape ``(1e10, 0)``) is refused too.
    Returns an owned, writable array."""
    import tokenize
    import zipfile
    import zlib

    import numpy as np

    info = archive.getinfo(member)
    headers = {(1, 0): np.lib.format.read_array_header_1_0, (2, 0): np.lib.format.read_array_header_2_0,
               (3, 0): _read_npy_header_3_0}
    try:
        with archive.open(info) as fh:
            version = np.lib.format.read_magic(fh)
            if version not in headers:
                raise ValueError(f"unsupported .npy version {version}")
            shape, fortran, dtype = headers[version](fh)
            if not isinstance(shape, tuple) or not all(type(d) is int and d >= 0 for d in shape):
                raise ValueError(f"shape is not valid: {shape!r}")  # negative or bool dimensions: numpy lets them by
            if dtype.hasobject:
                raise error(f"{what} holds Python objects (a pickle), which ftcal never loads. Fix: {fix}.")
            n_bytes = float(np.prod([float(d) for d in shape])) * dtype.itemsize
            n_items = n_bytes / max(dtype.itemsize, 1)
            if any(d > max(n_items, max_empty_dim) for d in shape):  # (1e10, 0): no bytes, an absurd length
                raise error(f"{what} declares shape {shape}, a dimension longer than the {int(n_items)} values it "
                            f"holds; the file is damaged. Fix: {fix}.")
            if n_bytes > info.file_size:  # checked before any allocation
                raise error(f"{what} declares shape {shape} ({format_bytes(n_bytes)}) but holds only "
                            f"{format_bytes(info.file_size)}; the file is damaged. Fix: {fix}.")
            check_allocation(n_bytes, f"{what} of shape {shape} ({dtype})", memory_fix)
            data = fh.read(int(n_bytes))
    except (error, MemoryLimitError):
        raise
    except (OSError, ValueError, TypeError, EOFError, SyntaxError, tokenize.TokenError, zipfile.BadZipFile,
            zlib.error) as exc:  # a damaged header fails in numpy's parser its own ways
        raise error(f"{what} is not a readable numpy array ({' '.join(str(exc).split())[:120]}); the file is "
                    f"truncated or damaged. Fix: {fix}.") from None
    if len(data) != int(n_bytes):
        raise error(f"{what} is truncated ({len(data)} of {int(n_bytes)} bytes). Fix: {fix}.")
    array = np.frombuffer(data, dtype=dtype)
    return np.array(array.reshape(shape[::-1]).T if fortran else array.reshape(shape))
