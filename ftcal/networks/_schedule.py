"""The three-phase training schedule of the thesis (III-A-d) as skorch callbacks, for ``K >= 1`` members: the only
definition of the schedule (the phases and the stop rule: ``docs/architecture.md``, "The three-phase schedule").
"""

from __future__ import annotations

import math

import torch
from skorch.callbacks import Callback

__all__ = ["phase_of_epoch", "TrainingPhase", "RecoverStop", "RestoreBestWeights", "schedule_callbacks"]


def phase_of_epoch(epoch: int, max_epochs: int, plateau_epochs: int) -> int:
    """Phase (1, 2 or 3) of the 1-based ``epoch`` (``tests/test_schedule.py`` checks the boundaries)."""
    return 1 if epoch <= max_epochs else 2 if epoch <= max_epochs + plateau_epochs else 3


def _running_losses(net, monitor: str) -> list[tuple[int, float]]:
    """``(k, loss)``: the last epoch's monitored loss of each member ``k`` not stopped yet."""
    return [(k, loss) for k, loss in enumerate(net.history[-1, monitor]) if net.stop_reasons_[k] is None]


class TrainingPhase(Callback):
    """The learning rate by phase: each epoch's ``phase`` and rates (``member_lr``; ``lr``: member 0's) are recorded
    in ``net.history``; in phase 2, torch's ``ReduceLROnPlateau`` steps each member's optimiser on its loss."""

    def __init__(self, max_epochs: int, plateau_epochs: int, factor: float, patience: int, min_lr: float,
                 monitor: str = "member_valid_loss"):
        self.max_epochs, self.plateau_epochs = max_epochs, plateau_epochs
        self.factor, self.patience, self.min_lr, self.monitor = factor, patience, min_lr, monitor

    def on_train_begin(self, net, **kwargs):
        self.schedulers_ = None

    def on_epoch_begin(self, net, **kwargs):
        net.history.record("phase", phase_of_epoch(len(net.history), self.max_epochs, self.plateau_epochs))
        rates = [float(opt.param_groups[0]["lr"]) for opt in net.optimizers_]
        net.history.record("member_lr", rates)
        net.history.record("lr", rates[0])

    def on_epoch_end(self, net, **kwargs):
        if net.history[-1, "phase"] != 2:
            return
        if self.schedulers_ is None:
            self.schedulers_ = [torch.optim.lr_scheduler.ReduceLROnPlateau(
                opt, mode="min", factor=self.factor, patience=self.patience, min_lr=self.min_lr)
                for opt in net.optimizers_]
        for k, loss in _running_losses(net, self.monitor):
            self.schedulers_[k].step(loss)


class RecoverStop(Callback):
    """Stop each member in phase 3 (from epoch ``phase_3_start``) by the rule of ``docs/architecture.md``.

    Its stop reason: ``"within_tolerance"``, ``"recover_cap"``, or ``"schedule_end"`` after phase 2 when
    ``max_recover_epochs`` is 0. A stopped member is frozen (``net.stop_reasons_[k]`` set, so it gets no gradient);
    when every member has stopped, training ends the skorch way (``KeyboardInterrupt``, as ``EarlyStopping`` does).
    """

    def __init__(self, tolerance: float, max_recover_epochs: int, phase_3_start: int,
                 monitor: str = "member_valid_loss"):
        self.tolerance, self.max_recover_epochs, self.phase_3_start = tolerance, max_recover_epochs, phase_3_start
        self.monitor = monitor

    def on_train_begin(self, net, **kwargs):
        self.best_ = [math.inf] * len(net.optimizers_)

    def on_epoch_end(self, net, **kwargs):
        reasons, recover_epochs = net.stop_reasons_, len(net.history) - self.phase_3_start + 1
        stopped = [None] * len(reasons)
        for k, loss in _running_losses(net, self.monitor):
            self.best_[k] = min(self.best_[k], loss)
            if recover_epochs <= 0:
                reason = "schedule_end" if recover_epochs == 0 and self.max_recover_epochs == 0 else None
            elif loss <= (1.0 + self.tolerance) * self.best_[k]:
                reason = "within_tolerance"
            else:
                reason = "recover_cap" if recover_epochs >= self.max_recover_epochs else None
            stopped[k] = reasons[k] = reason
        if any(stopped):
            net.history.record("member_stop_reason", stopped)
            if len(reasons) == 1:
                net.history.record("stop_reason", stopped[0])
        if all(reasons):
            raise KeyboardInterrupt  # skorch's way to end fit_loop early (as in EarlyStopping)


class RestoreBestWeights(Callback):
    """Keep each member's weights of its epoch with the lowest monitored loss; load them at the end."""

    def __init__(self, monitor: str = "member_valid_loss"):
        self.monitor = monitor

    def on_train_begin(self, net, **kwargs):
        K = len(net.optimizers_)
        self.best_loss_, self.best_epoch_, self.best_state_ = [math.inf] * K, [0] * K, [None] * K

    def on_epoch_end(self, net, **kwargs):
        for k, loss in _running_losses(net, self.monitor):
            if loss < self.best_loss_[k]:
                self.best_loss_[k], self.best_epoch_[k] = float(loss), len(net.history)
                self.best_state_[k] = [p.detach().clone() for p in net.member_parameters(k)]

    def on_train_end(self, net, **kwargs):
        with torch.no_grad():
            for k, state in enumerate(self.best_state_):
                for p, best in zip(net.member_parameters(k), state or ()):
                    p.copy_(best)


def schedule_callbacks(estimator) -> list:
    """The named callbacks of ``estimator``'s whole schedule, in the order they must run (its own ``callbacks``
    after the epoch's phase and rate are recorded, before the phase-3 stop rule: they also see the last epoch)."""
    e = estimator
    phase1 = e._schedule_epochs()[0]
    monitor = "member_train_loss" if e.validation_fraction is None else "member_valid_loss"
    return [
        ("training_phase", TrainingPhase(phase1, e.plateau_epochs, e.plateau_factor, e.plateau_patience, e.min_lr,
                                         monitor)),
        ("restore_best_weights", RestoreBestWeights(monitor)),
        *list(e.callbacks or []),
        ("recover_stop", RecoverStop(e.recover_tolerance, e.max_recover_epochs, phase1 + e.plateau_epochs + 1,
                                     monitor)),
    ]
