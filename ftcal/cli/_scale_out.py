"""Scale-out on an existing engine: run joblib's parallel work on a Dask cluster.

The artificial benchmark (:func:`ftcal.benchmark.run_artificial_benchmark`) and the searches
(:func:`ftcal.compose.search_calibrator`, ``ftcal tune``) distribute their fits with joblib.
:func:`dask_backend` points joblib at a Dask cluster: ``"local"`` starts a
``distributed.LocalCluster`` on this machine (one single-threaded worker process
per core), any other value is the address of a running scheduler
(``tcp://host:8786``), e.g. one started on a cluster with ``dask scheduler``
and ``dask worker tcp://host:8786 --nthreads 1`` on each node (every worker
needs ftcal installed). Results come back to the calling process, which writes
every file, so the benchmark's cache and resumability are unchanged.

Dask is an optional dependency: ``pip install "dask[distributed]"``. The command line's ``--scheduler`` is
its only user, so it lives here (the library's own entry points take joblib's backend from the caller).
"""

from __future__ import annotations

import contextlib
import re
from collections.abc import Iterator

from ..core import FtcalError

__all__ = ["dask_backend", "check_scheduler", "probe_scheduler", "SchedulerError", "CONNECT_TIMEOUT_S"]

#: Seconds to wait for a remote scheduler before giving up with a clear error.
CONNECT_TIMEOUT_S = 5.0
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
        raise SchedulerError(f"{{scheduler}} {scheduler!r} is not 'local' nor a scheduler address like "
                             "tcp://host:8786.", parameter="scheduler", value=scheduler)
    return scheduler


#: Largest first message a Dask scheduler sends (its handshake: a small dict) [bytes].
_MAX_HANDSHAKE_BYTES = 1 << 20


def probe_scheduler(scheduler: str, timeout_s: float = CONNECT_TIMEOUT_S) -> None:
    """Check, within ``timeout_s``, that a Dask scheduler answers at a ``tcp://`` address; else
    :class:`SchedulerError`.

    A Dask scheduler speaks first: on a new connection it sends its handshake, an 8-byte length then a small
    message. Anything else is refused before Dask's own client sees it: nothing listening, nothing said within
    the deadline (a plain HTTP server waits for a request: Dask's client would wait for ever), or a first message
    whose length is absurd (an HTTP answer read as a length made Dask try to allocate exabytes).
    """
    import socket
    import struct
    import time

    rest = scheduler.removeprefix("tcp://")  # a tcp:// or host:port address
    host, sep, port = rest.rpartition(":")
    if "://" in rest or not sep or not port.isdigit():  # tls://, inproc://, ucx://: Dask's own timeout applies
        return
    host, port = host.strip("[]"), int(port)
    deadline = time.monotonic() + timeout_s
    hint = "is a Dask scheduler (dask scheduler) running there, and is the address right?"
    if not 0 < port < 65536:
        raise SchedulerError(f"{{scheduler}} {scheduler}: port {port} is not a TCP port (1-65535).",
                             parameter="scheduler", value=scheduler)
    try:
        sock = socket.create_connection((host, port), timeout=timeout_s)
    except socket.timeout:
        raise SchedulerError(f"cannot reach the Dask scheduler at {scheduler} within {timeout_s:g} s; {hint}") from None
    except OSError as exc:
        raise SchedulerError(f"cannot reach the Dask scheduler at {scheduler} ({exc.strerror or exc}); {hint}") from None

    def read_exactly(n: int) -> bytes:
        data = b""
        while len(data) < n:
            sock.settimeout(max(deadline - time.monotonic(), 1e-3))
            chunk = sock.recv(min(n - len(data), 65536))
            if not chunk:
                raise ConnectionResetError("the server closed the connection")
            data += chunk
        return data

    with sock:
        try:
            (n_bytes,) = struct.unpack("<Q", read_exactly(8))
            if not 0 < n_bytes <= _MAX_HANDSHAKE_BYTES:
                raise SchedulerError(f"{scheduler} answered, but not as a Dask scheduler does (its first message "
                                     f"announces {n_bytes} bytes; is it a web server or another service?); {hint}")
            read_exactly(n_bytes)
        except socket.timeout:
            raise SchedulerError(f"{scheduler} accepted the connection but sent no Dask handshake within "
                                 f"{timeout_s:g} s (a web server or another service?); {hint}") from None
        except OSError as exc:
            raise SchedulerError(f"{scheduler} closed the connection before a Dask handshake ({exc.strerror or exc}); "
                                 f"{hint}") from None


@contextlib.contextmanager
def dask_backend(scheduler: str | None, *, timeout_s: float = CONNECT_TIMEOUT_S) -> Iterator[object | None]:
    """Within the block, joblib runs its tasks on the Dask cluster ``scheduler`` (``None``: unchanged).

    Parameters
    ----------
    scheduler : str or None
        ``"local"`` for a ``LocalCluster`` on this machine (one worker per core), or a scheduler address.
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
        raise SchedulerError('{scheduler} needs Dask: pip install "dask[distributed]"', parameter="scheduler",
                             value=scheduler) from None
    cluster = None
    try:
        if scheduler == "local":
            cluster = LocalCluster(threads_per_worker=1, processes=True, dashboard_address=None)
            client = Client(cluster)
        else:
            probe_scheduler(scheduler, timeout_s)
            client = Client(scheduler, timeout=timeout_s)
    except SchedulerError:
        raise
    except Exception as exc:  # every failure of Dask's connection (OSError, TimeoutError, its own errors): one line
        if cluster is not None:
            cluster.close()
        what = "start a local Dask cluster" if scheduler == "local" else f"connect to the Dask scheduler at {scheduler}"
        raise SchedulerError(f"cannot {what} within {timeout_s:g} s ({type(exc).__name__}: "
                             f"{' '.join(str(exc).split())[:200]}); is it running, and is the address right?") from None
    try:
        with joblib.parallel_config(backend="dask"):
            yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
