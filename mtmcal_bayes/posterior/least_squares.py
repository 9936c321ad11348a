"""The deterministic identification of a described machine: linearised least squares (SPEC §19).

The thesis machine keeps the thesis' formulas (``identify``); a described machine has none, and gets what a
calibration engineer would compute: the least-squares solution of the chain's first order at the home pose, the
nuisance terms held to their set-up knowledge (their priors act as pseudo-observations), the deviations free (no
prior), at a fixed σ_model.  Only what the campaign determines is stated — each deviation determined one by one
and each identifiable combination (:func:`~mtmcal_bayes.inference.identifiability.campaign_identifiability`), all of
them estimable functions, whose estimate and covariance do not depend on the generalised inverse chosen.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .. import units
from ..inference.analytic import linearisation
from ..inference.identifiability import Identifiability


@dataclass
class LeastSquares:
    """Estimates of the determined deviations and combinations: ``table`` with columns ``quantity, estimate, u,
    unit`` (display units), at ``sigma_model_um``."""

    table: pd.DataFrame
    sigma_model_um: float

    def to_json(self) -> dict:
        return {"sigma_model_um": self.sigma_model_um,
                "estimates": {r["quantity"]: {"estimate": r["estimate"], "u": r["u"], "unit": r["unit"]}
                              for _, r in self.table.iterrows()}}


def least_squares(post, ident: Identifiability, sigma_model: float) -> LeastSquares:
    """The least-squares identification of ``post``'s campaign and data at ``sigma_model`` (mm, every scale)."""
    A, c = linearisation(post)
    V = post.likelihood.variance_at(sigma_model)
    names = post.space.names
    deviation = np.array([p.group == "deviation" for p in post.space.parameters])
    priors = post.priors.priors[:post.p]
    prior_prec = np.where(deviation, 0.0, 1.0 / np.array([q.sd for q in priors]) ** 2)
    centre = np.where(deviation, 0.0, np.array([q.centre for q in priors]))
    scale = post.space.display_scale()  # solved in display units (µm, ″): one footing for every column
    Ad = A * scale
    prec = Ad.T @ (Ad / V[:, None]) + np.diag(prior_prec * scale**2)
    rhs = Ad.T @ ((post.likelihood.y - c) / V) + prior_prec * scale * centre
    cov = np.linalg.pinv(prec, hermitian=True)
    est = cov @ rhs
    rows = []
    quantities = [(n, {n: 1.0}) for n in ident.determined] + [(k.name, k.weights) for k in ident.combinations]
    for name, weights in quantities:
        w = np.zeros(len(names))
        for n, v in weights.items():
            w[names.index(n)] = v
        unit = next(p.unit for p in post.space.parameters if p.name == next(iter(weights)))
        rows.append({"quantity": name, "estimate": float(w @ est), "u": float(np.sqrt(w @ cov @ w)), "unit": unit})
    return LeastSquares(pd.DataFrame(rows, columns=["quantity", "estimate", "u", "unit"]),
                        float(units.from_internal(sigma_model, "um")))


@dataclass
class DescribedIdentification:
    """``identify`` on a described machine: what its campaign determines and the least-squares estimates, at
    σ_model = 0 (the measurements' own scatter and the instruments' accuracy: the deterministic method's view)."""

    campaign: object
    data: str
    ident: Identifiability
    estimates: LeastSquares

    def to_json(self) -> dict:
        return {"campaign": self.campaign.source, "machine": self.campaign.machine.description.configuration,
                "data": self.data, "identifiability": self.ident.as_dict(), **self.estimates.to_json()}

    def to_text(self) -> str:
        lines = [f"Least-squares identification of {self.campaign.source} ({self.campaign.machine.description.configuration}, "
                 f"{self.data} data; the chain's first order, the nuisance terms within their set-up knowledge, "
                 f"σ_model = {self.estimates.sigma_model_um:g} µm)"]
        for _, r in self.estimates.table.iterrows():
            lines.append(f"  {r['quantity']:34s} {r['estimate']:10.3f} ± {r['u']:.3f} {units.SYMBOL[r['unit']]}")
        if self.ident.undetermined:
            lines.append("  not determined by this campaign: " + ", ".join(self.ident.undetermined))
        return "\n".join(lines)


def identify_described(campaign, data: str) -> DescribedIdentification:
    """The least-squares identification of a described machine's campaign from its ``data``."""
    from ..inference.log_posterior import LogPosterior
    from ..inference.identifiability import campaign_identifiability

    post = LogPosterior(campaign, "linear", data=data, sigma_model=0.0)
    ident = campaign_identifiability(post)
    return DescribedIdentification(campaign, data, ident, least_squares(post, ident, 0.0))
