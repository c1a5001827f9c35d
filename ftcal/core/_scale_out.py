"""Scale-out on an existing engine: run joblib's parallel work on a Dask cluster (issue 13).

The artificial benchmark (:func:`ftcal.run_artificial_benchmark`) and the searches
(:func:`ftcal.search_calibrator`, ``ftcal tune``) distribute their fits with joblib.
:func:`dask_backend` points joblib at a Dask cluster: ``"local"`` starts a
``distributed.LocalCluster`` on this machine (one single-threaded worker process
per core), any other value is the address of a running scheduler
(``tcp://host:8786``), e.g. one started on a cluster with ``dask scheduler``
and ``dask worker tcp://host:8786 --nthreads 1`` on each node (every worker
needs ftcal installed). Results come back to the calling process, which writes
every file, so the benchmark's cache and resumability are unchanged.

Dask is an optional dependency: ``pip install "dask[distributed]"``.
"""

from __future__ import annotations

import contextlib
import re
from collections.abc import Iterator

from ._exceptions import FtcalError

__all__ = ["dask_backend", "check_scheduler", "SchedulerError", "CONNECT_TIMEOUT_S"]

#: Seconds to wait for a remote scheduler before giving up with a clear error.
CONNECT_TIMEOUT_S = 10.0
_ADDRESS = re.compile(r"(tcp|tls|inproc|ucx)://[^\s/]+(:\d+)?|[A-Za-z0-9_.\-]+:\d+")


class SchedulerError(FtcalError, ValueError):
    """A Dask scheduler that cannot be used: a malformed address, unreachable, or Dask not installed."""


def check_scheduler(scheduler: str) -> str:
    """``scheduler`` if it is ``"local"`` or looks like a scheduler address, else :class:`SchedulerError`.

    Examples
    --------
    >>> check_scheduler("tcp://10.0.0.5:8786"), check_scheduler("local")
    ('tcp://10.0.0.5:8786', 'local')
    """
    if scheduler != "local" and not _ADDRESS.fullmatch(scheduler):
        raise SchedulerError(f"--scheduler {scheduler!r} is not 'local' nor a scheduler address like tcp://host:8786.")
    return scheduler


@contextlib.contextmanager
def dask_backend(scheduler: str | None, *, n_workers: int | None = None,
                 timeout_s: float = CONNECT_TIMEOUT_S) -> Iterator[object | None]:
    """Within the block, joblib runs its tasks on the Dask cluster ``scheduler`` (``None``: unchanged).

    Parameters
    ----------
    scheduler : str or None
        ``"local"`` for a ``LocalCluster`` on this machine, or a scheduler address.
    n_workers : int or None
        Workers of the local cluster (default: one per core).
    timeout_s : float
        How long to try to reach a remote scheduler [s].

    Yields
    ------
    distributed.Client or None

    Raises
    ------
    SchedulerError
        Dask missing, an address that is not one, or a scheduler not reached within ``timeout_s``.
    """
    if scheduler is None:
        yield None
        return
    check_scheduler(scheduler)
    try:
        import joblib
        from distributed import Client, LocalCluster
    except ImportError:
        raise SchedulerError('--scheduler needs Dask: pip install "dask[distributed]"') from None
    cluster = None
    try:
        if scheduler == "local":
            cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
        else:
            client = Client(scheduler, timeout=timeout_s)
    except (OSError, TimeoutError) as exc:
        if cluster is not None:
            cluster.close()
        raise SchedulerError(
            f"cannot reach the Dask scheduler at {scheduler} within {timeout_s:g} s ({type(exc).__name__}); "
            "is it running, and is the address right?"
        ) from None
    try:
        with joblib.parallel_config(backend="dask"):
            yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
