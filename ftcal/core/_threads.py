"""Thread limits of a fit that never reach another thread of the user's program.

ftcal's fits are many small matrix problems: with a threaded BLAS they run several times slower
(``benchmarks/thread_limits.py``: 4.8-17x on a busy 2-core machine), so a fit runs its BLAS single-threaded, and
the networks run torch on ``n_threads``. But OpenBLAS keeps **one** thread count per process (its
``openblas_set_num_threads_local`` too, measured on the OpenBLAS 0.3.31 numpy ships): a ``threadpool_limits``
inside ``fit`` would slow every other thread of the program while the fit runs. So :func:`limit_threads_here`

* limits OpenMP (torch's intra-op pool) for the calling thread alone: OpenMP keeps a count per thread;
* limits BLAS only when no other live thread computes: every other thread is one known to only wait (joblib's
  executor manager and queue feeder threads, which stay alive after any process pool, tqdm's monitor, ftcal's own
  progress timer: :func:`is_idle_thread`), or the whole process is declared ftcal's (:func:`whole_process_is_ftcal`,
  for a test session whose harness threads never compute); otherwise, beside threads of the user's (a
  notebook's), it leaves BLAS as it is (wrap the fit in :func:`threadpoolctl.threadpool_limits` to choose
  yourself). The limit is shared by the fits that run at once: the first sets it, the last restores it.

The loaded libraries come from one cached :class:`threadpoolctl.ThreadpoolController` (building one scans the
process' libraries, ~1 ms; limiting through a cached one takes ~20 µs), rebuilt when modules were imported since.
"""

from __future__ import annotations

import contextlib
import sys
import threading
from collections.abc import Iterator

__all__ = ["limit_threads_here", "whole_process_is_ftcal", "is_idle_thread", "IDLE_THREAD_PREFIX"]

_lock = threading.Lock()
_cache: dict = {"modules": -1, "controller": None}
_claims = [0]  # open whole_process_is_ftcal blocks
_blas = {"users": 0, "limiter": None}  # fits inside the shared BLAS limit, and the limit to restore after the last

#: Name prefix of ftcal's own threads that never compute (a progress timer): :func:`is_idle_thread`.
IDLE_THREAD_PREFIX = "ftcal-idle-"
#: Threads of other packages known to only wait, by ``(class module, class name)``; and by thread name, the
#: feeder thread of every :class:`multiprocessing.Queue` (a plain ``Thread``).
_IDLE_CLASSES = {("joblib.externals.loky.process_executor", "_ExecutorManagerThread"), ("tqdm._monitor", "TMonitor")}
_IDLE_NAMES = {"QueueFeederThread"}


def is_idle_thread(thread: threading.Thread) -> bool:
    """Whether ``thread`` is one known never to compute: ftcal's own (named with :data:`IDLE_THREAD_PREFIX`),
    joblib's process-pool manager and queue feeders, tqdm's monitor.

    Examples
    --------
    >>> import threading
    >>> done = threading.Event()
    >>> timer = threading.Thread(target=done.wait, name=IDLE_THREAD_PREFIX + "progress")
    >>> is_idle_thread(timer), is_idle_thread(threading.Thread(target=done.wait))
    (True, False)
    """
    kind = type(thread)
    return (thread.name.startswith(IDLE_THREAD_PREFIX) or thread.name in _IDLE_NAMES
            or (kind.__module__, kind.__name__) in _IDLE_CLASSES)


def _no_other_thread_computes() -> bool:
    """Whether every live thread but the calling one is idle (:func:`is_idle_thread`) or the process is ftcal's."""
    if _claims[0] or threading.active_count() == 1:
        return True
    me = threading.current_thread()
    return all(t is me or is_idle_thread(t) for t in threading.enumerate())


@contextlib.contextmanager
def whole_process_is_ftcal() -> Iterator[None]:
    """Declare the process ftcal's for the block: no thread computes beside its fits, whatever threads are alive.

    For a test session (its harness' threads, execnet's, never call BLAS); never for a library call or the
    command, where other threads may be the user's (those ftcal knows idle need no claim: :func:`is_idle_thread`).

    Yields
    ------
    None
        Within the block, fits limit BLAS (one count per process) to one thread.

    Examples
    --------
    >>> import threading
    >>> from threadpoolctl import threadpool_info, threadpool_limits
    >>> done = threading.Event()
    >>> other = threading.Thread(target=done.wait); other.start()
    >>> with threadpool_limits(2, user_api="blas"), whole_process_is_ftcal(), limit_threads_here(1):
    ...     {pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"}
    {1}
    >>> done.set(); other.join()
    """
    with _lock:
        _claims[0] += 1
    try:
        yield
    finally:
        with _lock:
            _claims[0] -= 1


@contextlib.contextmanager
def _shared_blas_limit(controller, n_threads: int) -> Iterator[None]:
    """The process' BLAS at ``n_threads`` while any fit is inside: the first entrant sets the limit, the last
    leaver restores what was there before the first (fits that overlap in time never restore out of order)."""
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


def _controller():
    """The cached :class:`threadpoolctl.ThreadpoolController`, rebuilt when modules were imported since."""
    with _lock:
        if _cache["modules"] != len(sys.modules):
            from threadpoolctl import ThreadpoolController

            _cache.update(controller=ThreadpoolController(), modules=len(sys.modules))
        return _cache["controller"]


@contextlib.contextmanager
def limit_threads_here(n_threads: int | None, *, openmp: bool = False) -> Iterator[None]:
    """Limit the threads the calling thread's numerical work uses to ``n_threads``, never another thread's.

    BLAS is limited only when no other live thread computes (checked on entry: every other thread is idle,
    :func:`is_idle_thread`, or the process is claimed, :func:`whole_process_is_ftcal`); fits that overlap share
    the limit (the first entrant's count). With ``openmp``, OpenMP (torch's threads) is limited for the calling
    thread, whatever else runs. ``None`` changes nothing. Everything is restored on exit.

    Examples
    --------
    >>> import threading
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
        if _no_other_thread_computes():  # none that computes can see the process' BLAS count
            stack.enter_context(_shared_blas_limit(controller, int(n_threads)))
        if openmp:
            stack.enter_context(controller.select(user_api="openmp").limit(limits=int(n_threads)))
        yield
