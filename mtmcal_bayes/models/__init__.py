"""Forward models: parameter batches ``(n, p)`` to predicted eccentricities ``(n, m)``.

Every model has ``name``, ``campaign``, ``space`` (:class:`~mtmcal_bayes.parameters.ParameterSpace`),
``observations`` (:class:`~mtmcal_bayes.observations.Observations`) and
``predict(theta)`` taking ``(n, p)`` in internal units (mm, rad) and returning
``(n, m)`` in mm, in one vectorised call.  :func:`make_model` builds one by name.
"""

from __future__ import annotations

from ..errors import MtmcalError
from .kinematic import HTMModel, jacobian
from .linear import LinearModel, linear_coefficients

MODELS = ("linear", "htm-literal", "htm-thesis")


def make_model(name: str, campaign, space=None):
    """The forward model ``name`` (one of :data:`MODELS`) for ``campaign``."""
    if name == "linear":
        return LinearModel(campaign, space)
    if name in ("htm-literal", "htm-thesis"):
        return HTMModel(campaign, name, space)
    raise MtmcalError(f"unknown model {name!r} (expected one of {', '.join(MODELS)})")


__all__ = ["MODELS", "make_model", "LinearModel", "HTMModel", "jacobian", "linear_coefficients"]
