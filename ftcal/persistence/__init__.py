"""What a fitted model becomes outside Python: pickle-free, bounded, versioned model files
(:func:`save_model` / :func:`load_model`, each class declaring its fitted state next to itself), ONNX graphs
(:func:`export_onnx`) and the 6xN matrix of an affine model (:func:`linear_calibration_matrix`).

Layer: above :mod:`ftcal.compose` (a file may name only the registry's classes). Imports :mod:`ftcal.core`,
:mod:`ftcal.calibrators`, :mod:`ftcal.networks` and :mod:`ftcal.compose`.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package -> the private module holding each.
_PUBLIC = dict(
    save_model="_model_io", load_model="_model_io", model_data="_model_io", FORMAT_VERSION="_model_io",
    export_onnx="_onnx", exportable_types="_onnx", linear_calibration_matrix="_matrix",
)
_PUBLIC.update(  # names the CLI uses
    matrix_export_dict="_matrix", is_model_file="_model_io",
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
