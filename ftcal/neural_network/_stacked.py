"""Several network calibrators trained at once as one stacked module (issue 13).

Training one small net costs far more than its arithmetic: every mini-batch
is a dozen tiny torch calls. :func:`fit_stacked` trains ``K`` nets of one
architecture together: each layer's weights of all ``K`` nets are stacked
into one ``(K, n_in, n_out)`` parameter, a mini-batch step runs each layer
of all ``K`` nets as one ``torch.baddbmm``, and one Adam update (torch's
fused kernel while the members share a learning rate) moves all of them.
The members stay independent:

* the loss is the sum of the members' own losses, so member ``k``'s gradient
  is exactly that of its own loss; Adam is elementwise, so its update is
  exactly that of member ``k`` alone;
* each member keeps its own seed, hence its own weight initialisation,
  validation split (``ValidSplit``) and per-epoch batch order, the same
  ones a separate ``fit`` would draw;
* each runs its own three-phase schedule (:mod:`ftcal.neural_network._schedule`): its own
  learning rate (``ReduceLROnPlateau`` in phase 2), its own phase-3 stop,
  its own best weights. A member that has stopped leaves the stack.

The result equals separate fits up to float32 rounding (the batched matrix
products sum in another order); ``tests/test_stacked.py`` checks the
predictions agree.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import numpy as np
import torch
from numpy.typing import ArrayLike
from skorch.history import History
from threadpoolctl import threadpool_limits
from torch.optim.adam import adam as _functional_adam

from ..core._exceptions import CalibrationInputError
from ._base import NetworkCalibrator, torch_threads
from ._modules import activate, activation_backward, mlp_layers
from ._schedule import phase_of_epoch, recover_stop_reason

__all__ = ["StackedMLP", "fit_stacked"]

_BETA1, _BETA2, _EPS = 0.9, 0.999, 1e-8  # torch.optim.Adam's defaults, which the member nets use


class StackedMLP(torch.nn.Module):
    """``K`` fully connected nets of one architecture as one module: ``(K, B, n_in) -> (K, B, n_out)``.

    Built from ``K`` modules whose ``layers`` is an ``nn.Sequential`` of
    ``Linear`` layers and ``ReLU`` / ``Tanh`` activations (the calibrators'
    nets, :func:`ftcal.neural_network._modules.mlp`). All weights live in one
    1-D parameter ``flat``, layer after layer: the weights of layer ``l`` of
    all members are one contiguous ``(K, n_in, n_out)`` block (the bias
    ``(K, 1, n_out)``), so a layer is one ``torch.baddbmm`` and one optimiser
    step over one tensor updates every member.

    Examples
    --------
    >>> import torch
    >>> from ftcal.neural_network import DirectionalNet
    >>> nets = [DirectionalNet(6, (8, 4)) for _ in range(3)]
    >>> stacked = StackedMLP(nets)
    >>> x = torch.randn(3, 5, 6)
    >>> bool(torch.allclose(stacked(x)[1], nets[1](x[1]), atol=1e-6))
    True
    """

    def __init__(self, modules: Sequence[torch.nn.Module], flat: torch.Tensor | None = None):
        super().__init__()
        if len(modules) < 1:
            raise CalibrationInputError("StackedMLP needs at least one module (K >= 1); got none.")
        per_module = [mlp_layers(module) for module in modules]
        signature = None
        for k, layers in enumerate(per_module):
            if layers is None:
                raise CalibrationInputError(
                    f"StackedMLP: module {k} ({type(modules[k]).__name__}) is not an MLP of Linear / ReLU / Tanh "
                    "layers in a `layers` Sequential."
                )
            shape = [(layer.in_features, layer.out_features, activation) for layer, activation in layers]
            if signature is None:
                signature = shape
            elif shape != signature:
                raise CalibrationInputError(
                    f"StackedMLP: module {k} has layers {shape}, module 0 {signature}; stacked nets must share "
                    "one architecture."
                )
        #: per layer: (n_in, n_out, activation)
        self.layout: list[tuple[int, int, str]] = signature
        self.n_members = len(modules) if flat is None else flat.numel() // self._row_size()
        if flat is None:
            blocks = []
            for i in range(len(self.layout)):
                linears = [layers[i][0] for layers in per_module]
                blocks += [torch.stack([layer.weight.detach().T for layer in linears]).reshape(-1),
                           torch.stack([layer.bias.detach() for layer in linears]).reshape(-1)]
            flat = torch.cat(blocks)
        self.flat = torch.nn.Parameter(flat.detach().clone())
        self.flat.grad = self._grad = torch.zeros_like(self.flat)
        # the storage never moves (updates are in place): its layer views are made once
        self._param_views = self.views(self.flat.detach())
        self._grad_views = self.views(self._grad)

    def _row_size(self) -> int:
        return sum(n_in * n_out + n_out for n_in, n_out, _ in self.layout)

    def views(self, t: torch.Tensor) -> list[tuple[torch.Tensor, torch.Tensor]]:
        """``(weight (K, n_in, n_out), bias (K, 1, n_out))`` per layer: views of ``t``, laid out like ``flat``."""
        K, out, offset = self.n_members, [], 0
        for n_in, n_out, _ in self.layout:
            weight = t[offset:offset + K * n_in * n_out].view(K, n_in, n_out)
            offset += K * n_in * n_out
            bias = t[offset:offset + K * n_out].view(K, 1, n_out)
            offset += K * n_out
            out.append((weight, bias))
        return out

    def select(self, t: torch.Tensor, index: torch.Tensor) -> torch.Tensor:
        """The members ``index`` of ``t`` (laid out like ``flat``), laid out for ``len(index)`` members."""
        return torch.cat([block.reshape(self.n_members, -1)[index].reshape(-1)
                          for pair in self.views(t) for block in pair])

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        h = x
        for (weight, bias), (*_, activation) in zip(self.views(self.flat), self.layout):
            h = activate(torch.baddbmm(bias, h, weight), activation)
        return h

    def loss_and_gradients(self, X: torch.Tensor, y: torch.Tensor, weights: torch.Tensor, row_weight) -> torch.Tensor:
        """Each member's loss ``sum_i row_weight_i sum_j weights_j (f(x_i)_j - y_ij)²``, its gradient written to
        ``flat.grad`` by hand (the arithmetic of autograd in half the calls; ``tests/test_stacked.py``
        compares). ``weights`` (K, 1, n_out); ``row_weight`` a number (1 / batch) or (K, B, 1). Returns (K,)."""
        with torch.no_grad():
            params = self._param_views
            hs, h = [X], X
            for (weight, bias), (*_, activation) in zip(params, self.layout):
                h = activate(torch.baddbmm(bias, h, weight), activation)
                hs.append(h)
            error = h - y
            weighted = error * weights * row_weight
            losses = (weighted * error).sum(dim=(1, 2))
            if self.flat.grad is not self._grad:  # autograd (a user's backward) replaced or dropped the buffer
                self.flat.grad = self._grad = torch.zeros_like(self.flat)
                self._grad_views = self.views(self._grad)
            grads = self._grad_views
            grad = 2.0 * weighted
            for i in range(len(self.layout) - 1, -1, -1):
                grad = activation_backward(grad, hs[i + 1], self.layout[i][2])
                torch.bmm(hs[i].transpose(1, 2), grad, out=grads[i][0])
                torch.sum(grad, dim=1, keepdim=True, out=grads[i][1])
                if i:
                    grad = torch.bmm(grad, params[i][0].transpose(1, 2))
        return losses

    def member_row(self, k: int) -> torch.Tensor:
        """Member ``k``'s weights as one row (a copy), layer after layer: what :meth:`load_member` takes."""
        return torch.cat([block.detach()[k].reshape(-1) for pair in self.views(self.flat) for block in pair])

    def load_member(self, row: torch.Tensor, module: torch.nn.Module) -> None:
        """Copy one member's weights (a :meth:`member_row`) into ``module`` (an unstacked net of the same shape)."""
        offset = 0
        with torch.no_grad():
            for (layer, _), (n_in, n_out, _) in zip(mlp_layers(module), self.layout):
                layer.weight.copy_(row[offset:offset + n_in * n_out].view(n_in, n_out).T)
                offset += n_in * n_out
                layer.bias.copy_(row[offset:offset + n_out])
                offset += n_out


