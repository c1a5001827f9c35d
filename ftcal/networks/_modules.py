"""Torch modules and loss of the network calibrators (thesis III-C, III-D-a; eq. 9 and 10) and :class:`StackedMLP`."""

from __future__ import annotations

from collections.abc import Sequence

import torch
from torch import nn

from ..core._exceptions import CalibrationInputError

__all__ = ["DirectionalNet", "ComparativeNet", "WeightedSquaredError", "StackedMLP", "mlp_layers",
           "weighted_squared_error"]

_ACTIVATIONS = {nn.ReLU: "relu", nn.Tanh: "tanh"}


def mlp_layers(module: nn.Module, what: str = "the module") -> list[tuple[nn.Linear, str]]:
    """``(Linear, activation)`` per layer of ``module.layers``, a Sequential of Linear layers and ReLU / Tanh.

    ``activation`` is ``"relu"``, ``"tanh"`` or ``"identity"`` (the output layer); any other module is an error.

    Examples
    --------
    >>> [a for _, a in mlp_layers(DirectionalNet(6, (8, 4)))]
    ['relu', 'tanh', 'identity']
    """
    sequential = getattr(module, "layers", None)
    modules = list(sequential) if isinstance(sequential, nn.Sequential) else None
    linears, following = (modules or [])[::2], [type(m) for m in (modules or [])[1::2]]
    if modules is None or any(type(m) is not nn.Linear for m in linears) or not set(following) <= set(_ACTIVATIONS):
        raise CalibrationInputError(f"{what} ({type(module).__name__}) is not an MLP of Linear / ReLU / Tanh layers "
                                    "in a `layers` Sequential.")
    return [(linear, _ACTIVATIONS.get(a, "identity")) for linear, a in zip(linears, [*following, None])]


def activate_(h: torch.Tensor, activation: str) -> torch.Tensor:
    """``h`` through ``"relu"``, ``"tanh"`` or ``"identity"``, in place, for a layer's fresh output that nothing else
    holds (a linear layer's backward needs its inputs, not its output; ReLU's and tanh's backward use their result):
    the same values, one allocation and one pass over memory fewer per layer (~6 % of a stacked 5-member step)."""
    return h.relu_() if activation == "relu" else h.tanh_() if activation == "tanh" else h


class _MLPNet(nn.Module):
    """ReLU hidden layers, ``last_hidden`` on the last one, a linear output layer (in ``self.layers``)."""

    last_hidden: type[nn.Module]

    def __init__(self, n_inputs: int, hidden_layer_sizes: Sequence[int], n_outputs: int):
        super().__init__()
        widths, layers = [n_inputs, *map(int, hidden_layer_sizes)], []
        for i in range(len(widths) - 1):
            layers += [nn.Linear(widths[i], widths[i + 1]), self.last_hidden() if i == len(widths) - 2 else nn.ReLU()]
        self.layers = nn.Sequential(*layers, nn.Linear(widths[-1], n_outputs))
        self._plan = mlp_layers(self)

    @classmethod
    def state_shapes(cls, n_inputs: int, hidden_layer_sizes: Sequence[int], n_outputs: int
                     ) -> dict[str, tuple[int, ...]]:
        """The ``state_dict`` names and shapes of this net for these widths, without allocating it (built on torch's
        ``meta`` device, which holds shapes only: model files check a file's arrays against them before reading
        any).

        Examples
        --------
        >>> DirectionalNet.state_shapes(6, (8,), 7)
        {'layers.0.weight': (8, 6), 'layers.0.bias': (8,), 'layers.2.weight': (7, 8), 'layers.2.bias': (7,)}
        """
        with torch.device("meta"):
            net = cls(n_inputs, hidden_layer_sizes, n_outputs)
        return {name: tuple(value.shape) for name, value in net.state_dict().items()}

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        for layer, activation in self._plan:  # the layers' arithmetic without a module call per layer
            x = activate_(nn.functional.linear(x, layer.weight, layer.bias), activation)
        return x


