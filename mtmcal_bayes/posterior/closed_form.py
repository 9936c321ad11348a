"""The instant answer: the closed-form Gaussian posterior of the linear model at a fixed sigma_model.

Exact for the ``linear`` model when sigma_model is known (SPEC §5); the
sampler's posterior marginalises sigma_model instead.  The 95 % interval of a
Gaussian is its mean ± z·sd with z = Φ⁻¹(0.975), which is also its HDI.
"""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd
from scipy import stats

from .. import units
from ..errors import ParameterError
from ..inference.analytic import gaussian_posterior
from ..inference.log_posterior import LogPosterior
from ..iso import iso_symbol
from ..parameters import IDENTIFIABLE, QUANTITIES, weights

#: probability of the reported interval
PROB = 0.95


@dataclass
class ClosedFormResult:
    """Mean, sd and 95 % interval of the eight quantities; ``summary`` indexed by quantity (display units)."""

    summary: pd.DataFrame
    sigma_model_um: float
    fix_dx_BT: bool = False

    def to_json(self) -> dict:
        return {"model": "linear", "closed_form": True, "sigma_model_um": self.sigma_model_um,
                "summary": {n: {c: (r[c] if c == "unit" else (r[c] if isinstance(r[c], str) else None) if c == "iso"
                                    else float(r[c])) for c in self.summary.columns}
                            for n, r in self.summary.iterrows()}}

    def to_text(self) -> str:
        lines = [f"Closed-form Gaussian posterior, linear model, sigma_model fixed at {self.sigma_model_um:g} µm"]
        for n, r in self.summary.iterrows():
            lines.append(f"  {n:18s} {r['iso'] if isinstance(r['iso'], str) else '—':10s} {r['mean']:9.2f} ± {r['sd']:6.2f} {units.SYMBOL[r['unit']]}   "
                         f"95 %: [{r['hdi_low']:.2f}, {r['hdi_high']:.2f}]")
        return "\n".join(lines)


def closed_form(campaign, *, sigma_model_um: float = 0.0, fix_dx_BT: bool = False,
                model: str = "linear") -> ClosedFormResult:
    """The Gaussian posterior of the eight quantities with sigma_model fixed at ``sigma_model_um`` µm."""
    if model != "linear":
        raise ParameterError("model", f"the closed form is exact for the linear model only, not {model}")
    sigma = units.to_internal(sigma_model_um, "um")
    post = LogPosterior(campaign, "linear", fix_dx_BT=fix_dx_BT, sigma_model=sigma)
    g = gaussian_posterior(post, sigma_model=sigma)
    z = float(stats.norm.ppf(0.5 + PROB / 2))
    rows = {}
    for name in IDENTIFIABLE:
        m, sd = g.linear_combination(weights(name, g.names))
        unit = QUANTITIES[name].unit
        m, sd = units.from_internal(m, unit), units.from_internal(sd, unit)
        rows[name] = {"iso": iso_symbol(name), "mean": m, "sd": sd, "hdi_low": m - z * sd, "hdi_high": m + z * sd,
                      "unit": unit}
    return ClosedFormResult(pd.DataFrame.from_dict(rows, orient="index"), sigma_model_um, fix_dx_BT)
