"""Model selection by held-out error: the one fold rule (:class:`FoldPlan`: whole groups held out, folds that
cannot judge replaced), the one comparison engine (:func:`compare` -> :class:`Comparison`, raced, with paired
differences in symmetric words), the one held-out engine (:func:`held_out_predictions`, on scikit-learn's
``cross_validate``), the one-standard-error rule, standard errors over the groups, and the gates every kept model
passes (degenerate predictions, unseen outputs).

Layer: right above :mod:`ftcal.core`, below every estimator (the calibrators' own inner choices use it).
Imports only :mod:`ftcal.core`.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package -> the private module holding each.
_PUBLIC = dict(
    FoldPlan="_plan", RowStatus="_comparison", ComparisonRow="_comparison", Comparison="_comparison",
    PairedDifference="_comparison", ChoiceStability="_comparison", compare="_comparison",
    choice_stability="_comparison", model_cost="_comparison",
    calibration_folds="_selection", held_out_predictions="_selection", fold_predictions="_selection",
    check_groups="_selection", grouped_subsample="_selection", routed_groups="_selection",
    simplest_within_one_se="_selection", one_se_qualified="_selection", paired_excess="_selection",
    mean_and_se="_selection", rmse_and_se="_selection", se_units="_selection",
    check_not_degenerate="_selection", degenerate_reason="_selection", DegenerateCalibrationError="_selection",
    unseen_outputs="_selection",
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
