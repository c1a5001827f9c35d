"""Torch modules and the loss of the two network calibrators.

* :class:`DirectionalNet` (thesis III-C): ReLU hidden layers, a tanh
  second-to-last layer (the last hidden layer) and a linear output layer of
  7 units (6-D direction + scale factor).
* :class:`ComparativeNet` (Oh et al., III-D-a): ReLU hidden layers and a
  linear output layer of 6 units (the wrench).
* :class:`WeightedSquaredError`: ``mean_i sum_j w_j (y_ij - ŷ_ij)²``; with unit
  weights it is eq. 9, with ``[1, 1, 1, a, a, a]`` eq. 10.
"""

from __future__ import annotations

from collections.abc import Sequence

import torch
from torch import nn

from ..core._exceptions import CalibrationInputError

__all__ = ["DirectionalNet", "ComparativeNet", "WeightedSquaredError", "StackedMLP", "mlp", "mlp_layers",
           "activate", "weighted_squared_error"]


def mlp(n_inputs: int, hidden_layer_sizes: Sequence[int], n_outputs: int, last_hidden: type[nn.Module]) -> nn.Sequential:
    """Fully connected net: ReLU hidden layers, ``last_hidden`` on the last one, linear output.

    Examples
    --------
    >>> [type(m).__name__ for m in mlp(6, (8, 4), 7, nn.Tanh)]
    ['Linear', 'ReLU', 'Linear', 'Tanh', 'Linear']
    """
    widths, layers = [n_inputs, *map(int, hidden_layer_sizes)], []
    for i in range(len(widths) - 1):
        layers += [nn.Linear(widths[i], widths[i + 1]), last_hidden() if i == len(widths) - 2 else nn.ReLU()]
    return nn.Sequential(*layers, nn.Linear(widths[-1], n_outputs))


_ACTIVATIONS = {nn.ReLU: "relu", nn.Tanh: "tanh"}


def mlp_layers(module: nn.Module) -> list[tuple[nn.Linear, str]] | None:
    """``(Linear, activation)`` per layer of an :func:`mlp` (``module.layers``), or None for any other module.

    ``activation`` is ``"relu"``, ``"tanh"`` or ``"identity"`` (the output layer).

    Examples
    --------
    >>> [a for _, a in mlp_layers(DirectionalNet(6, (8, 4)))]
    ['relu', 'tanh', 'identity']
    """
    sequential = getattr(module, "layers", None)
    if not isinstance(sequential, nn.Sequential):
        return None
    modules, out = list(sequential), []
    for i in range(0, len(modules), 2):  # Linear, activation, Linear, ..., Linear
        following = type(modules[i + 1]) if i + 1 < len(modules) else None
        if type(modules[i]) is not nn.Linear or (following is not None and following not in _ACTIVATIONS):
            return None
        out.append((modules[i], _ACTIVATIONS.get(following, "identity")))
    return out


def activate(h: torch.Tensor, activation: str) -> torch.Tensor:
    """``h`` through ``"relu"``, ``"tanh"`` or ``"identity"``."""
    return torch.relu(h) if activation == "relu" else torch.tanh(h) if activation == "tanh" else h


class _MLPNet(nn.Module):
    """An :func:`mlp` as a module whose activation of the last hidden layer is ``last_hidden``."""

    last_hidden: type[nn.Module]

    def __init__(self, n_inputs: int, hidden_layer_sizes: Sequence[int], n_outputs: int):
        super().__init__()
        self.layers = mlp(n_inputs, hidden_layer_sizes, n_outputs, self.last_hidden)
        self._plan = mlp_layers(self)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        for layer, activation in self._plan:  # the layers' arithmetic without a module call per layer
            x = activate(nn.functional.linear(x, layer.weight, layer.bias), activation)
        return x


class DirectionalNet(_MLPNet):
    """Directional DNN: unit reading (N) -> [unit wrench direction (6), scale factor (1)].

    ``n_outputs`` is 7 for a wrench (k + 1 for k targets).
    """

    last_hidden = nn.Tanh

    def __init__(self, n_inputs: int = 6, hidden_layer_sizes: Sequence[int] = (64, 64, 64), n_outputs: int = 7):
        super().__init__(n_inputs, hidden_layer_sizes, n_outputs)


class ComparativeNet(_MLPNet):
    """Direct-mapping DNN of Oh et al.: standardised reading (N) -> standardised wrench (6, or k targets)."""

    last_hidden = nn.ReLU

    def __init__(self, n_inputs: int = 6, hidden_layer_sizes: Sequence[int] = (64, 64, 64), n_outputs: int = 6):
        super().__init__(n_inputs, hidden_layer_sizes, n_outputs)


