"""Tolerance decisions with the way forward: for an *undecided* quantity, the planner's best next measurement.

An undecided verdict is not an end: one more measurement may narrow the coverage interval until it lies
on one side of the limit.  For each undecided quantity the planner (closed form, ball-bar candidates, at
the posterior median of sigma_model) names the candidate that makes it most certain, its expected sd
after, and the sd at which the decision would fall if the estimate stayed where it is: the distance from
the estimate to the nearest limit over k = 1.96.
"""

from __future__ import annotations

import math

from ..inference.gum import K_GAUSSIAN
from ..planning import best_measurement
from ..posterior.conformity import UNDECIDED

SUGGESTION_COLUMNS = ["next_measurement", "sd_after", "sd_to_decide", "would_decide"]


def add_suggestions(result, campaign) -> None:
    """Fill :data:`SUGGESTION_COLUMNS` of ``result.conformity`` (a :class:`~mtmcal_bayes.posterior.PosteriorResult`)
    for its undecided quantities, in place."""
    table = result.conformity
    if table is None or table.empty:
        return
    for c in SUGGESTION_COLUMNS:
        table[c] = None
    sigma_um = result.sigma_model_um
    for name, row in table.iterrows():
        if row["conformity"] != UNDECIDED:
            continue
        y = result.summary.loc[name, "mean"]
        limits = [v for v in (row["tolerance_low"], row["tolerance_high"]) if v == v]
        need = min(abs(y - v) for v in limits) / K_GAUSSIAN
        best = best_measurement(campaign, name, sigma_model_um=sigma_um, model=result.model, data=result.data)
        table.at[name, "sd_to_decide"] = need
        if best is not None:
            table.at[name, "next_measurement"] = best["name"]
            table.at[name, "sd_after"] = best["sd_after"]
            table.at[name, "would_decide"] = bool(best["sd_after"] < need)


def suggestion_text(name: str, row, unit_symbol: str) -> str:
    """"plan: BZ @ RB1 would bring its sd to 1.7″ (deciding needs < 3.0″ if the estimate stays): it would decide"."""
    if row.get("next_measurement") is None or (isinstance(row.get("next_measurement"), float)
                                                and math.isnan(row["next_measurement"])):
        return "no candidate measurement of the planner narrows it"
    verdict = "it would decide" if row["would_decide"] else "not enough on its own"
    return (f"next measurement: {row['next_measurement']} (mtmcal-bayes plan --target {name}) would bring its sd to "
            f"{row['sd_after']:.2g} {unit_symbol}; deciding needs < {row['sd_to_decide']:.2g} {unit_symbol} if the "
            f"estimate stays where it is: {verdict}")
