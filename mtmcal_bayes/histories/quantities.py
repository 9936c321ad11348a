"""The quantities a history tracks: those its machine reports (a plug-in's: the thesis' eight of Table 4.5), else
the deviations every campaign of the history determines.

Which deviations the ball bar determines is computed from each campaign's linear design
(:func:`~mtmcal_bayes.inference.identifiability.campaign_identifiability`, the T ball taken as centred as in a
single campaign); without a plug-in's list a deviation is tracked when every campaign determines it one by one.  The
others stay in the model (their states are integrated with their priors and drift) but are never shown as
measured: each is listed with why (undetermined, its posterior is its prior; determined only in a combination,
named; not determined by every campaign; or determined, but not among the quantities the machine reports).
"""

from __future__ import annotations

from ..inference.identifiability import campaign_identifiability
from ..machines.plugins import provided
from ..parameters import data_instruments

#: each instrument in words
INSTRUMENT_WORDS = {"ballbar": "the ball bar", "probe": "the touch probe", "rtest": "the R-test"}


def instruments_in_words(campaigns, posts) -> str:
    """The instruments whose data the history's campaigns use (``posts``: their log posteriors), in words."""
    used = dict.fromkeys(i for c, p in zip(campaigns, posts) for i in data_instruments(p.data, c))
    return " and ".join(INSTRUMENT_WORDS[i] for i in used)


def history_quantities(campaigns, posts, deviations) -> tuple[list[str], list[dict]]:
    """The tracked quantities (names, in the order of ``deviations``) and the deviations left out
    (``[{"quantity", "why"}]``), from the campaigns and their log posteriors ``posts`` (one each, on the data the
    history uses)."""
    own = provided(campaigns[-1].machine, "reported_quantities")  # a plug-in's (the thesis': Table 4.5's eight)
    idents = [campaign_identifiability(p) for p in posts]
    determined = [d for d in deviations if all(d in i.determined for i in idents)]
    tracked = determined if own is None else list(own)
    last = idents[-1]
    combos = {n: c.name for c in last.combinations for n in c.weights}
    left = []
    for d in deviations:
        if d in tracked:
            continue
        if d in determined:
            why = "determined, but not among the quantities the machine reports"
        elif d in last.undetermined:
            why = f"undetermined by {instruments_in_words(campaigns, posts)}: its posterior is its prior"
        elif d in combos:
            why = f"determined only in combination: {combos[d]}"
        else:
            why = "not determined by every campaign of the history"
        left.append({"quantity": d, "why": why})
    return tracked, left
