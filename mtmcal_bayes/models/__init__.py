"""Forward models: parameter batches ``(n, p)`` to predicted eccentricities ``(n, m)``; the model registry.

Every model has ``name``, ``campaign``, ``space`` (:class:`~mtmcal_bayes.parameters.ParameterSpace`),
``observations`` (:class:`~mtmcal_bayes.observations.Observations`) and
``predict(theta)`` taking ``(n, p)`` in internal units (mm, rad) and returning
``(n, m)`` in mm, in one vectorised call; a model whose ``predict`` also carries complex parameters (a
complex-step derivative) says so with ``complex_step = True``.  :func:`make_model` builds one by
name; :data:`MODELS` is the one list of names every command offers.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..machines.plugins import provided
from ..machines.space import described_space
from ..parameters import DATA_INSTRUMENTS, ParameterSpace, ballbar_probe_data, data_instruments
from .ballbar import BallbarModel, ChainBallbarModel
from .chain_models import ChainProbeModel, FirstOrderModel
from .jacobian import jacobian, jacobian_at_zero
from .joint import JointModel
from .probe import ProbeModel
from .rtest import RTestModel

#: the kinematic (homogeneous-transform) models of the thesis machine, which can also compensate NC programs (their
#: code is the thesis plug-in's: ``mtmcal_bayes.plugins.thesis``)
KINEMATIC_MODELS = ("htm-literal", "htm-thesis")
#: the kinematic chain of any described machine (SPEC §19); on the thesis machine, ``htm-literal``
CHAIN = "chain"
#: every forward model any machine offers, by name: the thesis relations first (the command line's choices; a
#: machine offers its own, :func:`models_of`)
MODELS = ("linear",) + KINEMATIC_MODELS + (CHAIN,)
#: the engine's models, on every machine: its chain and the chain's first order (a plug-in may offer others)
ENGINE_MODELS = ("linear", CHAIN)
#: the name kept for scripts that imported it
DESCRIBED_MODELS = ENGINE_MODELS


def check_model(name: str, allowed=MODELS, parameter: str = "model") -> str:
    """``name`` if it is one of ``allowed``, else a :class:`ParameterError` listing them."""
    if name not in allowed:
        raise ParameterError(parameter, f"unknown model {name!r} (expected one of {', '.join(allowed)})")
    return name


def models_of(machine) -> tuple[str, ...]:
    """The forward models ``machine`` offers: its plug-ins' (the thesis machine: :data:`MODELS`), else the engine's."""
    return provided(machine, "models", ENGINE_MODELS)


def default_kinematic_model(machine) -> str:
    """The default kinematic model of ``machine``: its plug-in's (the thesis machine: ``htm-thesis``), else ``chain``."""
    return provided(machine, "kinematic_model", CHAIN)


#: which measurements a likelihood uses: ball-bar eccentricities, touch-probe readings, both of them, R-test
#: readings, the R-test with one of the others, or every instrument the campaign has
#: (:data:`~mtmcal_bayes.parameters.DATA_INSTRUMENTS`)
DATA = tuple(DATA_INSTRUMENTS)


def default_data(campaign) -> str:
    """The data a likelihood of ``campaign`` takes when none is asked for: what its machine's plug-in states (the
    thesis machine: the ball bar) where the campaign has those instruments, else every instrument it has readings of
    (``"all"`` where it has R-test runs)."""
    stated = provided(campaign.machine, "default_data")
    if stated is not None and set(data_instruments(stated, campaign)) <= set(data_instruments("all", campaign)):
        return stated
    if campaign.has_rtest_readings():
        return "all"
    return "both" if campaign.ballbar.runs and campaign.has_probe_readings() else \
        "probe" if not campaign.ballbar.runs else "ballbar"


def check_data(data: str, campaign=None, parameter: str = "data") -> str:
    """``data`` if it is one of :data:`DATA` (and ``campaign`` has the readings it asks for)."""
    if data not in DATA:
        raise ParameterError(parameter, f"unknown data {data!r} (expected one of {', '.join(DATA)})")
    used = data_instruments(data, campaign)
    if campaign is not None and not used:
        raise ParameterError(parameter, f"{data!r}: the campaign {campaign.source} has no readings of any instrument")
    if "rtest" in used and campaign is not None and not campaign.has_rtest_readings():
        raise ParameterError(parameter, f"{data!r} needs R-test readings, and the campaign {campaign.source} has no "
                             "[[rtest.runs]]")
    if "rtest" in used and campaign is not None and campaign.machine.description is None:
        raise ParameterError(parameter, f"{data!r}: the R-test model needs the machine's description, and the "
                             f"campaign {campaign.source} names none")
    if DATA_INSTRUMENTS[data] is not None and ("ballbar" in used or "probe" in used):
        return _check_ballbar_probe(ballbar_probe_data(used), data, campaign, parameter)
    return data


