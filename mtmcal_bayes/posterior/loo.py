"""Leave-one-out consistency: does each measurement agree with what the others predict?

PSIS-LOO (Vehtari, Gelman & Gabry 2017, through :func:`arviz.loo`) estimates, for every observed mean
``y_i``, the log predictive density of ``y_i`` under the posterior of all the *other* observations,
``elpd_loo_i = log p(y_i | y_−i)``, by Pareto-smoothed importance sampling of the posterior draws (the
pointwise log-likelihood is in the InferenceData's ``log_likelihood`` group).  Two things come out per
observation:

* **Pareto k**, how far the leave-one-out posterior is from the full one.  Above
  :data:`K_INFLUENTIAL` (0.7) the importance sampling is unreliable for that observation: leaving it out
  changes the posterior a lot, i.e. the observation is *influential* — nothing else in the campaign
  measures what it measures.  Where k is high the estimate is optimistic (too high an elpd_loo_i):
  checked against exact leave-one-out refits of the linear model (docs/report.md), PSIS gave −26 for the
  thesis campaign where the refits give −43.
* **elpd_loo_i**, compared with the median of its kind (eccentricities, probe readings): an observation
  :data:`ELPD_DROP` (4.5) or more below it is predicted by the others about as badly as a residual of
  three predictive sds (a Normal log density drops by z²/2) — a measurement that disagrees with the rest.
  With a high k the drop is understated, not invented, so a large drop is a signal either way; a small
  drop proves nothing where k is high.

On a nearly saturated design — about as many observed means as sampled parameters, as the thesis
campaign (10 means, 25 parameters) — every observation is influential: k > 0.7 for nearly all of them
without any error in the data, and a gross error in a measurement nothing else repeats is absorbed by
the parameters (and σ_model) it alone fixes.  LOO then has little power; it helps where measurements are
redundant (several runs seeing the same deviations), where one bad run stands out by its elpd_loo_i.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..arviz_import import az
from ..errors import MtmcalError
from ..parameters import DERIVED

#: Pareto k above which PSIS-LOO is unreliable for an observation: it is influential
K_INFLUENTIAL = 0.7
#: elpd_loo_i this far below the median of its kind flags a measurement the others do not predict (z²/2 at z = 3)
ELPD_DROP = 4.5
#: what the flags say
INFLUENTIAL_NOTE = "LOO unreliable here: the observation is influential"
OUTLIER_NOTE = "the other measurements do not predict it: check this measurement"

LOO_COLUMNS = ["variable", "elpd_loo", "pareto_k", "influential", "elpd_drop", "outlier", "note"]


@dataclass
class LooResult:
    """PSIS-LOO of every observation (``table``, one row per observation label, :data:`LOO_COLUMNS`) and
    the totals: ``elpd_loo`` with its standard error ``se``, the effective number of parameters ``p_loo``,
    the numbers of observations, sampled parameters and posterior draws."""

    table: pd.DataFrame
    elpd_loo: float
    se: float
    p_loo: float
    n_observations: int
    n_parameters: int
    n_draws: int

    @property
    def influential(self) -> list[str]:
        """Observations with Pareto k > 0.7."""
        return list(self.table.index[self.table["influential"]])

    @property
    def outliers(self) -> list[str]:
        """Observations whose elpd_loo lies :data:`ELPD_DROP` or more below the median of their kind."""
        return list(self.table.index[self.table["outlier"]])

    @property
    def saturated(self) -> bool:
        """Nearly saturated design: most observations are influential (each the only one fixing some parameters)."""
        return len(self.influential) > self.n_observations / 2

    def power_sentence(self) -> str:
        """What LOO can tell on this design, in words, with its numbers."""
        m, q, n_k = self.n_observations, self.n_parameters, len(self.influential)
        head = (f"PSIS-LOO: elpd_loo {self.elpd_loo:.1f} (se {self.se:.1f}), p_loo {self.p_loo:.1f}, Pareto k > "
                f"{K_INFLUENTIAL} for {n_k} of {m} observations ({q} sampled parameters, {self.n_draws} draws).")
        if self.saturated:
            return head + (
                f" With {m} observed means and {q} sampled parameters the design is nearly saturated: almost every "
                "observation is the only one fixing some combination of the parameters, so leaving it out changes "
                "the posterior a lot and its Pareto k is high even when nothing is wrong. There PSIS-LOO is "
                "unreliable (its elpd_loo is optimistic), and a gross error in a measurement that no other run "
                "repeats is absorbed by the parameters it alone fixes: LOO has little power here. It helps where "
                "measurements are redundant (several runs seeing the same deviations): there a bad run stands "
                f"out with an elpd_loo {ELPD_DROP:g} or more below the others'.")
        return head + (
            f" An observation with k > {K_INFLUENTIAL} is the only one fixing some parameters (LOO unreliable "
            f"there, its elpd_loo optimistic); one whose elpd_loo lies {ELPD_DROP:g} or more below the median of "
            "its kind is predicted by the other measurements about as badly as a three-sd residual.")

    def outlier_sentences(self) -> list[str]:
        """One sentence per flagged outlier."""
        return [f"{lab}: elpd_loo {r['elpd_loo']:.1f}, {r['elpd_drop']:.1f} below the median of its kind "
                f"(Pareto k {r['pareto_k']:.2f}) — {OUTLIER_NOTE}" for lab, r in self.table.iterrows() if r["outlier"]]

    def to_text(self) -> str:
        lines = ["Leave-one-out consistency (PSIS-LOO):", "  " + self.power_sentence()]
        lines += [f"  {s}" for s in self.outlier_sentences()] or ["  No observation stands out by its elpd_loo."]
        return "\n".join(lines)

    def to_json(self) -> dict:
        return {"elpd_loo": self.elpd_loo, "se": self.se, "p_loo": self.p_loo, "n_observations": self.n_observations,
                "n_parameters": self.n_parameters, "n_draws": self.n_draws,
                "observations": self.table.reset_index().to_dict(orient="records")}


def _n_parameters(idata) -> int:
    return len([v for v in idata.posterior.data_vars if v not in DERIVED])


def loo_check(idata) -> LooResult:
    """PSIS-LOO of every observation variable of ``idata`` (``eccentricity``, ``probe_reading``, ``rtest_reading``).

    ``idata`` needs a ``log_likelihood`` group (every posterior written by this version has one).  ArviZ's
    warning about high Pareto k is silenced: the table and :meth:`LooResult.power_sentence` say it.
    """
    if "log_likelihood" not in idata.groups():
        raise MtmcalError("this posterior has no log_likelihood group (written by an older version): "
                          "sample it again for the leave-one-out check")
    frames, p_loo = [], 0.0
    for var in idata.log_likelihood.data_vars:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            res = az.loo(idata, var_name=var, pointwise=True)
        elpd_i = np.asarray(res.loo_i, dtype=float)
        k = np.asarray(res.pareto_k, dtype=float)
        (dim,) = [d for d in idata.log_likelihood[var].dims if d not in ("chain", "draw")]
        drop = np.median(elpd_i) - elpd_i
        frames.append(pd.DataFrame({"variable": var, "elpd_loo": elpd_i, "pareto_k": k,
                                    "influential": k > K_INFLUENTIAL, "elpd_drop": drop, "outlier": drop >= ELPD_DROP},
                                   index=pd.Index(idata.log_likelihood[dim].values.astype(str), name="observation")))
        p_loo += float(res.p_loo)
    table = pd.concat(frames)
    table["note"] = ["; ".join(n for n, flag in ((OUTLIER_NOTE, o), (INFLUENTIAL_NOTE, i)) if flag)
                     for o, i in zip(table["outlier"], table["influential"])]
    elpd = table["elpd_loo"].to_numpy()
    n_draws = idata.posterior.sizes["chain"] * idata.posterior.sizes["draw"]
    return LooResult(table[LOO_COLUMNS], float(elpd.sum()), float(np.sqrt(len(elpd) * np.var(elpd))), p_loo,
                     len(elpd), _n_parameters(idata), int(n_draws))