class _Member:
    """One calibrator's data, schedule state and history while it trains in the stack."""

    def __init__(self, estimator: NetworkCalibrator, inputs, targets, seed: int, net) -> None:
        self.estimator, self.targets, self.net = estimator, targets, net
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)  # what a separate fit does: the same initial weights ...
            net.initialize()
            self.generator = torch.Generator()
            self.generator.set_state(torch.get_rng_state())  # ... and then the same batch orders
        train_ds, valid_ds = net.get_split_datasets(inputs.astype(np.float32), targets.astype(np.float32))
        train_idx = getattr(train_ds, "indices", np.arange(len(inputs)))
        valid_idx = None if valid_ds is None else valid_ds.indices
        X = torch.as_tensor(inputs, dtype=torch.float32)
        y = torch.as_tensor(targets, dtype=torch.float32)
        self.X_train, self.y_train = X[train_idx], y[train_idx]
        self.X_valid = None if valid_idx is None else X[valid_idx]
        self.y_valid = None if valid_idx is None else y[valid_idx]
        self.weights = net.criterion_.weights.detach().clone()
        self.monitor = "train_loss" if valid_idx is None else "valid_loss"
        self.lr = float(net.lr)
        self.rows: list[dict] = []
        self.best_loss, self.best_epoch, self.best_row = math.inf, 0, None
        self.plateau = None
        self.stop_reason: str | None = None


