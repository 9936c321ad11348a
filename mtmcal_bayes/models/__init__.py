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
from ..machines.space import described_space
from ..parameters import ParameterSpace
from .chain_thesis import ThesisChainModel
from .described import ChainBallbarModel, ChainProbeModel, FirstOrderModel
from .joint import JointModel
from .kinematic import HTMModel, jacobian
from .linear import LinearModel, linear_coefficients
from .probe_model import LinearProbeModel, ProbeModel

#: the kinematic (homogeneous-transform) models, which can also compensate NC programs
KINEMATIC_MODELS = ("htm-literal", "htm-thesis")
#: the kinematic chain of any described machine (SPEC §19); on the thesis machine, ``htm-literal``
CHAIN = "chain"
#: every forward model, by name: the thesis relations first
MODELS = ("linear",) + KINEMATIC_MODELS + (CHAIN,)
#: the models of a described machine: its chain and the chain's first order
DESCRIBED_MODELS = ("linear", CHAIN)


def check_model(name: str, allowed=MODELS, parameter: str = "model") -> str:
    """``name`` if it is one of ``allowed``, else a :class:`ParameterError` listing them."""
    if name not in allowed:
        raise ParameterError(parameter, f"unknown model {name!r} (expected one of {', '.join(allowed)})")
    return name


#: which measurements a likelihood uses: ball-bar eccentricities, touch-probe readings, or both
DATA = ("ballbar", "probe", "both")


def check_data(data: str, campaign=None, parameter: str = "data") -> str:
    """``data`` if it is one of :data:`DATA` (and ``campaign`` has probe readings when it asks for them)."""
    if data not in DATA:
        raise ParameterError(parameter, f"unknown data {data!r} (expected one of {', '.join(DATA)})")
    if data != "ballbar" and campaign is not None and not campaign.has_probe_readings():
        where = "[[probe.runs]]" if campaign.machine.described else "[probe.c_axis] or [probe.b_axis.styli]"
        raise ParameterError(parameter, f"{data!r} needs touch-probe readings, and the campaign {campaign.source} "
                             f"has no {where}")
    if data != "probe" and campaign is not None and campaign.machine.described and not campaign.ballbar.runs:
        raise ParameterError(parameter, f"{data!r} needs ball-bar runs, and the campaign {campaign.source} has no "
                             "[[ballbar.runs]] (a probe-only campaign: use the probe data)")
    return data


def make_model(name: str, campaign, space=None, data: str = "ballbar", *, observations=None, probe_layout=None):
    """The forward model ``name`` (one of :data:`MODELS`) for ``campaign``'s ``data`` (one of :data:`DATA`);
    ``observations``, ``probe_layout``: the campaign's ball-bar :class:`~mtmcal_bayes.observations.Observations` and
    its :class:`~.probe_model.ProbeLayout` (the probe's readings), if already made."""
    check_model(name)
    check_data(data, campaign)
    if campaign.machine.described:
        return _described_model(name, campaign, space, data=data, observations=observations)
    if space is None:
        space = ParameterSpace.for_campaign(campaign, data=data)
    parts = []
    if data in ("ballbar", "both"):
        parts.append(LinearModel(campaign, space, observations=observations) if name == "linear"
                     else ThesisChainModel(campaign, space, observations=observations) if name == CHAIN
                     else HTMModel(campaign, name, space, observations=observations))
    if data in ("probe", "both"):
        probe = (LinearProbeModel(campaign, space, probe_layout) if name == "linear"
                 else ProbeModel(campaign, "htm-literal" if name == CHAIN else name, space, probe_layout))
        if name == CHAIN:
            probe.name = CHAIN  # the thesis machine's chain is htm-literal, its probe model too
        parts.append(probe)
    return parts[0] if len(parts) == 1 else JointModel(parts)


def _described_model(name: str, campaign, space, *, data: str, observations):
    """The ``chain`` or ``linear`` model of a described machine's campaign."""
    check_model(name, DESCRIBED_MODELS)
    if space is None:
        space = described_space(campaign, data=data)
    parts = []
    if data in ("ballbar", "both"):
        parts.append(ChainBallbarModel(campaign, space, observations=observations))
    if data in ("probe", "both"):
        parts.append(ChainProbeModel(campaign, space))
    if name == "linear":
        parts = [FirstOrderModel(p) for p in parts]
    return parts[0] if len(parts) == 1 else JointModel(parts)


def first_order_gap(campaign, theta: np.ndarray, space=None, *, observations=None) -> float:
    """Largest difference, mm, between ``htm-thesis`` and its first order (``linear``) at ``theta`` (p,)
    (``observations``: the campaign's ball-bar observations, if already made).

    Above the instrument accuracy, the deviations are too large for the linear model.
    """
    if campaign.machine.described:  # the chain against its own first order
        if not campaign.ballbar.runs:
            return 0.0
        chain = ChainBallbarModel(campaign, space, observations=observations)
        return float(np.abs(chain.predict(theta) - FirstOrderModel(chain).predict(theta)).max())
    linear = LinearModel(campaign, space, observations=observations)
    kinematic = HTMModel(campaign, "htm-thesis", linear.space, observations=linear.observations)
    return float(np.abs(kinematic.predict(theta) - linear.predict(theta)).max())


__all__ = ["MODELS", "KINEMATIC_MODELS", "CHAIN", "DESCRIBED_MODELS", "ThesisChainModel", "ChainBallbarModel",
           "ChainProbeModel", "FirstOrderModel", "DATA", "check_model", "check_data", "make_model", "ProbeModel",
           "LinearProbeModel", "JointModel", "first_order_gap", "LinearModel", "HTMModel",
           "jacobian", "linear_coefficients"]
