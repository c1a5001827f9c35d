"""Deprecated alias of :mod:`ftcal.benchmark` and :mod:`ftcal.reporting` (the thesis' benchmarks and the demo
moved to :mod:`ftcal.benchmark`; the calibration report and the plots to :mod:`ftcal.reporting`).

Each old public name still answers, with a :class:`FutureWarning`, for one release. Layer: none of its own;
it imports nothing at import time.
"""

from ..core._lazy import lazy_namespace

__all__: list[str] = []
#: Old public name -> its public path now (each access warns with a FutureWarning).
_MOVED: dict[str, str] = {
    name: f"ftcal.benchmark.{name}" for name in (
        "wilcoxon_pvalue", "format_mean_std", "dataset_seeds", "summarize_results", "THESIS_TABLES", "make_model",
        "SPLIT_NAMES", "run_demo", "OutputFiles")
}
__getattr__, __dir__ = lazy_namespace(__name__, {}, _MOVED)
