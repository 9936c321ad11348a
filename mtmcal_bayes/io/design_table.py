"""The ``[design]`` table of a campaign (targets, contraction, budget, time overrides, the designed probe and R-test
runs), written alike on any machine."""

from __future__ import annotations

from ..campaign import DesignGoal
from ..parameters import QUANTITIES


def design_to_dict(g: DesignGoal, quantities: dict | None = None) -> dict:
    """The ``[design]`` table: targets with their unit (``alpha_BT_arcsec``), contraction, budget, time overrides, the
    designed probe and R-test runs' tables (``to_fill_in``: table id -> run name)."""
    d: dict = {}
    if g.contraction is not None:
        d["contraction"] = g.contraction
    if g.budget_min is not None:
        d["budget_min"] = g.budget_min
    if g.targets:
        table = QUANTITIES if quantities is None else quantities  # a described machine's deviations
        d["targets"] = {f"{n}_{table[n].unit}": float(v) for n, v in g.targets.items()}
    if g.times:
        d["times"] = {k: float(v) for k, v in g.times.items()}
    if g.to_fill_in:
        d["to_fill_in"] = dict(g.to_fill_in)
    return d


__all__ = ["design_to_dict"]
