"""The thesis machine's own values of a compensation: its ball-bar values (Table 4.5) and its default posterior."""

from __future__ import annotations

import numpy as np

from .... import units
from ....compensation.values import Draws
from ....errors import MtmcalError
from ....inference.analytic import gaussian_posterior
from ....inference.log_posterior import LogPosterior
from ....compensation.options import N_DRAWS, SIGMA_MODEL_UM
from ..identification import identify
from ....parameters import DERIVED, DEVIATIONS



def ballbar_values(campaign) -> np.ndarray:
    """(13,) the deterministic ball-bar values (thesis Table 4.5 for the thesis campaign), internal units.

    As the thesis: dx_BT = 0 (Eq 4.2), so a derived quantity is carried by its first deviation
    (dx_CZ = dx_CZ − dx_BT); dz_BT and the squareness terms 0.
    """
    ident = identify(campaign).ballbar
    theta = np.zeros(len(DEVIATIONS))
    for name, v in ident.items():
        if v.value is None:
            raise MtmcalError(f"the ball-bar value of {name} cannot be computed: it {v.missing}")
        key = next(iter(DERIVED[name])) if name in DERIVED else name
        theta[list(DEVIATIONS).index(key)] = v.value
    return theta


def default_posterior(campaign, *, n: int = N_DRAWS, seed: int = 0) -> Draws:
    """The thesis machine's default posterior of a compensation: ``n`` draws (seeded) of the closed-form posterior
    of the linear model at σ_model :data:`~mtmcal_bayes.compensation.options.SIGMA_MODEL_UM` from the ball bar, by
    deviation (internal units), with its log posterior."""
    sigma = units.to_internal(SIGMA_MODEL_UM, "um")
    lp = LogPosterior(campaign, "linear", sigma_model=sigma)
    g = gaussian_posterior(lp, sigma, allow_non_normal=True)
    raw = g.draws(n, np.random.default_rng(seed))
    draws = {name: raw[:, i] for i, name in enumerate(g.names) if name in DEVIATIONS}
    return Draws(draws, lp, f"closed-form posterior of the linear model (sigma_model {SIGMA_MODEL_UM:g} µm)")
