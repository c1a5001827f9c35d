"""The network calibrators (torch, trained through skorch's loop in one engine for K >= 1 nets; numpy
inference): directional and comparative calibrators, their modules and loss, the three-phase schedule and
:func:`fit_stacked`.

Layer: above :mod:`ftcal.calibrators`. Imports :mod:`ftcal.core`, :mod:`ftcal.model_selection` and
:mod:`ftcal.calibrators` (the base class); nothing above.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package -> the private module holding each.
_PUBLIC = dict(
    DirectionalCalibrator="_directional", ComparativeCalibrator="_comparative",
    DirectionalNet="_modules", ComparativeNet="_modules", WeightedSquaredError="_modules",
    StackedMLP="_modules", fit_stacked="_stacked", NetworkCalibrator="_base",
    NetworkRegressor="_engine", RestoreBestWeights="_schedule",
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
