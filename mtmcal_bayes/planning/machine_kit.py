"""What planning asks of a campaign's machine (SPEC §20): its catalogue's rules, clock and the shape of its planned
runs, in one object.

The ball-bar catalogue, its feasibility and the tool-length sweep are one for every machine (:mod:`.catalogue`),
and so is the touch-probe catalogue (:mod:`.probe_catalogue`); the kit holds the rules of the campaign format they
follow.  The engine's own kit serves every machine from its
description (the chain's patterns ``<axis><R|T|A|X|Y|Z>``, its arcs, held axes and W-ball positions).  A machine
whose plug-in has a campaign format of its own contributes ``planning``, a :class:`PlanningKit` built from its
functions (the thesis plug-in: its catalogue rules, clock and run records).  The planner is one
for every machine (:class:`~.design.Planner`): it asks the machine what it provides.  Planning asks
:func:`kit_of` and never which kind of machine it holds.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..machines.plugins import provided


@dataclass(frozen=True)
class PlanningKit:
    """The planning contributions of one campaign format.

    ``catalogue_rules`` what its ball-bar catalogue varies (:class:`.catalogue.CatalogueRules`);
    ``clock(time_model, campaign)`` the machine minutes of runs; ``where(candidate)`` the geometry
    columns of the plan's table; ``sweep_pattern(table, campaign)`` the sweep's pattern when none is asked for;
    ``feasibility_note`` what the plan says of it; ``run_columns`` and
    ``run_records(design, programs)`` the design's runs as records; ``planned_geometry(planned, candidate,
    campaign)`` what a planned run records beyond pattern, set-up and mount (the arc and held axes);
    ``read_candidates(path, campaign)`` the user's candidates from a ``--candidates`` file."""

    catalogue_rules: object
    clock: Callable
    where: Callable
    sweep_pattern: Callable
    feasibility_note: str
    run_columns: list
    run_records: Callable
    planned_geometry: Callable
    read_candidates: Callable


def kit_of(campaign) -> PlanningKit:
    """The planning kit of ``campaign``'s machine: its plug-in's, else the engine's (:func:`engine_kit`)."""
    return provided(campaign.machine, "planning") or engine_kit()


def engine_kit() -> PlanningKit:
    """The engine's planning, for any machine from its description."""
    from . import chain_candidates as dc
    from .catalogue import CatalogueRules
    from .chain_clock import engine_clock
    from .run_records import RUN_COLUMNS, chain_records

    def where(c) -> dict:
        return {"setup": c.setup.id, "R_B_mm": c.setup.R_B, "Z_T_mm": np.nan, "mount": c.mount.id, "R_C_mm": np.nan}

    def sweep_pattern(table, campaign) -> str:
        best = table[table["kind"] == "tool length"]
        best = best[best["mount"] == next(iter(campaign.ballbar.mounts))]  # the sweep is at the first mount
        if not len(best):
            return str(table["pattern"].iloc[0])
        # the pattern whose value depends most on the tool length (AA, along its axis, does not at all)
        spread = best.groupby("pattern", sort=False)["eig_bits"].agg(np.ptp)
        return str(spread.idxmax())

    def planned_geometry(planned, candidate, campaign) -> None:
        planned.arc_deg = dc.arc_of(candidate, campaign.machine.description)
        planned.hold_deg = dict(candidate.hold_deg) or None

    return PlanningKit(
        catalogue_rules=CatalogueRules(), clock=engine_clock, where=where, sweep_pattern=sweep_pattern,
        feasibility_note="feasible = every command of every point (the arc, the held axes, the linear axes) lies "
                         "within the travels of the machine's description",
        run_columns=RUN_COLUMNS, run_records=chain_records,
        planned_geometry=planned_geometry, read_candidates=dc.read_chain_candidates)


def catalogue_of(campaign) -> list:
    """The candidate catalogue of ``campaign``'s machine (:func:`.catalogue.catalogue`)."""
    from .catalogue import catalogue

    return catalogue(campaign)


def feasibility_of(campaign):
    """``check(candidate) -> (feasible, why)`` for ``campaign``'s machine (:func:`.catalogue.feasibility_check`)."""
    from .catalogue import feasibility_check

    return feasibility_check(campaign)


def planner_for(campaign, candidates: list, targets=None, **kw):
    """The :class:`~.design.Planner` of ``campaign`` (one for every machine; keywords as its)."""
    from .design import Planner

    return Planner(campaign, candidates, targets, **kw)
