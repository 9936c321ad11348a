"""The quantities a history tracks: the thesis' eight, or what a described machine's campaigns determine.

On the thesis machine a history tracks :data:`~mtmcal_bayes.parameters.IDENTIFIABLE`.  On a described machine its
deviations are its own (ISO 230-7 names, :func:`~mtmcal_bayes.machines.deviations.selected`), and which of them the
ball bar determines is computed from each campaign's linear design
(:func:`~mtmcal_bayes.inference.identifiability.campaign_identifiability`, the T ball taken as centred as in a
single campaign).  A deviation is tracked when every campaign of the history determines it one by one.  The
others stay in the model (their states are integrated with their priors and drift) but are never shown as
measured: each is listed with why (undetermined, its posterior is its prior; determined only in a combination,
named; or not determined by every campaign).
"""

from __future__ import annotations

from ..inference.identifiability import campaign_identifiability
from ..machines.plugins import provided


def history_quantities(campaigns, posts, deviations) -> tuple[list[str], list[dict]]:
    """The tracked quantities (names, in the order of ``deviations``) and the deviations left out
    (``[{"quantity", "why"}]``), from the campaigns and their ball-bar log posteriors ``posts`` (one each)."""
    own = provided(campaigns[-1].machine, "reported_quantities")  # a plug-in's (the thesis': Table 4.5's eight)
    if own is not None:
        return list(own), []
    idents = [campaign_identifiability(p) for p in posts]
    determined = [d for d in deviations if all(d in i.determined for i in idents)]
    last = idents[-1]
    combos = {n: c.name for c in last.combinations for n in c.weights}
    left = []
    for d in deviations:
        if d in determined:
            continue
        if d in last.undetermined:
            why = "undetermined by the ball bar: its posterior is its prior"
        elif d in combos:
            why = f"determined only in combination: {combos[d]}"
        else:
            why = "not determined by every campaign of the history"
        left.append({"quantity": d, "why": why})
    return determined, left
