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
           "rows_within_limit"]

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
    if n_bytes > limit and settings:
        raise MemoryLimitError(f"{what} would need {format_bytes(n_bytes)}, over ftcal's memory limit of "
                               f"{format_bytes(limit)}.", fix=f"{fix} (or raise the limit with FTCAL_MEMORY_LIMIT_GB)",
                               settings=settings)
    if n_bytes > limit:
        raise MemoryLimitError(
            f"{what} would need {format_bytes(n_bytes)}, over ftcal's memory limit of {format_bytes(limit)}; "
            f"{fix} (or raise the limit with FTCAL_MEMORY_LIMIT_GB).")


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
