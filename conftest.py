"""Test-session settings shared by the doctests in ftcal/ and the tests in tests/."""

import os

import pytest

# scikit-learn's common checks include check_array_api_input, which is *skipped* unless SciPy's array
# API support is switched on before SciPy is imported. Switch it on so the check runs and its outcome
# (an expected failure, listed with its reason in tests/test_sklearn_compat.py) shows in the report.
os.environ.setdefault("SCIPY_ARRAY_API", "1")


#: Test files whose tests or doctests look at what a fit does beside threads of the user's (besides tests marked
#: ``user_threads``): the process is not claimed for ftcal there.
USER_THREADS_FILES = {"ftcal/core/_threads.py"}


@pytest.fixture(autouse=True)
def _the_test_process_is_ftcal_s(request):
    """Every test and doctest runs with the process declared ftcal's: the test runner's own threads (execnet's,
    under ``pytest -n``) never compute, but ftcal cannot know them idle, so without this every fit would run with
    the process' BLAS threads, several times slower. Tests of what a fit does beside the user's own threads are
    marked ``user_threads`` (or are in :data:`USER_THREADS_FILES`) and run without it.

    A test that leaves the process' BLAS thread count changed fails (a fit must restore it); torch's thread count,
    which the benchmark scripts some tests run in-process set for themselves, is restored after each test."""
    import torch

    from ftcal.core._threads import _controller, whole_process_is_ftcal

    def blas_threads() -> dict:  # through ftcal's cached controller: threadpool_info() scans the libraries, ~10 ms
        return {pool["filepath"]: pool["num_threads"] for pool in _controller().info() if pool["user_api"] == "blas"}

    torch_threads, blas_before = torch.get_num_threads(), blas_threads()
    users = (request.node.get_closest_marker("user_threads") is not None
             or request.node.nodeid.split("::")[0] in USER_THREADS_FILES)
    try:
        if users:
            yield
        else:
            with whole_process_is_ftcal():
                yield
    finally:
        if torch.get_num_threads() != torch_threads:
            torch.set_num_threads(torch_threads)
    blas_after = {path: n for path, n in blas_threads().items() if path in blas_before}
    assert blas_after == blas_before, f"the test left the process' BLAS threads at {blas_after} (were {blas_before})"
