"""The one training engine of ftcal's networks: skorch's own loop (``fit_loop``, ``train_step``, ``get_loss``,
history, callback hooks) over ``K >= 1`` nets of one architecture; the design: ``docs/architecture.md``.
"""

from __future__ import annotations

import numpy as np
import torch
from skorch import NeuralNetRegressor
from skorch.dataset import ValidSplit

from ._modules import StackedMLP, weighted_squared_error

__all__ = ["NetworkRegressor", "MemberSquaredError", "MemberBatches"]


class MemberSquaredError(torch.nn.Module):
    """Sum over members ``k`` of ``mean_i sum_j weights[k, j] (y_pred[i, k, j] - y_true[i, k, j])²`` over k's rows
    (``y_true``'s last column is the row mask when the batch has padding rows, :class:`MemberBatches`)."""

    def __init__(self, weights):
        super().__init__()
        self.register_buffer("weights", torch.as_tensor(np.asarray(weights, dtype=np.float32)).reshape(
            1, -1, np.shape(weights)[-1]))

    def member_losses(self, y_pred: torch.Tensor, y_true: torch.Tensor) -> torch.Tensor:
        """Each member's mean loss over its real rows of the batch, shape ``(K,)``."""
        if y_true.shape[-1] == y_pred.shape[-1]:  # no padding in this batch (no mask column): every row is real
            return weighted_squared_error(y_pred, y_true, self.weights).mean(dim=0)
        mask = y_true[..., -1]
        squared = weighted_squared_error(y_pred, y_true[..., :-1], self.weights) * mask
        return squared.sum(dim=0) / mask.sum(dim=0).clamp(min=1.0)

    def forward(self, y_pred: torch.Tensor, y_true: torch.Tensor) -> torch.Tensor:
        losses = self.member_losses(y_pred, y_true)
        self.last_ = (y_pred, losses.detach())  # read back by NetworkRegressor.on_batch_end (no second pass)
        return losses.sum()


class MemberBatches:
    """Mini-batches of ``K`` members' rows, ``X (B, K, n_in)``, ``y (B, K, n_out + 1)``, slices of tensors loaded once;
    ``y``'s last column marks real rows (1) and padding (0; left out of a batch without padding). Each iteration
    reshuffles every member with its generator (skorch iterates one iterator every epoch)."""

    def __init__(self, X: torch.Tensor, y: torch.Tensor, counts: list[int], batch_size: int, generators: list):
        self.X, self.y, self.counts, self.batch_size, self.generators = X, y, counts, batch_size, generators

    def __iter__(self):
        n_max, K = self.y.shape[:2]
        order = torch.arange(n_max).repeat(K, 1)
        for k, (n, generator) in enumerate(zip(self.counts, self.generators)):
            order[k, :n] = torch.randperm(n, generator=generator)  # a member's padding rows stay at its end
        order = order.T
        members = torch.arange(K)
        X, y = self.X[order, members], self.y[order, members]  # shuffled once; the batches are views
        for start in range(0, n_max, self.batch_size):
            stop = start + self.batch_size
            padded = min(self.counts) < min(stop, n_max)  # else the mask column is all ones: left out
            yield X[start:stop], y[start:stop] if padded else y[start:stop, :, :-1]


