"""What knows every calibrator: the registry of names (``make_calibrator``), model files
(``save_model`` / ``load_model``), ONNX export, seed ensembles, the automatic cross-validated choice
(``AutoCalibrator``) and the hyperparameter search.

Imports :mod:`ftcal.core`, :mod:`ftcal.calibrators` and :mod:`ftcal.neural_network`. Register a new
calibrator in ``_registry.py`` (its name) and ``_model_io.py`` (its fitted arrays).
"""
