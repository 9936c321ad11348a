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
from ..inference.identifiability import campaign_identifiability
from ..inference.log_posterior import LogPosterior
from ..iso import iso_symbol
from ..machines.plugins import provided
from ..parameters import QUANTITIES, quantity_unit, weights

#: probability of the reported interval
PROB = 0.95


@dataclass
class ClosedFormResult:
    """Mean, sd and 95 % interval of the reported quantities; ``summary`` indexed by quantity (display units)."""

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
                model: str = "linear", data: str = "ballbar") -> ClosedFormResult:
    """The Gaussian posterior of the quantities a campaign's ``data`` determine, with sigma_model fixed at
    ``sigma_model_um`` µm: the ones its machine's plug-in reports (the thesis machine: the eight of Table 4.5),
    else every deviation determined one by one and every combination determined only as a whole
    (:func:`~mtmcal_bayes.inference.identifiability.campaign_identifiability`)."""
    if model != "linear":
        raise ParameterError("model", f"the closed form is exact for the linear model only, not {model}")
    sigma = units.to_internal(sigma_model_um, "um")
    post = LogPosterior(campaign, "linear", fix_dx_BT=fix_dx_BT, sigma_model=sigma, data=data)
    g = gaussian_posterior(post, sigma_model=sigma)
    z = float(stats.norm.ppf(0.5 + PROB / 2))
    rows = {}
    for name, coefficients, unit in _reported(post, g.names):
        m, sd = g.linear_combination(coefficients)
        m, sd = units.from_internal(m, unit), units.from_internal(sd, unit)
        rows[name] = {"iso": iso_symbol(name), "mean": m, "sd": sd, "hdi_low": m - z * sd, "hdi_high": m + z * sd,
                      "unit": unit}
    return ClosedFormResult(pd.DataFrame.from_dict(rows, orient="index"), sigma_model_um, fix_dx_BT)


def _reported(post, names) -> list[tuple[str, dict, str]]:
    """``(name, coefficients, unit)`` of each reported quantity: the coefficients over ``names`` give its value in
    internal units of ``unit`` (a combination of lengths and angles scaled to its leading deviation's unit)."""
    own = provided(post.campaign.machine, "reported_quantities")
    if own is not None:
        return [(n, weights(n, names), QUANTITIES[n].unit) for n in own]
    ident = campaign_identifiability(post)
    per_display = {n: units.from_internal(1.0, quantity_unit(n)) for n in ident.deviations}
    out = [(n, {n: 1.0}, quantity_unit(n)) for n in ident.determined]
    out += [(c.name, {k: w * per_display[k] / units.from_internal(1.0, c.unit) for k, w in c.weights.items()}, c.unit)
            for c in ident.combinations]
    return out
