"""What simulation-based calibration ranks and when a quantity passes."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np



@dataclass(frozen=True)
class Checked:
    """The quantities ranked for one posterior and how each is read from parameter draws.

    ``names``: in ranking order; ``identified``: those the verdict is over (the reported quantities the campaign
    determines one by one and its identifiable combinations); ``weights``: the combinations, name -> {deviation:
    weight per display unit}, their values Σ w·θ in display units; ``identifiability``: the campaign's
    :class:`~mtmcal_bayes.inference.identifiability.Identifiability` (None: not computed).
    """

    names: tuple[str, ...]
    identified: tuple[str, ...]
    weights: dict[str, dict[str, float]] = field(default_factory=dict)
    identifiability: object | None = None

    def values(self, post, theta: np.ndarray) -> np.ndarray:
        """The ranked quantities ``(n, Q)`` (display units) of parameter draws ``(n, q)`` (internal units)."""
        from ..inference.results import display_draws

        d = display_draws(post.names, theta)
        for name, w in self.weights.items():
            d[name] = sum(v * d[n] for n, v in w.items())
        return np.column_stack([d[q] for q in self.names])


def checked_quantities(post) -> Checked:
    """What SBC ranks for ``post``, on every machine (SPEC §20): the quantities the posterior reports
    (:func:`~mtmcal_bayes.inference.analytic.reported`; on the thesis machine in Table 4.5's order, derived ones
    included) that its campaign determines one by one, its identifiable combinations (both from
    :func:`~mtmcal_bayes.inference.identifiability.campaign_identifiability`), then the discrepancy scales; the
    deviations it does not determine are not ranked (their width is set by priors)."""
    from ..inference.analytic import reported
    from ..inference.identifiability import DETERMINED, campaign_identifiability

    ident = campaign_identifiability(post)
    combos = {c.name: dict(c.weights) for c in ident.combinations}
    determined = tuple(n for n in reported(post) if ident.of(n)[0] == DETERMINED)
    identified = determined + tuple(combos)
    return Checked(identified + tuple(post.scales), identified, combos, ident)


def sbc_quantities(post) -> tuple[str, ...]:
    """The quantities ranked for a posterior (:func:`checked_quantities`)."""
    return checked_quantities(post).names


#: probabilities of the highest-density intervals whose coverage is counted
INTERVALS: tuple[float, ...] = (0.5, 0.9, 0.95)
#: the verdict's false-alarm rate per kind of test, over all the quantities it is over: each of those Q quantities
#: fails when its uniformity p-value is at most P_MIN / Q or its 90 % coverage lies outside the central 1 − P_MIN / Q
#: binomial range (Bonferroni), so a calibrated posterior fails the verdict in at most 2 × P_MIN of runs whatever Q
#: (tested one by one at P_MIN, a run of 35 quantities would fail about half the time)
P_MIN = 0.01


def quantity_level(family: int) -> float:
    """The level each of ``family`` quantities is tested at: ``P_MIN / family`` (at least one quantity)."""
    return P_MIN / max(int(family), 1)
