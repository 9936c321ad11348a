"""Tables and text of the deterministic identification, for the console and the report."""

from __future__ import annotations

import pandas as pd

from .... import units
from ....iso import iso_symbol


def identification_table(values: dict, *, reread: bool = False) -> pd.DataFrame:
    """One row per quantity of ``{name: Identified}``: recomputed and published value (display units),
    difference, flag (``reread``: the data read another way than the thesis', so a difference is what the reading
    changes, not a failure to reproduce)."""
    rows = []
    for name, ident in values.items():
        if ident.reproduced is None:
            flag = "not computed: " + ident.missing if ident.missing else ("no published value" if ident.reported is None else "")
        elif reread:
            flag = "as printed" if ident.reproduced else "changed by the reading"
        else:
            flag = "reproduced" if ident.reproduced else "NOT REPRODUCED"
        rows.append({
            "quantity": name,
            "ISO 230-7": iso_symbol(name) or "—",
            "unit": units.SYMBOL[ident.unit],
            "recomputed": "—" if ident.display is None else f"{ident.display:.2f}",
            "thesis": "—" if ident.reported is None else f"{ident.reported_display:.{ident.reported.decimals}f}",
            "difference": "—" if ident.difference is None else f"{ident.difference:+.3f}",
            "Eq": ident.equation,
            "status": flag,
            "note": ident.note or "",
        })
    return pd.DataFrame(rows)


def text_table(df: pd.DataFrame) -> str:
    """Plain-text table with text columns left-aligned."""
    left = {c: (lambda w: (lambda v: f"{v:<{w}}"))(max(len(c), df[c].astype(str).str.len().max()))
            for c in ("quantity", "status", "note") if c in df}
    header = {c: c.ljust(max(len(c), df[c].astype(str).str.len().max())) for c in left}
    return df.rename(columns=header).to_string(index=False, formatters={header[c]: f for c, f in left.items()})


def format_identification(result) -> str:
    """Human-readable text of an :class:`~.result.IdentificationResult`."""
    out = [f"Campaign: {result.source}", "",
           "Ball bar, thesis Eqs 4.10–4.18 on the means of the repeats, beside [reported.ballbar] (thesis: Table 4.5)"]
    out.append(text_table(identification_table(result.ballbar)))
    if result.ballbar_in_convention is not None:
        out += ["", f"Ball bar, the same equations on the offsets read in the campaign's convention ({result.convention}; "
                "docs/conventions.md), beside [reported.ballbar]"]
        out.append(text_table(identification_table(result.ballbar_in_convention, reread=True)))
    out += ["", "Touch probe, thesis Eqs 5.1–5.19, beside [reported.probe] (thesis: Table 5.3)"]
    if result.probe:
        out.append(text_table(identification_table(result.probe)))
    else:
        out.append("  (no probe data in this campaign)")
    if result.checks:
        out += ["", "Checks the deterministic method leaves out:"] + [f"  - {c}" for c in result.checks]
    if result.assumptions:
        out += ["", "Assumptions:"] + [f"  - {a}" for a in result.assumptions]
    return "\n".join(out)
