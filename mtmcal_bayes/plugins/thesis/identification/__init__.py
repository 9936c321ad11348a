"""The thesis' deterministic identification, recomputed and compared with what it printed.

* :func:`identify_ballbar` — Eqs 4.10–4.18 from the mean of the repeats of BX,
  BY, CR, CA at the first tool setup and CR at a second tool length.
* :func:`identify_probe` — Eqs 5.1–5.19 from the averaged touch-probe sphere
  centres (Table 5.2) and the nominal positions given in the campaign.
* :func:`identify` — both, each value beside the ``[reported]`` one with a flag
  when they differ by more than the rounding of the printed value.

Known discrepancies of the thesis are listed by :func:`thesis_checks` and in
``docs/thesis-notes.md``.
"""

from __future__ import annotations

import copy

import numpy as np

from ....campaign import Campaign
from ....conventions import machine_repeats, reads_as_thesis, run_convention, run_matrix
from .ballbar import identify_ballbar, thesis_checks
from .probe import identify_probe, missing_probe
from .result import IdentificationResult, Identified


def in_machine_frame(campaign: Campaign) -> Campaign | None:
    """A copy of ``campaign`` whose runs carry their offsets in the machine frame (read in the thesis' way), or None
    when every run already is (the campaign's reading convention is the thesis' for all its runs)."""
    bb = campaign.ballbar
    if reads_as_thesis(bb):
        return None
    out = copy.deepcopy(campaign)
    for run, new in zip(bb.runs, out.ballbar.runs):
        new.repeats, new.convention = machine_repeats(run, bb), None
    out.ballbar.convention = "thesis"
    return out


def identify(campaign: Campaign) -> IdentificationResult:
    """Ball-bar and touch-probe identification with published values and flags.

    The ball-bar equations run on the offsets as entered, read in the thesis' way: the thesis' reproduction.  Where
    the campaign reads some runs otherwise (``[ballbar] convention`` or a run's ``convention``), they run again on
    the offsets in the machine frame (:attr:`IdentificationResult.ballbar_in_convention`)."""
    ballbar = identify_ballbar(campaign)
    for name, ident in ballbar.items():
        ident.reported = campaign.reported.get("ballbar", {}).get(name)
    probe, assumptions = identify_probe(campaign)
    assumptions = ["ball bar: means of the repeats; Eq 4.13 assumes dx_BT = 0 as the thesis does (Eq 4.2)"] + assumptions
    machine = in_machine_frame(campaign)
    own = identify_ballbar(machine) if machine is not None else None
    for name, ident in (own or {}).items():
        ident.reported = campaign.reported.get("ballbar", {}).get(name)
    bb = campaign.ballbar
    used = sorted({f"{run.pattern}: {run_convention(run, bb)}" for run in bb.runs
                   if not np.allclose(run_matrix(run, bb), np.eye(2))})
    return IdentificationResult(ballbar, probe, thesis_checks(campaign, ballbar), assumptions, campaign.source,
                                own, "; ".join(used) if used else bb.convention, missing_probe(campaign))


__all__ = ["identify", "identify_ballbar", "identify_probe", "thesis_checks", "IdentificationResult", "Identified"]
