"""The thesis' benchmarks and the demo: the artificial benchmark (Tables II-III), the real-world benchmark
(Tables IV-V), their summary files (never replacing a file they did not write), their per-fit caches (JSON records
with a fingerprint of their data), and the demo that compares
the thesis' three calibrators on simulated data.

Layer: above :mod:`ftcal.reporting` and :mod:`ftcal.experiment`; may import every ftcal package except
:mod:`ftcal.cli`.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package -> the private module holding each.
_PUBLIC = dict(
    run_artificial_benchmark="_artificial", run_real_world_benchmark="_real_world", real_world_markdown="_real_world",
    wilcoxon_pvalue="_artificial", format_mean_std="_artificial", dataset_seeds="_artificial",
    summarize_results="_artificial", THESIS_TABLES="_artificial", make_model="_artificial",
    SPLIT_NAMES="_real_world", THESIS_TABLES_IV_V="_real_world", run_demo="_demo", DemoResult="_demo",
    OutputFiles="_outputs", read_json_record="_records", data_fingerprint="_records", package_versions="_records",
)
_PUBLIC.update(  # names the CLI uses
    demo_files="_demo",
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
