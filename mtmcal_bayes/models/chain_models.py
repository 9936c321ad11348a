"""The first order of a forward model (``linear``), and the engine's probe model by its old name (the ball bar's
model: :mod:`.ballbar`; the probe's: :mod:`.probe`).

* :class:`FirstOrderModel` — ``θ ↦ J θ``, ``J`` the model's Jacobian at zero (the chain's at the home pose, zero
  deviations), a design matrix; a probe model's first-order readings through its layout.
* :func:`ChainProbeModel` — the engine's probe model with the chain as its kernel.
"""

from __future__ import annotations

import numpy as np

from .ballbar import as_numbers
from .jacobian import jacobian_at_zero
from .probe import SOLVE_STEPS, ProbeModel  # noqa: F401  (SOLVE_STEPS: the name kept for callers)


def ChainProbeModel(campaign, space=None, *, layout=None) -> ProbeModel:
    """The engine's probe model (:class:`~.probe.ProbeModel`) with its default kernel, the chain (the name kept for
    callers)."""
    return ProbeModel(campaign, space, layout=layout)


class FirstOrderModel:
    """The ``linear`` model of a forward model: ``θ ↦ J θ`` with ``J`` its Jacobian at zero, by the complex step
    where the model is analytic (``complex_step``: the chain's), else by central differences."""

    name = "linear"

    def __init__(self, model):
        self.campaign, self.space = model.campaign, model.space
        self.observations = model.observations
        self.complex_step = getattr(model, "complex_step", False)  # a linear map takes what its model took
        self.layout = getattr(model, "layout", None)  # a probe model's layout: its nominal readings and frames
        self.nominal = None if self.layout is None else self.layout.nominal  # (k, 3) mm
        self.design = jacobian_at_zero(model)

    def predict(self, theta: np.ndarray) -> np.ndarray:
        return as_numbers(theta) @ self.design.T

    def centres(self, theta: np.ndarray) -> np.ndarray:
        """A probe model's first-order readings ``(k, 3)`` for one ``theta`` (p,), in the reading frame, mm."""
        return self.layout.centres(self.predict(theta))

    __call__ = predict
