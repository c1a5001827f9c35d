"""Deprecated alias of :mod:`ftcal.networks` (the network calibrators moved there).

Each old public name still answers, with a :class:`FutureWarning`, for one release. Layer: none of its own;
it imports nothing at import time.
"""

from ..core._lazy import lazy_namespace

__all__: list[str] = []
#: Old public name -> its public path now (each access warns with a FutureWarning).
_MOVED: dict[str, str] = {
    name: f"ftcal.networks.{name}" for name in (
        "DirectionalNet", "ComparativeNet", "WeightedSquaredError", "StackedMLP", "fit_stacked",
        "NetworkCalibrator", "NetworkRegressor", "RestoreBestWeights")
}
__getattr__, __dir__ = lazy_namespace(__name__, {}, _MOVED)
