"""mtmcal_bayes — Bayesian uncertainty analysis of turn-mill machine-tool calibration.

The package reads a calibration campaign (ball-bar eccentricities, touch-probe
centres; :func:`load_campaign`, the thesis campaign built in), reproduces the
deterministic identification of the thesis (:func:`identify`), and predicts
eccentricities from parameter batches with forward models
(:class:`LinearModel`; parameters ordered by :class:`ParameterSpace`).

Units: internally mm and rad; files and displays use µm, ″, mm, °.
"""

from .campaign import Campaign, load_campaign, parse_campaign, save_campaign
from .errors import InputError, MtmcalError
from .identify import identify, identify_ballbar, identify_probe
from .models.linear import LinearModel
from .models.probe import fit_sphere
from .ncode import read_dprnt
from .observations import Observations
from .parameters import DEVIATIONS, IDENTIFIABLE, ParameterSpace

__version__ = "0.1.0"

__all__ = [
    "Campaign", "load_campaign", "parse_campaign", "save_campaign",
    "InputError", "MtmcalError",
    "identify", "identify_ballbar", "identify_probe",
    "LinearModel", "fit_sphere", "read_dprnt", "Observations",
    "DEVIATIONS", "IDENTIFIABLE", "ParameterSpace",
]
