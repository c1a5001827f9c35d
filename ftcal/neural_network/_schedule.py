"""The three-phase training schedule of the thesis (III-A-d) as skorch callbacks.

Epochs are numbered from 1 (as in ``net.history``). With ``max_epochs = P1``
and ``plateau_epochs = P2``:

* **phase 1**, epochs ``1 .. P1``: Adam at the constant initial ``lr``;
* **phase 2**, epochs ``P1+1 .. P1+P2``: ``ReduceLROnPlateau`` on the
  monitored loss (factor ``plateau_factor``, patience ``plateau_patience``,
  floor ``min_lr``); the rate it reaches is kept afterwards;
* **phase 3**, from epoch ``P1+P2+1``: training continues until an epoch's
  monitored loss is within ``recover_tolerance`` of the lowest seen so far
  (``loss <= (1 + tol) * best``), or ``max_recover_epochs`` phase-3 epochs
  have run (the hard cap; 0 skips phase 3).

The weights of the epoch with the lowest monitored loss are restored at the
end (:class:`RestoreBestWeights`). Each epoch of ``net.history`` records
``phase`` (1, 2, 3) and ``lr`` (the rate used in that epoch); the last one
records ``stop_reason``: ``"within_tolerance"``, ``"recover_cap"`` or
``"schedule_end"`` (no phase 3). The monitored loss is ``valid_loss`` when
the net has a validation split, ``train_loss`` otherwise.
"""

from __future__ import annotations

import torch
from skorch.callbacks import Callback

__all__ = [
    "phase_of_epoch",
    "TrainingPhase",
    "PlateauLR",
    "RecoverStop",
    "RestoreBestWeights",
    "schedule_callbacks",
    "recover_stop_reason",
]


def phase_of_epoch(epoch: int, max_epochs: int, plateau_epochs: int) -> int:
    """Phase (1, 2 or 3) of the 1-based ``epoch``.

    Examples
    --------
    >>> [phase_of_epoch(e, 2, 1) for e in range(1, 6)]
    [1, 1, 2, 3, 3]
    """
    if epoch <= max_epochs:
        return 1
    if epoch <= max_epochs + plateau_epochs:
        return 2
    return 3


class TrainingPhase(Callback):
    """Record each epoch's ``phase`` and learning rate ``lr`` in ``net.history``."""

    def __init__(self, max_epochs: int, plateau_epochs: int):
        self.max_epochs = max_epochs
        self.plateau_epochs = plateau_epochs

    def on_epoch_begin(self, net, **kwargs):
        epoch = len(net.history)
        net.history.record("phase", phase_of_epoch(epoch, self.max_epochs, self.plateau_epochs))
        net.history.record("lr", float(net.optimizer_.param_groups[0]["lr"]))


class PlateauLR(Callback):
    """``ReduceLROnPlateau`` stepped on the monitored loss, in phase 2 only."""

    def __init__(self, factor: float, patience: int, min_lr: float, monitor: str = "valid_loss"):
        self.factor = factor
        self.patience = patience
        self.min_lr = min_lr
        self.monitor = monitor

    def on_train_begin(self, net, **kwargs):
        self.scheduler_ = None

    def on_epoch_end(self, net, **kwargs):
        if net.history[-1, "phase"] != 2:
            return
        if self.scheduler_ is None:
            self.scheduler_ = torch.optim.lr_scheduler.ReduceLROnPlateau(
                net.optimizer_, mode="min", factor=self.factor, patience=self.patience, min_lr=self.min_lr
            )
        self.scheduler_.step(net.history[-1, self.monitor])


def recover_stop_reason(losses: list[float], phase_3_start: int, tolerance: float, max_recover_epochs: int) -> str | None:
    """Why training stops after the last of ``losses`` (the monitored loss per epoch so far), or None.

    Examples
    --------
    >>> recover_stop_reason([1.0, 0.5, 0.6], phase_3_start=3, tolerance=0.05, max_recover_epochs=10) is None
    True
    >>> recover_stop_reason([1.0, 0.5, 0.51], phase_3_start=3, tolerance=0.05, max_recover_epochs=10)
    'within_tolerance'
    >>> recover_stop_reason([1.0, 0.5], phase_3_start=3, tolerance=0.05, max_recover_epochs=0)
    'schedule_end'
    """
    epoch = len(losses)
    recover_epochs = epoch - phase_3_start + 1
    if recover_epochs <= 0:
        return "schedule_end" if epoch == phase_3_start - 1 and max_recover_epochs == 0 else None
    if losses[-1] <= (1.0 + tolerance) * min(losses):
        return "within_tolerance"
    if recover_epochs >= max_recover_epochs:
        return "recover_cap"
    return None


class RecoverStop(Callback):
    """Stop in phase 3 once the loss is within ``tolerance`` of the best, or at the cap."""

    def __init__(self, tolerance: float, max_recover_epochs: int, phase_3_start: int, monitor: str = "valid_loss"):
        self.tolerance = tolerance
        self.max_recover_epochs = max_recover_epochs
        self.phase_3_start = phase_3_start
        self.monitor = monitor

    def on_epoch_end(self, net, **kwargs):
        if len(net.history) < self.phase_3_start - 1:  # phases 1-2: nothing to decide, no need to read the losses
            return
        reason = recover_stop_reason(net.history[:, self.monitor], self.phase_3_start, self.tolerance,
                                     self.max_recover_epochs)
        if reason is not None:
            self._stop(net, reason)

    @staticmethod
    def _stop(net, reason: str) -> None:
        net.history.record("stop_reason", reason)
        raise KeyboardInterrupt  # skorch's way to end fit_loop early (as in EarlyStopping)


class RestoreBestWeights(Callback):
    """Keep a copy of the weights of the epoch with the lowest loss; load it at the end."""

    def __init__(self, monitor: str = "valid_loss"):
        self.monitor = monitor

    def on_train_begin(self, net, **kwargs):
        self.best_loss_ = float("inf")
        self.best_epoch_ = 0
        self.best_state_ = None

    def on_epoch_end(self, net, **kwargs):
        loss = float(net.history[-1, self.monitor])
        if loss < self.best_loss_:
            self.best_loss_ = loss
            self.best_epoch_ = len(net.history)
            self.best_state_ = {k: v.detach().clone() for k, v in net.module_.state_dict().items()}

    def on_train_end(self, net, **kwargs):
        if self.best_state_ is not None:
            net.module_.load_state_dict(self.best_state_)


def schedule_callbacks(
    *,
    max_epochs: int,
    plateau_epochs: int,
    plateau_patience: int,
    plateau_factor: float,
    min_lr: float,
    recover_tolerance: float,
    max_recover_epochs: int,
    monitor: str,
    extra: list | tuple = (),
) -> list:
    """The named callbacks of the whole schedule, in the order they must run.

    ``extra`` callbacks (a user's progress bar or logger) run after the
    schedule has recorded the epoch's phase and learning rate and before the
    phase-3 stop rule, so they also see the last epoch.
    """
    return [
        ("training_phase", TrainingPhase(max_epochs, plateau_epochs)),
        ("plateau_lr", PlateauLR(plateau_factor, plateau_patience, min_lr, monitor)),
        ("restore_best_weights", RestoreBestWeights(monitor)),
        *extra,
        ("recover_stop", RecoverStop(recover_tolerance, max_recover_epochs, max_epochs + plateau_epochs + 1, monitor)),
    ]
