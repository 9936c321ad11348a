"""A design's runs as records (``design --json``'s ``runs``, design.html's table): the thesis' lever arms, or a
described machine's W ball, arc and held axes (the two campaign formats' planning kits, :mod:`.machine_kit`)."""

from __future__ import annotations

from .chain_candidates import arc_of, arc_spec


def _mm(v) -> float:
    """A length to a thousandth of a µm: 12.2877, not 12.287700000000001 (112.2877 − 100)."""
    return round(float(v), 6)


def program_name(order: int, pattern: str) -> str:
    return f"programs/{order:02d}_{pattern}.nc"


#: the columns of a design's run records, in order (the table of a design without runs has them too)
RUN_COLUMNS = ["order", "pattern", "setup", "mount", "R_B_mm", "Z_T_mm", "X_T_mm", "R_C_mm", "Z_C_mm", "length_mm",
               "repeats", "minutes", "program", "why", "candidate"]


#: ... on a described machine: the W ball's position, the arc and the held axes instead of the thesis' lever arms
DESCRIBED_RUN_COLUMNS = ["order", "pattern", "setup", "mount", "R_B_mm", "position_mm", "arc_deg", "hold_deg",
                         "length_mm", "repeats", "minutes", "program", "why", "candidate"]


def thesis_records(design: Design, programs: bool) -> list[dict]:
    """Run records in the thesis' campaign format: each run's lever arms."""
    out = []
    for i, (r, m, why) in enumerate(zip(design.runs, design.minutes, design.why), start=1):
        out.append({"order": i, "pattern": r.pattern, "setup": r.setup.id, "mount": r.mount.id,
                    "R_B_mm": _mm(r.setup.R_B), "Z_T_mm": _mm(r.setup.Z_T), "X_T_mm": _mm(r.setup.X_T),
                    "R_C_mm": _mm(r.mount.R_C), "Z_C_mm": _mm(r.mount.Z_C), "length_mm": _mm(r.length), "repeats": r.repeats, "minutes": round(m, 2),
                    "program": program_name(i, r.pattern) if programs else None, "why": why,
                    "candidate": r.candidate.name})
    return out


def described_records(design: Design, programs: bool) -> list[dict]:
    """Run records of a machine from its description: each run's W ball, arc and held axes."""
    out = []
    for i, (r, m, why) in enumerate(zip(design.runs, design.minutes, design.why), start=1):
        arc = arc_spec(arc_of(r.candidate, design.campaign.machine.description))
        out.append({"order": i, "pattern": r.pattern, "setup": r.setup.id, "mount": r.mount.id,
                    "R_B_mm": _mm(r.setup.R_B), "position_mm": [_mm(x) for x in r.mount.position],
                    "arc_deg": list(arc),
                    "hold_deg": {a: float(v) for a, v in r.candidate.hold_deg}, "length_mm": _mm(r.length),
                    "repeats": r.repeats, "minutes": round(m, 2),
                    "program": program_name(i, r.pattern) if programs else None, "why": why,
                    "candidate": r.candidate.name})
    return out
