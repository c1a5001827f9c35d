"""Test-session settings shared by the doctests in ftcal/ and the tests in tests/."""

import os
import sys

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
    """Every test and doctest runs as in the ``ftcal`` command: the process is ftcal's (joblib's executor and
    tqdm's monitor threads, alive after the first parallel test, never compute), so fits limit BLAS to one thread
    as the command's do; without this, every fit after the first parallel test ran with the process' BLAS
    threads, 2-13x slower. Tests of what a fit does beside the user's own threads are marked ``user_threads`` (or
    are in :data:`USER_THREADS_FILES`) and run without it.

    torch's thread count, which a benchmark script run in the test's process may set for itself, is restored
    after each test, so that no test sees another's."""
    import torch

    from ftcal.core._threads import whole_process_is_ftcal

    torch_threads = torch.get_num_threads()
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
