"""Every meta-estimator and what must sit beside them: the automatic cross-validated choice
(:class:`AutoCalibrator`) and its stack (:class:`StackedCalibrator`), seed ensembles, temperature
compensation, the load-history wrapper, metadata routing of ``groups`` through them, the one registry of
calibrator names (:func:`make_calibrator`, :func:`register_calibrator`) and the hyperparameter search.

The registry and the search live here because they need what ``auto`` needs (every calibrator, networks
included, and the wrappers, by name) and ``auto`` reads the registry's candidates.

Layer: above :mod:`ftcal.networks`. Imports :mod:`ftcal.core`, :mod:`ftcal.model_selection`,
:mod:`ftcal.calibrators` and :mod:`ftcal.networks`.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package -> the private module holding each.
_PUBLIC = dict(
    AutoCalibrator="_auto", StackedCalibrator="_auto", EnsembleCalibrator="_ensemble",
    TemperatureCompensatedCalibrator="_temperature_compensation", HistoryCalibrator="_history",
    reading_history="_history", default_candidates="_auto", check_calibration="_auto",
    CALIBRATOR_NAMES="_registry", SCHEDULE_NAMES="_registry", make_calibrator="_registry",
    register_calibrator="_registry", calibrator_parameters="_registry", training_schedule="_registry",
    registered_candidates="_registry", registered_search_spaces="_registry",
    search_calibrator="_search", search_summary="_search", parse_search_space="_search",
    DEFAULT_SEARCH_SPACES="_search",
)
_PUBLIC.update(  # names the CLI uses
    comparison_table="_auto", history_reach="_history", provides_std="_auto", reads_history="_history",
    score_candidates="_auto", spread_flags="_history", requests_groups="_routing",
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
