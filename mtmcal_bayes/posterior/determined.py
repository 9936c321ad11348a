"""What a described machine's campaign determines, beside its posterior (SPEC §19).

The identifiability is computed from the campaign's Jacobian at the home pose (deviations and nuisance terms),
with the T ball taken as centred, as the thesis does (its centring check holds it to ±1 µm;
:func:`~mtmcal_bayes.inference.identifiability.identifiability`); each named combination gets its posterior
from the draws.
"""

from __future__ import annotations

import numpy as np

from ..arviz_import import az
from ..inference.identifiability import Identifiability, identifiability
from ..inference.results import HDI_PROB
from ..models import jacobian

#: nuisance terms the set-up fixes: the T ball is centred before the runs (thesis Sec 4.2.2)
CENTRED = ("xT", "yT", "zT")


def campaign_identifiability(post) -> Identifiability:
    """The identifiability of ``post``'s campaign and data (its forward model's Jacobian at zero)."""
    space = post.space
    known = [b for b in CENTRED if any(p.base == b for p in space.parameters)]
    return identifiability(jacobian(post.forward), space, known=known)


def combination_summaries(ident: Identifiability, idata) -> list[dict]:
    """Each combination with its posterior: ``{"name", "weights", "mean", "sd", "hdi_low", "hdi_high", "unit"}``
    (display units; weights per display unit)."""
    out = []
    for c in ident.combinations:
        draws = sum(w * np.asarray(idata.posterior[n]) for n, w in c.weights.items())
        flat = np.ravel(draws)
        low, high = az.hdi(flat, hdi_prob=HDI_PROB)
        out.append({"name": c.name, "weights": dict(c.weights), "mean": float(flat.mean()),
                    "sd": float(flat.std(ddof=1)), "hdi_low": float(low), "hdi_high": float(high), "unit": c.unit})
    return out