class WeightedSquaredError(nn.Module):
    """``mean over samples of sum_j weights[j] * (y_pred[:, j] - y_true[:, j])²``.

    Examples
    --------
    >>> loss = WeightedSquaredError((1.0, 2.0))
    >>> float(loss(torch.tensor([[1.0, 1.0]]), torch.tensor([[0.0, 0.0]])))
    3.0
    """

    def __init__(self, weights: Sequence[float]):
        super().__init__()
        self.register_buffer("weights", torch.as_tensor(list(weights), dtype=torch.float32))

    def forward(self, y_pred: torch.Tensor, y_true: torch.Tensor) -> torch.Tensor:
        return weighted_squared_error(y_pred, y_true, self.weights).mean()


def weighted_squared_error(y_pred: torch.Tensor, y_true: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
    """``sum_j weights[..., j] * (y_pred[..., j] - y_true[..., j])²`` per row (the last axis summed)."""
    return (((y_pred - y_true) ** 2) * weights).sum(dim=-1)


class StackedMLP(nn.Module):
    """``K`` :func:`mlp` nets of one architecture as one module: ``(K, B, n_in) -> (K, B, n_out)``.

    Layer ``l`` of all ``K`` members is one parameter ``weight_l`` of shape
    ``(K, n_in, n_out)`` and one ``bias_l`` of shape ``(K, 1, n_out)``, so a
    layer of every member is one ``torch.baddbmm``; autograd differentiates
    it. :meth:`member_parameters` gives member ``k``'s slices (views sharing
    storage: an optimiser over them moves that member only).

    Examples
    --------
    >>> import torch
    >>> nets = [DirectionalNet(6, (8, 4)) for _ in range(3)]
    >>> stacked = StackedMLP(nets)
    >>> x = torch.randn(3, 5, 6)
    >>> bool(torch.allclose(stacked(x)[1], nets[1](x[1]), atol=1e-6))
    True
    """

    def __init__(self, modules: Sequence[nn.Module]):
        super().__init__()
        per_module = [mlp_layers(module) for module in modules]
        if not per_module:
            raise CalibrationInputError("StackedMLP needs at least one module (K >= 1); got none.")
        layout = None
        for k, layers in enumerate(per_module):
            if layers is None:
                raise CalibrationInputError(
                    f"StackedMLP: module {k} ({type(modules[k]).__name__}) is not an MLP of Linear / ReLU / Tanh "
                    "layers in a `layers` Sequential.")
            shape = [(layer.in_features, layer.out_features, activation) for layer, activation in layers]
            if layout is not None and shape != layout:
                raise CalibrationInputError(f"StackedMLP: module {k} has layers {shape}, module 0 {layout}; stacked "
                                            "nets must share one architecture.")
            layout = shape
        #: per layer: (n_in, n_out, activation)
        self.layout: list[tuple[int, int, str]] = layout
        self.n_members = len(modules)
        for i in range(len(layout)):
            linears = [layers[i][0] for layers in per_module]
            self.register_parameter(f"weight_{i}", nn.Parameter(torch.stack([m.weight.detach().T for m in linears])))
            self.register_parameter(f"bias_{i}", nn.Parameter(torch.stack([m.bias.detach()[None] for m in linears])))

    def _layers(self) -> list[tuple[torch.Tensor, torch.Tensor, str]]:
        return [(getattr(self, f"weight_{i}"), getattr(self, f"bias_{i}"), a) for i, (*_, a) in enumerate(self.layout)]

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        h = x
        for weight, bias, activation in self._layers():
            h = activate(torch.baddbmm(bias, h, weight), activation)
        return h

    def member_parameters(self, k: int) -> list[torch.Tensor]:
        """Member ``k``'s weights and biases: detached views of the stacked parameters (updates reach them)."""
        return [p.detach()[k] for p in self.parameters()]

    def member_row(self, k: int) -> torch.Tensor:
        """Member ``k``'s weights as one row (a copy), layer after layer: what :meth:`load_member` takes."""
        return torch.cat([p.detach().reshape(-1) for p in self.member_parameters(k)])

    def load_member(self, row: torch.Tensor, module: nn.Module) -> nn.Module:
        """Copy one member's weights (a :meth:`member_row`) into ``module``, an unstacked net of the same shape."""
        offset = 0
        with torch.no_grad():
            for (layer, _), (n_in, n_out, _) in zip(mlp_layers(module), self.layout):
                layer.weight.copy_(row[offset:offset + n_in * n_out].view(n_in, n_out).T)
                offset += n_in * n_out
                layer.bias.copy_(row[offset:offset + n_out])
                offset += n_out
        return module
