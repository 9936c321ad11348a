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
(:func:`make_model` by name, the parameters ordered by :class:`ParameterSpace`;
the thesis machine's :class:`LinearModel` and :class:`HTMModel` are its plug-in's,
``mtmcal_bayes.plugins.thesis``).

Layers, each importing only those below it (``tests/test_architecture.py``)::

    errors, units, progress, version, datasets,          foundation
    lazy_names
    arviz_import
    parameters, patterns                                 names of quantities and patterns
    campaign, observations, machine_time                 the data of a calibration, its machine minutes
    io                                                   files in and out
    models                                               forward models
    identification, inference, figure_style              DPRNT sphere fit, Bayesian engine, figure look
    posterior, planning, compensation, validation,       features
    simulation
    reporting                                            the report, built on posterior and planning
    fleets                                               many machines at once
    plugins                                              one machine's own code (the thesis'), imported by no layer
    api, cli                                             the Python API, the command line

Units: internally mm and rad; files and displays use µm, ″, mm, °.
"""

from .lazy_names import lazy_names
from .version import __version__

#: each public name and the module it comes from, imported on first use (PEP 562): ``import mtmcal_bayes``
#: loads no numpy, so the command line can choose the BLAS threads before numpy starts (:mod:`.cli`); the thesis
#: machine's models and identification come from its plug-in, by module name (no layer imports a plug-in)
_HOME = {
    **dict.fromkeys(("identify", "probe_fit", "simulate", "sensitivity", "sample", "closed_form", "report", "plan",
                     "ncgen", "instruments", "compensate", "sbc", "history", "simulate_history", "fleet", "design",
                     "next_run", "axis_lines", "isg_csv"), "api"),
    "CampaignAnalysis": "analysis", "Campaign": "campaign", "Truth": "campaign",
    "InputError": "errors", "MtmcalError": "errors", "ParameterError": "errors",
    "identify_ballbar": "plugins.thesis.identification", "identify_probe": "plugins.thesis.identification",
    "load_campaign": "io", "parse_campaign": "io", "read_dprnt": "io", "save_campaign": "io",
    "read_sigma_model_prior": "io", "write_sigma_model_prior": "io", "SigmaModelPrior": "sigma_prior",
    "MODELS": "models", "HTMModel": "plugins.thesis.kinematic", "LinearModel": "plugins.thesis.linear",
    "make_model": "models",
    "Observations": "observations", "DEVIATIONS": "parameters", "IDENTIFIABLE": "parameters",
    "ParameterSpace": "parameters", "ProgressEvent": "progress", "fit_sphere": "sphere",
}


__getattr__, __dir__ = lazy_names(__name__, _HOME, globals(), modules=("units",))


__all__ = [
    "identify", "probe_fit", "simulate", "sensitivity", "sample", "closed_form", "report", "plan", "ncgen",
    "instruments", "compensate", "sbc", "history", "simulate_history", "fleet", "design", "next_run", "axis_lines",
    "isg_csv",
    "Campaign", "CampaignAnalysis", "Truth", "load_campaign", "parse_campaign", "save_campaign", "read_dprnt",
    "SigmaModelPrior", "read_sigma_model_prior", "write_sigma_model_prior",
    "InputError", "MtmcalError", "ParameterError", "ProgressEvent",
    "identify_ballbar", "identify_probe", "fit_sphere",
    "MODELS", "LinearModel", "HTMModel", "make_model", "Observations",
    "DEVIATIONS", "IDENTIFIABLE", "ParameterSpace", "units", "__version__",
]
