"""Is the instruments' consistency check calibrated?  Its p-values over campaigns simulated without a conflict.

:func:`null_p_values` simulates ``n`` campaigns of a campaign's design from the fused linear model — both
instruments from one truth, so they cannot disagree — and runs :func:`~.consistency.predictive_check` in both
directions on each, with the exact posteriors of each instrument's data.  Without a conflict every group's p-value
is uniform on [0, 1]: a χ² taken on the wrong number of degrees of freedom piles them up near 1 (too many) or near
0 (too few).

The truth is drawn from the priors, except the nuisance terms broader than ``WIDE`` (the sphere's placement, the
stylus length, the reading datum), which stay at ``wide_value`` times their prior sd: their priors say where the
sphere or the datum may be, not where it is, and the check must not depend on it (the demo campaigns hold them at
zero).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..inference.log_posterior import LogPosterior
from .consistency import predictive_check
from .misreading import DRAWS, _marginal

#: nuisance terms whose prior sd exceeds this (mm) are held at ``wide_value`` prior sds in the simulation
WIDE = 0.1


def null_p_values(campaign, n: int = 200, seed: int = 0, *, wide_value: float = 0.0) -> pd.DataFrame:
    """One row per simulated campaign and reading group: ``replicate``, ``given``, ``group``, ``chi2``, ``dof``,
    ``p_value``; ``n`` campaigns of ``campaign``'s design simulated from the fused linear prior (module docstring)."""
    fused = LogPosterior(campaign, "linear", data="both")
    bb, pr = LogPosterior(campaign, "linear", data="ballbar"), LogPosterior(campaign, "linear", data="probe")
    rng = np.random.default_rng(seed)
    theta = fused.priors.rvs(n, rng)
    sd = fused.priors.width[: fused.p]
    loc = np.array([q.loc for q in fused.priors.priors[: fused.p]])
    wide = [i for i, p in enumerate(fused.space.parameters) if p.group != "deviation" and sd[i] > WIDE]
    theta[:, wide] = loc[wide] + wide_value * sd[wide]
    y = fused.likelihood.replicate(fused.forward.predict(theta[:, : fused.p]), fused.sigma(theta), rng)
    m_bb = len(bb.likelihood.y)  # the fused observations: the ball bar's, then the probe's
    mb, mp = _marginal(bb), _marginal(pr)
    rows = []
    for i in range(n):
        b, p = bb.with_means(y[i, :m_bb]), pr.with_means(y[i, m_bb:])
        tb, sb = mb.draw(y[i, :m_bb], DRAWS, rng)
        tp, sp = mp.draw(y[i, m_bb:], DRAWS, rng)
        for g in (predictive_check(b, p, draws=np.column_stack([tb, sb]))[1],
                  predictive_check(p, b, draws=np.column_stack([tp, sp]))[1]):
            rows += [{"replicate": i, "given": r.given, "group": r.group, "chi2": r.chi2, "dof": r.dof,
                      "p_value": r.p_value} for r in g.itertuples()]
    return pd.DataFrame(rows)
