"""Shared basics every layer uses: the domain errors, the wrench conventions (units, torque scaling),
input validation, metrics, CSV columns, safe output files, calibration folds, the thermal drift model
and the Dask scale-out.

Imports only numpy, scipy, scikit-learn and the standard library; never another ftcal package.
"""

from ._lazy import lazy_namespace

#: Public names of this package (beyond those of ``ftcal`` itself) -> the private module holding each.
_PUBLIC = dict(
    plain_json="_files", write_json="_files", atomic_output="_files", is_finite_number="_files",
    read_json_record="_files", data_fingerprint="_files", package_versions="_files", mean_std="_metrics",
    calibration_folds="_model_selection", MIN_CHANNELS="_wrench", ALPHA_RANGE_PER_M="_wrench", check_alpha="_wrench",
    check_allocation="_memory", MemoryLimitError="_memory", memory_limit_bytes="_memory",
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