def _padded(tensors: list[torch.Tensor]) -> tuple[torch.Tensor, torch.Tensor]:
    """Stack row blocks of unequal length into ``(K, n_max, width)`` with a ``(K, n_max)`` row mask."""
    n_max = max(len(t) for t in tensors)
    out = torch.zeros(len(tensors), n_max, tensors[0].shape[1])
    mask = torch.zeros(len(tensors), n_max)
    for k, t in enumerate(tensors):
        out[k, : len(t)] = t
        mask[k, : len(t)] = 1.0
    return out, mask


class _StackedRun:
    """The epoch loop of :func:`fit_stacked` over the members still training."""

    def __init__(self, members: list[_Member], template: NetworkCalibrator) -> None:
        self.members = members
        self.template = template
        self.batch = int(template.batch_size)
        self._restack(list(range(len(members))), None)
        self.m = torch.zeros_like(self.module.flat)
        self.v = torch.zeros_like(self.module.flat)
        self.step = torch.zeros(len(members), 1, 1)

    def _restack(self, active: list[int], flat: torch.Tensor | None) -> None:
        self.active = active
        members = [self.members[i] for i in active]
        self.module = StackedMLP([m.net.module_ for m in members], flat=flat)
        self.X_train, self.train_mask = _padded([m.X_train for m in members])
        self.y_train, _ = _padded([m.y_train for m in members])
        self.n_train = torch.tensor([len(m.X_train) for m in members])
        self.weights = torch.stack([m.weights for m in members]).unsqueeze(1)
        if members[0].X_valid is not None:
            self.X_valid, self.valid_mask = _padded([m.X_valid for m in members])
            self.y_valid, _ = _padded([m.y_valid for m in members])

    def _drop_stopped(self) -> None:
        keep = [i for i, k in enumerate(self.active) if self.members[k].stop_reason is None]
        if len(keep) == len(self.active):
            return
        if not keep:
            self.active = []
            return
        index = torch.tensor(keep)
        select = self.module.select
        flat, self.m, self.v = select(self.module.flat.detach(), index), select(self.m, index), select(self.v, index)
        self.step = self.step[index]
        self._restack([self.active[i] for i in keep], flat)

    def _adam(self, lr: torch.Tensor, moving: torch.Tensor | None) -> None:
        """One Adam step of every member (torch.optim.Adam's arithmetic) with its own rate ``lr`` (K, 1, 1);
        ``moving``: the members that had a batch (the others keep their weights, moments and step count)."""
        views = self.module.views
        with torch.no_grad():
            self.step += 1 if moving is None else moving
            correction1 = 1 - _BETA1 ** self.step
            correction2 = (1 - _BETA2 ** self.step).sqrt()
            rate = lr if moving is None else lr * moving
            blocks = zip(views(self.module.flat.detach()), views(self.module.flat.grad), views(self.m), views(self.v))
            for param_pair, grad_pair, m_pair, v_pair in blocks:
                for p, grad, m, v in zip(param_pair, grad_pair, m_pair, v_pair):
                    if moving is None:
                        m.lerp_(grad, 1 - _BETA1)
                        v.mul_(_BETA2).addcmul_(grad, grad, value=1 - _BETA2)
                    else:
                        on = moving.bool()
                        m.copy_(torch.where(on, torch.lerp(m, grad, 1 - _BETA1), m))
                        v.copy_(torch.where(on, v * _BETA2 + (1 - _BETA2) * grad * grad, v))
                    denom = (v.sqrt() / correction2).add_(_EPS)
                    p.sub_(rate / correction1 * m / denom)

    def train_epoch(self) -> list[float]:
        """One epoch of every active member; their mean training losses."""
        members = [self.members[k] for k in self.active]
        K, n_max, batch = len(members), self.X_train.shape[1], self.batch
        order = torch.zeros(K, n_max, dtype=torch.long)
        for i, member in enumerate(members):
            order[i, :len(member.X_train)] = torch.randperm(len(member.X_train), generator=member.generator)
        mask = self.train_mask  # a member's shuffled rows stay its first n_train rows
        uneven = bool((self.n_train != n_max).any())
        lr = torch.tensor([m.lr for m in members]).view(K, 1, 1)
        # one rate and one step count for all: torch's fused Adam does the update in one kernel
        fused = not uneven and bool((lr == lr[0]).all()) and bool((self.step == self.step[0]).all())
        if fused:
            fused_step = torch.tensor(float(self.step[0, 0, 0]))
            fused_state = dict(params=[self.module.flat.detach()], grads=[self.module.flat.grad], exp_avgs=[self.m],
                               exp_avg_sqs=[self.v], max_exp_avg_sqs=[], state_steps=[fused_step], fused=True,
                               amsgrad=False, beta1=_BETA1, beta2=_BETA2, lr=float(lr[0, 0, 0]), weight_decay=0.0,
                               eps=_EPS, maximize=False)
        rows = torch.arange(K).unsqueeze(1)
        n_steps = -(-n_max // batch)
        total = torch.zeros(K)
        self.module.train()
        X_epoch, y_epoch = self.X_train[rows, order], self.y_train[rows, order]  # shuffled once; batches are views
        loss_and_gradients = self.module.loss_and_gradients
        for start in range(0, n_max, batch):
            stop = min(start + batch, n_max)
            X, y = X_epoch[:, start:stop], y_epoch[:, start:stop]
            if uneven:
                rows_mask = mask[:, start:stop]
                count = rows_mask.sum(dim=1)
                row_weight = (rows_mask / count.clamp(min=1).unsqueeze(1)).unsqueeze(2)
                moving = (count > 0).float().view(K, 1, 1)
            else:
                row_weight, moving = 1.0 / (stop - start), None
            losses = loss_and_gradients(X, y, self.weights, row_weight)
            if fused:  # torch's fused Adam kernel (what the members' own fits use), functional form
                _functional_adam(**fused_state)
            else:
                self._adam(lr, moving)
            if uneven:
                total += losses * count
            else:
                total.add_(losses, alpha=float(stop - start))
        if fused:
            self.step += n_steps
        return (total / self.n_train).tolist()

    def valid_losses(self) -> list[float]:
        self.module.eval()
        with torch.no_grad():
            squared = (((self.module(self.X_valid) - self.y_valid) ** 2) * self.weights).sum(dim=2)
            return ((squared * self.valid_mask).sum(dim=1) / self.valid_mask.sum(dim=1)).tolist()

    def run(self) -> None:
        t = self.template
        n_epochs = t.max_epochs + t.plateau_epochs + t.max_recover_epochs
        phase_3_start = t.max_epochs + t.plateau_epochs + 1
        for epoch in range(1, n_epochs + 1):
            began = time.perf_counter()
            phase = phase_of_epoch(epoch, t.max_epochs, t.plateau_epochs)
            members = [self.members[k] for k in self.active]
            lrs = [m.lr for m in members]
            train = self.train_epoch()
            valid = self.valid_losses() if members[0].X_valid is not None else [None] * len(members)
            seconds = (time.perf_counter() - began) / len(members)
            for i, member in enumerate(members):
                row = {"epoch": epoch, "phase": phase, "lr": lrs[i], "train_loss": train[i], "dur": seconds,
                       "train_batch_count": -(-len(member.X_train) // self.batch)}
                if valid[i] is not None:
                    row.update(valid_loss=valid[i], valid_batch_count=1)
                member.rows.append(row)
                self._schedule(member, i, row, epoch, phase, phase_3_start)
            self._drop_stopped()
            if not self.active:
                return

    def _schedule(self, member: _Member, i: int, row: dict, epoch: int, phase: int, phase_3_start: int) -> None:
        """The callbacks of :mod:`ftcal.neural_network._schedule` for one member, in their order."""
        t = self.template
        loss = float(row[member.monitor])
        if phase == 2:  # PlateauLR: torch's own ReduceLROnPlateau on a stand-in optimiser holding the member's rate
            if member.plateau is None:
                stand_in = torch.optim.SGD([torch.zeros(1, requires_grad=True)], lr=member.lr)
                member.plateau = torch.optim.lr_scheduler.ReduceLROnPlateau(
                    stand_in, mode="min", factor=t.plateau_factor, patience=t.plateau_patience, min_lr=t.min_lr)
            member.plateau.step(loss)
            member.lr = float(member.plateau.optimizer.param_groups[0]["lr"])
        if loss < member.best_loss:  # RestoreBestWeights
            member.best_loss, member.best_epoch = loss, epoch
            member.best_row = self.module.member_row(i)
        if epoch >= phase_3_start - 1:  # RecoverStop
            member.stop_reason = recover_stop_reason([r[member.monitor] for r in member.rows], phase_3_start,
                                                     t.recover_tolerance, t.max_recover_epochs)
        if member.stop_reason is not None:
            row["stop_reason"] = member.stop_reason

    def finish(self) -> None:
        """Give every member's skorch net its best weights, its history and its schedule's outcome."""
        for member in self.members:
            net = member.net
            if member.best_row is not None:
                self.module.load_member(member.best_row, net.module_)
            net.history = History()
            for row in member.rows:
                net.history.new_epoch()
                for key, value in row.items():
                    net.history.record(key, value)
            best = dict(net.callbacks_)["restore_best_weights"]
            best.best_loss_, best.best_epoch_, best.best_state_ = member.best_loss, member.best_epoch, None


def _stacking_key(estimator) -> tuple:
    """What stacked members must share: class and every training parameter (not seed, tare or scale)."""
    params = estimator.get_params(deep=False)
    for name in ("random_state", "alpha", "zero_reading", "verbose"):
        params.pop(name, None)
    return type(estimator), tuple(sorted((k, repr(v)) for k, v in params.items()))


def _datasets(X, y, K: int) -> list[tuple]:
    if isinstance(X, (list, tuple)) != isinstance(y, (list, tuple)):
        raise CalibrationInputError(
            "fit_stacked: pass X and y both as arrays (one dataset for every estimator) or both as lists "
            f"(one dataset per estimator); got X as {type(X).__name__} and y as {type(y).__name__}."
        )
    if not isinstance(X, (list, tuple)):
        return [(X, y)] * K
    if len(X) != K or len(y) != K:
        raise CalibrationInputError(
            f"fit_stacked: {K} estimators need {K} datasets; got {len(X)} X and {len(y)} y."
        )
    return list(zip(X, y))


def fit_stacked(
    estimators: Sequence[NetworkCalibrator],
    X: ArrayLike | Sequence[ArrayLike],
    y: ArrayLike | Sequence[ArrayLike],
) -> list[NetworkCalibrator]:
    """Fit ``K`` network calibrators of one kind together, as one stacked module (see the module doc).

    Each estimator ends fitted exactly as its own ``fit`` would leave it (the
    skorch ``net_`` with its history, the schedule's outcome, the scales and
    tare), with the weights a separate fit would reach up to float32
    rounding. Training ``K`` nets this way costs far less than ``K`` fits
    (``benchmarks/network_speed.py``).

    Parameters
    ----------
    estimators : sequence of DirectionalCalibrator or ComparativeCalibrator
        ``K >= 1`` calibrators of one class with the same parameters except
        ``random_state``, ``alpha``, ``zero_reading`` and ``verbose`` (they
        share the architecture and the schedule), and no ``callbacks`` (the
        skorch callbacks run per net; fit such an estimator by itself).
    X : array-like of shape (n, N), or a list of K of them
        Raw readings: one dataset for every estimator (seed ensembles), or
        one per estimator (K datasets at once).
    y : array-like of shape (n, 6), or a list of K of them
        Reference wrenches, like ``X``.

    Returns
    -------
    list
        The fitted estimators (the same objects).

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import DirectionalCalibrator, fit_stacked
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(60, 6)); raw = w @ rng.normal(size=(6, 6))
    >>> nets = [DirectionalCalibrator(max_epochs=3, plateau_epochs=1, max_recover_epochs=1, random_state=s)
    ...         for s in range(3)]
    >>> fitted = fit_stacked(nets, raw, w)
    >>> [m.predict(raw[:1]).shape for m in fitted]
    [(1, 6), (1, 6), (1, 6)]
    """
    estimators = list(estimators)
    if not estimators:
        raise CalibrationInputError("fit_stacked needs at least one estimator (K >= 1); got an empty list.")
    for k, est in enumerate(estimators):
        if not isinstance(est, NetworkCalibrator):
            raise CalibrationInputError(
                f"fit_stacked trains network calibrators (DirectionalCalibrator, ComparativeCalibrator); "
                f"estimator {k} is {type(est).__name__}. Fit it with its own fit()."
            )
        if est.callbacks:
            raise CalibrationInputError(
                f"fit_stacked: estimator {k} has callbacks={est.callbacks!r}; skorch callbacks run per net, "
                "so fit that estimator by itself."
            )
        if _stacking_key(est) != _stacking_key(estimators[0]):
            raise CalibrationInputError(
                f"fit_stacked: estimator {k} differs from estimator 0 in a training parameter; stacked nets "
                "share the architecture and the schedule (only random_state, alpha and zero_reading may differ)."
            )
        if est.device != "cpu":
            raise CalibrationInputError(f"fit_stacked trains on the CPU; estimator {k} has device={est.device!r}.")
    members = []
    with threadpool_limits(1, user_api="blas"):
        for est, (X_k, y_k) in zip(estimators, _datasets(X, y, len(estimators))):
            X_k, y_k = est._prepare_fit(X_k, y_k)
            members.append(_Member(est, *est._training_setup(X_k, y_k)))
    run = _StackedRun(members, estimators[0])
    with torch_threads(1):  # a Ctrl-C is a plain KeyboardInterrupt here: no skorch loop swallows it
        run.run()
    run.finish()
    for member in members:
        member.estimator._finish_training(member.net, member.targets)
    return estimators
