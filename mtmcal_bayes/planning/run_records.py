"""A design's runs as records (``design --json``'s ``runs``, design.html's table): each run's W ball, arc and held
axes (the engine's planning kit, :mod:`.machine_kit`; a plug-in's kit may write its own campaign keys instead)."""

from __future__ import annotations

from .chain_candidates import arc_of, arc_spec


def rounded_mm(v) -> float:
    """A length to a thousandth of a µm: 12.2877, not 12.287700000000001 (112.2877 − 100)."""
    return round(float(v), 6)


def program_name(order: int, pattern: str) -> str:
    return f"programs/{order:02d}_{pattern}.nc"


#: the columns of a design's run records, in order (the table of a design without runs has them too)
RUN_COLUMNS = ["order", "pattern", "setup", "mount", "R_B_mm", "position_mm", "arc_deg", "hold_deg", "length_mm",
               "repeats", "minutes", "program", "why", "candidate"]


def chain_records(design, programs: bool) -> list[dict]:
    """Run records of a machine from its description (``design``: a :class:`~.design_make.Design`): each run's W ball,
    arc and held axes."""
    out = []
    for i, (r, m, why) in enumerate(zip(design.runs, design.minutes, design.why), start=1):
        arc = arc_spec(arc_of(r.candidate, design.campaign.machine.description))
        out.append({"order": i, "pattern": r.pattern, "setup": r.setup.id, "mount": r.mount.id,
                    "R_B_mm": rounded_mm(r.setup.R_B), "position_mm": [rounded_mm(x) for x in r.mount.position],
                    "arc_deg": list(arc),
                    "hold_deg": {a: float(v) for a, v in r.candidate.hold_deg}, "length_mm": rounded_mm(r.length),
                    "repeats": r.repeats, "minutes": round(m, 2),
                    "program": program_name(i, r.pattern) if programs else None, "why": why,
                    "candidate": r.candidate.name})
    return out
