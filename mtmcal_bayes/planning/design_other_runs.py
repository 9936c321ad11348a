"""A design's touch-probe and R-test runs in its outputs (docs/design.md, "Every instrument"): their records in
``design --json`` and the text, their programs' names, and the tables to fill in (``to_fill_in.toml``).

A ball-bar run is written into the designed campaign as a planned run; the campaign format has no planned probe or
R-test run, so each of theirs is written as the ``[[probe.runs]]`` / ``[[rtest.runs]]`` table it becomes once
measured, its readings empty (``centres_mm = []``, ``displacement_um = []``): fill them in and add the table to the
campaign.  The designed campaign's ``[design] to_fill_in`` names them (table id -> run name): ``next`` counts a run
whose table the campaign holds as measured and the others as planned (:func:`planned_other`).
"""

from __future__ import annotations

from .plan import rtest_run_table, rtest_where

#: the file of a design's probe and R-test tables
FILL_IN = "to_fill_in.toml"


def other_program_name(order: int, run) -> str:
    """``programs/NN_<instrument>_<axis>.nc`` of a probe or R-test run."""
    return f"programs/{order:02d}_{run.candidate.kind}_{run.candidate.axis}.nc"


def run_id(campaign, order: int, run) -> str:
    """The id a designed probe or R-test run has in its table: ``design NN <kind> <axis>``, the order making it unique
    among the design's runs and a suffix ``-2``, ``-3``, … among the campaign's measured probe and R-test runs (a
    re-plan by ``next`` numbers its runs from 1 again)."""
    taken = set(measured_ids(campaign))
    base = f"design {order:02d} {run.candidate.kind} {run.candidate.axis}"
    out, k = base, 2
    while out in taken:
        out, k = f"{base}-{k}", k + 1
    return out


def measured_ids(campaign) -> list[str]:
    """The ids of the campaign's measured probe and R-test runs."""
    return [r.id for part in (campaign.probe, campaign.rtest) if part is not None for r in part.runs]


def planned_other(campaign) -> dict[str, str]:
    """The designed probe and R-test runs the campaign plans (its ``[design] to_fill_in``), table id -> run name,
    without those measured (a run of that id among its ``[[probe.runs]]`` / ``[[rtest.runs]]``)."""
    if campaign.design is None:
        return {}
    done = set(measured_ids(campaign))
    return {k: v for k, v in campaign.design.to_fill_in.items() if k not in done}


def other_record(campaign, order: int, run, *, minutes: float, why: str, programs: bool) -> dict:
    """The record of a designed probe or R-test run (``design --json``'s ``runs``)."""
    c = run.candidate
    if c.instrument == "probe":
        where = {"setup": f"stylus {c.stylus_length:g} mm", "mount": "sphere at [" + ", ".join(
            f"{x:g}" for x in c.sphere) + "] mm", "angles_deg": {a: list(v) for a, v in c.positions}}
    else:
        where = {k: rtest_where(c)[k] for k in ("setup", "mount")} | {"angles_deg": c.angles_deg(),
                                                                      "swept": c.sweep_span is not None}
    return {"order": order, "pattern": c.pattern, "instrument": c.instrument, **where, "repeats": c.repeats,
            "minutes": round(minutes, 2), "program": other_program_name(order, run) if programs else None,
            "why": why, "candidate": run.label, "table": run_id(campaign, order, run)}


def fill_in_tables(campaign, ordered: list[tuple[int, object]]) -> dict:
    """The ``[probe]`` and ``[rtest]`` tables of the designed probe and R-test runs ``(order, run)``: each run's table
    with empty readings, and a stylus of the catalogue's own length as the run's ``R_B_mm``."""
    probe, rtest = [], []
    styli = {} if campaign.probe is None else {campaign.probe.centre_length(s): s for s in campaign.probe.styli}
    for order, run in ordered:
        c = run.candidate
        if c.instrument == "probe":
            t = {"id": run_id(campaign, order, run)}
            if c.stylus_length in styli:
                t["stylus"] = styli[c.stylus_length]
            else:
                t["R_B_mm"] = float(c.stylus_length)
            t |= {"sphere_mm": [float(x) for x in c.sphere], "angles_deg": {a: [_deg(x) for x in v]
                                                                          for a, v in c.positions},
                  "centres_mm": []}
            probe.append(t)
        else:
            t = rtest_run_table(c)
            t["id"] = run_id(campaign, order, run)
            t["angles_deg"] = {a: [_deg(x) for x in v] for a, v in t["angles_deg"].items()}
            t.pop("repeats", None)
            t.pop("swept", None)
            t["displacement_um"] = []
            rtest.append(t)
    out = {}
    if probe:
        out["probe"] = {"runs": probe}
    if rtest:
        out["rtest"] = {"runs": rtest}
    return out


def _deg(x) -> float:
    """An angle as the table shows it: to a nanodegree (0, not the 1.4e-14 a sum of 10° steps leaves)."""
    return round(float(x), 9) + 0.0


__all__ = ["FILL_IN", "other_program_name", "other_record", "fill_in_tables", "run_id", "measured_ids",
           "planned_other"]
