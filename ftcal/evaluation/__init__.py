"""Benchmarks and reports: the artificial (Tables II-III) and real-world (Tables IV-V) benchmarks,
the plots, and the demo.

May import every ftcal package except :mod:`ftcal.cli`.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package (beyond those of ``ftcal`` itself) -> the private module holding each.
_PUBLIC = dict(
    wilcoxon_pvalue="_benchmark_artificial", format_mean_std="_benchmark_artificial",
    dataset_seeds="_benchmark_artificial", summarize_results="_benchmark_artificial",
    THESIS_TABLES="_benchmark_artificial", make_model="_benchmark_artificial", SPLIT_NAMES="_benchmark_real_world", run_demo="_demo", OutputFiles="_outputs",
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
