"""The comparative direct-mapping DNN of Oh et al. (thesis III-D-a, III-E-a)."""

from __future__ import annotations

from numbers import Real

import numpy as np
from sklearn.utils._param_validation import Interval

from ._base import NetworkCalibrator
from ._modules import ComparativeNet
from ..core._wrench import torque_slice

__all__ = ["ComparativeCalibrator"]


class ComparativeCalibrator(NetworkCalibrator):
    """Direct-mapping DNN (Oh et al.): raw reading -> wrench, loss eq. 10.

    The loss (squared force errors plus ``alpha_`` times squared torque errors, [N²]) is computed on standardised
    inputs and targets, weighted to stay eq. 10 up to a constant factor (``docs/architecture.md``, "The network
    calibrators"). ReLU on every hidden layer, linear outputs; phase 1 is 3000 epochs by default (III-E-a), the rest
    of the schedule the directional one. Parameters and attributes are those of :class:`~ftcal.DirectionalCalibrator`
    except ``min_relative_magnitude``, plus ``input_mean_``, ``input_scale_``, ``target_mean_``, ``target_scale_``.

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import ComparativeCalibrator
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(40, 6)); raw = w @ rng.normal(size=(6, 6))
    >>> model = ComparativeCalibrator(phase1_epochs=2, plateau_epochs=1, max_recover_epochs=1, random_state=0).fit(raw, w)
    >>> model.predict(raw[:2]).shape
    (2, 6)
    """

    _module_class = ComparativeNet
    _default_phase1_epochs = 3000  # III-E-a

    def _network_outputs(self) -> int:
        return int(getattr(self, "n_outputs_", 6))

    def _loss_weights(self) -> list[float]:
        eq10 = np.ones(self._network_outputs())
        eq10[torque_slice(len(eq10), self.axes_)] = self.alpha_  # the torques weighted by alpha_ (eq. 10)
        weights = eq10 * self.target_scale_**2
        return list(weights / weights.mean())

    def _training_pairs(self, X, y):
        self.input_mean_, self.target_mean_ = X.mean(axis=0), y.mean(axis=0)
        std_X, std_y = X.std(axis=0), y.std(axis=0)  # a constant column keeps scale 1
        self.input_scale_, self.target_scale_ = np.where(std_X > 0, std_X, 1.0), np.where(std_y > 0, std_y, 1.0)
        return self._network_inputs(X), (y - self.target_mean_) / self.target_scale_

    def _network_inputs(self, X):
        return (X - self.input_mean_) / self.input_scale_

    def _decode(self, outputs, X):
        return outputs * self.target_scale_ + self.target_mean_

    _fitted_state = ("input_mean_", "input_scale_", "target_mean_", "target_scale_")
    _fitted_constraints: dict = {"input_scale_": [Interval(Real, 0, None, closed="neither")],
                                 "target_scale_": [Interval(Real, 0, None, closed="neither")]}

    def _emit_onnx(self, g, x: str) -> str:
        inputs = g.op("Div", g.op("Sub", x, g.const(self.input_mean_)), g.const(self.input_scale_))
        out = g.mlp(inputs, self._numpy_layers())
        return g.op("Add", g.op("Mul", out, g.const(self.target_scale_)), g.const(self.target_mean_))
