"""The posterior beside the thesis' deterministic values: is each inside the 95 % HDI, how many sd away."""

from __future__ import annotations

import pandas as pd

from ..parameters import IDENTIFIABLE, QUANTITIES

#: the deterministic values a posterior is compared with, as columns of :func:`comparison`
REFERENCES = ("ballbar", "probe_reported", "probe_recomputed")


def comparison(summary: pd.DataFrame, ident) -> pd.DataFrame:
    """Each quantity's posterior against the ball-bar and touch-probe values of ``ident``
    (an :class:`~mtmcal_bayes.plugins.thesis.identification.IdentificationResult`).

    Rows: the identifiable quantities, then any other deviation of the summary
    with a touch-probe value (dx_CZ, dx_BT, dz_BT).  For every reference value:
    whether it lies in the 95 % HDI, and its distance from the posterior mean in
    posterior sd.  The ball-bar values are the thesis equations on the offsets read
    as the campaign reads them (its convention: the data the posterior saw); the
    thesis' own reading of them is in ``ident.ballbar``.
    """
    ballbar = ident.ballbar_in_convention if ident.ballbar_in_convention is not None else ident.ballbar
    rows = []
    extra = [n for n in summary.index if n in QUANTITIES and n not in IDENTIFIABLE and n in ident.probe]
    for name in [n for n in IDENTIFIABLE if n in summary.index] + extra:
        r = summary.loc[name]
        refs = {"ballbar": ballbar.get(name).display if name in ballbar else None}
        probe = ident.probe.get(name)
        refs["probe_reported"] = probe.reported_display if probe is not None and probe.reported else None
        refs["probe_recomputed"] = probe.display if probe is not None else None
        row = {"quantity": name, "unit": QUANTITIES[name].unit, "mean": r["mean"], "sd": r["sd"],
               "hdi_low": r["hdi_low"], "hdi_high": r["hdi_high"]}
        for key, v in refs.items():
            row[key] = v
            row[f"{key}_in_hdi"] = None if v is None else bool(r["hdi_low"] <= v <= r["hdi_high"])
            row[f"{key}_z"] = None if v is None else (v - r["mean"]) / r["sd"]
        rows.append(row)
    return pd.DataFrame(rows).set_index("quantity")
