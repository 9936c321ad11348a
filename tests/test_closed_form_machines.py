"""The closed form (``sample --closed-form``) on every built-in type: the quantities the campaign determines, each
the Gaussian posterior at the fixed σ_model, checked against the exact sampler's independent draws of that same
posterior and against the Jacobian's statement of what is determined."""

from __future__ import annotations

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes.inference.identifiability import campaign_identifiability
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes import units

TYPES = ("integrex-i200", "trunnion", "vertical-turn-mill", "head-head")
SIGMA_UM = 0.5


@pytest.mark.parametrize("machine", TYPES)
def test_the_closed_form_is_the_exact_posterior_of_what_the_campaign_determines(machine):
    """Each reported quantity's mean and sd against 4 000 exact draws at the same σ_model: the mean within 4 Monte-Carlo
    standard errors (4·sd/√n, 0.063 sd), the sd within 4 of its own (4·sd/√(2n), 4.5 %).  On a described machine the
    quantities are the deviations the Jacobian determines one by one and its combinations, nothing else; on the
    thesis machine the eight of Table 4.5."""
    campaign = mb.load_campaign(demo_campaign(machine))
    cf = mb.closed_form(campaign, sigma_model_um=SIGMA_UM)
    data = "ballbar" if machine == "integrex-i200" else ("both" if campaign.has_probe_readings() else "ballbar")
    if machine == "integrex-i200":
        assert list(cf.summary.index) == list(mb.IDENTIFIABLE)
    else:
        ident = campaign_identifiability(LogPosterior(campaign, "linear", data=data,
                                                      sigma_model=units.to_internal(SIGMA_UM, "um")))
        assert list(cf.summary.index) == list(ident.determined) + [c.name for c in ident.combinations]
        assert not set(cf.summary.index) & set(ident.undetermined)
    post = mb.sample(campaign, sampler="exact", sigma_model_um=SIGMA_UM, seed=3, data=data)
    n = 4000
    for name, row in cf.summary.iterrows():
        draws = _draws(post, name)
        rng = np.random.default_rng(0)
        draws = rng.choice(draws, size=min(n, len(draws)), replace=False)
        k = len(draws)
        assert abs(draws.mean() - row["mean"]) <= 4 * row["sd"] / np.sqrt(k), name
        assert abs(draws.std(ddof=1) - row["sd"]) <= 4 * row["sd"] / np.sqrt(2 * (k - 1)), name
        assert row["hdi_low"] < row["mean"] < row["hdi_high"]


def _draws(post, name: str) -> np.ndarray:
    """Display-unit draws of a quantity or a combination of the sampled posterior."""
    frame = post.idata.posterior
    if name in frame:
        return np.asarray(frame[name]).ravel()
    combo = next(c for c in post.combinations if c["name"] == name)
    return sum(w * np.asarray(frame[k]).ravel() for k, w in combo["weights"].items())
