"""The parameter space of a campaign on a described machine: its selected deviations and nuisance terms."""

from __future__ import annotations

from ..parameters import ParameterSpace, data_instruments
from .deviations import quantities
from .probe_terms import probe_terms, rtest_terms
from .selection import selected


def described_space(campaign, deviations=None, data: str = "ballbar") -> ParameterSpace:
    """The space of ``campaign`` (a described machine's) for ``data``: the deviations (default the machine's
    selection, :func:`~.selection.selected`), per ball-bar setup ``xT, yT, zT, dRB`` and per mount ``xW, yW, zW``
    with ball-bar data, the probe's terms (:func:`~.probe_terms.probe_terms`) with probe data, the R-test's
    (:func:`~.probe_terms.rtest_terms`) with R-test data."""
    desc = campaign.machine.description
    names = [d.name for d in selected(desc)] if deviations is None else list(deviations)
    used = data_instruments(data, campaign)
    bb = "ballbar" in used
    probe = probe_terms(desc, campaign.probe) if "probe" in used and campaign.probe else ()
    rtest = rtest_terms(desc, campaign.rtest) if "rtest" in used and campaign.rtest else ()
    return ParameterSpace(list(campaign.ballbar.setups) if bb else [], list(campaign.ballbar.mounts) if bb else [],
                          names, probe, table=quantities(desc), rtest=rtest)
