"""Thread limits of a fit that never reach another thread of the user's program.

ftcal's fits are many small matrix problems: on a busy machine a threaded BLAS makes them several times slower
(``benchmarks/thread_limits.py``: a degree-2 polynomial fit of 5000 rows 20x, the LTM 4x), so a fit runs its BLAS
single-threaded, and the networks run torch on ``n_threads``. But OpenBLAS keeps **one** thread count per
process (its ``openblas_set_num_threads_local`` too, measured on the OpenBLAS 0.3.31 numpy ships): a
``threadpool_limits`` inside ``fit`` would slow every other thread of the program while the fit runs. So
:func:`limit_threads_here`

* limits OpenMP (torch's intra-op pool) for the calling thread alone: OpenMP keeps a count per thread;
* limits BLAS only when the calling thread is the process' only Python thread (a script, a worker process of
  ``joblib``), where no other thread can see it, or when the whole process is ftcal's own program
  (:func:`whole_process_is_ftcal`: the ``ftcal`` command, whose other threads, a progress timer and joblib's
  executor, never compute); otherwise, with threads of the user's alive (a notebook's), it leaves BLAS as it is
  (wrap the fit in :func:`threadpoolctl.threadpool_limits` to choose yourself).

Leaving BLAS threaded costs much: the same fits took 2-13x longer with a second, idle thread alive (the ``ftcal``
command's progress timer did that to every fit it showed), which is why the command claims its process.

The loaded libraries come from one cached :class:`threadpoolctl.ThreadpoolController` (building one scans the
process' libraries, ~1 ms; limiting through a cached one takes ~20 µs), rebuilt when modules were imported since.
"""

from __future__ import annotations

import contextlib
import sys
import threading

__all__ = ["limit_threads_here", "whole_process_is_ftcal"]

_lock = threading.Lock()
_cache: dict = {"modules": -1, "controller": None}
_claims = [0]  # open whole_process_is_ftcal blocks


@contextlib.contextmanager
def whole_process_is_ftcal():
    """Within this block the process is ftcal's own program: no thread but the fitting one computes, so fits
    limit BLAS (one count per process) whatever other threads are alive.

    For the ``ftcal`` command (its progress timer and joblib's executor threads never call BLAS) and for a test
    session; never for a library call, where the other threads may be the user's.

    Examples
    --------
    >>> import threading
    >>> import numpy as np
    >>> from threadpoolctl import threadpool_info
    >>> done = threading.Event()
    >>> other = threading.Thread(target=done.wait); other.start()
    >>> with whole_process_is_ftcal(), limit_threads_here(1):  # another thread is alive, but it is ftcal's
    ...     {pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"} == {1}
    True
    >>> done.set(); other.join()
    """
    with _lock:
        _claims[0] += 1
    try:
        yield
    finally:
        with _lock:
            _claims[0] -= 1


def _controller():
    """The cached :class:`threadpoolctl.ThreadpoolController`, rebuilt when modules were imported since."""
    with _lock:
        if _cache["modules"] != len(sys.modules):
            from threadpoolctl import ThreadpoolController

            _cache.update(controller=ThreadpoolController(), modules=len(sys.modules))
        return _cache["controller"]


@contextlib.contextmanager
def limit_threads_here(n_threads: int | None, *, openmp: bool = False):
    """Limit the threads the calling thread's numerical work uses to ``n_threads``, never another thread's.

    BLAS is limited only while the calling thread is the process' only Python thread (checked on entry) or
    within :func:`whole_process_is_ftcal`;
    with ``openmp``, OpenMP (torch's threads) is limited for the calling thread, whatever else runs. ``None``
    changes nothing. Everything is restored on exit.

    Examples
    --------
    >>> import threading
    >>> import numpy as np
    >>> from threadpoolctl import threadpool_info
    >>> def blas_threads():
    ...     return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]
    >>> before = blas_threads()
    >>> done = threading.Event()
    >>> other = threading.Thread(target=done.wait); other.start()  # alive until the check is over
    >>> with limit_threads_here(1):  # another thread is alive: BLAS is left alone
    ...     blas_threads() == before
    True
    >>> done.set(); other.join()
    """
    if n_threads is None:
        yield
        return
    controller = _controller()
    with contextlib.ExitStack() as stack:
        if threading.active_count() == 1 or _claims[0]:  # no other thread computes to see the process' BLAS count
            stack.enter_context(controller.select(user_api="blas").limit(limits=int(n_threads)))
        if openmp:
            stack.enter_context(controller.select(user_api="openmp").limit(limits=int(n_threads)))
        yield
