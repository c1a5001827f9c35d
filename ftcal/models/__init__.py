"""What knows every calibrator: the registry of names (``make_calibrator``), model files
(``save_model`` / ``load_model``), ONNX export, seed ensembles, the automatic cross-validated choice
(``AutoCalibrator``) and the hyperparameter search.

Imports :mod:`ftcal.core`, :mod:`ftcal.calibrators` and :mod:`ftcal.neural_network`. A new calibrator is one
module (its fitted state declared next to its class: ``_fitted_state``, with bounds, and for state it encodes
itself ``_encoded_state`` and its hooks) and one line in ``_registry.py``; ``_model_io.py`` needs no edit.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package (beyond those of ``ftcal`` itself) -> the private module holding each.
_PUBLIC = dict(search_summary="_search", DEFAULT_SEARCH_SPACES="_search", stock_baselines="_baselines",
               STOCK_BASELINE_NAMES="_baselines", SubsampledRegressor="_baselines", default_candidates="_auto",
               check_calibration="_auto")
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
