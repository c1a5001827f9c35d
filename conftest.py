"""Test-session settings shared by the doctests in ftcal/ and the tests in tests/."""

import os

# scikit-learn's common checks include check_array_api_input, which is *skipped* unless SciPy's array
# API support is switched on before SciPy is imported. Switch it on so the check runs and its outcome
# (an expected failure, listed with its reason in tests/test_sklearn_compat.py) shows in the report.
os.environ.setdefault("SCIPY_ARRAY_API", "1")
