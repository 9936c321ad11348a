"""The thesis' deterministic identification, recomputed and compared with what it printed.

* :func:`identify_ballbar` — Eqs 4.10–4.18 from the mean of the repeats of BX,
  BY, CR, CA at the first tool setup and CR at a second tool length.
* :func:`identify_probe` — Eqs 5.1–5.19 from the averaged touch-probe sphere
  centres (Table 5.2) and the nominal positions given in the campaign.
* :func:`identify` — both, each value beside the ``[reported]`` one with a flag
  when they differ by more than the rounding of the printed value.
* :func:`probe_fit` — least-squares sphere fit of DPRNT probe output (Fig 5.13).

Known discrepancies of the thesis are listed by :func:`thesis_checks` and in
``docs/thesis-notes.md``.
"""

from __future__ import annotations

from ..campaign import Campaign
from .ballbar import identify_ballbar, thesis_checks
from .probe import identify_probe
from .probe_fit import ProbeFit, probe_fit
from .result import IdentificationResult, Identified


def identify(campaign: Campaign) -> IdentificationResult:
    """Ball-bar and touch-probe identification with published values and flags."""
    ballbar = identify_ballbar(campaign)
    for name, ident in ballbar.items():
        ident.reported = campaign.reported.get("ballbar", {}).get(name)
    probe, assumptions = identify_probe(campaign)
    assumptions = ["ball bar: means of the repeats; Eq 4.13 assumes dx_BT = 0 as the thesis does (Eq 4.2)"] + assumptions
    return IdentificationResult(ballbar, probe, thesis_checks(campaign, ballbar), assumptions, campaign.source)


__all__ = ["identify", "identify_ballbar", "identify_probe", "thesis_checks", "IdentificationResult", "Identified",
           "ProbeFit", "probe_fit"]