class DirectionalNet(_MLPNet):
    """Directional DNN: unit reading (N) -> [unit wrench direction (6), scale factor (1)] (k + 1 for k targets);
    ReLU hidden layers, a tanh last hidden layer, a linear output layer."""

    last_hidden = nn.Tanh

    def __init__(self, n_inputs: int = 6, hidden_layer_sizes: Sequence[int] = (64, 64, 64), n_outputs: int = 7):
        super().__init__(n_inputs, hidden_layer_sizes, n_outputs)


class ComparativeNet(_MLPNet):
    """Direct-mapping DNN of Oh et al.: standardised reading (N) -> standardised wrench (6, or k targets), ReLU
    hidden layers and a linear output layer."""

    last_hidden = nn.ReLU

    def __init__(self, n_inputs: int = 6, hidden_layer_sizes: Sequence[int] = (64, 64, 64), n_outputs: int = 6):
        super().__init__(n_inputs, hidden_layer_sizes, n_outputs)


def weighted_squared_error(y_pred: torch.Tensor, y_true: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
    """``sum_j weights[..., j] * (y_pred[..., j] - y_true[..., j])²`` per row (the last axis summed)."""
    return (((y_pred - y_true) ** 2) * weights).sum(dim=-1)


class WeightedSquaredError(nn.Module):
    """``mean over samples of sum_j weights[j] * (y_pred[:, j] - y_true[:, j])²`` (eq. 9: unit weights; eq. 10:
    ``[1, 1, 1, a, a, a]``).

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


class StackedMLP(nn.Module):
    """``K`` nets of one :func:`mlp_layers` architecture as one module: ``(K, B, n_in) -> (K, B, n_out)``.

    Layer ``l`` of all ``K`` members is one parameter ``weight_l`` of shape ``(K, n_in, n_out)`` and one
    ``bias_l`` of shape ``(K, 1, n_out)``, so a layer of every member is one ``torch.baddbmm``; autograd
    differentiates it. :meth:`member_parameters` gives member ``k``'s slices (views sharing storage: an
    optimiser over them moves that member only).

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
        per_module = [mlp_layers(module, f"StackedMLP: module {k}") for k, module in enumerate(modules)]
        if not per_module:
            raise CalibrationInputError("StackedMLP needs at least one module (K >= 1); got none.")
        shapes = [[(layer.in_features, layer.out_features, a) for layer, a in layers] for layers in per_module]
        for k, shape in enumerate(shapes):
            if shape != shapes[0]:
                raise CalibrationInputError(f"StackedMLP: module {k} has layers {shape}, module 0 {shapes[0]}; stacked "
                                            "nets must share one architecture.")
        #: per layer: (n_in, n_out, activation)
        self.layout: list[tuple[int, int, str]] = shapes[0]
        self.n_members = len(per_module)
        for i, linears in enumerate(zip(*per_module)):
            self.register_parameter(f"weight_{i}", nn.Parameter(torch.stack([m.weight.detach().T for m, _ in linears])))
            self.register_parameter(f"bias_{i}", nn.Parameter(torch.stack([m.bias.detach()[None] for m, _ in linears])))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        for i, (*_, activation) in enumerate(self.layout):
            x = activate_(torch.baddbmm(getattr(self, f"bias_{i}"), x, getattr(self, f"weight_{i}")), activation)
        return x

    def member_parameters(self, k: int) -> list[torch.Tensor]:
        """Member ``k``'s weights and biases: detached views of the stacked parameters (updates reach them)."""
        return [p.detach()[k] for p in self.parameters()]

    def member_row(self, k: int) -> torch.Tensor:
        """Member ``k``'s weights as one row (a copy), layer after layer: what :meth:`load_member` takes."""
        return torch.cat([p.detach().reshape(-1) for p in self.member_parameters(k)])

    def load_member(self, row: torch.Tensor, module: nn.Module) -> nn.Module:
        """Copy one member's weights (a :meth:`member_row`) into ``module``, an unstacked net of the same shape."""
        chunks = iter(row.split([size for n_in, n_out, _ in self.layout for size in (n_in * n_out, n_out)]))
        with torch.no_grad():
            for (layer, _), (n_in, n_out, _), weight, bias in zip(mlp_layers(module), self.layout, chunks, chunks):
                layer.weight.copy_(weight.view(n_in, n_out).T)
                layer.bias.copy_(bias)
        return module
