"""Forward models: parameter batches ``(n, p)`` to predicted eccentricities ``(n, m)``; the model registry.

Every model has ``name``, ``campaign``, ``space`` (:class:`~mtmcal_bayes.parameters.ParameterSpace`),
``observations`` (:class:`~mtmcal_bayes.observations.Observations`) and
``predict(theta)`` taking ``(n, p)`` in internal units (mm, rad) and returning
``(n, m)`` in mm, in one vectorised call.  :func:`make_model` builds one by
name; :data:`MODELS` is the one list of names every command offers.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from .kinematic import HTMModel, jacobian
from .linear import LinearModel, linear_coefficients

#: the kinematic (homogeneous-transform) models, which can also compensate NC programs
KINEMATIC_MODELS = ("htm-literal", "htm-thesis")
#: every forward model, by name: the thesis relations first
MODELS = ("linear",) + KINEMATIC_MODELS


def check_model(name: str, allowed=MODELS, parameter: str = "model") -> str:
    """``name`` if it is one of ``allowed``, else a :class:`ParameterError` listing them."""
    if name not in allowed:
        raise ParameterError(parameter, f"unknown model {name!r} (expected one of {', '.join(allowed)})")
    return name


def make_model(name: str, campaign, space=None):
    """The forward model ``name`` (one of :data:`MODELS`) for ``campaign``."""
    if check_model(name) == "linear":
        return LinearModel(campaign, space)
    return HTMModel(campaign, name, space)


def first_order_gap(campaign, theta: np.ndarray, space=None) -> float:
    """Largest difference, mm, between ``htm-thesis`` and its first order (``linear``) at ``theta`` (p,).

    Above the instrument accuracy, the deviations are too large for the linear model.
    """
    linear = LinearModel(campaign, space)
    kinematic = HTMModel(campaign, "htm-thesis", linear.space)
    return float(np.abs(kinematic.predict(theta) - linear.predict(theta)).max())


__all__ = ["MODELS", "KINEMATIC_MODELS", "check_model", "make_model", "first_order_gap", "LinearModel", "HTMModel",
           "jacobian", "linear_coefficients"]
