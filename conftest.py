"""Test-session settings shared by the doctests in ftcal/ and the tests in tests/."""

import os

import pytest

# scikit-learn's common checks include check_array_api_input, which is *skipped* unless SciPy's array
# API support is switched on before SciPy is imported. Switch it on so the check runs and its outcome
# (an expected failure, listed with its reason in tests/test_sklearn_compat.py) shows in the report.
os.environ.setdefault("SCIPY_ARRAY_API", "1")


@pytest.fixture(autouse=True)
def _threads_left_as_found():
    """A test that leaves the process' BLAS thread count changed fails (a fit's scoped limit must be restored);
    torch's thread count, which the benchmark scripts some tests run in-process set for themselves, is restored
    after each test."""
    import torch

    from ftcal.core._threads import _controller

    def blas_threads() -> dict:  # through ftcal's cached controller: threadpool_info() scans the libraries, ~10 ms
        return {pool["filepath"]: pool["num_threads"] for pool in _controller().info() if pool["user_api"] == "blas"}

    torch_threads, blas_before = torch.get_num_threads(), blas_threads()
    try:
        yield
    finally:
        if torch.get_num_threads() != torch_threads:
            torch.set_num_threads(torch_threads)
    blas_after = {path: n for path, n in blas_threads().items() if path in blas_before}
    assert blas_after == blas_before, f"the test left the process' BLAS threads at {blas_after} (were {blas_before})"


@pytest.hookimpl(tryfirst=True)
def pytest_cmdline_main(config):
    """``-n N`` without ``--dist`` (the README's ``python -m pytest -n 2``) distributes by work stealing: xdist's
    default, ``load``, leaves a worker with the chunk it was handed while the other idles at the end (2-6 % of the
    wall time, replayed from a whole run's durations; ``benchmarks/RESULTS.md``, "Test suite time"); an idle
    worker here takes half of the other's queue. An explicit ``--dist`` is kept."""
    if getattr(config.option, "numprocesses", None) and getattr(config.option, "dist", None) == "no":
        config.option.dist = "worksteal"



def pytest_configure(config):
    """An xdist worker runs torch on one thread: ``-n 2`` on 2 cores is one worker a core (torch's default, a thread
    a core in each worker, oversubscribes them: a network test took 30-60x its time alone)."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        import torch

        torch.set_num_threads(1)
