"""The per-fit caches of the thesis' benchmarks (and of the scripts in ``benchmarks/``): a cached result is a
JSON record read back only when it is what a program wrote for that purpose (:func:`read_json_record`),
holding a fingerprint of its data (:func:`data_fingerprint`) and the package versions it was fitted with
(:func:`package_versions`).

Layer: :mod:`ftcal.benchmark` (only the benchmarks keep such caches). Imports only :mod:`ftcal.core`.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from ..core._files import is_finite_number

__all__ = ["read_json_record", "data_fingerprint", "package_versions", "RECORDED_PACKAGES"]


def read_json_record(path: str | os.PathLike, *, numbers: tuple[str, ...] = (), **expected) -> dict | None:
    """A JSON object read from ``path``, or None when it is not one a program wrote for this purpose.

    None when the file is missing or unreadable (not UTF-8, not JSON, nested beyond the parser's limit), is
    not a JSON object, has a key of ``expected`` with another value, or has a key of ``numbers`` that is not
    a finite number >= 0 (they are errors, floors and counts). The per-fit caches of the benchmarks read their
    files this way: None means "fit again".

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "fit.json"
    >>> _ = path.write_text('{"model": "linear", "rmse": 4.6}')
    >>> read_json_record(path, numbers=("rmse",), model="linear")
    {'model': 'linear', 'rmse': 4.6}
    >>> read_json_record(path, model="directional") is None
    True
    """
    try:
        record = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return None
    if not isinstance(record, dict) or any(record.get(k) != v for k, v in expected.items()):
        return None
    return record if all(is_finite_number(record.get(k)) and record[k] >= 0 for k in numbers) else None


def data_fingerprint(*arrays) -> str:
    """A short SHA-256 of the values of ``arrays``: the data a cached result was computed on.

    Each array counts by its shape and its values as float64 (real numbers: booleans, integers up to 2**53,
    floats; NaN counts as a value). A benchmark's per-fit cache keyed by its configuration alone keeps a result
    when the code that makes the data changes (a simulator, a robot model, a package's version); a fingerprint
    of the arrays stored in the result and compared on reading makes such a result a miss, so it is fitted again.

    Raises
    ------
    CalibrationInputError
        An argument that is not an array of real numbers (complex, text, objects, a masked array).

    Examples
    --------
    >>> import numpy as np
    >>> a = np.arange(6.0).reshape(2, 3)
    >>> data_fingerprint(a) == data_fingerprint(a.copy()), data_fingerprint(a) == data_fingerprint(a.T)
    (True, False)
    >>> data_fingerprint(a) == data_fingerprint(a + 1e-12), data_fingerprint(1.0) == data_fingerprint([1.0])
    (False, False)
    """
    import hashlib

    import numpy as np

    from ..core._exceptions import CalibrationInputError

    digest = hashlib.sha256()
    for k, array in enumerate(arrays):
        masked = isinstance(array, np.ma.MaskedArray)
        try:
            values = np.asarray(array)
        except ValueError:  # a ragged nest of lists
            raise CalibrationInputError(f"data_fingerprint: argument {k} is not a rectangular array (rows of "
                                        "different lengths); give arrays of real numbers.") from None
        if masked or values.dtype.kind not in "biuf":
            what = "a masked array (fill it first, e.g. a.filled(np.nan))" if masked else f"of dtype {values.dtype}"
            raise CalibrationInputError(f"data_fingerprint: argument {k} is {what}; give arrays of real numbers.")
        digest.update(repr(values.shape).encode())
        digest.update(np.ascontiguousarray(values, dtype=np.float64).data)  # no copy of a C-ordered float64 array
    return digest.hexdigest()[:16]


#: Distributions whose versions :func:`package_versions` records (what a benchmark's figures depend on).
RECORDED_PACKAGES = ("ftcal", "numpy", "scipy", "scikit-learn", "torch", "skorch", "pin", "example-robot-data")


def package_versions(names: tuple[str, ...] = RECORDED_PACKAGES) -> dict[str, str | None]:
    """The installed version of each distribution in ``names`` (None when not installed), without importing it.

    A benchmark stores them with each cached result, so a table built over sessions can say how many package
    environments its results come from.

    Examples
    --------
    >>> versions = package_versions(("numpy", "no-such-distribution"))
    >>> isinstance(versions["numpy"], str), versions["no-such-distribution"]
    (True, None)
    """
    from importlib.metadata import PackageNotFoundError, version

    found: dict[str, str | None] = {}
    for name in names:
        try:
            found[name] = version(name)
        except PackageNotFoundError:
            found[name] = None
    return found
