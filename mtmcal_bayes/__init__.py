"""mtmcal_bayes — Bayesian uncertainty analysis of turn-mill machine-tool calibration.

The package reads a calibration campaign (ball-bar eccentricities, touch-probe
centres; :func:`load_campaign`, the thesis campaign built in), reproduces the
thesis' deterministic identification (:func:`identify`), samples the posterior
of the deviations and nuisance offsets (:func:`sample`), writes a report
(:func:`report`), plans the next measurement (:func:`plan`), designs whole campaigns and
guides their measuring (:func:`design`, :func:`next_run`), compensates NC
programs (:func:`compensate`) and checks its own inference (:func:`sbc`).
Each of these is the function a command of ``mtmcal-bayes`` calls
(:mod:`mtmcal_bayes.api`); they return objects with ``to_text()`` and
``to_json()``, the command's two outputs.

Forward models predict eccentricities from parameter batches ``(n, p)``
(:class:`LinearModel`, :class:`HTMModel`; :func:`make_model` by name, the
parameters ordered by :class:`ParameterSpace`).

Layers, each importing only those below it (``tests/test_architecture.py``)::

    errors, units, progress, version, datasets,          foundation
    arviz_import
    parameters, patterns                                 names of quantities and patterns
    campaign, observations, machine_time                 the data of a calibration, its machine minutes
    io                                                   files in and out
    models                                               forward models
    identification, inference, figure_style              thesis method, Bayesian engine, figure look
    posterior, planning, compensation, validation,       features
    simulation
    reporting                                            the report, built on posterior and planning
    api, cli                                             the Python API, the command line

Units: internally mm and rad; files and displays use µm, ″, mm, °.
"""

from . import units
from .api import (
    closed_form,
    compensate,
    design,
    fleet,
    history,
    identify,
    instruments,
    ncgen,
    next_run,
    plan,
    probe_fit,
    report,
    sample,
    sbc,
    sensitivity,
    simulate,
    simulate_history,
)
from .analysis import CampaignAnalysis
from .campaign import Campaign, Truth
from .errors import InputError, MtmcalError, ParameterError
from .identification import identify_ballbar, identify_probe
from .io import load_campaign, parse_campaign, read_dprnt, save_campaign
from .models import MODELS, HTMModel, LinearModel, make_model
from .observations import Observations
from .parameters import DEVIATIONS, IDENTIFIABLE, ParameterSpace
from .progress import ProgressEvent
from .sphere import fit_sphere
from .version import __version__

__all__ = [
    "identify", "probe_fit", "simulate", "sensitivity", "sample", "closed_form", "report", "plan", "ncgen",
    "instruments", "compensate", "sbc", "history", "simulate_history", "fleet", "design", "next_run",
    "Campaign", "CampaignAnalysis", "Truth", "load_campaign", "parse_campaign", "save_campaign", "read_dprnt",
    "InputError", "MtmcalError", "ParameterError", "ProgressEvent",
    "identify_ballbar", "identify_probe", "fit_sphere",
    "MODELS", "LinearModel", "HTMModel", "make_model", "Observations",
    "DEVIATIONS", "IDENTIFIABLE", "ParameterSpace", "units", "__version__",
]
