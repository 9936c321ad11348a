"""A prior of the model-discrepancy scales learnt elsewhere — by a fleet of machines of one type — for one campaign.

By default a campaign's posterior samples ``sigma_model`` (ball bar) and ``sigma_model_probe`` (touch probe) under
an assumed half-normal prior (:mod:`mtmcal_bayes.inference.priors`), and most of every interval's width comes from
that assumption.  A :class:`SigmaModelPrior` replaces it by what other machines of the type have shown: per scale a
log-normal, ``ln σ ~ Normal(ln median, log_sd²)``.  It is read and written by
:mod:`mtmcal_bayes.io.sigma_prior_file` (format ``mtmcal-sigma-model-prior/1``, ``docs/inference.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from . import units
from .parameters import SCALE_LABEL

#: the one distribution a learnt scale may have
DISTRIBUTION = "lognormal"
#: narrowest and widest sd of ln σ: below 1 % the prior fixes σ (fix it instead), above 3 (a factor 20 per sd) it
#: says nothing was learnt
LOG_SD_RANGE = (0.01, 3.0)
#: largest median, µm (as for a fixed σ_model)
MEDIAN_MAX_UM = 1000.0


@dataclass(frozen=True)
class SigmaModelPrior:
    """Learnt log-normal priors of the discrepancy scales.

    Attributes
    ----------
    scales : scale name (``"sigma_model"``, optionally ``"sigma_model_probe"``) → ``(median_um, log_sd)``: the
        median of σ in µm and the sd of ln σ.  A scale not named keeps the assumed default prior.
    source : where it was learnt, free text (``fleet plant/: type "INTEGREX i-200", 3 machines, 14 campaigns``);
        the uncertainty budget states it
    """

    scales: dict[str, tuple[float, float]]
    source: str

    def __post_init__(self):
        if not isinstance(self.source, str) or not self.source.strip():
            raise ValueError("a learnt σ_model prior needs its source (where it was learnt)")
        if "sigma_model" not in self.scales:
            raise ValueError("a learnt σ_model prior needs the ball bar's scale, sigma_model")
        clean = {}
        for name, pair in self.scales.items():
            if name not in SCALE_LABEL:
                raise ValueError(f"{name!r} is not a discrepancy scale (expected one of {', '.join(SCALE_LABEL)})")
            median, log_sd = (float(x) for x in pair)
            if problem := median_problem(median) or log_sd_problem(log_sd):
                raise ValueError(f"{name}: {problem}")
            clean[name] = (median, log_sd)
        object.__setattr__(self, "scales", clean)

    def __hash__(self) -> int:  # the analyses of a campaign are cached by it (CampaignAnalysis.key)
        return hash((tuple(sorted(self.scales.items())), self.source))

    def frozen(self, name: str):
        """The :mod:`scipy.stats` log-normal of scale ``name``, internal units (mm)."""
        from scipy import stats

        median, log_sd = self.scales[name]
        return stats.lognorm(s=log_sd, scale=units.to_internal(median, "um"))

    def describe(self, name: str) -> str:
        """``LogNormal(median 2.74 µm, log sd 0.34)``."""
        median, log_sd = self.scales[name]
        return f"LogNormal(median {median:g} µm, log sd {log_sd:g})"


def median_problem(median_um: float) -> str | None:
    """What is wrong with a median of σ (µm), or None."""
    if not (math.isfinite(median_um) and 0.0 < median_um <= MEDIAN_MAX_UM):
        return f"median_um must be positive and at most {MEDIAN_MAX_UM:g} µm, got {median_um:g}"
    return None


def log_sd_problem(log_sd: float) -> str | None:
    """What is wrong with an sd of ln σ, or None."""
    low, high = LOG_SD_RANGE
    if not (math.isfinite(log_sd) and log_sd > 0.0):
        return f"log_sd must be positive, got {log_sd:g}"
    if log_sd < low:
        return f"log_sd {log_sd:g} is below {low:g}: a prior that narrow fixes σ_model (fix it instead)"
    if log_sd > high:
        return f"log_sd {log_sd:g} is above {high:g} (a factor {math.exp(high):.0f} per sd): that is not a learnt scale"
    return None
