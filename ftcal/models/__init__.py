"""Deprecated alias of :mod:`ftcal.compose`, :mod:`ftcal.calibrators` and :mod:`ftcal.persistence` (the
registry, ``auto``, the search and ensembles moved to :mod:`ftcal.compose`; the stock baselines to
:mod:`ftcal.calibrators`; model files, ONNX and the matrix export to :mod:`ftcal.persistence`).

Each old public name still answers, with a :class:`FutureWarning`, for one release. Layer: none of its own;
it imports nothing at import time.
"""

from ..core._lazy import lazy_namespace

__all__: list[str] = []
#: Old public name -> its public path now (each access warns with a FutureWarning).
_MOVED: dict[str, str] = dict(
    search_summary="ftcal.compose.search_summary", DEFAULT_SEARCH_SPACES="ftcal.compose.DEFAULT_SEARCH_SPACES",
    default_candidates="ftcal.compose.default_candidates", stock_baselines="ftcal.calibrators.stock_baselines",
    STOCK_BASELINE_NAMES="ftcal.calibrators.STOCK_BASELINE_NAMES",
    SubsampledRegressor="ftcal.calibrators.SubsampledRegressor", check_calibration="ftcal.compose.check_calibration",
)
__getattr__, __dir__ = lazy_namespace(__name__, {}, _MOVED)
