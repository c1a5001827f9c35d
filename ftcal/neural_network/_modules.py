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

__all__ = ["DirectionalNet", "ComparativeNet", "WeightedSquaredError", "mlp", "mlp_layers", "activate",
           "activation_backward"]


def mlp(n_inputs: int, hidden_layer_sizes: Sequence[int], n_outputs: int, last_hidden: type[nn.Module]) -> nn.Sequential:
    """Fully connected net: ReLU hidden layers, ``last_hidden`` on the last one, linear output.

    Examples
    --------
    >>> mlp(6, (8, 4), 7, nn.Tanh)
    Sequential(
      (0): Linear(in_features=6, out_features=8, bias=True)
      (1): ReLU()
      (2): Linear(in_features=8, out_features=4, bias=True)
      (3): Tanh()
      (4): Linear(in_features=4, out_features=7, bias=True)
    )
    """
    layers: list[nn.Module] = []
    width = n_inputs
    for i, size in enumerate(hidden_layer_sizes):
        layers += [nn.Linear(width, int(size)), last_hidden() if i == len(hidden_layer_sizes) - 1 else nn.ReLU()]
        width = int(size)
    layers.append(nn.Linear(width, n_outputs))
    return nn.Sequential(*layers)


def mlp_layers(module: nn.Module) -> list[tuple[nn.Linear, str]] | None:
    """``(Linear, activation)`` per layer of an :func:`mlp` (``module.layers``), or None for any other module.

    ``activation`` is ``"relu"``, ``"tanh"`` or ``"identity"`` (the output layer).

    Examples
    --------
    >>> [a for _, a in mlp_layers(DirectionalNet(6, (8, 4)))]
    ['relu', 'tanh', 'identity']
    """
    layers = getattr(module, "layers", None)
    if not isinstance(layers, nn.Sequential):
        return None
    layers, out = list(layers), []
    for i, layer in enumerate(layers):
        if isinstance(layer, nn.Linear):
            following = layers[i + 1] if i + 1 < len(layers) else None
            if following is not None and not isinstance(following, (nn.ReLU, nn.Tanh)):
                return None
            out.append((layer, "relu" if isinstance(following, nn.ReLU)
                        else "tanh" if isinstance(following, nn.Tanh) else "identity"))
        elif not isinstance(layer, (nn.ReLU, nn.Tanh)):
            return None
    return out


def activate(h: torch.Tensor, activation: str) -> torch.Tensor:
    """``h`` through ``"relu"``, ``"tanh"`` or ``"identity"``."""
    if activation == "relu":
        return torch.relu(h)
    if activation == "tanh":
        return torch.tanh(h)
    return h


def activation_backward(grad: torch.Tensor, out: torch.Tensor, activation: str) -> torch.Tensor:
    """The gradient before the activation, from the one after it and the activation's output ``out``.

    ReLU: ``grad`` where ``out > 0``, else 0; tanh: ``grad * (1 - out²)``; each one kernel, the ones
    autograd itself runs (``threshold_backward``, ``tanh_backward``).
    """
    if activation == "relu":
        return torch.ops.aten.threshold_backward(grad, out, 0)
    if activation == "tanh":
        return torch.ops.aten.tanh_backward(grad, out)
    return grad


class _MLPNet(nn.Module):
    """An :func:`mlp` as a module whose activation of the last hidden layer is ``last_hidden``."""

    last_hidden: type[nn.Module]

    def __init__(self, n_inputs: int, hidden_layer_sizes: Sequence[int], n_outputs: int):
        super().__init__()
        self.layers = mlp(n_inputs, hidden_layer_sizes, n_outputs, self.last_hidden)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.layers(x)


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
        return (((y_pred - y_true) ** 2) * self.weights).sum(dim=1).mean()
