"""What a campaign lacks, in the words a report reader needs."""

from __future__ import annotations

from ..parameters import data_instruments
from ..posterior.instrument_check import INSTRUMENT_NAME


def missing_data(campaign, ident) -> list[str]:
    """Sentences naming the measurements the campaign does not have and what that costs (``ident``: the campaign's
    deterministic identification, :class:`~mtmcal_bayes.plugins.thesis.identification.IdentificationResult`, where its machine's
    plug-ins give one; None: there are no deterministic values to miss).

    Empty for a complete campaign (the thesis campaign).
    """
    out = []
    probe = campaign.probe
    have = data_instruments("all", campaign)
    if probe is None:
        out.append("No touch-probe data in this campaign: no probe values are marked in the figures and the "
                   "probe columns of summary.csv are empty." if ident is not None else
                   "No touch-probe data in this campaign: nothing checks the ball bar's deviations against a second "
                   "instrument." if have == ("ballbar",) else
                   "No touch-probe data in this campaign." if len(have) > 1 else
                   f"One instrument in this campaign, the {INSTRUMENT_NAME[have[0]]}: nothing checks its deviations "
                   "against a second one.")
    elif ident is not None:  # the probe sections its deterministic method needs (the thesis': Eqs 5.1–5.19)
        out += list(getattr(ident, "missing_probe", ()))
    if not campaign.ballbar.runs:
        out.append("No ball-bar runs in this campaign: no ball-bar trajectories, no predictive check of "
                   + ("eccentricities and no comparison of the instruments." if len(have) < 2 else
                      "eccentricities (the other instruments are compared pair by pair)."))
    if not campaign.ballbar.setups:
        out.append("No ball-bar set-up in this campaign: the planner's catalogue of candidate measurements starts "
                   "from one, so the report has no plan of the next measurement.")
    if campaign.has_probe_readings() and (gap := campaign.probe_gap()) is not None:
        out.append(gap.skipped("The comparison of the instruments (the ball-bar-only, probe-only and fused posteriors "
                               "side by side, the consistency check, the weighing of a conflict's explanations)"))
    for name, v in (ident.ballbar.items() if ident is not None else ()):
        if v.value is None and v.missing:
            out.append(f"No ball-bar value for {name} (thesis Eq {v.equation}): it {v.missing}. "
                       "The posterior still reports it; see below whether the data identify it.")
    return out
