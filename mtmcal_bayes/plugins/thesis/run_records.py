"""A design's runs in the thesis' campaign format (``design --json``'s ``runs``, design.html's table): each run's
lever arms R_B, Z_T, X_T and its mount's R_C, Z_C, as ``[ballbar]`` of that format gives them."""

from __future__ import annotations

from ...planning.run_records import program_name, rounded_mm

#: the columns of a design's run records, in order (the table of a design without runs has them too)
RUN_COLUMNS = ["order", "pattern", "setup", "mount", "R_B_mm", "Z_T_mm", "X_T_mm", "R_C_mm", "Z_C_mm", "length_mm",
               "repeats", "minutes", "program", "why", "candidate"]


def thesis_records(design, programs: bool) -> list[dict]:
    """Run records in the thesis' campaign format: each run's lever arms (mm)."""
    out = []
    for i, (r, m, why) in enumerate(zip(design.runs, design.minutes, design.why), start=1):
        out.append({"order": i, "pattern": r.pattern, "setup": r.setup.id, "mount": r.mount.id,
                    "R_B_mm": rounded_mm(r.setup.R_B), "Z_T_mm": rounded_mm(r.setup.Z_T), "X_T_mm": rounded_mm(r.setup.X_T),
                    "R_C_mm": rounded_mm(r.mount.R_C), "Z_C_mm": rounded_mm(r.mount.Z_C), "length_mm": rounded_mm(r.length),
                    "repeats": r.repeats, "minutes": round(m, 2),
                    "program": program_name(i, r.pattern) if programs else None, "why": why,
                    "candidate": r.candidate.name})
    return out