class NetworkRegressor(NeuralNetRegressor):
    """skorch's ``NeuralNetRegressor`` training ``len(seeds)`` nets of one architecture at once; ``fit(X, y)`` takes
    lists of ``K`` float32 arrays (one dataset per member). Beyond skorch's parameters: ``seeds``, one per member (its
    initial weights, ``torch.manual_seed(seed)`` before building its module, validation split and batch order), and
    ``validation_fraction``, each member's share of rows held out (``ValidSplit``; None: no split)."""

    def __init__(self, module, *args, seeds=(0,), validation_fraction=None, **kwargs):
        super().__init__(module, *args, **kwargs)
        self.seeds, self.validation_fraction = seeds, validation_fraction

    # -- parameters: a member's own module (K = 1) or the stack, and one Adam per member --------------------
    def initialize_module(self):
        kwargs = self.get_params_for("module")
        members = []
        for seed in self.seeds:
            torch.manual_seed(int(seed))
            members.append(self.module(**kwargs))
        self.module_ = members[0] if len(members) == 1 else StackedMLP(members)
        return self

    def member_parameters(self, k: int) -> list[torch.Tensor]:  # member k's (views into the stack when K > 1)
        return list(self.module_.parameters()) if len(self.seeds) == 1 else self.module_.member_parameters(k)

    def initialize_optimizer(self, triggered_directly=None):
        _, kwargs = self.get_params_for_optimizer("optimizer", self.get_all_learnable_params())
        self.trained_parameters_ = list(self.module_.parameters())
        self.optimizers_ = [self.optimizer(self.member_parameters(k), **kwargs) for k in range(len(self.seeds))]
        # K > 1: one optimiser over the member slices (regrouped by rate), or over the stacked tensors while all step
        self.member_optimizer_ = self.optimizers_[0] if len(self.seeds) == 1 else self.optimizer(
            [p for optimizer in self.optimizers_ for p in optimizer.param_groups[0]["params"]], **kwargs)
        self.stacked_path_ = len(self.seeds) > 1
        self.optimizer_ = self.optimizer(self.trained_parameters_, **kwargs) if self.stacked_path_ \
            else self.member_optimizer_
        return self

    def _leave_stacked_path(self) -> None:
        """Step each member's slices from now on (one stalls, stops or gets its own rate); Adam's state handed over."""
        for i, parameter in enumerate(self.trained_parameters_):
            for key, value in self.optimizer_.state.get(parameter, {}).items():  # moments: k's slice; step: a copy
                for k, optimizer in enumerate(self.optimizers_):
                    self.member_optimizer_.state[optimizer.param_groups[0]["params"][i]][key] = value.clone() if (
                        not torch.is_tensor(value) or value.shape != parameter.shape) else value[k].clone()
        self.optimizer_, self.stacked_path_ = self.member_optimizer_, False
        self._group_by_rate()  # the members' current rates (they may have dropped together on the stacked path)

    def _group_by_rate(self) -> None:
        groups: dict[float, dict] = {}
        for member in (optimizer.param_groups[0] for optimizer in self.optimizers_):
            groups.setdefault(member["lr"], {**member, "params": []})["params"] += member["params"]
        self.optimizer_.param_groups = list(groups.values())

    def infer(self, x, **fit_params):
        if isinstance(self.module_, StackedMLP):  # members first inside the stack
            return self.module_(x.transpose(0, 1), **fit_params).transpose(0, 1)
        return super().infer(x[:, 0], **fit_params)[:, None]  # K = 1: the module sees (B, n_in), as in any skorch net

    def _set_training(self, training=True):
        if self.module_.training != training or self.criterion_.training != training:  # a no-op costs a tree walk
            super()._set_training(training)

    def _zero_grad_optimizer(self, set_to_none=None):
        for p in self.trained_parameters_:
            p.grad = None

    def _rows(self, batch) -> torch.Tensor:  # each member's number of real rows in the batch
        y, width = batch[1], self.criterion_.weights.shape[-1]
        return y[..., -1].sum(dim=0) if y.shape[-1] > width else torch.full((y.shape[1],), float(len(y)))

    def train_step(self, batch, **fit_params):
        if len(self.seeds) > 1:
            rows = self._rows(batch).tolist()
            self.moving_ = [n > 0 and reason is None for n, reason in zip(rows, self.stop_reasons_)]
        return super().train_step(batch, **fit_params)

    def _step_optimizer(self, step_fn):
        step_fn()  # forward, loss, backward and on_grad_computed, once for all members
        if self.stacked_path_ and not all(self.moving_):
            self._leave_stacked_path()
        if len(self.optimizers_) > 1 and not self.stacked_path_:  # member slices; none if out of rows or stopped
            grads = [p.grad for p in self.trained_parameters_]
            for k, optimizer in enumerate(self.optimizers_):
                for view, grad in zip(optimizer.param_groups[0]["params"], grads):
                    view.grad = grad[k] if self.moving_[k] and grad is not None else None
        self.optimizer_.step()

    # -- data: each member's split and batch order ----------------------------------------------------------
    def check_data(self, X, y):  # the calibrators validated every member's data
        pass

    def get_split_datasets(self, X, y=None, **fit_params):
        train, valid, n_in = [], [], np.shape(X[0])[1]
        for seed, X_k, y_k in zip(self.seeds, X, y):
            data = np.hstack([X_k, y_k, np.ones((len(X_k), 1), dtype=np.float32)])  # a row mask last
            if self.validation_fraction is None:
                train.append(data)
                continue
            train_ds, valid_ds = ValidSplit(self.validation_fraction, random_state=int(seed))(self.get_dataset(X_k, y_k))
            train.append(data[train_ds.indices])
            valid.append(data[valid_ds.indices])

        def split(blocks):  # side by side, (n_max, K, n_in + n_out + 1), zeros (mask 0) after a member's rows
            both = np.zeros((max(map(len, blocks)), len(blocks), blocks[0].shape[1]), dtype=np.float32)
            for k, block in enumerate(blocks):
                both[:len(block), k] = block
            both = torch.from_numpy(both)
            return both[..., :n_in], both[..., n_in:], [len(b) for b in blocks]

        self.generators_ = [torch.Generator().manual_seed(int(seed)) for seed in self.seeds]
        return split(train), (split(valid) if valid else None)

    def get_iterator(self, dataset, training=False):
        X, y, counts = dataset  # validation: one batch of every row, in order
        return MemberBatches(X, y, counts, int(self.batch_size), self.generators_) if training else [(X, y)]

    # -- each member's epoch losses -------------------------------------------------------------------------
    def on_train_begin(self, net, X=None, y=None, **kwargs):
        self.stop_reasons_ = [None] * len(self.seeds)

    def on_epoch_begin(self, net, **kwargs):
        super().on_epoch_begin(net, **kwargs)
        rates = {float(optimizer.param_groups[0]["lr"]) for optimizer in self.optimizers_}
        if self.stacked_path_ and len(rates) > 1:
            self._leave_stacked_path()
        if self.stacked_path_:
            self.optimizer_.param_groups[0]["lr"] = rates.pop()
        elif len(self.optimizers_) > 1:
            self._group_by_rate()
        K = len(self.seeds)
        self._loss_sums, self._row_counts = ({True: torch.zeros(K), False: torch.zeros(K)} for _ in range(2))

    def on_batch_end(self, net, batch=None, training=False, y_pred=None, **kwargs):
        rows = self._rows(batch)
        last = getattr(self.criterion_, "last_", None)
        if last is None or last[0] is not y_pred:  # a get_loss override that bypassed the criterion
            with torch.no_grad():
                last = (y_pred, self.criterion_.member_losses(y_pred, batch[1]))
        self._loss_sums[training] += last[1] * rows
        self._row_counts[training] += rows

    def on_epoch_end(self, net, **kwargs):
        self.criterion_.last_ = None  # a training batch's output holds its graph: not kept (nor pickled)
        for training, prefix in ((True, "train"), (False, "valid")):
            if self._row_counts[training].any():
                losses = self._loss_sums[training] / self._row_counts[training].clamp(min=1.0)
                self.history.record(f"member_{prefix}_loss", losses.tolist())
