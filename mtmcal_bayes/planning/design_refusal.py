"""Targets a design cannot serve, refused by name with what would serve them (docs/design.md, "Targets").

* A target on a quantity that neither the campaign's runs nor any candidate run determines (the Jacobian rule,
  :mod:`.determined`) would be "met" by its prior alone: refused, saying what would determine it — the combination
  the runs do determine it in, a run of the catalogue beyond the travels (which axis, how far), touch-probe runs.
* A target no design of the candidates reaches: refused with the best reachable sd, and, where a run beyond the
  travels would lower it further, which run and which axis keeps it out.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from .candidates import Candidate
from .machine_kit import catalogue_of, feasibility_of
from .design import MIN_GAIN
from .determined import Determination

#: one line names at most this many runs
NAMED = 1


def beyond_travels(campaign, cands: list[Candidate]) -> list[tuple[Candidate, str]]:
    """The catalogue's new ball-bar runs at the campaign's bar length that the travels exclude, with why (the axis
    and its commands against its travel, as ``plan`` states it)."""
    fits = feasibility_of(campaign)
    taken = {(c.pattern, c.setup.id, c.mount.id, c.arc_deg, c.hold_deg) for c in cands if c.instrument == "ballbar"}
    out = []
    for c in catalogue_of(campaign):
        if c.repeat_of is not None or c.kind == "bar length":
            continue
        if (c.pattern, c.setup.id, c.mount.id, c.arc_deg, c.hold_deg) in taken:
            continue
        ok, why = fits(c)
        if not ok:
            out.append((c, why))
    return out


def probe_candidates(campaign) -> list:
    """The catalogue's feasible touch-probe runs (none without a ``[probe]`` to take them from)."""
    from .probe_catalogue import probe_catalogue, probe_feasibility

    return [c for c in probe_catalogue(campaign) if probe_feasibility(c, campaign)[0]]


def _wider(problem, extra: list, target: str):
    """A planner over the design's candidates plus ``extra`` valuing ``target`` alone, and its determination."""
    from .machine_kit import planner_for

    p = problem.planner
    wide = planner_for(p.campaign, list(p.candidates) + list(extra), [target], model=p.model)
    return wide, Determination(wide, [A for A, _ in wide.candidate_rows()])


def what_would_determine(problem, target: str) -> str:
    """What would determine ``target``, which the campaign and the design's candidates leave undetermined."""
    campaign = problem.planner.campaign
    K = len(problem.candidates)
    parts = []
    ident = problem.determination.identifiability()
    for c in ident.combinations:
        if target in c.weights:
            parts.append(f"the runs determine it only in the combination {c.name}")
            break
    beyond = beyond_travels(campaign, problem.candidates)
    # the catalogue's probe runs where the design does not choose among them already
    probes = [] if any(c.instrument == "probe" for c in problem.candidates) else probe_candidates(campaign)
    try:
        wide, det = _wider(problem, [c for c, _ in beyond] + probes, target)
    except (ParameterError, KeyError, ValueError):  # a candidate the planner cannot take: say nothing of it
        wide, det = None, None
    if det is not None:
        base = np.zeros(len(wide.candidates), dtype=int)
        base[:K] = 1
        plus = det.determined_plus_one(base)[:, 0]
        helping = [beyond[j] for j in range(len(beyond)) if plus[K + j]]
        if helping:
            c, why = helping[0]
            parts.append(f"{len(helping)} run(s) beyond the travels would, e.g. {c.name} ({why})")
        with_probe = base.copy()
        with_probe[K + len(beyond):] = 1
        if probes and det.determined(with_probe)[0]:
            parts.append("touch-probe runs would (--instruments with probe)")
        elif probes:
            parts.append("touch-probe runs of the catalogue would not either")
    if not any("beyond" in p or "touch-probe runs would (" in p for p in parts):
        parts.append("no run of the catalogue at another tool length, W-ball placement or held pose would: give "
                     "one that does (--candidates) or another instrument")
    return "; ".join(parts)


def refuse_undetermined(problem, goal) -> None:
    """Refuse the first target that no candidate run (with the campaign's) determines, saying what would."""
    K = len(problem.candidates)
    every = problem.determination.determined(np.ones(K, dtype=int))
    for i in np.flatnonzero(np.isfinite(goal.targets) & ~every):
        t = problem.planner.targets[i]
        raise ParameterError("targets", f"{t}: no run determines it — neither the campaign's runs nor any of the {K} "
                             "candidate runs within the travels (its sd would be its prior's, met by no measurement); "
                             + what_would_determine(problem, t))


def beyond_note(problem, target: str) -> str:
    """``"; N runs of the catalogue lie beyond the travels; the one that would lower it most, X: why"`` when a run
    of the catalogue beyond the travels would lower ``target``'s sd (empty otherwise)."""
    beyond = beyond_travels(problem.planner.campaign, problem.candidates)
    if not beyond:
        return ""
    try:
        wide, _ = _wider(problem, [c for c, _ in beyond], target)
    except (ParameterError, KeyError, ValueError):
        return ""
    ev = wide.evaluate()  # one run of each candidate added to the campaign
    sd, before = ev.sd_after[:, 0], ev.sd_before[0]
    K = len(problem.candidates)
    j = int(np.argmin(sd[K:]))
    if sd[K + j] >= (1.0 - MIN_GAIN) * before:
        return ""
    c, why = beyond[j]
    return (f"; {len(beyond)} run(s) of the catalogue lie beyond the travels, the one that would lower it most "
            f"{c.name}: {why}")


__all__ = ["beyond_travels", "probe_candidates", "what_would_determine", "refuse_undetermined", "beyond_note"]