def _check_ballbar_probe(part: str, data: str, campaign, parameter: str) -> str:
    """The checks of the ball-bar and probe part ``part`` (``"ballbar"``, ``"probe"``, ``"both"``) of ``data``."""
    if part != "ballbar" and campaign is not None and not campaign.has_probe_readings():
        where = provided(campaign.machine, "probe_sections", "[[probe.runs]]")
        raise ParameterError(parameter, f"{data!r} needs touch-probe readings, and the campaign {campaign.source} "
                             f"has no {where}")
    if part != "probe" and campaign is not None and not campaign.ballbar.runs and (
            campaign.has_probe_readings() or campaign.has_rtest_readings()):
        use = ("a probe-only campaign: use the probe data" if not campaign.has_rtest_readings() else
               "use the data of the instruments it has, e.g. all")
        raise ParameterError(parameter, f"{data!r} needs ball-bar runs, and the campaign {campaign.source} has no "
                             f"[[ballbar.runs]] ({use})")
    return data


def make_model(name: str, campaign, space=None, data: str = "ballbar", *, observations=None, probe_layout=None):
    """The forward model ``name`` (one of the machine's :func:`models_of`) for ``campaign``'s ``data`` (one of
    :data:`DATA`); ``observations``, ``probe_layout``: the campaign's ball-bar
    :class:`~mtmcal_bayes.observations.Observations` and its probe layout (the probe's readings, the plug-in's
    ``probe_layout``), if already made.  A machine's plug-in may build its own models (the thesis' campaign
    format)."""
    check_model(name, models_of(campaign.machine))
    check_data(data, campaign)
    return build_model(name, campaign, space, data, observations=observations, probe_layout=probe_layout)


def build_model(name: str, campaign, space=None, data: str = "ballbar", *, observations=None, probe_layout=None):
    """:func:`make_model` without its checks of ``name`` and ``data``: for a caller that checked them against the
    campaign it plans for and builds the rows of other campaigns (a planner's candidate runs).  The ball-bar and
    probe part is the machine's (its plug-in's where it builds its own), the R-test part the engine's on every
    machine."""
    used = data_instruments(data, campaign)
    part = ballbar_probe_data(used)
    if "rtest" not in used:  # the ball bar, the probe or both, by the name a machine's own models know ("all" too)
        build = provided(campaign.machine, "make_model", _engine_model)
        return build(name, campaign, space, part or data, observations=observations, probe_layout=probe_layout)
    if space is None:
        own = provided(campaign.machine, "make_model") is not None  # its own models lay out their own space
        space = ParameterSpace.for_campaign(campaign, data=data) if own else described_space(campaign, data=data)
    parts = []
    if part is not None:
        build = provided(campaign.machine, "make_model", _engine_model)
        first = build(name, campaign, space, part, observations=observations, probe_layout=probe_layout)
        parts += first.parts if isinstance(first, JointModel) else [first]
    rtest = RTestModel(campaign, space)
    parts.append(FirstOrderModel(rtest) if name == "linear" else rtest)
    return parts[0] if len(parts) == 1 else JointModel(parts)


def _engine_model(name: str, campaign, space, data: str, *, observations, probe_layout=None):
    """The ``chain`` or ``linear`` model of a campaign of any described machine."""
    if space is None:
        space = described_space(campaign, data=data)
    parts = []
    used = data_instruments(data, campaign)
    if "ballbar" in used:
        parts.append(ChainBallbarModel(campaign, space, observations=observations))
    if "probe" in used:
        parts.append(ProbeModel(campaign, space, layout=probe_layout))
    if name == "linear":
        parts = [FirstOrderModel(p) for p in parts]
    return parts[0] if len(parts) == 1 else JointModel(parts)


def first_order_gap(campaign, theta: np.ndarray, space=None, *, observations=None) -> float:
    """Largest difference, mm, between the machine's kinematic model and its first order (``linear``) at ``theta``
    (p,) (``observations``: the campaign's ball-bar observations, if already made).

    Above the instrument accuracy, the deviations are too large for the linear model.
    """
    if not campaign.ballbar.runs:  # a probe-only campaign: the gap is of the ball bar's eccentricities
        return 0.0
    gap = provided(campaign.machine, "first_order_gap", _engine_gap)
    return gap(campaign, theta, space, observations=observations)


def _engine_gap(campaign, theta: np.ndarray, space=None, *, observations=None) -> float:
    """The chain against its own first order."""
    chain = ChainBallbarModel(campaign, space, observations=observations)
    return float(np.abs(chain.predict(theta) - FirstOrderModel(chain).predict(theta)).max())


__all__ = ["MODELS", "KINEMATIC_MODELS", "CHAIN", "ENGINE_MODELS", "DESCRIBED_MODELS", "BallbarModel", "ChainBallbarModel",
           "ProbeModel", "ChainProbeModel", "RTestModel", "FirstOrderModel", "DATA", "check_model", "check_data",
           "default_data", "make_model", "build_model",
           "models_of", "default_kinematic_model", "JointModel", "first_order_gap", "jacobian",
           "jacobian_at_zero"]
