"""One scoped thread limit around ftcal's own small-matrix work, as scikit-learn's ``KMeans`` does.

ftcal's fits are many small matrix problems (least squares of a few dozen columns, a GP's Cholesky factors of a
few hundred rows, repeated by the optimiser): a threaded BLAS gains nothing on them and, on a busy machine, its
threads wait for each other (``benchmarks/thread_limits.py``: 5-17x slower). So :func:`limit_threads_here` runs
the block with BLAS on ``n_threads`` (one), unconditionally, and restores the count on exit; it never looks at
other threads. The fits enter it (``BaseCalibrator.fit``), and so do auto's and the report's fold loops.

What it costs the rest of a program: OpenBLAS keeps **one** thread count per process, so while a fit runs, BLAS
calls of the program's other threads also run on one thread (scikit-learn's ``KMeans.fit`` does the same). The
count is back when the last fit leaves (fits that overlap in time share the limit: the first sets it, the last
restores it). With ``openmp`` (the networks' ``n_threads``), torch's OpenMP threads are limited for the calling
thread alone (OpenMP keeps a count per thread).

A program's own policy is set once, outside ftcal: the ``ftcal`` command runs its whole process with one BLAS
thread (:func:`ftcal.cli.main`); a script wraps its work in :func:`threadpoolctl.threadpool_limits`.

The loaded libraries come from one cached :class:`threadpoolctl.ThreadpoolController` (building one scans the
process' libraries, ~1 ms; limiting through a cached one takes ~20 µs), rebuilt when modules were imported since.
"""

from __future__ import annotations

import contextlib
import sys
import threading
from collections.abc import Iterator

__all__ = ["limit_threads_here"]

_lock = threading.Lock()
_cache: dict = {"modules": -1, "controller": None}
_blas = {"users": 0, "limiter": None}  # blocks inside the shared BLAS limit, and the limit to restore after the last


def _controller():
    """The cached :class:`threadpoolctl.ThreadpoolController`, rebuilt when modules were imported since."""
    with _lock:
        if _cache["modules"] != len(sys.modules):
            from threadpoolctl import ThreadpoolController

            _cache.update(controller=ThreadpoolController(), modules=len(sys.modules))
        return _cache["controller"]


@contextlib.contextmanager
def _shared_blas_limit(controller, n_threads: int) -> Iterator[None]:
    """The process' BLAS at ``n_threads`` while any block is inside: the first entrant sets the limit, the last
    leaver restores what was there before the first (blocks that overlap in time never restore out of order)."""
    with _lock:
        if _blas["users"] == 0:
            _blas["limiter"] = controller.select(user_api="blas").limit(limits=int(n_threads))
        _blas["users"] += 1
    try:
        yield
    finally:
        with _lock:
            _blas["users"] -= 1
            if _blas["users"] == 0:
                _blas["limiter"].restore_original_limits()
                _blas["limiter"] = None


@contextlib.contextmanager
def limit_threads_here(n_threads: int | None, *, openmp: bool = False) -> Iterator[None]:
    """Run the block with BLAS on ``n_threads`` threads (the process' count, restored on exit), unconditionally.

    For ftcal's own small-matrix loops (a fit, a fold loop): see the module's docstring for what it costs the
    program's other threads while the block runs. Blocks that overlap (nested, or in several threads) share one
    limit, the first entrant's count. With ``openmp``, OpenMP (torch's intra-op threads) is limited for the calling
    thread alone. ``None`` changes nothing.

    Parameters
    ----------
    n_threads : int or None
        Threads for BLAS (and OpenMP with ``openmp``) inside the block; ``None``: no limit.
    openmp : bool, default=False
        Also limit OpenMP in the calling thread.

    Yields
    ------
    None

    Examples
    --------
    >>> from threadpoolctl import threadpool_info, threadpool_limits
    >>> def blas_threads():
    ...     return {pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"}
    >>> with threadpool_limits(2, user_api="blas"):
    ...     with limit_threads_here(1):
    ...         inside = blas_threads()
    ...     inside, blas_threads()
    ({1}, {2})
    """
    if n_threads is None:
        yield
        return
    controller = _controller()
    with contextlib.ExitStack() as stack:
        stack.enter_context(_shared_blas_limit(controller, int(n_threads)))
        if openmp:
            stack.enter_context(controller.select(user_api="openmp").limit(limits=int(n_threads)))
        yield
