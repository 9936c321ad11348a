"""What a campaign lacks, in the words a report reader needs."""

from __future__ import annotations


def missing_data(campaign, ident) -> list[str]:
    """Sentences naming the measurements the campaign does not have and what that costs
    (``ident``: the campaign's :class:`~mtmcal_bayes.identification.IdentificationResult`).

    Empty for a complete campaign (the thesis campaign).
    """
    out = []
    probe = campaign.probe
    if probe is None:
        out.append("No touch-probe data in this campaign: no probe values are marked in the figures and the "
                   "probe columns of summary.csv are empty.")
    else:
        if probe.c_axis is None:
            out.append("No C-axis touch-probe data: alpha_CZ, beta_CZ, dx_CZ and dy_CZ have no probe value.")
        if probe.b_axis is None or not probe.b_axis.styli:
            out.append("No B-axis touch-probe data: alpha_XB, beta_XB, gamma_XB, dx_BT and dz_BT have no probe value.")
    if campaign.has_probe_readings() and (gap := campaign.probe_gap()) is not None:
        out.append(gap.skipped("The comparison of the instruments (the ball-bar-only, probe-only and fused posteriors "
                               "side by side, the consistency check, the weighing of a conflict's explanations)"))
    for name, v in ident.ballbar.items():
        if v.value is None and v.missing:
            out.append(f"No ball-bar value for {name} (thesis Eq {v.equation}): it {v.missing}. "
                       "The posterior still reports it; see below whether the data identify it.")
    return out
